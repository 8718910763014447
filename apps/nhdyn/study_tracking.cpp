// `nhdyn study tracking MODEL`: for feedback gains 0 (none) .. 100 and tolerances 1e-4 .. 1e-10,
// a model with programs against its exact solution — the error of the solution beside the
// programs' residuals (studies/tracking.hpp, docs/studies/tracking.md). Prints the table, writes it
// as CSV (one row per run), a second CSV with one row per tolerance for the plot, and the plot.
#include <fmt/format.h>

#include <cmath>
#include <filesystem>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "nhdyn/core/error.hpp"
#include "nhdyn/core/join.hpp"
#include "nhdyn/core/shown_text.hpp"
#include "nhdyn/frontend/load_model.hpp"
#include "nhdyn/frontend/provenance.hpp"
#include "nhdyn/io/atomic_file.hpp"
#include "nhdyn/io/csv.hpp"
#include "nhdyn/io/xy_plot.hpp"
#include "nhdyn/studies/run_times.hpp"
#include "nhdyn/studies/tracking.hpp"
#include "run_files.hpp"
#include "study.hpp"

namespace nhdyn::cli {
namespace {

struct TrackingArgs {
  std::string model;
  std::vector<double> tolerances{1e-4, 1e-5, 1e-6, 1e-7, 1e-8, 1e-9, 1e-10};
  std::vector<double> gains{0.0, 1.0, 10.0, 100.0};
  std::string integrator = "dopri5";
  double atol_factor = 1e-2;
  std::optional<double> t_end;
  std::optional<double> output_step;
  std::vector<std::string> sets;
  std::string output = "results/tracking.csv";
  std::string plot;
  bool quiet = false;
};

std::string gain_label(double gain) { return gain == 0.0 ? std::string("none") : fmt::format("{:g}", gain); }

// Both files say what made them (io/provenance.hpp): the model as loaded and the study's options.
std::string tracking_provenance(const Model& model, const ModelSource& source, const TrackingOptions& options,
                                const TrackingArgs& args) {
  std::vector<std::string> gains, tolerances;
  for (double gain : args.gains) gains.push_back(fmt::format("{}", gain));
  for (double tolerance : args.tolerances) tolerances.push_back(fmt::format("{}", tolerance));
  return format_provenance(make_command_provenance(
      model, source, "study tracking",
      {{"gains", join(gains, ",")},
       {"integrator", std::string(integrator_name(options.integrator))},
       {"tolerances", join(tolerances, ",")},
       {"atol_factor", fmt::format("{}", args.atol_factor)},
       {"t_end", fmt::format("{}", args.t_end.value_or(model.defaults.t_end))},
       {"output_step", fmt::format("{}", args.output_step.value_or(model.defaults.output_step))}}));
}

// The by-tolerance series (one row per tolerance: each gain's error and residual, NaN where the run
// failed) and the table's text (one line per run).
std::string write_tracking_series(const Tracking& study, bool pos, const std::string& provenance, double atol_factor,
                                  CsvWriter& series) {
  // Like for like: the error of q against the position residual, of q' against the velocity one.
  const auto error_of = [&](const TrackingRun& r) { return pos ? r.max_error_q : r.max_error_v; };
  const auto residual_of = [&](const TrackingRun& r) { return pos ? r.max_residual_pos : r.max_residual_vel; };
  std::vector<double> row;
  for (std::size_t k = 0; k < study.tolerances.size(); ++k) {
    row.assign(1, study.tolerances[k]);
    for (std::size_t g = 0; g < study.gains.size(); ++g) {
      const TrackingRun& r = study.run(g, k);
      const bool ok = r.summary.status == Status::ok;
      row.push_back(ok ? error_of(r) : std::nan(""));
      row.push_back(ok ? residual_of(r) : std::nan(""));
    }
    series.write_row(row);
  }
  std::string text = provenance + "gain,rtol,atol,max_error_q,max_error_v,max_residual_pos,max_residual_vel,max_residual_acc,"
                     "steps,rhs_evaluations,status\n";
  for (const TrackingRun& r : study.runs)
    text += fmt::format("{:g},{:.3g},{:.3g},{:.6e},{:.6e},{:.6e},{:.6e},{:.6e},{},{},{}\n", r.gain, r.tolerance,
                        r.tolerance * atol_factor, r.max_error_q, r.max_error_v, r.max_residual_pos,
                        r.max_residual_vel, r.max_residual_acc, r.summary.stats.steps, r.summary.stats.rhs_evaluations,
                        format_status(r.summary));
  return text;
}

// --plot: each run a point (its program residual, its error); the runs of one gain joined in the
// order of the tolerances. On the diagonal the residual equals the error.
void plot_tracking(const Tracking& study, const Model& model, bool pos, const std::filesystem::path& series_path,
                   const std::string& plot) {
  XyPlotRequest request;
  request.title = fmt::format("{}: error of the solution against the {} program residual, rtol {:g} .. {:g}",
                              model.name, pos ? "position" : "velocity", study.tolerances.front(),
                              study.tolerances.back());
  request.csv = series_path;
  for (double gain : study.gains) {
    request.y.push_back("error_gain_" + gain_label(gain));
    request.x_of_curve.push_back("residual_gain_" + gain_label(gain));
    request.titles.push_back(gain == 0.0 ? std::string("no feedback")
                                         : fmt::format("feedback alpha = beta = {:g} 1/s", gain));
  }
  request.x_label = fmt::format("max |{} program residual| over the run (tracking error)", pos ? "position" : "velocity");
  request.y_label = fmt::format("max |error of {}| against the exact programmed motion", pos ? "q" : "q'");
  request.diagonal = true;
  write_xy_plot(request, plot);
}

// The summary on standard output: one line per run, and where the files went.
void print_tracking(const Tracking& study, const Model& model, const TrackingArgs& args,
                    const std::filesystem::path& table_path, const std::filesystem::path& series_path) {
  const double t_end = args.t_end.value_or(model.defaults.t_end);
  fmt::print("nhdyn study tracking {}: t = {:g} .. {:g} s, {}, atol = {:g} rtol, reference: the model's exact "
             "solution\n",
             model.name, model.t0, t_end, args.integrator, args.atol_factor);
  fmt::print("{:>6} {:>7} {:>10} {:>10} {:>10} {:>10} {:>10} {:>8}\n", "gain", "rtol", "err q", "err q'", "res pos",
             "res vel", "res acc", "steps");
  for (const TrackingRun& r : study.runs)
    fmt::print("{:>6} {:>7.0e} {:>10.2e} {:>10.2e} {:>10.2e} {:>10.2e} {:>10.2e} {:>8}{}\n", gain_label(r.gain),
               r.tolerance, r.max_error_q, r.max_error_v, r.max_residual_pos, r.max_residual_vel, r.max_residual_acc,
               r.summary.stats.steps,
               format_failure_note(r.summary));
  fmt::print("table -> {}\nby tolerance -> {}\n", shown_text(table_path.string()), shown_text(series_path.string()));
  if (!args.plot.empty()) fmt::print("plot -> {}\n", shown_text(args.plot));
}

int run_tracking(const TrackingArgs& args) {
  RunFiles files(args.model);
  const ModelSource source = read_model_source(args.model);
  const LoadedModel resolved = load_model_described(source, parse_parameter_sets(args.sets));
  const Model& model = resolved.model;
  TrackingOptions options;
  options.tolerances = args.tolerances;
  options.gains = args.gains;
  options.atol_factor = args.atol_factor;
  options.integrator = parse_integrator(args.integrator);
  options.t_end = args.t_end.value_or(0.0);
  options.output_step = args.output_step.value_or(0.0);
  check_study_run_times(model, args.t_end, args.output_step);  // the library's check, before any file

  namespace fs = std::filesystem;
  const fs::path table_path = args.output;
  const fs::path series_path = by_tolerance_path(table_path);
  files.output(table_path, "the table CSV", Folder::make);
  files.output(series_path, "the by-tolerance CSV");
  files.plot(args.plot);
  files.check();
  // The residual the plot and the by-tolerance CSV use: position level when a program has one.
  bool pos = false;
  for (const ProgramConstraint& p : model.program_constraints) pos = pos || p.level == ConstraintLevel::position;
  std::vector<std::string> columns{"tolerance"};
  for (double gain : args.gains) {
    columns.push_back("error_gain_" + gain_label(gain));
    columns.push_back("residual_gain_" + gain_label(gain));
  }
  const std::string provenance = tracking_provenance(model, source, options, args);
  CsvWriter& series = files.open_csv(series_path, columns, provenance);
  AtomicFile& table = files.open(table_path);

  const Tracking study = study_tracking(model, options);
  table.write(write_tracking_series(study, pos, provenance, args.atol_factor, series));
  files.commit();

  if (!args.plot.empty()) plot_tracking(study, model, pos, series_path, args.plot);

  if (!args.quiet) print_tracking(study, model, args, table_path, series_path);
  std::vector<std::string> failures;
  for (const TrackingRun& r : study.runs)
    if (r.summary.status != Status::ok) failures.push_back(r.summary.message);
  return study_exit("tracking", model, study.runs.size(), failures);
}

}  // namespace

std::function<int()> add_tracking_study(CLI::App& study) {
  auto args = std::make_shared<TrackingArgs>();
  CLI::App* cmd = study.add_subcommand("tracking",
                                       "Error of program motion against the program residual, over tolerances and "
                                       "feedback gains");
  cmd->add_option("MODEL", args->model, "A model file with [[programs]] and a [solution]")->required();
  cmd->add_option("--tolerances", args->tolerances, "rtol of each run, comma-separated")
      ->delimiter(',')
      ->capture_default_str();
  cmd->add_option("--gains", args->gains,
                  "Feedback gains alpha = beta [1/s] of --program-feedback, comma-separated; 0 is no feedback")
      ->delimiter(',')
      ->capture_default_str();
  cmd->add_option("--integrator", args->integrator, adaptive_integrator_names())->capture_default_str();
  cmd->add_option("--atol-factor", args->atol_factor, "atol of each run = this x rtol")->capture_default_str();
  cmd->add_option("--t-end", args->t_end, "End time [s] (default: the model's)");
  cmd->add_option("--output-step", args->output_step, "Time between measured outputs [s] (default: the model's)");
  cmd->add_option("--set", args->sets,
                  "Set a parameter, NAME=EXPR: a number or an expression in numbers, pi, e and the other parameters "
                  "(repeatable)");
  cmd->add_option("-o,--output", args->output, "Table CSV, one row per run; the by-tolerance CSV goes next to it")
      ->capture_default_str();
  cmd->add_option("--plot", args->plot, "PNG of the error against the program residual, one curve per gain (log-log)");
  cmd->add_flag("-q,--quiet", args->quiet, "Print no table");
  return [args] { return run_tracking(*args); };
}

}  // namespace nhdyn::cli
