// The panel layout of a plot: which columns share a panel, in what order, on what kind of axis —
// pure functions of the columns' names, roles and ranges, tested on their own. The first step of
// a figure (plot.hpp): write_plot asks calc_plot_panels for the panels of a run, the compare
// command calc_comparison_panels for its own; plot.cpp then writes the gnuplot script that draws
// them.
#pragma once

#include <optional>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

namespace nhdyn {

// What a column is; decides its panel (calc_plot_panels).
// `mode`: a contact's mode column (NAME_mode: 0 rolling, 1 sliding, 2 free; docs/contact-modes.md).
enum class PlotRole { coordinate, velocity, reaction, actuator, residual, energy_error, other, mode };

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
  steps,    // piecewise-constant curves (contact modes): each value holds until the next row
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
//   actuator forces, other columns (outputs, accelerations, ...), the contacts' modes (one steps
//   panel, axis 0 rolling .. 2 free), |residuals| on a log scale, the energy balance error (drift
//   from its first value).
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

}  // namespace nhdyn
