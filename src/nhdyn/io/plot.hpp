// Plots of a finished run: reads a CSV written by nhdyn and has gnuplot draw one PNG with a
// panel for each group of columns (coordinates, reactions, constraint residuals, the path of a
// planar system, energy drift). Last stage of the pipeline, after the simulation and its CSV;
// the CLI calls it for `--plot`. The library draws nothing itself: it writes a gnuplot script
// and runs the external `gnuplot` program, so gnuplot is needed only when a plot is asked for.
#pragma once

#include <filesystem>
#include <optional>
#include <string>
#include <utility>
#include <vector>

namespace nhdyn {

// What to draw. Columns are named as in the first (header) row of the CSV; column 1 is time.
// Empty lists and unset optionals leave their panel out; at least one panel must remain.
struct PlotRequest {
  std::string title;                     // heading of the picture, e.g. "sled — sanh, dopri5"
  std::filesystem::path csv;             // header row of comma-separated names, then numeric rows
  std::vector<std::string> coordinates;  // coordinate columns against time, e.g. "x", "y", "phi"
  std::vector<std::string> reactions;    // reaction columns against time, e.g. "R_x"
  std::vector<std::string> residuals;    // residual columns, |r| against time on a log scale
  std::vector<std::string> actuators = {};  // actuator force columns against time, e.g. "u_heading"
  // Columns x and y of a planar system, drawn as its path y(x) with equal axis scales.
  std::optional<std::pair<std::string, std::string>> path;
  std::optional<std::string> energy;  // energy column, drawn as its drift E(t) - E(0)
};

// Draws `request` into the PNG file `png` (about 1200 x 900 px; gnuplot's pngcairo terminal
// when it has one, else its png terminal), one panel per group in a grid of two columns:
// coordinates, reactions, |residual| on a log scale (exact zeros are left out; if every
// residual is exactly zero the panel says so on a linear scale), the path y(x) with equal axis
// scales, the energy drift. A CSV of more than 50 000 rows is thinned to about 50 000 drawn
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

// Whether `gnuplot` on PATH runs and has a PNG terminal. Probed once per process (one short
// gnuplot run), then cached; thread-safe.
bool gnuplot_available();

}  // namespace nhdyn
