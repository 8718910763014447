// `nhdyn report RESULT.csv --model MODEL -o report.html`: the HTML report (io/report.hpp) of a run
// written earlier by `nhdyn simulate`; the CSV must have the model's columns, and when it carries
// its provenance (io/provenance.hpp), the model's hash, whose parameters are then the run's.
#include <fmt/format.h>

#include <cmath>
#include <filesystem>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "commands.hpp"
#include "nhdyn/core/error.hpp"
#include "nhdyn/core/shown_text.hpp"
#include "nhdyn/frontend/load_model.hpp"
#include "nhdyn/frontend/provenance.hpp"
#include "nhdyn/io/csv.hpp"
#include "nhdyn/io/report.hpp"
#include "run_files.hpp"

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
  cmd->add_option("--set", args->sets,
                  "Set a parameter, NAME=EXPR, after the run's own values read from the CSV's provenance header "
                  "(repeatable; needed only for a CSV without one)");
  cmd->add_option("-o,--output", args->output, "HTML file to write")->required();
  cmd->add_option("--max-frames", args->max_frames, "Most rows shown (longer runs are thinned for display)")
      ->capture_default_str();
  cmd->add_flag("-q,--quiet", args->quiet, "Print nothing");
  return [args] {
    ReportOptions options;
    options.max_frames = args->max_frames;
    check_report_options(options);  // before any work
    // Every file of the run, checked together before any work (run_files.hpp); an unwritable -o is
    // refused here.
    RunFiles files(args->model);
    files.input(args->csv, "the result CSV");
    files.page(args->output, "-o");
    files.check();
    const CsvTable table = load_csv(args->csv);
    // A CSV with its provenance (io/provenance.hpp) names its model's hash and its parameters as
    // run: the model must be that one, and the run's values are applied before any --set.
    const ModelSource source = read_model_source(args->model);
    ParameterOverrides overrides;
    if (const std::optional<Provenance> provenance = parse_provenance(table.comments, args->csv))
      overrides = check_provenance(*provenance, source, args->csv);
    for (auto& set : parse_parameter_sets(args->sets)) overrides.push_back(std::move(set));
    const LoadedModel resolved = load_model_described(source, overrides);
    const ResultColumns columns = make_result_columns(resolved.model);
    check_report_columns(table.header, columns, args->csv, resolved.model.name);
    check_report_times(table, args->csv);            // finite and never decreasing
    check_report_values(table, columns, args->csv);  // finite but for the contact forces
    files.commit();  // nothing of its own to commit: the report's writer writes it whole
    const std::string notice = write_model_report(resolved.model, resolved.description.get(), table,
                       fmt::format("{}: {}", resolved.model.name, args->csv), {{"results", args->csv}}, args->output,
                       options);
    if (!args->quiet) {
      fmt::print("nhdyn report {}: {} rows -> {}\n", resolved.model.name, table.rows.size(), shown_text(args->output));
      if (!notice.empty()) fmt::print("  note: {}\n", notice);
    }
    return 0;
  };
}

}  // namespace nhdyn::cli
