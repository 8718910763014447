// The subcommands of the nhdyn command line, each in its own file: how it registers its options
// with CLI11 and what it runs. Exit codes: 0 success, 1 the simulation failed numerically,
// 2 bad input (unknown model, invalid option, unwritable file).
#pragma once

#include <CLI/CLI.hpp>
#include <functional>

namespace nhdyn::cli {

// Each returns the function that runs the subcommand once the command line is parsed.
std::function<int()> add_simulate_command(CLI::App& app);
std::function<int()> add_list_command(CLI::App& app);
std::function<int()> add_equations_command(CLI::App& app);
std::function<int()> add_codegen_command(CLI::App& app);
std::function<int()> add_compare_command(CLI::App& app);
std::function<int()> add_study_command(CLI::App& app);
std::function<int()> add_example_command(CLI::App& app);
std::function<int()> add_linearize_command(CLI::App& app);
std::function<int()> add_sweep_command(CLI::App& app);
std::function<int()> add_batch_command(CLI::App& app);
std::function<int()> add_report_command(CLI::App& app);

}  // namespace nhdyn::cli
