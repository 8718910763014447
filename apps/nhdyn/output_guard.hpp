// What every command that writes files checks and guarantees, so that their messages and
// behaviour stay the same: the model file of the run is never an output (protect_model_file),
// the table's directory exists (made when asked), gnuplot is there when a plot is asked for, and
// an interrupted run (SIGINT, SIGTERM) removes its temporary files, says where it stopped and
// exits 130 or 143.
#pragma once

#include <filesystem>
#include <string>
#include <utility>
#include <vector>

namespace CLI {
class App;
}

namespace nhdyn::cli {

// Registers the MODEL argument, when it names a file, as an input no output may replace
// (io/atomic_file.hpp, protect_input). Call before opening any output.
void protect_model_file(const std::string& model);

// The one rule for a command's files (io/run_paths.hpp) for a command whose input is its model
// file: refuses (FileError, naming both) an output that is the model or two outputs that are one
// file. `outputs` pairs a path with the option that names it; empty paths are skipped. Call before
// any work.
void check_command_paths(const std::string& model,
                         const std::vector<std::pair<std::filesystem::path, std::string>>& outputs);

// Makes the directory that will hold `file` (and its parents); errors are left to the writer,
// which names the path when it cannot open the file.
void make_parent_directory(const std::filesystem::path& file);

// Throws FileError saying how to install gnuplot when `plot` is not empty and gnuplot with a PNG
// terminal is missing, and FileError when `plot` names an input of the run.
void check_plot_possible(const std::string& plot);

// --plot-columns: refused without --plot (InputError saying to give both), and each name checked
// against the columns the plot can draw (require_plot_columns, io/plot.hpp). Nothing when not given.
void check_plot_columns(const std::string& plot, const std::vector<std::string>& columns,
                        const std::vector<std::string>& chosen);

// Installs the SIGINT and SIGTERM handlers: remove the temporary files under way, print
// "interrupted by SIGINT at t = ..." (the last time passed to note_time, if any) and exit with
// 128 + the signal's number.
void install_interrupt_handlers();
// The name of the first option given with an empty value in the parsed command line (searched
// through the subcommands that were given), or "" when none.
std::string first_empty_value(const CLI::App& app);

// Records how far the run has come, for the message of an interrupted run. Lock-free.
void note_time(double t);

}  // namespace nhdyn::cli
