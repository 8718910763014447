// What every command that writes tables and plots checks before it computes anything: that the
// table's directory exists (made when asked) and that gnuplot is there when a plot is asked for.
// Shared by compare and the studies, so their messages and behaviour stay the same.
#pragma once

#include <filesystem>
#include <string>

namespace nhdyn::cli {

// Makes the directory that will hold `file` (and its parents); errors are left to the writer,
// which names the path when it cannot open the file.
void make_parent_directory(const std::filesystem::path& file);

// Throws FileError saying how to install gnuplot when `plot` is not empty and gnuplot with a PNG
// terminal is missing.
void check_plot_possible(const std::string& plot);

}  // namespace nhdyn::cli
