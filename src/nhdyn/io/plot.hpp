// Plots of a finished run: reads a CSV written by nhdyn and has gnuplot draw one PNG with a
// panel for each group of columns of like units and scale (angles, other coordinates,
// velocities, the path of a planar system, reactions, actuator forces, constraint residuals,
// the energy balance error), the events marked on every time axis. Last stage of the pipeline, after the simulation and its CSV;
// the CLI calls it for `--plot`. The library draws nothing itself: it writes a gnuplot script
// and runs the external `gnuplot` program, so gnuplot is needed only when a plot is asked for.
// The panels come from plot_panels.hpp; plot.cpp writes the script, gnuplot.cpp runs it.
#pragma once

#include <filesystem>
#include <optional>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "nhdyn/io/plot_panels.hpp"  // the panels a figure is made of

namespace nhdyn {

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
  std::vector<std::string> modes = {};       // contact mode columns (NAME_mode), drawn as steps
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


// Draws `request` as write_plot draws its panels; throws as write_plot does.
void write_panel_plot(const PanelPlotRequest& request, const std::filesystem::path& png);

// Whether `gnuplot` on PATH runs and has a PNG terminal. Probed once per process (one short
// gnuplot run), then cached; thread-safe.
bool gnuplot_available();

}  // namespace nhdyn

