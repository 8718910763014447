// `nhdyn report RESULT.csv --model MODEL -o report.html`: the HTML report (io/report.hpp) of a run
// written earlier by `nhdyn simulate`; the CSV must have the model's columns.
#include <fmt/format.h>

#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "commands.hpp"
#include "nhdyn/core/error.hpp"
#include "nhdyn/frontend/load_model.hpp"
#include "nhdyn/io/atomic_file.hpp"
#include "nhdyn/io/csv.hpp"
#include "nhdyn/io/report.hpp"

namespace nhdyn::cli {

std::function<int()> add_report_command(CLI::App& app) {
  struct Args {
    std::string csv;
    std::string model;
    std::vector<std::string> sets;
    std::string output;
    int max_frames = ReportOptions{}.max_frames;
    bool quiet = false;
  };
  auto args = std::make_shared<Args>();
  CLI::App* cmd = app.add_subcommand("report", "Write the HTML report (3-D animation, plots, equations) of a CSV result");
  cmd->add_option("RESULT", args->csv, "A CSV written by `nhdyn simulate`")->required();
  cmd->add_option("--model", args->model, "The model that made it: a model file (.toml) or a built-in model")
      ->required();
  cmd->add_option("--set", args->sets, "The parameters set for the run, NAME=EXPR (repeatable)");
  cmd->add_option("-o,--output", args->output, "HTML file to write")->required();
  cmd->add_option("--max-frames", args->max_frames, "Most rows shown (longer runs are thinned for display)")
      ->capture_default_str();
  cmd->add_flag("-q,--quiet", args->quiet, "Print nothing");
  return [args] {
    if (args->max_frames < 2)
      throw InputError(fmt::format("--max-frames {}: give at least 2", args->max_frames));
    std::optional<AtomicFile> probe(args->output);  // an unwritable path is refused before any work
    const LoadedModel resolved = load_model_argument(args->model, args->sets);
    const CsvTable table = load_csv(args->csv);
    check_report_columns(table.header, make_result_columns(resolved.model), args->csv, resolved.model.name);
    probe.reset();
    ReportOptions options;
    options.max_frames = args->max_frames;
    const std::string notice = write_model_report(resolved.model, resolved.description.get(), table,
                       fmt::format("{}: {}", resolved.model.name, args->csv), {{"results", args->csv}}, args->output,
                       options);
    if (!args->quiet) {
      fmt::print("nhdyn report {}: {} rows -> {}\n", resolved.model.name, table.rows.size(), args->output);
      if (!notice.empty()) fmt::print("  note: {}\n", notice);
    }
    return 0;
  };
}

}  // namespace nhdyn::cli
