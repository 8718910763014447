// The panel layout (plot_panels.hpp): columns grouped by role, angles told from other coordinates,
// groups split by scale, the path's axes chosen from its spans; the comparison figure's grid.
#include "nhdyn/io/plot_panels.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstddef>

namespace nhdyn {
namespace {

// A curve joins a panel only if the panel's range, with it, spans at most this many times the
// curve's own span: every curve then fills at least a tenth of its panel's height.
constexpr double scale_ratio = 10.0;
// The path is drawn with equal axes when its span ratio y/x lies in this interval: a panel is
// about 620 x 300 px, so both sides of the drawn box keep at least a third of the panel.
constexpr double path_ratio_low = 0.2;
constexpr double path_ratio_high = 1.5;

// The coordinate a velocity (x') or a reaction (R_x) belongs to.
std::string_view base_coordinate(const PlotColumn& c) {
  std::string_view name = c.name;
  if (c.role == PlotRole::velocity)
    while (!name.empty() && name.back() == '\'') name.remove_suffix(1);
  if (c.role == PlotRole::reaction && name.starts_with("R_")) name.remove_prefix(2);
  return name;
}

// A column whose values vary by no more than this fraction of the largest magnitude among the
// columns of its role is constant to round-off: a reaction that is zero up to 1e-17 is drawn as
// the zero it is, not magnified into noise. Below the tolerance of any run (rtol 1e-8 by
// default), such a variation is the integrator's error, not the motion.
constexpr double round_off = 1e-9;

struct ScaleGroup {
  std::vector<std::string> names;
  std::optional<std::pair<double, double>> y_range;  // set for a group of constants
};

// Splits columns of like units into groups of like scale (scale_ratio). Largest spans first,
// so a group's first member sets its range; each group keeps the columns in their given order,
// and the groups come in the order of their first column. `role_scale` is the largest |value|
// among the columns of their role (round_off).
std::vector<ScaleGroup> split_by_scale(const std::vector<const PlotColumn*>& columns, double role_scale) {
  const auto span = [&](const PlotColumn* c) {
    const double s = c->max - c->min;
    if (!std::isfinite(s)) return 0.0;
    return s <= round_off * role_scale ? 0.0 : s;
  };
  std::vector<std::size_t> order(columns.size());
  for (std::size_t i = 0; i < order.size(); ++i) order[i] = i;
  std::stable_sort(order.begin(), order.end(),
                   [&](std::size_t a, std::size_t b) { return span(columns[a]) > span(columns[b]); });
  struct Group {
    double lo = NAN, hi = NAN;
    double smallest = INFINITY;  // smallest positive span of a member
    std::vector<std::size_t> members;
  };
  std::vector<Group> groups;
  for (std::size_t i : order) {
    const PlotColumn* c = columns[i];
    const bool finite = std::isfinite(c->min) && std::isfinite(c->max);
    Group* home = nullptr;
    for (Group& g : groups) {
      if (!finite || std::isnan(g.lo)) {  // no values to place: any group will do
        home = &g;
        break;
      }
      const double lo = std::min(g.lo, c->min), hi = std::max(g.hi, c->max);
      const double smallest = span(c) > 0.0 ? std::min(g.smallest, span(c)) : g.smallest;
      // A group of constants takes any other constant: flat lines at their levels read well.
      if (!std::isfinite(smallest) || hi - lo <= scale_ratio * smallest) {
        home = &g;
        break;
      }
    }
    if (!home) home = &groups.emplace_back();
    home->members.push_back(i);
    if (finite) {
      home->lo = std::isnan(home->lo) ? c->min : std::min(home->lo, c->min);
      home->hi = std::isnan(home->hi) ? c->max : std::max(home->hi, c->max);
      if (span(c) > 0.0) home->smallest = std::min(home->smallest, span(c));
    }
  }
  // Each group's members in their given order; the groups in the order of their first member
  // (the first member of a group is its smallest index).
  std::vector<std::pair<std::size_t, std::size_t>> first;  // (first member, group)
  for (std::size_t k = 0; k < groups.size(); ++k) {
    std::sort(groups[k].members.begin(), groups[k].members.end());
    first.emplace_back(groups[k].members.front(), k);
  }
  std::sort(first.begin(), first.end());
  std::vector<ScaleGroup> out;
  for (const auto& [unused, k] : first) {
    const Group& g = groups[k];
    ScaleGroup& group = out.emplace_back();
    for (std::size_t i : g.members) group.names.push_back(columns[i]->name);
    if (std::isfinite(g.smallest) || std::isnan(g.lo)) continue;
    // Constants: a range around them wide enough that round-off does not show, and that holds
    // every level with a margin.
    const double mid = 0.5 * (g.lo + g.hi);
    double half = std::max({0.6 * (g.hi - g.lo), 0.5 * std::abs(mid), 0.1 * role_scale});
    if (!(half > 0.0)) half = 1.0;
    group.y_range.emplace(mid - half, mid + half);
  }
  return out;
}

}  // namespace

bool is_angle_name(std::string_view coordinate) {
  std::string_view stem = coordinate.substr(0, coordinate.find_first_of("_0123456789'"));
  while (!stem.empty() && stem.back() >= 'A' && stem.back() <= 'Z') stem.remove_suffix(1);
  static constexpr std::array<std::string_view, 13> angles = {
      "alpha", "beta", "gamma", "delta", "theta", "vartheta", "th", "phi", "varphi", "chi", "psi", "angle", "ang"};
  return std::find(angles.begin(), angles.end(), stem) != angles.end();
}

std::vector<PlotPanel> calc_plot_panels(const std::vector<PlotColumn>& columns,
                                        const std::optional<std::pair<PlotColumn, PlotColumn>>& path,
                                        const std::vector<std::string>& angles) {
  const auto is_angle = [&](std::string_view coordinate) {
    return is_angle_name(coordinate) || std::find(angles.begin(), angles.end(), coordinate) != angles.end();
  };
  std::vector<PlotPanel> panels;
  const auto lines = [&](PlotRole role, int which, std::string_view title) {
    // which: 1 only the angles, 0 only the others, -1 every column of the role.
    std::vector<const PlotColumn*> chosen;
    double role_scale = 0.0;
    // Reactions and actuator forces are both generalized forces: one scale for the two roles.
    const auto same_scale = [&](PlotRole r) {
      const auto forces = [](PlotRole x) { return x == PlotRole::reaction || x == PlotRole::actuator; };
      return r == role || (forces(r) && forces(role));
    };
    for (const PlotColumn& c : columns) {
      if (same_scale(c.role) && std::isfinite(c.max - c.min))
        role_scale = std::max({role_scale, std::abs(c.min), std::abs(c.max)});
      if (c.role != role) continue;
      if (which >= 0 && is_angle(base_coordinate(c)) != (which == 1)) continue;
      chosen.push_back(&c);
    }
    for (ScaleGroup& group : split_by_scale(chosen, role_scale)) {
      PlotPanel& p = panels.emplace_back(PlotPanel{std::string(title), PanelKind::lines, std::move(group.names)});
      p.y_range = group.y_range;
      if (p.y_range) p.title += ", constant to round-off";
    }
  };
  lines(PlotRole::coordinate, 1, "angles");
  lines(PlotRole::coordinate, 0, "coordinates");
  lines(PlotRole::velocity, 1, "angular velocities");
  lines(PlotRole::velocity, 0, "velocities");
  if (path) {
    const double xs = path->first.max - path->first.min;
    const double ys = path->second.max - path->second.min;
    const double scale = std::max({std::abs(path->first.min), std::abs(path->first.max), std::abs(path->second.min),
                                   std::abs(path->second.max)});
    if (std::isfinite(xs) && std::isfinite(ys) && xs > round_off * scale && ys > round_off * scale) {
      const double ratio = ys / xs;
      PlotPanel p{fmt::format("path {}({})", path->second.name, path->first.name), PanelKind::path,
                  {path->first.name, path->second.name}};
      p.equal_axes = ratio >= path_ratio_low && ratio <= path_ratio_high;
      panels.push_back(std::move(p));
    }
  }
  lines(PlotRole::reaction, 1, "reactions on angles");
  lines(PlotRole::reaction, 0, "reactions");
  lines(PlotRole::actuator, -1, "actuator forces u");
  lines(PlotRole::other, -1, "other columns");
  // The contacts' modes share one panel whatever their values: a mode is a level, not a scale.
  std::vector<std::string> modes;
  for (const PlotColumn& c : columns)
    if (c.role == PlotRole::mode) modes.push_back(c.name);
  if (!modes.empty())
    panels.push_back(PlotPanel{"contact modes: 0 rolling, 1 sliding, 2 free", PanelKind::steps, modes, {}, false,
                               std::make_pair(-0.25, 2.25)});
  std::vector<std::string> residuals;
  for (const PlotColumn& c : columns)
    if (c.role == PlotRole::residual) residuals.push_back(c.name);
  if (!residuals.empty()) panels.push_back(PlotPanel{"|residual|", PanelKind::log_abs, residuals});
  for (const PlotColumn& c : columns) {
    if (c.role != PlotRole::energy_error) continue;
    panels.push_back(PlotPanel{c.name == "balance_error" ? "energy balance error h - h0 - W" : "energy drift",
                               PanelKind::drift, {c.name}});
  }
  return panels;
}

std::vector<PlotPanel> calc_comparison_panels(const std::vector<std::string>& methods,
                                              const std::vector<std::string>& integrators,
                                              const std::vector<std::string>& quantities) {
  const auto column = [](const std::string& quantity, const std::string& method, const std::string& integrator) {
    return fmt::format("{}_{}_{}", quantity, method, integrator);
  };
  std::vector<PlotPanel> panels;
  if (integrators.size() == 1 || methods.size() == 1) {
    const bool by_method = integrators.size() == 1;
    for (const std::string& outer : by_method ? methods : integrators) {
      PlotPanel& p = panels.emplace_back();
      p.kind = PanelKind::log_abs;
      p.title = by_method ? fmt::format("{} ({})", outer, integrators.front())
                          : fmt::format("{} ({})", outer, methods.front());
      for (const std::string& q : quantities) {
        p.columns.push_back(by_method ? column(q, outer, integrators.front()) : column(q, methods.front(), outer));
        p.labels.push_back(q);
      }
    }
    return panels;
  }
  for (const std::string& q : quantities)
    for (const std::string& m : methods) {
      PlotPanel& p = panels.emplace_back();
      p.kind = PanelKind::log_abs;
      p.title = fmt::format("{}: {}", q, m);
      for (const std::string& i : integrators) {
        p.columns.push_back(column(q, m, i));
        p.labels.push_back(i);
      }
    }
  return panels;
}

void select_panel_columns(std::vector<PlotPanel>& panels, const std::vector<std::string>& chosen) {
  if (chosen.empty()) return;
  for (PlotPanel& p : panels) {
    for (std::size_t i = p.columns.size(); i-- > 0;) {
      if (std::find(chosen.begin(), chosen.end(), p.columns[i]) != chosen.end()) continue;
      p.columns.erase(p.columns.begin() + static_cast<std::ptrdiff_t>(i));
      if (i < p.labels.size()) p.labels.erase(p.labels.begin() + static_cast<std::ptrdiff_t>(i));
    }
  }
  std::erase_if(panels, [](const PlotPanel& p) { return p.columns.empty(); });
}

}  // namespace nhdyn
