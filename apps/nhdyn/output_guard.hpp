// What guards a command's output files against a signal: an interrupted run (SIGINT, SIGTERM)
// removes its temporary files (those of run_files.hpp and every AtomicFile), says where it stopped
// and exits 130 or 143. Also the command line's refusal of an option given an empty value.
#pragma once

#include <string>

namespace CLI {
class App;
}

namespace nhdyn::cli {

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
