// Plots of a study: one panel of curves y_i(x) read from a CSV, on logarithmic axes by default —
// error against tolerance, relative error against mass ratio. The studies of docs/studies/ draw
// their figures with it. Its script is written in plot.cpp beside those of the plots of a run
// (plot.hpp), sharing the quoting of strings; gnuplot.hpp runs it.
#pragma once

#include <filesystem>
#include <string>
#include <vector>

namespace nhdyn {

struct XyPlotRequest {
  std::string title;
  std::filesystem::path csv;   // header row of comma-separated names, then numeric rows
  std::string x;               // the column on the horizontal axis
  std::vector<std::string> y;  // one curve (lines and points) per column, titled by its name
  // Optional, one per curve: its own x column (error against residual, say), and its own title.
  std::vector<std::string> x_of_curve;
  std::vector<std::string> titles;
  std::string x_label, y_label;
  bool log_x = true, log_y = true;
  bool diagonal = false;  // also draw the line y = x (where x and y are equal)
};

// Draws `request` into the PNG file `png` (about 1000 x 700 px). x_of_curve and titles, when
// given, must have one entry per y column (else InputError). On a logarithmic axis a value
// that is zero or negative has no place; that point is left out of its curve (a gap), and if
// every point of the plot is left out the axis is drawn linear instead of failing. Throws as
// write_plot does: InputError for a column the CSV does not have (named), an empty request or a
// CSV without data rows; FileError when gnuplot is missing or fails, or `png` cannot be written.
// Nothing is left behind on failure.
void write_xy_plot(const XyPlotRequest& request, const std::filesystem::path& png);

}  // namespace nhdyn
