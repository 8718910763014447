// `nhdyn study NAME`: the command that holds the studies (study.hpp); each study is a subcommand
// defined in its own file.

#include <fmt/format.h>

#include <string>
#include <utility>
#include <vector>

#include "commands.hpp"
#include "study.hpp"

namespace nhdyn::cli {

std::filesystem::path by_tolerance_path(const std::filesystem::path& table) {
  std::filesystem::path series = table;
  series.replace_filename(table.stem().string() + "-by-tolerance.csv");
  return series;
}

int study_exit(const std::string& study, const Model& model, std::size_t runs, const std::vector<std::string>& failures) {
  if (failures.empty()) return 0;
  fmt::print(stderr, "nhdyn: error: study {} of '{}': {} of its {} runs failed (marked FAILED in the table); the first: {}\n",
             study, model.name, failures.size(), runs, failures.front());
  return 1;
}

std::function<int()> add_study_command(CLI::App& app) {
  CLI::App* cmd = app.add_subcommand("study", "Reproduce a study of docs/studies/ (table, CSV and plot)");
  cmd->require_subcommand(1);
  std::vector<std::pair<CLI::App*, std::function<int()>>> studies;
  // One line per study: the subcommand it adds is the last one of `cmd`.
  const auto add = [&](std::function<int()> (*adder)(CLI::App&)) {
    std::function<int()> run = adder(*cmd);
    studies.emplace_back(cmd->get_subcommands([](CLI::App*) { return true; }).back(), std::move(run));
  };
  add(add_error_relation_study);
  add(add_spread_masses_study);
  add(add_tracking_study);
  return [studies] {
    for (const auto& [sub, run] : studies)
      if (sub->parsed()) return run();
    return 2;
  };
}

}  // namespace nhdyn::cli
