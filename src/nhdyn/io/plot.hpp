// Plots of a finished run: reads a CSV written by nhdyn and has gnuplot draw one PNG with a
// panel for each group of columns of like units and scale (angles, other coordinates,
// velocities, the path of a planar system, reactions, actuator forces, constraint residuals,
// the energy balance error), the events marked on every time axis. Last stage of the pipeline, after the simulation and its CSV;
// the CLI calls it for `--plot`. The library draws nothing itself: it writes a gnuplot script
// and runs the external `gnuplot` program, so gnuplot is needed only when a plot is asked for.
#pragma once

#include <filesystem>
#include <optional>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

namespace nhdyn {

// What a column is; decides its panel (calc_plot_panels).
enum class PlotRole { coordinate, velocity, reaction, actuator, residual, energy_error, other };

// A column with the range of its values over the drawn rows (finite values only; min == max for
// a constant column, both NaN when it has no finite value).
struct PlotColumn {
  std::string name;
  PlotRole role = PlotRole::other;
  double min = 0.0;
  double max = 0.0;
};

enum class PanelKind {
  lines,    // curves against time on a linear axis
  log_abs,  // |value| against time on a logarithmic axis (exact zeros left out)
  drift,    // value(t) - value(t0) against time
  path,     // columns[1] against columns[0]
};

// One panel of a figure: its heading, what it draws, its curves (for a path: {x, y}).
struct PlotPanel {
  std::string title;
  PanelKind kind = PanelKind::lines;
  std::vector<std::string> columns;
  std::vector<std::string> labels = {};  // legend entry of each curve; empty: the column names
  bool equal_axes = false;               // path only: one unit is as long on x as on y
  // lines only: a fixed range for a panel of constants (else gnuplot's autoscale)
  std::optional<std::pair<double, double>> y_range = {};
};

// Whether a coordinate's name reads as an angle (a model knows no units of its coordinates, so
// the name decides): its stem, the name without a trailing part of digits, of an underscore and
// what follows, or of capital letters (phi_r, th1, thetaR), is one of alpha, beta, gamma, delta,
// theta, vartheta, th, phi, varphi, chi, psi, angle, ang. Greek letters that name lengths as
// often as angles (xi, eta, rho, sigma, ...) are not in the list.
bool is_angle_name(std::string_view coordinate);

// The panels of a run's figure, a pure function of the columns and their ranges (docs/cli.md,
// "What --plot draws"). In this order:
//   coordinates that are angles, other coordinates (lengths, and names that say nothing),
//   velocities of angles, other velocities, the path, reactions on angles, other reactions,
//   actuator forces, other columns (outputs, accelerations, ...), |residuals| on a log scale, the
//   energy balance error (drift from its first value).
// A group of linear curves is split further by scale: a curve joins a panel only if the panel's
// range, with it, spans at most `scale_ratio` (10) times the curve's own span, so every curve
// spans at least a tenth of its panel's height (a constant curve joins a panel whose range it
// keeps within that bound). A curve that varies by at most 1e-9 of the largest |value| among
// the columns of its role (reactions and actuator forces count as one role: both are generalized
// forces), below any run's tolerance, counts as constant (round-off is not drawn as a
// signal); a panel of constants only gets a fixed range around them and says so in its title. The path (x, y) is drawn with equal axes when its span ratio
// y/x lies in [1/5, 3/2] (the shape of a panel: both sides of the drawn box keep at least a
// third of the panel), with separate padded scales otherwise, and is left out when either span
// is not finite or at most 1e-9 of the largest |x| or |y| (a line or a point, to round-off, says
// nothing a time series does not).
// `angles` names coordinates known to be angles besides those whose names say so (a model file's
// coordinates that appear inside sin, cos or tan, symbolic::VisualScene::angles).
std::vector<PlotPanel> calc_plot_panels(const std::vector<PlotColumn>& columns,
                                        const std::optional<std::pair<PlotColumn, PlotColumn>>& path,
                                        const std::vector<std::string>& angles = {});

// An event to mark on the time axes: a dashed vertical line at t, named in the legend, and a
// point on the path where `state` gives the path's columns.
struct PlotEvent {
  std::string name;
  double t = 0.0;
  std::vector<std::pair<std::string, double>> state = {};  // column name -> value at t
};

// What to draw. Columns are named as in the first (header) row of the CSV; column 1 is time.
// Empty lists and unset optionals leave their panel out; at least one panel must remain.
struct PlotRequest {
  std::string title;                     // heading of the picture, e.g. "sled — sanh, dopri5"
  std::filesystem::path csv;             // header row of comma-separated names, then numeric rows
  std::vector<std::string> coordinates;  // coordinate columns against time, e.g. "x", "y", "phi"
  std::vector<std::string> reactions;    // reaction columns against time, e.g. "R_x"
  std::vector<std::string> residuals;    // residual columns, |r| against time on a log scale
  std::vector<std::string> actuators = {};  // actuator force columns against time, e.g. "u_heading"
  std::vector<std::string> velocities = {};  // velocity columns, e.g. "x'"
  std::vector<std::string> others = {};      // any other columns against time (outputs, x'', ...)
  // Columns x and y of a planar system, drawn as its path y(x) (calc_plot_panels says how).
  std::optional<std::pair<std::string, std::string>> path;
  std::optional<std::string> energy;  // energy column, drawn as its drift E(t) - E(0)
  std::vector<PlotEvent> events = {};
  // Coordinates that are angles besides those named like one (calc_plot_panels).
  std::vector<std::string> angles = {};
};

// Keeps in `request` only the columns named in `chosen` (--plot-columns A,B,...): each stays in
// its role; a chosen column in no role of the request joins `others`; the path stays only if
// both its columns are chosen. `all` is every column of the CSV to come, checked before a run:
// a name not in it throws InputError naming it, `option` and every column. An empty `chosen`
// leaves the request as it is.
void select_plot_columns(PlotRequest& request, const std::vector<std::string>& all,
                         const std::vector<std::string>& chosen, std::string_view option = "--plot-columns");

// Checks `chosen` against `all` as select_plot_columns does (InputError listing the columns).
void require_plot_columns(const std::vector<std::string>& all, const std::vector<std::string>& chosen,
                          std::string_view option = "--plot-columns");

// Draws `request` into the PNG file `png` (gnuplot's pngcairo terminal when it has one, else
// its png terminal): reads the ranges of the columns (one pass over the CSV), lays out the
// panels of calc_plot_panels in a grid of 1 to 3 columns (about 600 x 330 px a panel), marks
// the events. |residual| panels leave exact zeros out; if every value is exactly zero the
// panel says so on a linear scale. A CSV of more than 50 000 rows is thinned to about 50 000 drawn
// rows (every k-th row; each panel's title says "1 row in k drawn"): a panel ~550 px wide
// cannot show more, and gnuplot would spend seconds per curve on a million rows. Cost: one
// gnuplot run reading the CSV once per curve; ~4 s of CPU for 1e6 rows and 10 curves.
// gnuplot writes to a temporary file next to `png`, renamed onto `png` only on success, so a
// failed run leaves neither a partial image nor a temporary file behind.
// Throws InputError if a column name is not in the CSV header (the message names it), if the
// request has no panel, if the CSV has no data row, or if the first energy value is not a
// finite number; FileError if the CSV cannot be read, gnuplot is not installed, the directory
// of `png` cannot be written, or gnuplot fails (the message carries gnuplot's stderr).
void write_plot(const PlotRequest& request, const std::filesystem::path& png);

// A figure of given panels (the compare command's: one panel per method or integrator).
// `same_log_range`: every log_abs panel gets the one range that holds all their values, so
// heights compare across panels.
struct PanelPlotRequest {
  std::string title;
  std::filesystem::path csv;
  std::vector<PlotPanel> panels;
  std::vector<PlotEvent> events = {};
  bool same_log_range = false;
  int layout_columns = 0;  // panels per row of the grid; 0: 1 for one panel, 2 up to four, else 3
};

// The panels of `nhdyn compare`'s figure, whose series CSV names its columns
// QUANTITY_METHOD_INTEGRATOR (error_sanh_dopri5, residual_vel_lagrange_rk4), all |value| on a log
// scale: with one integrator, one panel per method (a curve per quantity); with one method, one
// panel per integrator; with several of both, one panel per quantity and method (a curve per
// integrator, in the same colour in every panel), quantities in rows and methods in columns of
// the grid (layout_columns = the number of methods).
std::vector<PlotPanel> calc_comparison_panels(const std::vector<std::string>& methods,
                                              const std::vector<std::string>& integrators,
                                              const std::vector<std::string>& quantities);

// Keeps in each panel only the columns named in `chosen` and drops the panels left empty; an
// empty `chosen` keeps everything. Names are not checked here (require_plot_columns).
void select_panel_columns(std::vector<PlotPanel>& panels, const std::vector<std::string>& chosen);

// Draws `request` as write_plot draws its panels; throws as write_plot does.
void write_panel_plot(const PanelPlotRequest& request, const std::filesystem::path& png);

// Whether `gnuplot` on PATH runs and has a PNG terminal. Probed once per process (one short
// gnuplot run), then cached; thread-safe.
bool gnuplot_available();

}  // namespace nhdyn
