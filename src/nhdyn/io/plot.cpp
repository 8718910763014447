// The script writer of the plots (plot.hpp, xy_plot.hpp): from a request to the gnuplot script of
// its figure. write_plot and write_panel_plot resolve the panels' columns against the CSV
// (plot_csv.hpp), lay them out (plot_panels.hpp) and write one multiplot script; write_xy_plot
// writes its single panel; gnuplot.hpp runs the script and puts the picture in place.
#include "nhdyn/io/plot.hpp"
#include "nhdyn/io/xy_plot.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <array>
#include <charconv>
#include <cmath>
#include <cstdint>
#include <string_view>
#include <system_error>

#include "nhdyn/core/error.hpp"
#include "nhdyn/io/detail/gnuplot.hpp"
#include "nhdyn/io/detail/plot_csv.hpp"

namespace nhdyn {
namespace {

namespace fs = std::filesystem;

// A time-series panel is ~550 px wide; 50 000 points per curve is ~90 per pixel column, enough
// for any curve that the picture can resolve, and keeps gnuplot well under 1 s per curve.
constexpr std::uintmax_t max_rows_per_curve = 50000;

// ---------------------------------------------------------------------------------------------
// Quoting for gnuplot.

// A label (title, legend entry) on one line: control characters become spaces.
std::string one_line(std::string_view text) {
  std::string out(text);
  for (char& c : out) {
    const auto byte = static_cast<unsigned char>(c);
    if (byte < 0x20 || byte == 0x7f) c = ' ';
  }
  return out;
}

// A gnuplot string expression whose value is exactly `text` (for file names and labels).
// Single-quoted gnuplot strings take every byte literally: no backslash escapes, no `backquote`
// command substitution, no @macro expansion. The quote itself is joined in as a double-quoted
// "'" ('it'."'".'s'): gnuplot's doubled quote ('it''s') works for one quote but not for two in a
// row (q''). A control character, which cannot sit inside a single-quoted string on one script
// line, is joined in as a double-quoted octal escape ('a'."\012".'b').
std::string gp_string(std::string_view text) {
  std::string out = "'";
  for (char c : text) {
    const auto byte = static_cast<unsigned char>(c);
    if (c == '\'') {
      out += "'.\"'\".'";
    } else if (byte < 0x20 || byte == 0x7f) {
      out += fmt::format("'.\"\\{:03o}\".'", static_cast<unsigned>(byte));
    } else {
      out += c;
    }
  }
  out += '\'';
  return out;
}

// A label as a gnuplot string literal.
std::string gp_label(std::string_view text) { return gp_string(one_line(text)); }

// ---------------------------------------------------------------------------------------------
// The script.

struct Column {
  int index;         // 1-based, as gnuplot counts
  std::string name;  // as in the header
};

// One curve: `rows` selects the rows (" skip 1 every 20"), `using_spec` the columns.
std::string plot_clause(std::string_view rows, std::string_view using_spec, std::string_view style,
                        std::string_view title) {
  return fmt::format("csv_file{} using {} with {} title {}", rows, using_spec, style,
                     gp_label(title));
}

std::string join_clauses(const std::vector<std::string>& clauses) {
  std::string out = "plot ";
  for (std::size_t i = 0; i < clauses.size(); ++i) {
    out += (i == 0 ? "" : ", \\\n     ") + clauses[i];
  }
  return out + "\n";
}

// Colours of the event lines, one per event name in order of first appearance: dark enough
// on white, distinct from gnuplot's first curve colours.
constexpr std::array<std::string_view, 6> event_colours = {"#c00000", "#7030a0", "#c07000",
                                                           "#006060", "#606060", "#a00060"};
// With more events than this, the lines carry no text (the legend names them).
constexpr std::size_t max_labelled_events = 8;
// Vertical lines drawn at most; a run that records thousands of crossings gets a thinned comb.
constexpr std::size_t max_drawn_events = 400;

struct ScriptPanel {
  PlotPanel panel;
  std::vector<Column> curves;  // resolved columns; for a path {x, y}
};

struct ScriptInput {
  std::string title;
  std::string time_name;
  fs::path csv;     // absolute
  fs::path output;  // absolute, the temporary file
  std::vector<ScriptPanel> panels;
  std::vector<PlotEvent> events;
  std::vector<double> drift0;  // first value of each drift panel's column, in panel order
  std::optional<std::pair<double, double>> log_range;  // shared |value| range of the log panels
  int header_lines = 1;       // lines before the first data row
  std::uintmax_t stride = 1;  // draw every stride-th row
  int layout_columns = 0;     // 0: from the number of panels
};

// Writes the script of a figure, one method per kind of panel; they share the rows drawn, the
// event marks and the script text `s`.
class ScriptWriter {
 public:
  explicit ScriptWriter(const ScriptInput& in)
      : in_(in),
        // gnuplot skips the header lines; `every` also thins the rows, `all` takes them all.
        all_(fmt::format(" skip {}", in.header_lines)),
        every_(in.stride > 1 ? fmt::format("{} every {}", all_, in.stride) : all_),
        thinned_(in.stride > 1 ? fmt::format(" (1 row in {} drawn)", in.stride) : ""),
        event_step_(in.events.size() > max_drawn_events
                        ? (in.events.size() + max_drawn_events - 1) / max_drawn_events
                        : 1),
        label_events_(in.events.size() <= max_labelled_events) {
    // Events: one colour per name; the names in order of first appearance.
    for (const PlotEvent& e : in.events)
      if (std::find(event_names_.begin(), event_names_.end(), e.name) == event_names_.end())
        event_names_.push_back(e.name);
  }

  std::string write() {
    write_header();
    std::size_t drift_index = 0;
    for (const ScriptPanel& p : in_.panels) {
      switch (p.panel.kind) {
        case PanelKind::lines:
          write_lines(p);
          break;
        case PanelKind::steps:
          write_lines(p, true);
          break;
        case PanelKind::drift:
          write_drift(p, in_.drift0[drift_index++]);
          break;
        case PanelKind::log_abs:
          write_log_abs(p);
          break;
        case PanelKind::path:
          write_path(p);
          break;
      }
    }
    s_ += "unset multiplot\n";
    s_ += "set output\n";  // closes and flushes the PNG
    return s_;
  }

 private:
  void write_header() {
    const int panels = static_cast<int>(in_.panels.size());
    const int layout_columns = in_.layout_columns > 0 ? std::min(in_.layout_columns, panels)
                               : panels == 1          ? 1
                               : panels <= 4          ? 2
                                                      : 3;
    const int layout_rows = (panels + layout_columns - 1) / layout_columns;
    const int width = layout_columns == 1 ? 1000 : 620 * layout_columns;
    const int height = 80 + 340 * layout_rows;
    s_ += "# Written by nhdyn (src/nhdyn/io/plot.cpp) for one plot; deleted after the run.\n";
    s_ += "set encoding utf8\n";
    s_ += "if (strstrt(' '.GPVAL_TERMINALS.' ', ' pngcairo ') > 0) {\n";
    s_ += fmt::format("  set terminal pngcairo size {},{} font 'Sans,10' noenhanced\n", width, height);
    s_ += "} else {\n";
    s_ += fmt::format("  set terminal png size {},{} noenhanced\n", width, height);
    s_ += "}\n";
    // Names such as residual_vel_blade or x' are drawn as written, not as enhanced-text markup.
    s_ += "set termoption noenhanced\n";
    // Absolute paths, so no file name can read as one of gnuplot's special files
    // ('-', '+', '<command', '~/...').
    s_ += fmt::format("csv_file = {}\n", gp_string(in_.csv.string()));
    s_ += fmt::format("output_file = {}\n", gp_string(in_.output.string()));
    s_ += "set output output_file\n";
    s_ += "set datafile separator comma\n";
    s_ += "set grid\n";
    s_ += "set key below horizontal height 1\n";  // a little air between x label and legend
    s_ += fmt::format("set multiplot layout {},{} title {} font ',13'\n", layout_rows, layout_columns,
                      gp_label(in_.title));
  }

  std::string_view colour_of(const std::string& name) const {
    const auto at = std::find(event_names_.begin(), event_names_.end(), name) - event_names_.begin();
    return event_colours[static_cast<std::size_t>(at) % event_colours.size()];
  }

  // The events on a time axis: dashed vertical lines (arrows from the bottom to the top of the
  // graph), their names written along them when there are few, and one legend entry per name.
  void mark_events(std::vector<std::string>& clauses) {
    if (in_.events.empty()) return;
    int tag = 1;
    for (std::size_t i = 0; i < in_.events.size(); i += event_step_) {
      const PlotEvent& e = in_.events[i];
      s_ += fmt::format("set arrow {} from {:.17g}, graph 0 to {:.17g}, graph 1 nohead dashtype 2 lw 1.2 "
                        "linecolor rgb '{}' front\n",
                        tag, e.t, e.t, colour_of(e.name));
      if (label_events_)
        s_ += fmt::format("set label {} {} at {:.17g}, graph 0.97 rotate by 90 right offset character -0.7,0 "
                          "font ',8' textcolor rgb '{}' front\n",
                          tag, gp_label(e.name), e.t, colour_of(e.name));
      ++tag;
    }
    for (const std::string& name : event_names_)
      clauses.push_back(fmt::format("NaN with lines dashtype 2 lw 1.2 linecolor rgb '{}' title {}", colour_of(name),
                                    gp_label("event " + name)));
  }

  void clear_marks() { s_ += "unset arrow\nunset label\n"; }

  static const std::string& title_of(const ScriptPanel& p, std::size_t i) {
    return p.panel.labels.size() == p.curves.size() ? p.panel.labels[i] : p.curves[i].name;
  }

  // steps: each value holds until the next row (a mode column; its switch row, at the event,
  // carries the mode after it), every row drawn so no switch is thinned away.
  void write_lines(const ScriptPanel& p, bool steps = false) {
    s_ += fmt::format("set title {}\n", gp_label(fmt::format("{}{}", p.panel.title, thinned_)));
    s_ += fmt::format("set xlabel {}\nset ylabel ''\n", gp_label(in_.time_name));
    std::vector<std::string> clauses;
    for (std::size_t i = 0; i < p.curves.size(); ++i)
      clauses.push_back(plot_clause(steps ? all_ : every_, fmt::format("1:{}", p.curves[i].index),
                                    steps ? "steps" : "lines", title_of(p, i)));
    mark_events(clauses);
    if (steps) s_ += "set ytics 1\n";
    if (p.panel.y_range)
      s_ += fmt::format("set yrange [{:.17g}:{:.17g}]\n", p.panel.y_range->first, p.panel.y_range->second);
    s_ += join_clauses(clauses);
    if (p.panel.y_range) s_ += "set autoscale y\n";
    if (steps) s_ += "set ytics autofreq\n";
    clear_marks();
  }

  void write_drift(const ScriptPanel& p, double drift0) {
    const Column& e = p.curves.front();
    // Exponent form: always a gnuplot float (a bare "1" would be an integer), all 17 digits.
    s_ += fmt::format("drift0 = {:.16e}\n", drift0);
    s_ += fmt::format("set title {}\n", gp_label(fmt::format("{}{}", p.panel.title, thinned_)));
    s_ += fmt::format("set xlabel {}\nset ylabel ''\n", gp_label(in_.time_name));
    std::vector<std::string> clauses{plot_clause(every_, fmt::format("1:(column({}) - drift0)", e.index), "lines",
                                                 drift0 == 0.0 ? title_of(p, 0)
                                                               : fmt::format("{0}(t) - {0}(t0)", title_of(p, 0)))};
    mark_events(clauses);
    s_ += join_clauses(clauses);
    clear_marks();
  }

  void write_log_abs(const ScriptPanel& p) {
    // A value that is exactly zero (at t = 0, or a constraint met to the last bit) has no
    // logarithm. It is left out (mapped to NaN, which gnuplot skips, leaving a gap in the
    // line) rather than clamped to a floor such as 1e-300, which would stretch the axis over
    // 300 empty decades and draw a comb of spikes down to it. If no drawn row has a nonzero
    // value, gnuplot would stop on "all points y value undefined": a first pass (stats)
    // finds the largest |r| over the rows drawn, and when it is 0 the panel shows |r| on a
    // linear axis instead. Expressions are written inline: calling a user-defined gnuplot
    // function costs several times more per row.
    std::string largest = "largest = 0";
    for (const Column& c : p.curves)
      largest += fmt::format(", largest = (abs(column({0})) > largest ? abs(column({0})) : largest)", c.index);
    s_ += fmt::format("stats csv_file{} using ({}, largest) nooutput\n", every_, largest);
    s_ += fmt::format("set xlabel {}\nset ylabel ''\n", gp_label(in_.time_name));
    std::vector<std::string> log_clauses;
    std::vector<std::string> linear_clauses;
    for (std::size_t i = 0; i < p.curves.size(); ++i) {
      const Column& c = p.curves[i];
      log_clauses.push_back(plot_clause(
          every_, fmt::format("1:(column({0}) != 0 ? abs(column({0})) : NaN)", c.index), "lines", title_of(p, i)));
      linear_clauses.push_back(
          plot_clause(every_, fmt::format("1:(abs(column({})))", c.index), "lines", title_of(p, i)));
    }
    mark_events(log_clauses);
    mark_events(linear_clauses);
    s_ += "if (STATS_max > 0) {\n";
    s_ += fmt::format("set title {}\n",
                      gp_label(fmt::format("{}, log scale, exact zeros left out{}", p.panel.title, thinned_)));
    s_ += "set logscale y\nset format y '1e%L'\n";
    if (in_.log_range)
      s_ += fmt::format("set yrange [{:.17g}:{:.17g}]\n", in_.log_range->first, in_.log_range->second);
    s_ += join_clauses(log_clauses);
    s_ += "unset logscale y\nset format y '% h'\nset autoscale y\n";
    s_ += "} else {\n";
    s_ += fmt::format("set title {}\n",
                      gp_label(fmt::format("{}, every value exactly 0{}", p.panel.title, thinned_)));
    s_ += join_clauses(linear_clauses);
    s_ += "}\n";
    clear_marks();
  }

  void write_path(const ScriptPanel& p) {
    const Column& x = p.curves[0];
    const Column& y = p.curves[1];
    s_ += fmt::format("set title {}\n",
                      gp_label(fmt::format("{}{}{}", p.panel.title,
                                           p.panel.equal_axes ? ", equal scales" : ", scales not equal", thinned_)));
    s_ += fmt::format("set xlabel {}\nset ylabel {}\n", gp_label(x.name), gp_label(y.name));
    if (p.panel.equal_axes) {
      // Equal scales make the panel narrow: choose an x tic step giving ~4 intervals so the
      // tic labels do not run into each other.
      s_ += fmt::format("stats csv_file{} using {} nooutput\n", every_, x.index);
      s_ += "if (STATS_max > STATS_min) {\n";
      s_ += "  path_step = (STATS_max - STATS_min) / 4.0\n";
      s_ += "  path_unit = 10.0**floor(log10(path_step))\n";
      s_ += "  path_f = path_step / path_unit\n";
      s_ += "  path_tic = (path_f < 1.5 ? 1 : path_f < 3.5 ? 2 : path_f < 7.5 ? 5 : 10) * path_unit\n";
      s_ += "  set xtics path_tic\n";  // not "set xtics (...)": that would read as a list of tics
      s_ += "}\n";
      s_ += "set size ratio -1\n";
    } else {
      // Each axis on its own scale, with a margin so the path does not run along the frame.
      s_ += "set offsets graph 0.05, graph 0.05, graph 0.05, graph 0.05\n";
    }
    // The events where the state is known: a circle at (x, y), named when there are few.
    int tag = 1;
    for (std::size_t i = 0; i < in_.events.size(); i += event_step_) {
      const PlotEvent& e = in_.events[i];
      std::optional<double> ex, ey;
      for (const auto& [name, value] : e.state) {
        if (name == x.name) ex = value;
        if (name == y.name) ey = value;
      }
      if (!ex || !ey) continue;
      s_ += fmt::format("set label {} {} at {:.17g}, {:.17g} point pointtype 6 pointsize 1.6 linecolor rgb '{}' "
                        "offset character 0.8,0.8 font ',8' textcolor rgb '{}' front\n",
                        tag++, gp_label(label_events_ ? e.name : ""), *ex, *ey, colour_of(e.name),
                        colour_of(e.name));
    }
    s_ += join_clauses({plot_clause(every_, fmt::format("{}:{}", x.index, y.index), "lines", "path"),
                        fmt::format("csv_file{} every ::0::0 using {}:{} with points pt 7 ps 1.2 title 'start'",
                                    all_, x.index, y.index)});
    s_ += "set size noratio\nset xtics autofreq\nset offsets 0, 0, 0, 0\n";
    clear_marks();
  }

  const ScriptInput& in_;
  const std::string all_;      // every data row
  const std::string every_;    // the drawn rows
  const std::string thinned_;  // said in the titles when rows are thinned
  const std::size_t event_step_;
  const bool label_events_;
  std::vector<std::string> event_names_;
  std::string s_;
};

std::string make_script(const ScriptInput& in) { return ScriptWriter(in).write(); }

std::string join_names(const std::vector<std::string>& names) {
  std::string out;
  for (std::size_t i = 0; i < names.size(); ++i) out += (i == 0 ? "" : ", ") + names[i];
  return out;
}

}  // namespace

void require_plot_columns(const std::vector<std::string>& all, const std::vector<std::string>& chosen,
                          std::string_view option) {
  for (const std::string& name : chosen) {
    if (std::find(all.begin(), all.end(), name) != all.end()) continue;
    throw InputError(fmt::format("{} names the column '{}', which this run does not write; its columns are: {}; "
                                 "choose among them (comma-separated)",
                                 option, name, join_names(all)));
  }
}

void select_plot_columns(PlotRequest& request, const std::vector<std::string>& all,
                         const std::vector<std::string>& chosen, std::string_view option) {
  if (chosen.empty()) return;
  require_plot_columns(all, chosen, option);
  const auto is_chosen = [&](const std::string& name) {
    return std::find(chosen.begin(), chosen.end(), name) != chosen.end();
  };
  std::vector<std::string> placed;
  for (std::vector<std::string>* role : {&request.coordinates, &request.velocities, &request.reactions,
                                         &request.actuators, &request.residuals, &request.others, &request.modes}) {
    std::erase_if(*role, [&](const std::string& name) { return !is_chosen(name); });
    placed.insert(placed.end(), role->begin(), role->end());
  }
  if (request.energy && !is_chosen(*request.energy)) request.energy.reset();
  if (request.energy) placed.push_back(*request.energy);
  if (request.path && !(is_chosen(request.path->first) && is_chosen(request.path->second))) request.path.reset();
  for (const std::string& name : chosen)
    if (std::find(placed.begin(), placed.end(), name) == placed.end()) {
      request.others.push_back(name);
      placed.push_back(name);
    }
}

namespace {

// Resolves the panels' columns, reads what the script needs from the CSV and draws it.
void draw_panels(const std::string& title, const fs::path& csv, const CsvHead& head, std::vector<PlotPanel> panels,
                 const std::vector<PlotEvent>& events, bool same_log_range, int layout_columns,
                 const fs::path& png) {
  std::error_code ec;
  ScriptInput in;
  in.csv = fs::absolute(csv, ec);
  if (ec) throw FileError(fmt::format("cannot resolve the CSV path '{}' ({})", csv.string(), ec.message()));
  const fs::path target = fs::absolute(png, ec);
  if (ec) throw FileError(fmt::format("cannot resolve the plot path '{}' ({})", png.string(), ec.message()));
  in.title = title;
  in.time_name = head.names.front();
  in.header_lines = head.header_lines;
  in.events = events;
  in.layout_columns = layout_columns;
  if (head.rows > max_rows_per_curve) in.stride = (head.rows + max_rows_per_curve - 1) / max_rows_per_curve;
  std::vector<int> log_indices;
  for (PlotPanel& p : panels) {
    ScriptPanel& sp = in.panels.emplace_back();
    for (const std::string& name : p.columns) sp.curves.push_back(Column{column_of(head, csv, name, "a"), name});
    if (p.kind == PanelKind::log_abs)
      for (const Column& c : sp.curves) log_indices.push_back(c.index);
    if (p.kind == PanelKind::drift) {
      const std::string& name = p.columns.front();
      const std::size_t i = static_cast<std::size_t>(sp.curves.front().index) - 1;
      const std::string field = i < head.first_row.size() ? head.first_row[i] : "";
      double first = 0.0;
      const auto [end, err] = std::from_chars(field.data(), field.data() + field.size(), first);
      if (err != std::errc{} || end != field.data() + field.size() || !std::isfinite(first)) {
        throw InputError(fmt::format(
            "cannot plot the energy drift: the first value '{}' of column '{}' in '{}' is not a "
            "finite number; check the CSV, or plot without the energy",
            field, name, csv.string()));
      }
      in.drift0.push_back(first);
    }
    sp.panel = std::move(p);
  }
  if (same_log_range && !log_indices.empty()) {
    double lo = INFINITY, hi = 0.0;
    for (const ColumnRange& r : read_column_ranges(csv, head.header_lines, log_indices, in.stride)) {
      if (std::isfinite(r.min_abs_positive)) lo = std::min(lo, r.min_abs_positive);
      if (std::isfinite(r.max_abs)) hi = std::max(hi, r.max_abs);
    }
    if (std::isfinite(lo) && hi > 0.0) {
      const double low = std::pow(10.0, std::floor(std::log10(lo)));
      double high = std::pow(10.0, std::ceil(std::log10(hi)));
      if (high <= low) high = low * 10.0;
      in.log_range.emplace(low, high);
    }
  }
  render_with_gnuplot(png, target, csv, [&](const fs::path& output) {
    in.output = output;
    return make_script(in);
  });
}

}  // namespace

void write_plot(const PlotRequest& request, const std::filesystem::path& png) {
  if (request.coordinates.empty() && request.reactions.empty() && request.residuals.empty() &&
      request.actuators.empty() && request.velocities.empty() && request.others.empty() && request.modes.empty() && !request.path &&
      !request.energy) {
    throw InputError(fmt::format(
        "nothing to plot into '{}': the request names no coordinate, velocity, reaction, residual, path, "
        "energy or other column",
        png.string()));
  }
  const CsvHead head = read_csv_head(request.csv);
  std::vector<PlotColumn> columns;
  std::vector<int> indices;
  const auto add = [&](const std::vector<std::string>& names, PlotRole role, std::string_view what) {
    for (const std::string& name : names) {
      indices.push_back(column_of(head, request.csv, name, what));
      columns.push_back(PlotColumn{name, role});
    }
  };
  add(request.coordinates, PlotRole::coordinate, "coordinate");
  add(request.velocities, PlotRole::velocity, "velocity");
  add(request.reactions, PlotRole::reaction, "reaction");
  add(request.actuators, PlotRole::actuator, "actuator force");
  add(request.others, PlotRole::other, "a");
  add(request.modes, PlotRole::mode, "contact mode");
  add(request.residuals, PlotRole::residual, "residual");
  if (request.energy) add({*request.energy}, PlotRole::energy_error, "energy");
  std::optional<std::pair<PlotColumn, PlotColumn>> path;
  if (request.path) {
    indices.push_back(column_of(head, request.csv, request.path->first, "path x"));
    indices.push_back(column_of(head, request.csv, request.path->second, "path y"));
    path.emplace(PlotColumn{request.path->first, PlotRole::coordinate},
                 PlotColumn{request.path->second, PlotRole::coordinate});
  }
  const std::uintmax_t stride =
      head.rows > max_rows_per_curve ? (head.rows + max_rows_per_curve - 1) / max_rows_per_curve : 1;
  const std::vector<ColumnRange> ranges = read_column_ranges(request.csv, head.header_lines, indices, stride);
  for (std::size_t i = 0; i < columns.size(); ++i) {
    columns[i].min = ranges[i].min;
    columns[i].max = ranges[i].max;
  }
  if (path) {
    path->first.min = ranges[columns.size()].min;
    path->first.max = ranges[columns.size()].max;
    path->second.min = ranges[columns.size() + 1].min;
    path->second.max = ranges[columns.size() + 1].max;
  }
  std::vector<PlotPanel> panels = calc_plot_panels(columns, path, request.angles);
  if (panels.empty()) {
    throw InputError(fmt::format("nothing to plot into '{}': the path {}({}) is a line or a point in '{}'; plot "
                                 "its columns against time instead",
                                 png.string(), request.path->second, request.path->first, request.csv.string()));
  }
  draw_panels(request.title, request.csv, head, std::move(panels), request.events, false, 0, png);
}

void write_panel_plot(const PanelPlotRequest& request, const std::filesystem::path& png) {
  if (request.panels.empty())
    throw InputError(fmt::format("nothing to plot into '{}': the request has no panel", png.string()));
  for (const PlotPanel& p : request.panels) {
    if (p.columns.empty() || (p.kind == PanelKind::path && p.columns.size() != 2) ||
        (p.kind == PanelKind::drift && p.columns.size() != 1))
      throw InputError(fmt::format("plot '{}': the panel '{}' has {} columns; a path takes 2, a drift 1, "
                                   "any other panel at least 1",
                                   png.string(), p.title, p.columns.size()));
    if (!p.labels.empty() && p.labels.size() != p.columns.size())
      throw InputError(fmt::format("plot '{}': the panel '{}' has {} labels for {} columns; give one per column "
                                   "or none",
                                   png.string(), p.title, p.labels.size(), p.columns.size()));
  }
  const CsvHead head = read_csv_head(request.csv);
  draw_panels(request.title, request.csv, head, request.panels, request.events, request.same_log_range,
              request.layout_columns, png);
}

void write_xy_plot(const XyPlotRequest& request, const std::filesystem::path& png) {
  if (request.y.empty())
    throw InputError(fmt::format("nothing to plot into '{}': the request names no y column", png.string()));
  std::error_code ec;
  const fs::path csv = fs::absolute(request.csv, ec);
  if (ec) throw FileError(fmt::format("cannot resolve the CSV path '{}' ({})", request.csv.string(), ec.message()));
  const fs::path target = fs::absolute(png, ec);
  if (ec) throw FileError(fmt::format("cannot resolve the plot path '{}' ({})", png.string(), ec.message()));
  const CsvHead head = read_csv_head(request.csv);
  if (!request.x_of_curve.empty() && request.x_of_curve.size() != request.y.size())
    throw InputError(fmt::format("plot '{}': {} x columns for {} curves; give one per curve or none", png.string(),
                                 request.x_of_curve.size(), request.y.size()));
  if (!request.titles.empty() && request.titles.size() != request.y.size())
    throw InputError(fmt::format("plot '{}': {} titles for {} curves; give one per curve or none", png.string(),
                                 request.titles.size(), request.y.size()));
  std::vector<Column> xs, ys;
  for (std::size_t i = 0; i < request.y.size(); ++i) {
    const std::string& x_name = request.x_of_curve.empty() ? request.x : request.x_of_curve[i];
    xs.push_back(Column{column_of(head, request.csv, x_name, "x"), x_name});
    ys.push_back(Column{column_of(head, request.csv, request.y[i], "y"),
                        request.titles.empty() ? request.y[i] : request.titles[i]});
  }

  render_with_gnuplot(png, target, request.csv, [&](const fs::path& output) {
    // Values without a logarithm become NaN, which gnuplot skips; a first pass (stats) finds
    // whether anything is left to draw on each logarithmic axis.
    // `log_x` and `log_y` are set by the script once it knows whether anything is left to draw
    // on a logarithmic axis (else the axis is linear and every value is drawn).
    const auto value = [](int column, const char* log) {
      return fmt::format("(({1} && column({0}) <= 0) ? NaN : column({0}))", column, log);
    };
    std::string s;
    s += "# Written by nhdyn (src/nhdyn/io/plot.cpp, write_xy_plot) for one plot; deleted after the run.\n";
    s += "set encoding utf8\n";
    s += "if (strstrt(' '.GPVAL_TERMINALS.' ', ' pngcairo ') > 0) {\n";
    s += "  set terminal pngcairo size 1000,700 font 'Sans,10' noenhanced\n";
    s += "} else {\n";
    s += "  set terminal png size 1000,700 noenhanced\n";
    s += "}\n";
    s += "set termoption noenhanced\n";
    s += fmt::format("csv_file = {}\n", gp_string(csv.string()));
    s += fmt::format("output_file = {}\n", gp_string(output.string()));
    s += "set output output_file\n";
    s += "set datafile separator comma\n";
    s += "set grid\n";
    s += "set key outside right top vertical\n";
    s += fmt::format("set title {}\n", gp_label(request.title));
    s += fmt::format("set xlabel {}\nset ylabel {}\n", gp_label(request.x_label.empty() ? request.x : request.x_label),
                     gp_label(request.y_label));
    const std::string skip = fmt::format(" skip {}", head.header_lines);
    s += "log_x = 0\nlog_y = 0\n";
    if (request.log_x) {
      std::string largest = "largest = 0";
      for (const Column& c : xs)
        largest += fmt::format(", largest = (column({0}) > largest ? column({0}) : largest)", c.index);
      s += "undefine STATS_*\n";
      s += fmt::format("stats csv_file{} using ({}, largest) nooutput\n", skip, largest);
      s += "log_x = exists('STATS_max') && STATS_max > 0\n";
      s += "if (log_x) { set logscale x; set format x '1e%L' }\n";
    }
    if (request.log_y) {
      std::string largest = "largest = 0";
      for (const Column& c : ys)
        largest += fmt::format(", largest = (column({0}) > largest ? column({0}) : largest)", c.index);
      s += "undefine STATS_*\n";
      s += fmt::format("stats csv_file{} using ({}, largest) nooutput\n", skip, largest);
      s += "log_y = exists('STATS_max') && STATS_max > 0\n";
      s += "if (log_y) { set logscale y; set format y '1e%L' }\n";
    }
    std::vector<std::string> clauses;
    for (std::size_t i = 0; i < ys.size(); ++i)
      clauses.push_back(plot_clause(skip,
                                    fmt::format("{}:{}", value(xs[i].index, "log_x"), value(ys[i].index, "log_y")),
                                    "linespoints", ys[i].name));
    if (request.diagonal) clauses.push_back("x with lines dashtype 2 linecolor 'gray40' title 'y = x'");
    s += join_clauses(clauses);
    s += "set output\n";
    return s;
  });
}

}  // namespace nhdyn
