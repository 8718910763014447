// nhdyn: simulate constrained mechanical systems in the form of Do Sanh. This file only wires the
// subcommands together and turns nhdyn's exceptions into messages and exit codes.
#include <fmt/format.h>

#include <CLI/CLI.hpp>
#include <cstdio>
#include <exception>
#include <functional>
#include <string>
#include <string_view>
#include <vector>

#include "commands.hpp"
#include "nhdyn/core/error.hpp"
#include "nhdyn/core/shown_text.hpp"
#include "nhdyn/core/version.hpp"
#include "output_guard.hpp"

namespace nhdyn::cli {

// The subcommands, once: each is its own file defining add_<name>_command, declared and listed
// here. The table's order is that of `nhdyn --help` and of the unknown-command message.
std::function<int()> add_simulate_command(CLI::App& app);
std::function<int()> add_compare_command(CLI::App& app);
std::function<int()> add_study_command(CLI::App& app);
std::function<int()> add_linearize_command(CLI::App& app);
std::function<int()> add_sweep_command(CLI::App& app);
std::function<int()> add_batch_command(CLI::App& app);
std::function<int()> add_report_command(CLI::App& app);
std::function<int()> add_list_command(CLI::App& app);
std::function<int()> add_equations_command(CLI::App& app);
std::function<int()> add_codegen_command(CLI::App& app);
std::function<int()> add_example_command(CLI::App& app);
std::function<int()> add_optimize_command(CLI::App& app);

struct Subcommand {
  const char* name;
  std::function<int()> (*add)(CLI::App& app);
};
constexpr Subcommand kSubcommands[] = {
    {"simulate", add_simulate_command}, {"compare", add_compare_command},   {"study", add_study_command},
    {"linearize", add_linearize_command}, {"sweep", add_sweep_command},     {"batch", add_batch_command},
    {"report", add_report_command},     {"list", add_list_command},         {"equations", add_equations_command},
    {"codegen", add_codegen_command},   {"example", add_example_command},   {"optimize", add_optimize_command},
};

}  // namespace nhdyn::cli

int main(int argc, char** argv) {
  CLI::App app{"nhdyn: equations of motion of constrained mechanical systems (Do Sanh form)", "nhdyn"};
  app.require_subcommand(1);
  app.set_version_flag("--version", fmt::format("nhdyn {} (commit {})", NHDYN_VERSION, NHDYN_GIT_COMMIT));
  std::vector<std::function<int()>> runs;
  std::string names;
  for (const nhdyn::cli::Subcommand& command : nhdyn::cli::kSubcommands) {
    runs.push_back(command.add(app));
    names += (names.empty() ? "" : ", ") + std::string(command.name);
  }
  if (argc > 1 && argv[1][0] != '-') {
    bool known = false;
    for (const CLI::App* sub : app.get_subcommands([](CLI::App*) { return true; }))
      known = known || sub->get_name() == argv[1];
    if (!known) {
      fmt::print(stderr, "nhdyn: error: unknown command '{}'; the commands are {} (see nhdyn --help)\n",
                 nhdyn::shown_text(argv[1]), names);
      return 2;
    }
  }
  // A comma-separated list with nothing but commas (--integrators ",,") is split by CLI11 into no
  // value, and the option then took the next argument ("-o") as its value: refused as empty first.
  for (int i = 2; i < argc; ++i) {
    const std::string_view value = argv[i];
    if (argv[i - 1][0] == '-' && !value.empty() && value.find_first_not_of(", ") == std::string_view::npos) {
      fmt::print(stderr, "nhdyn: error: {} '{}': the list is empty; give its items separated by commas (or leave the "
                         "option out)\n",
                 nhdyn::shown_text(argv[i - 1]), nhdyn::shown_text(value));
      return 2;
    }
  }
  // Every message shows what it echoes of the arguments with its invisible characters by code
  // (core/shown_text.hpp): CLI11's own, and nhdyn's below.
  app.failure_message([](const CLI::App* failed, const CLI::Error& e) {
    return nhdyn::shown_text(CLI::FailureMessage::simple(failed, e), true);
  });
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    return app.exit(e) == 0 ? 0 : 2;
  }
  // An empty value (-o '', --html '', --plot '') would otherwise read as "not given" and be
  // ignored silently: every option that takes a value needs a non-empty one.
  if (const std::string empty = nhdyn::cli::first_empty_value(app); !empty.empty()) {
    fmt::print(stderr, "nhdyn: error: {} '': the value is empty; give one (or leave the option out)\n",
               nhdyn::shown_text(empty));
    return 2;
  }
  nhdyn::cli::install_interrupt_handlers();
  try {
    for (std::size_t i = 0; i < runs.size(); ++i)
      if (app.got_subcommand(nhdyn::cli::kSubcommands[i].name)) return runs[i]();
  } catch (const nhdyn::Error& e) {
    fmt::print(stderr, "nhdyn: error: {}\n", nhdyn::shown_text(e.what(), true));
    return 2;
  } catch (const std::exception& e) {
    fmt::print(stderr, "nhdyn: internal error: {}\n", nhdyn::shown_text(e.what(), true));
    return 3;
  }
  return 0;
}
