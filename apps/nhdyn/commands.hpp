// The subcommands of the nhdyn command line, each in its own file: how it registers its options
// with CLI11 and what it runs. Exit codes: 0 success, 1 the simulation failed numerically,
// 2 bad input (unknown model, invalid option, unwritable file).
#pragma once

#include <CLI/CLI.hpp>
#include <functional>

namespace nhdyn::cli {

// Each subcommand's file defines `std::function<int()> add_<name>_command(CLI::App& app)`, which
// registers its options and returns the function that runs it once the command line is parsed;
// main.cpp declares them and lists them in its one table (kSubcommands).

}  // namespace nhdyn::cli
