// The panel rule of the plots (calc_plot_panels, calc_comparison_panels) and the choice of
// columns (--plot-columns), as pure functions: what goes into which panel, checked by the
// properties the rule promises (every curve fills at least a tenth of its panel, units and
// roles never share a panel) and on the shapes of the shipped examples.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <map>
#include <random>
#include <set>
#include <string>
#include <vector>

#include "nhdyn/core/error.hpp"
#include "nhdyn/io/plot.hpp"

namespace nhdyn {
namespace {

PlotColumn col(std::string name, PlotRole role, double min, double max) {
  return PlotColumn{std::move(name), role, min, max};
}

std::vector<std::vector<std::string>> names_of(const std::vector<PlotPanel>& panels) {
  std::vector<std::vector<std::string>> out;
  for (const PlotPanel& p : panels) out.push_back(p.columns);
  return out;
}

TEST(PlotPanels, AnglesAreToldByTheStemOfTheirName) {
  for (const char* angle : {"phi", "theta", "psi", "delta", "alpha", "beta", "gamma", "phi_r", "phi_l", "th1",
                            "th2", "thetaR", "thetaF", "theta1", "varphi", "angle"})
    EXPECT_TRUE(is_angle_name(angle)) << angle;
  for (const char* other : {"x", "y", "z", "x1", "q1", "s", "r", "rho", "xi", "eta", "sigma", "phase", "Phi",
                            "deltax", "alphabet", ""})
    EXPECT_FALSE(is_angle_name(other)) << other;
}

// The sled of examples/sled.toml over 10 s: x slides 250 m down the slope, y drifts 10 m, the
// heading stays below 0.3 rad, the reaction on phi is zero up to round-off.
TEST(PlotPanels, SledSplitsByUnitsAndScale) {
  const std::vector<PlotColumn> columns = {
      col("x", PlotRole::coordinate, 0, 252), col("y", PlotRole::coordinate, 0, 9.6),
      col("phi", PlotRole::coordinate, 0, 0.27), col("x'", PlotRole::velocity, 1, 49),
      col("y'", PlotRole::velocity, 0, 1.15), col("phi'", PlotRole::velocity, -0.2, 1),
      col("R_x", PlotRole::reaction, -0.25, 0.02), col("R_y", PlotRole::reaction, -0.1, 1.05),
      col("R_phi", PlotRole::reaction, -4e-16, 4e-16), col("residual_vel_blade", PlotRole::residual, 0, 1e-9),
      col("balance_error", PlotRole::energy_error, -4e-9, 3e-9)};
  const std::pair<PlotColumn, PlotColumn> path{col("x", PlotRole::coordinate, 0, 252),
                                               col("y", PlotRole::coordinate, 0, 9.6)};
  const std::vector<PlotPanel> panels = calc_plot_panels(columns, path);
  const std::vector<std::vector<std::string>> expected = {
      {"phi"}, {"x"}, {"y"}, {"phi'"}, {"x'"}, {"y'"}, {"x", "y"}, {"R_phi"}, {"R_x", "R_y"},
      {"residual_vel_blade"}, {"balance_error"}};
  EXPECT_EQ(names_of(panels), expected);
  ASSERT_EQ(panels.size(), expected.size());
  EXPECT_EQ(panels[0].title, "angles");
  EXPECT_EQ(panels[6].kind, PanelKind::path);
  EXPECT_FALSE(panels[6].equal_axes) << "a 10 m by 250 m path drawn to scale is a thin strip";
  // The reaction on phi is round-off: drawn flat in a range set by the other reactions.
  ASSERT_TRUE(panels[7].y_range.has_value());
  EXPECT_LT(panels[7].y_range->first, -0.1);
  EXPECT_GT(panels[7].y_range->second, 0.1);
  EXPECT_NE(panels[7].title.find("round-off"), std::string::npos);
  EXPECT_FALSE(panels[8].y_range.has_value());
  EXPECT_EQ(panels[9].kind, PanelKind::log_abs);
  EXPECT_EQ(panels[10].kind, PanelKind::drift);
  EXPECT_EQ(panels[10].title, "energy balance error h - h0 - W");
}

TEST(PlotPanels, PathHasEqualAxesOnlyWhenItsAspectAllows) {
  const auto path_panel = [](double x_span, double y_span) -> std::optional<PlotPanel> {
    const std::pair<PlotColumn, PlotColumn> path{col("x", PlotRole::coordinate, -x_span / 2, x_span / 2),
                                                 col("y", PlotRole::coordinate, 1, 1 + y_span)};
    for (const PlotPanel& p : calc_plot_panels({}, path))
      if (p.kind == PanelKind::path) return p;
    return std::nullopt;
  };
  ASSERT_TRUE(path_panel(1.1, 1.1));
  EXPECT_TRUE(path_panel(1.1, 1.1)->equal_axes);   // the rolling disk's circle
  EXPECT_TRUE(path_panel(1.0, 0.25)->equal_axes);
  EXPECT_TRUE(path_panel(1.0, 1.4)->equal_axes);
  EXPECT_FALSE(path_panel(250, 10)->equal_axes);   // the sled
  EXPECT_FALSE(path_panel(10, 30)->equal_axes);    // tall
  EXPECT_FALSE(path_panel(25, 0));                 // a line
  EXPECT_FALSE(path_panel(25, 2.5e-13));           // a line to round-off (the upright bicycle)
  EXPECT_FALSE(path_panel(0, 0));                  // a point
  EXPECT_FALSE(path_panel(NAN, 1));                // no finite values
}

// Random columns: whatever the ranges, each column is drawn exactly once, a panel holds one role
// and one kind of unit, and every curve that is not constant spans at least a tenth of its panel.
TEST(PlotPanels, EveryCurveFillsATenthOfItsPanel) {
  std::mt19937 random(12345);
  std::uniform_real_distribution<double> exponent(-3.0, 3.0), unit(-1.0, 1.0);
  const std::vector<std::string> names = {"x", "y", "z", "phi", "theta", "psi", "q1", "s"};
  for (int trial = 0; trial < 300; ++trial) {
    std::vector<PlotColumn> columns;
    std::map<std::string, PlotColumn> by_name;
    for (const std::string& n : names) {
      for (PlotRole role : {PlotRole::coordinate, PlotRole::velocity, PlotRole::reaction}) {
        const std::string name = role == PlotRole::coordinate ? n : role == PlotRole::velocity ? n + "'" : "R_" + n;
        const double centre = unit(random) * std::pow(10.0, exponent(random));
        const double span = trial % 5 == 0 && n == "s" ? 0.0 : std::pow(10.0, exponent(random));
        columns.push_back(col(name, role, centre, centre + span));
        by_name[name] = columns.back();
      }
    }
    const std::vector<PlotPanel> panels = calc_plot_panels(columns, std::nullopt);
    std::multiset<std::string> drawn;
    for (const PlotPanel& p : panels) {
      ASSERT_EQ(p.kind, PanelKind::lines);
      double lo = INFINITY, hi = -INFINITY, smallest = INFINITY;
      std::set<PlotRole> roles;
      std::set<bool> angles;
      for (const std::string& name : p.columns) {
        drawn.insert(name);
        const PlotColumn& c = by_name.at(name);
        roles.insert(c.role);
        std::string base = name;
        if (c.role == PlotRole::velocity) base.pop_back();
        if (c.role == PlotRole::reaction) base = base.substr(2);
        angles.insert(is_angle_name(base));
        lo = std::min(lo, c.min);
        hi = std::max(hi, c.max);
        if (c.max > c.min) smallest = std::min(smallest, c.max - c.min);
      }
      EXPECT_EQ(roles.size(), 1u);
      EXPECT_EQ(angles.size(), 1u);
      if (std::isfinite(smallest)) {
        EXPECT_LE(hi - lo, 10.0 * smallest * (1 + 1e-12)) << p.title;
      }
    }
    EXPECT_EQ(drawn.size(), columns.size());
    for (const PlotColumn& c : columns) EXPECT_EQ(drawn.count(c.name), 1u) << c.name;
  }
}

TEST(PlotPanels, ConstantsShareAPanelAtTheirLevels) {
  // The upright bicycle's wheel rates are constant; they are drawn together, in a fixed range
  // that holds both levels.
  const std::vector<PlotPanel> panels = calc_plot_panels(
      {col("thetaR'", PlotRole::velocity, -16.7, -16.7), col("thetaF'", PlotRole::velocity, -14.3, -14.3 + 1e-13)},
      std::nullopt);
  ASSERT_EQ(panels.size(), 1u);
  EXPECT_EQ(panels[0].columns, (std::vector<std::string>{"thetaR'", "thetaF'"}));
  ASSERT_TRUE(panels[0].y_range);
  EXPECT_LT(panels[0].y_range->first, -16.7);
  EXPECT_GT(panels[0].y_range->second, -14.3);
}

// Contacts with modes: every NAME_mode in one steps panel with the levels 0..2 in view, after the
// other columns and before the residuals, whatever the modes' values (a constant mode too).
TEST(PlotPanels, ContactModesShareOneStepsPanel) {
  const std::vector<PlotPanel> panels = calc_plot_panels(
      {col("x", PlotRole::coordinate, 0, 2), col("ball_N", PlotRole::other, 0.98, 0.98),
       col("ball_mode", PlotRole::mode, 0, 1), col("wheel_mode", PlotRole::mode, 2, 2),
       col("residual_pos", PlotRole::residual, 0, 1e-12)},
      std::nullopt);
  ASSERT_EQ(panels.size(), 4u);
  EXPECT_EQ(panels[2].kind, PanelKind::steps);
  EXPECT_EQ(panels[2].columns, (std::vector<std::string>{"ball_mode", "wheel_mode"}));
  ASSERT_TRUE(panels[2].y_range);
  EXPECT_LT(panels[2].y_range->first, 0.0);
  EXPECT_GT(panels[2].y_range->second, 2.0);
  EXPECT_EQ(panels[3].kind, PanelKind::log_abs);
}

// A model file names its angles by use (inside sin, cos, tan): alpha is one by its name, s by use.
TEST(PlotPanels, AnglesKnownByUseJoinTheAngles) {
  const std::vector<PlotColumn> columns = {col("s", PlotRole::coordinate, 0, 3), col("x", PlotRole::coordinate, 0, 2),
                                           col("alpha", PlotRole::coordinate, 0, 1),
                                           col("s'", PlotRole::velocity, 0, 1), col("R_s", PlotRole::reaction, 0, 1)};
  EXPECT_EQ(names_of(calc_plot_panels(columns, std::nullopt, {"s"})),
            (std::vector<std::vector<std::string>>{{"s", "alpha"}, {"x"}, {"s'"}, {"R_s"}}));
  const std::vector<PlotPanel> by_name = calc_plot_panels(columns, std::nullopt);
  EXPECT_EQ(by_name[0].columns, (std::vector<std::string>{"alpha"}));
  EXPECT_EQ(by_name[1].columns, (std::vector<std::string>{"s", "x"}));
}

// Without constraints the reactions are round-off; the actuator forces give them their scale.
TEST(PlotPanels, ReactionsAreMeasuredAgainstTheActuatorForces) {
  const std::vector<PlotPanel> panels = calc_plot_panels(
      {col("R_x", PlotRole::reaction, -3e-14, 1.5e-14), col("u_swing", PlotRole::actuator, -90, -8)}, std::nullopt);
  ASSERT_EQ(panels.size(), 2u);
  ASSERT_TRUE(panels[0].y_range);
  EXPECT_LT(panels[0].y_range->first, -1.0);
  EXPECT_GT(panels[0].y_range->second, 1.0);
  EXPECT_FALSE(panels[1].y_range);
}

TEST(PlotPanels, ActuatorsAndOtherColumnsComeBeforeTheResiduals) {
  const std::vector<PlotPanel> panels =
      calc_plot_panels({col("residual_pos_heading", PlotRole::residual, 0, 1e-10),
                        col("u_heading", PlotRole::actuator, -3, 7), col("x''", PlotRole::other, -1, 1),
                        col("E", PlotRole::energy_error, 1, 1.1)},
                       std::nullopt);
  ASSERT_EQ(panels.size(), 4u);
  EXPECT_EQ(panels[0].title, "actuator forces u");
  EXPECT_EQ(panels[1].title, "other columns");
  EXPECT_EQ(panels[2].kind, PanelKind::log_abs);
  EXPECT_EQ(panels[3].title, "energy drift");
}

PlotRequest sled_request() {
  PlotRequest request;
  request.coordinates = {"x", "y", "phi"};
  request.velocities = {"x'", "y'", "phi'"};
  request.reactions = {"R_x", "R_y", "R_phi"};
  request.residuals = {"residual_vel_blade"};
  request.path = std::make_pair(std::string("x"), std::string("y"));
  request.energy = "balance_error";
  return request;
}

const std::vector<std::string> sled_columns = {"t",   "x",   "y",   "phi", "x'",  "y'", "phi'", "x''", "y''",
                                               "phi''", "R_x", "R_y", "R_phi", "residual_vel_blade", "E",
                                               "balance_error"};

TEST(PlotColumns, ChosenColumnsKeepTheirRoles) {
  PlotRequest request = sled_request();
  select_plot_columns(request, sled_columns, {"phi", "x''", "R_y", "y"});
  EXPECT_EQ(request.coordinates, (std::vector<std::string>{"y", "phi"}));
  EXPECT_TRUE(request.velocities.empty());
  EXPECT_EQ(request.reactions, (std::vector<std::string>{"R_y"}));
  EXPECT_TRUE(request.residuals.empty());
  EXPECT_EQ(request.others, (std::vector<std::string>{"x''"}));
  EXPECT_FALSE(request.path) << "only y of the path was chosen";
  EXPECT_FALSE(request.energy);

  PlotRequest both = sled_request();
  select_plot_columns(both, sled_columns, {"x", "y", "balance_error"});
  ASSERT_TRUE(both.path);
  EXPECT_EQ(both.energy, "balance_error");

  PlotRequest untouched = sled_request();
  select_plot_columns(untouched, sled_columns, {});
  EXPECT_EQ(untouched.coordinates, sled_request().coordinates);
  EXPECT_TRUE(untouched.path);
}

TEST(PlotColumns, AnUnknownColumnIsRefusedWithTheListOfColumns) {
  PlotRequest request = sled_request();
  try {
    select_plot_columns(request, sled_columns, {"x", "theta"});
    FAIL() << "no InputError";
  } catch (const InputError& e) {
    const std::string message = e.what();
    EXPECT_NE(message.find("--plot-columns"), std::string::npos) << message;
    EXPECT_NE(message.find("'theta'"), std::string::npos) << message;
    for (const std::string& name : sled_columns) EXPECT_NE(message.find(name), std::string::npos) << name;
  }
  EXPECT_THROW(require_plot_columns(sled_columns, {""}), InputError);
  EXPECT_NO_THROW(require_plot_columns(sled_columns, {"t", "E"}));
}

TEST(ComparisonPanels, OnePanelPerMethodOrIntegrator) {
  const std::vector<PlotPanel> by_method =
      calc_comparison_panels({"sanh", "lagrange"}, {"dopri5"}, {"error", "residual_vel"});
  ASSERT_EQ(by_method.size(), 2u);
  EXPECT_EQ(by_method[1].columns, (std::vector<std::string>{"error_lagrange_dopri5", "residual_vel_lagrange_dopri5"}));
  EXPECT_EQ(by_method[1].labels, (std::vector<std::string>{"error", "residual_vel"}));
  EXPECT_EQ(by_method[1].kind, PanelKind::log_abs);

  const std::vector<PlotPanel> by_integrator = calc_comparison_panels({"sanh"}, {"rk4", "dop853"}, {"error"});
  ASSERT_EQ(by_integrator.size(), 2u);
  EXPECT_EQ(by_integrator[0].columns, (std::vector<std::string>{"error_sanh_rk4"}));

  // Several of both: quantity x method, a curve per integrator.
  std::vector<PlotPanel> grid = calc_comparison_panels({"sanh", "lagrange", "nullspace"}, {"rk4", "dopri5"},
                                                       {"error", "residual_pos"});
  ASSERT_EQ(grid.size(), 6u);
  for (const PlotPanel& p : grid) EXPECT_EQ(p.labels, (std::vector<std::string>{"rk4", "dopri5"}));
  EXPECT_EQ(grid[4].columns, (std::vector<std::string>{"residual_pos_lagrange_rk4", "residual_pos_lagrange_dopri5"}));

  select_panel_columns(grid, {"error_sanh_dopri5", "residual_pos_nullspace_rk4"});
  ASSERT_EQ(grid.size(), 2u);
  EXPECT_EQ(grid[0].columns, (std::vector<std::string>{"error_sanh_dopri5"}));
  EXPECT_EQ(grid[0].labels, (std::vector<std::string>{"dopri5"}));
  EXPECT_EQ(grid[1].columns, (std::vector<std::string>{"residual_pos_nullspace_rk4"}));
}

}  // namespace
}  // namespace nhdyn
