// nhdyn: simulate constrained mechanical systems in the form of Do Sanh. This file only wires the
// subcommands together and turns nhdyn's exceptions into messages and exit codes.
#include <fmt/format.h>

#include <CLI/CLI.hpp>
#include <cstdio>
#include <exception>

#include "commands.hpp"
#include "nhdyn/core/error.hpp"
#include "outputs.hpp"

int main(int argc, char** argv) {
  CLI::App app{"nhdyn: equations of motion of constrained mechanical systems (Do Sanh form)", "nhdyn"};
  app.require_subcommand(1);
  const auto simulate = nhdyn::cli::add_simulate_command(app);
  const auto list = nhdyn::cli::add_list_command(app);
  const auto equations = nhdyn::cli::add_equations_command(app);
  const auto codegen = nhdyn::cli::add_codegen_command(app);
  const auto compare = nhdyn::cli::add_compare_command(app);
  const auto study = nhdyn::cli::add_study_command(app);
  const auto example = nhdyn::cli::add_example_command(app);
  const auto linearize = nhdyn::cli::add_linearize_command(app);
  const auto sweep = nhdyn::cli::add_sweep_command(app);
  const auto batch = nhdyn::cli::add_batch_command(app);
  const auto report = nhdyn::cli::add_report_command(app);
  if (argc > 1 && argv[1][0] != '-') {
    bool known = false;
    for (const CLI::App* sub : app.get_subcommands([](CLI::App*) { return true; }))
      known = known || sub->get_name() == argv[1];
    if (!known) {
      fmt::print(stderr, "nhdyn: error: unknown command '{}'; the commands are simulate, compare, study, linearize, sweep, batch, report, list, equations, codegen, example "
                         "(see nhdyn --help)\n", argv[1]);
      return 2;
    }
  }
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    return app.exit(e) == 0 ? 0 : 2;
  }
  // An empty value (-o '', --html '', --plot '') would otherwise read as "not given" and be
  // ignored silently: every option that takes a value needs a non-empty one.
  if (const std::string empty = nhdyn::cli::first_empty_value(app); !empty.empty()) {
    fmt::print(stderr, "nhdyn: error: {} '': the value is empty; give one (or leave the option out)\n", empty);
    return 2;
  }
  nhdyn::cli::install_interrupt_handlers();
  try {
    if (app.got_subcommand("simulate")) return simulate();
    if (app.got_subcommand("list")) return list();
    if (app.got_subcommand("equations")) return equations();
    if (app.got_subcommand("codegen")) return codegen();
    if (app.got_subcommand("compare")) return compare();
    if (app.got_subcommand("study")) return study();
    if (app.got_subcommand("example")) return example();
    if (app.got_subcommand("linearize")) return linearize();
    if (app.got_subcommand("sweep")) return sweep();
    if (app.got_subcommand("batch")) return batch();
    if (app.got_subcommand("report")) return report();
  } catch (const nhdyn::Error& e) {
    fmt::print(stderr, "nhdyn: error: {}\n", e.what());
    return 2;
  } catch (const std::exception& e) {
    fmt::print(stderr, "nhdyn: internal error: {}\n", e.what());
    return 3;
  }
  return 0;
}
