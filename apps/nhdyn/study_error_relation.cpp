// `nhdyn study error-relation [MODEL]`: for tolerances from 1e-3 to 1e-12, every formulation and
// integrator against the model's exact solution — the global error beside the constraint
// residuals (studies/error_relation.hpp, docs/studies/error-relation.md). Prints the table, writes
// it as CSV (one row per run), a second CSV with one row per tolerance for the plot, and the plot.
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
#include "nhdyn/io/plot.hpp"
#include "nhdyn/io/xy_plot.hpp"
#include "nhdyn/studies/run_times.hpp"
#include "nhdyn/studies/error_relation.hpp"
#include "run_files.hpp"
#include "study.hpp"

namespace nhdyn::cli {
namespace {

struct ErrorRelationArgs {
  std::string model = "appell";
  std::vector<double> tolerances{1e-3, 1e-4, 1e-5, 1e-6, 1e-7, 1e-8, 1e-9, 1e-10, 1e-11, 1e-12};
  std::vector<std::string> methods;  // empty: every formulation the model allows
  std::vector<std::string> integrators{"dopri5", "cvode-bdf", "cvode-adams"};
  double atol_factor = 1.0;
  std::optional<double> t_end;
  std::optional<double> output_step;
  std::vector<std::string> sets;
  std::string output = "results/error-relation.csv";
  std::string plot;
  bool quiet = false;
};

StudyFormulation parse_study_formulation(const std::string& label) {
  if (label == "sanh" || label == "sanh-qr") return {Formulation::sanh, Complement::qr};
  if (label == "sanh-partition") return {Formulation::sanh, Complement::partition};
  if (label == "sanh-analytic") return {Formulation::sanh, Complement::analytic};
  if (label == "sanh-" || label.starts_with("sanh-"))
    throw InputError(fmt::format("unknown formulation '{}'; sanh takes its D from qr, partition or analytic: "
                                 "sanh-qr, sanh-partition, sanh-analytic",
                                 label));
  return {parse_formulation(label), Complement::qr};  // throws naming the valid methods
}

// A run's label in the column names: its formulation and integrator.
std::string run_label(const StudyFormulation& f, IntegratorKind i) {
  return fmt::format("{}_{}", formulation_label(f), integrator_name(i));
}

// The by-tolerance series: one row per tolerance, each run's error and residuals (NaN where it failed).
void write_series(const ErrorRelation& study, bool pos, bool vel, CsvWriter& series) {
  std::vector<double> row;
  for (std::size_t k = 0; k < study.tolerances.size(); ++k) {
    row.assign(1, study.tolerances[k]);
    for (std::size_t f = 0; f < study.formulations.size(); ++f)
      for (std::size_t i = 0; i < study.integrators.size(); ++i) {
        const ErrorRelationRun& r = study.run(f, i, k);
        const bool ok = r.summary.status == Status::ok;
        const double nan = std::nan("");
        row.push_back(ok ? std::max(r.max_error_q, r.max_error_v) : nan);
        if (vel) row.push_back(ok ? r.max_residual_vel : nan);
        if (pos) row.push_back(ok ? r.max_residual_pos : nan);
      }
    series.write_row(row);
  }
}

// The table: one line per run.
std::string table_text(const ErrorRelation& study, const std::string& provenance, double atol_factor) {
  std::string text = provenance + "formulation,integrator,rtol,atol,max_error_q,max_error_v,max_residual_pos,max_residual_vel,"
                     "steps,rhs_evaluations,status\n";
  for (const ErrorRelationRun& r : study.runs)
    text += fmt::format("{},{},{:.3g},{:.3g},{:.6e},{:.6e},{:.6e},{:.6e},{},{},{}\n", formulation_label(r.formulation),
                        integrator_name(r.integrator), r.tolerance, r.tolerance * atol_factor, r.max_error_q,
                        r.max_error_v, r.max_residual_pos, r.max_residual_vel, r.summary.stats.steps,
                        r.summary.stats.rhs_evaluations,
                        format_status(r.summary));
  return text;
}

// --plot: the relation itself. Each run is a point (its residual, its error); the points of one
// formulation and integrator are joined in the order of the tolerances. On the diagonal the
// residual equals the error.
void plot_error_relation(const ErrorRelation& study, const Model& model, bool vel,
                         const std::filesystem::path& series_path, const std::string& plot) {
  const std::string level = vel ? "vel" : "pos";
  XyPlotRequest request;
  request.title = fmt::format("{}: global error against the {} constraint residual, rtol {:g} .. {:g}", model.name,
                              vel ? "velocity" : "position", study.tolerances.front(), study.tolerances.back());
  request.csv = series_path;
  for (std::size_t f = 0; f < study.formulations.size(); ++f)
    for (std::size_t i = 0; i < study.integrators.size(); ++i) {
      const std::string label = run_label(study.formulations[f], study.integrators[i]);
      request.y.push_back("error_" + label);
      request.x_of_curve.push_back(fmt::format("residual_{}_{}", level, label));
      request.titles.push_back(fmt::format("{} {}", formulation_label(study.formulations[f]),
                                           integrator_name(study.integrators[i])));
    }
  request.x_label = fmt::format("max |{} residual| over the run", vel ? "velocity" : "position");
  request.y_label = study.analytic ? "max |error| against the exact solution" : "max |error| against a tight run";
  request.diagonal = true;
  write_xy_plot(request, plot);
}

// The summary on standard output: one line per run, and where the files went.
void print_error_relation(const ErrorRelation& study, const Model& model, const ErrorRelationArgs& args, bool pos,
                          bool vel, const std::filesystem::path& table_path, const std::filesystem::path& series_path) {
  const double t_end = args.t_end.value_or(model.defaults.t_end);
  fmt::print("nhdyn study error-relation {}: t = {:g} .. {:g} s, atol = {:g} rtol, reference: {}\n", model.name,
             model.t0, t_end, args.atol_factor,
             study.analytic ? "the model's exact solution" : "sanh, dopri5, rtol 1e-13 (no exact solution)");
  fmt::print("{:<16} {:<12} {:>7} {:>10} {:>10} {:>10} {:>10} {:>8}\n", "formulation", "integrator", "rtol",
             "err q", "err q'", "res pos", "res vel", "steps");
  for (const ErrorRelationRun& r : study.runs) {
    const auto level = [](double value, bool defined) { return defined ? fmt::format("{:.2e}", value) : std::string("-"); };
    fmt::print("{:<16} {:<12} {:>7.0e} {:>10.2e} {:>10.2e} {:>10} {:>10} {:>8}{}\n", formulation_label(r.formulation),
               integrator_name(r.integrator), r.tolerance, r.max_error_q, r.max_error_v, level(r.max_residual_pos, pos),
               level(r.max_residual_vel, vel), r.summary.stats.steps,
               format_failure_note(r.summary));
  }
  fmt::print("table -> {}\nby tolerance -> {}\n", shown_text(table_path.string()), shown_text(series_path.string()));
  if (!args.plot.empty()) fmt::print("plot -> {}\n", shown_text(args.plot));
}

// Both files say what made them (io/provenance.hpp): the model as loaded and the study's options.
std::string error_relation_provenance(const Model& model, const ModelSource& source,
                                      const ErrorRelationOptions& options, const ErrorRelationArgs& args) {
  std::vector<std::string> formulation_names, integrator_names, tolerances;
  for (const StudyFormulation& f : options.formulations) formulation_names.push_back(formulation_label(f));
  for (IntegratorKind i : options.integrators) integrator_names.emplace_back(integrator_name(i));
  for (double tolerance : options.tolerances) tolerances.push_back(fmt::format("{}", tolerance));
  return format_provenance(make_command_provenance(
      model, source, "study error-relation",
      {{"methods", join(formulation_names, ",")},
       {"integrators", join(integrator_names, ",")},
       {"tolerances", join(tolerances, ",")},
       {"atol_factor", fmt::format("{}", args.atol_factor)},
       {"t_end", fmt::format("{}", args.t_end.value_or(model.defaults.t_end))},
       {"output_step", fmt::format("{}", args.output_step.value_or(model.defaults.output_step))}}));
}

int run_error_relation(const ErrorRelationArgs& args) {
  RunFiles files(args.model);
  const ModelSource source = read_model_source(args.model);
  const LoadedModel resolved = load_model_described(source, parse_parameter_sets(args.sets));
  const Model& model = resolved.model;
  ErrorRelationOptions options;
  options.tolerances = args.tolerances;
  options.atol_factor = args.atol_factor;
  for (const std::string& m : args.methods) options.formulations.push_back(parse_study_formulation(m));
  options.integrators.clear();
  for (const std::string& i : args.integrators) options.integrators.push_back(parse_integrator(i));
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
  if (options.formulations.empty()) options.formulations = calc_study_formulations(model);
  const bool pos = model.position_constraints() > 0;
  const bool vel = model.velocity_constraints() > 0;
  std::vector<std::string> columns{"tolerance"};
  for (const StudyFormulation& f : options.formulations)
    for (IntegratorKind i : options.integrators) {
      columns.push_back("error_" + run_label(f, i));
      if (vel) columns.push_back("residual_vel_" + run_label(f, i));
      if (pos) columns.push_back("residual_pos_" + run_label(f, i));
    }
  // Both files are opened (and so checked writable) before the runs; they appear only on commit.
  const std::string provenance = error_relation_provenance(model, source, options, args);
  CsvWriter& series = files.open_csv(series_path, columns, provenance);
  AtomicFile& table = files.open(table_path);

  const ErrorRelation study = study_error_relation(model, options);
  write_series(study, pos, vel, series);
  table.write(table_text(study, provenance, args.atol_factor));
  files.commit();

  if (!args.plot.empty()) plot_error_relation(study, model, vel, series_path, args.plot);
  if (!args.quiet) print_error_relation(study, model, args, pos, vel, table_path, series_path);
  std::vector<std::string> failures;
  for (const ErrorRelationRun& r : study.runs)
    if (r.summary.status != Status::ok) failures.push_back(r.summary.message);
  return study_exit("error-relation", model, study.runs.size(), failures);
}

}  // namespace

std::function<int()> add_error_relation_study(CLI::App& study) {
  auto args = std::make_shared<ErrorRelationArgs>();
  CLI::App* cmd = study.add_subcommand("error-relation",
                                       "Global error against constraint residual for a range of tolerances");
  cmd->add_option("MODEL", args->model, "A model file (.toml) or a built-in model; one with an exact solution")
      ->capture_default_str();
  cmd->add_option("--tolerances", args->tolerances, "rtol of each run, comma-separated")
      ->delimiter(',')
      ->capture_default_str();
  cmd->add_option("--methods", args->methods,
                  "Formulations, comma-separated: sanh-qr, sanh-partition, sanh-analytic, lagrange, "
                  "udwadia-kalaba, nullspace (default: all the model allows)")
      ->delimiter(',');
  cmd->add_option("--integrators", args->integrators,
                  "Integrators, comma-separated: " + adaptive_integrator_names(", "))
      ->delimiter(',')
      ->capture_default_str();
  cmd->add_option("--atol-factor", args->atol_factor, "atol of each run = this x rtol")->capture_default_str();
  cmd->add_option("--t-end", args->t_end, "End time [s] (default: the model's)");
  cmd->add_option("--output-step", args->output_step, "Time between compared outputs [s] (default: the model's)");
  cmd->add_option("--set", args->sets, "Set a parameter, NAME=EXPR: a number or an expression in numbers, pi, e and the other parameters (repeatable)");
  cmd->add_option("-o,--output", args->output, "Table CSV, one row per run; the by-tolerance CSV goes next to it")
      ->capture_default_str();
  cmd->add_option("--plot", args->plot, "PNG of the error against the residual, one curve per run series (log-log)");
  cmd->add_flag("-q,--quiet", args->quiet, "Print no table");
  return [args] { return run_error_relation(*args); };
}

}  // namespace nhdyn::cli
