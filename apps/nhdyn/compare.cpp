// `nhdyn compare MODEL`: the formulations and integrators side by side on one model, against one
// reference (analysis/comparison.hpp). Prints a table, writes it as CSV, writes the error and the
// residuals against time as a second CSV, and plots them on a log scale.
#include <fmt/format.h>

#include <algorithm>
#include <filesystem>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "commands.hpp"
#include "nhdyn/analysis/comparison.hpp"
#include "nhdyn/analysis/exact_solution.hpp"
#include "nhdyn/core/error.hpp"
#include "nhdyn/core/join.hpp"
#include "nhdyn/core/shown_text.hpp"
#include "nhdyn/frontend/load_model.hpp"
#include "nhdyn/frontend/provenance.hpp"
#include "nhdyn/io/atomic_file.hpp"
#include "nhdyn/io/csv.hpp"
#include "nhdyn/io/plot.hpp"
#include "nhdyn/jit/compiled_evaluator.hpp"
#include "run_files.hpp"

namespace nhdyn::cli {
namespace {

struct CompareArgs {
  std::string model;
  std::string reference = "tight";
  std::vector<std::string> methods = names_of(kFormulations);
  bool methods_given = false;  // --methods on the command line (else the list above)
  std::vector<std::string> integrators{"dopri5"};
  std::string complement = "qr";
  std::optional<double> t_end;
  std::optional<double> output_step;
  std::optional<double> rtol;  // default: the model's (its file's [simulation], else RunOptions)
  std::optional<double> atol;
  std::string stabilize = "none";
  std::vector<std::string> sets;
  std::string output;
  std::string plot;
  std::vector<std::string> plot_columns;  // the series columns --plot draws (empty: all)
  bool quiet = false;
  std::string evaluator = "interpreted";  // interpreted | compiled | auto (jit/compiled_evaluator.hpp)
};

std::string case_name(const ComparisonCase& c) {
  return fmt::format("{}_{}", formulation_name(c.method), integrator_name(c.integrator));
}

// The accuracy of a run's energy: the largest |h - h0 - W| (docs/derivations/energy-balance.md),
// or, for a built-in model without a balance, the drift of its conserved E.
double energy_error(const SimulationSummary& s) {
  return s.energy.has_balance ? s.energy.balance_error : s.energy.drift;
}

// The methods compared: those asked for, except that programs and contacts that may slide or lift
// off are solved by sanh alone: by default it is then the one method compared, with a note; another
// one asked for by name is refused.
std::vector<std::string> compared_methods(const Model& model, const CompareArgs& args) {
  std::vector<std::string> methods = args.methods;
  if (model.m() > 0 || model.contact_modes) {
    const char* what = model.m() > 0 ? "programs ([[programs]])" : "contacts that may slide or lift off (friction or "
                                                                   "unilateral, docs/contact-modes.md)";
    for (const std::string& m : methods)
      if (args.methods_given && parse_formulation(m) != Formulation::sanh)
        throw InputError(fmt::format("--methods {}: model '{}' has {}, which only the sanh formulation solves; give "
                                     "--methods sanh (and --integrators to compare integrators)",
                                     m, model.name, what));
    if (!args.methods_given) {
      methods = {"sanh"};
      fmt::print(stderr, "nhdyn: note: model '{}' has {}, which only sanh solves: comparing sanh alone "
                         "(--integrators compares integrators)\n", model.name, what);
    }
  }
  // A name given twice would give two runs of one case and two columns of one name.
  for (std::size_t j = 0; j < methods.size(); ++j)
    for (std::size_t i = 0; i < j; ++i)
      if (parse_formulation(methods[i]) == parse_formulation(methods[j]))
        throw InputError(fmt::format("--methods: '{}' is named twice; name each method once", methods[j]));
  for (std::size_t j = 0; j < args.integrators.size(); ++j)
    for (std::size_t i = 0; i < j; ++i)
      if (parse_integrator(args.integrators[i]) == parse_integrator(args.integrators[j]))
        throw InputError(fmt::format("--integrators: '{}' is named twice; name each integrator once",
                                     args.integrators[j]));
  return methods;
}

// The comparison's options: the reference and the run options every case shares (the cases are
// added by the caller, each method with each integrator).
ComparisonOptions make_comparison_options(const Model& model, const CompareArgs& args) {
  ComparisonOptions options;
  options.reference = args.reference == "analytic" ? Reference::analytic : Reference::tight;
  if (options.reference == Reference::analytic) check_solution(model);  // before any file is opened
  options.run.t_end = args.t_end.value_or(model.defaults.t_end);
  options.run.output_step = args.output_step.value_or(model.defaults.output_step);
  options.run.formulation.complement = parse_complement(args.complement);
  options.run.integrator.rtol = args.rtol.value_or(model.defaults.rtol);
  options.run.integrator.atol = args.atol.value_or(model.defaults.atol);
  options.run.stabilization = parse_stabilization(args.stabilize);
  return options;
}

// The series CSV's columns: t, then per case its error and the residuals the model has.
std::vector<std::string> series_columns(const Model& model, const ComparisonOptions& options) {
  std::vector<std::string> columns{"t"};
  for (const ComparisonCase& c : options.cases) {
    columns.push_back("error_" + case_name(c));
    if (model.position_constraints() > 0) columns.push_back("residual_pos_" + case_name(c));
    if (model.velocity_constraints() > 0) columns.push_back("residual_vel_" + case_name(c));
  }
  return columns;
}

// Both files say what made them (io/provenance.hpp): the model as loaded and the cases compared.
std::string compare_provenance(const Model& model, const ModelSource& source, const CompareArgs& args,
                               const std::vector<std::string>& methods, const ComparisonOptions& options) {
  std::vector<std::string> method_names, integrator_names;
  for (const std::string& m : methods) method_names.emplace_back(formulation_name(parse_formulation(m)));
  for (const std::string& i : args.integrators) integrator_names.emplace_back(integrator_name(parse_integrator(i)));
  return format_provenance(make_command_provenance(
      model, source, "compare",
      {{"methods", join(method_names, ",")},
       {"integrators", join(integrator_names, ",")},
       {"reference", args.reference},
       {"complement", std::string(complement_name(options.run.formulation.complement))},
       {"rtol", fmt::format("{}", options.run.integrator.rtol)},
       {"atol", fmt::format("{}", options.run.integrator.atol)},
       {"t0", fmt::format("{}", model.t0)},
       {"t_end", fmt::format("{}", options.run.t_end)},
       {"output_step", fmt::format("{}", options.run.output_step)},
       {"stabilize", std::string(stabilization_name(options.run.stabilization))},
       {"evaluator", args.evaluator}}));
}

// compare measures every case against the reference row by row to t_end, so a stop event of the
// model (which would end each run at its own time) is not applied: said here, as simulate says
// that a stop condition never held, rather than left for the user to find.
void warn_stop_events(const Model& model, double t_end) {
  for (const Event& e : model.events)
    if (e.action == EventAction::stop)
      fmt::print(stderr,
                 "nhdyn: warning: {}{}the stop event '{}' ({}) is not applied by compare: every case runs to t = {:g} "
                 "to be measured against the reference row by row; nhdyn simulate stops there\n",
                 e.where, e.where.empty() ? "" : ": ", e.name, e.expression, t_end);
}

// The table CSV: one row per case, its cost, its residuals and errors, its outcome.
std::string format_table(const std::string& provenance, const Comparison& result) {
  std::string text = provenance +
      "method,integrator,solve_ns,steps,rhs_evaluations,wall_time_s,max_residual_pos,max_residual_vel,"
      "max_residual_acc,energy_error,max_error_q,max_error_v,status\n";
  for (const ComparisonResult& r : result.results) {
    const SimulationSummary& s = r.summary;
    text += fmt::format("{},{},{:.4g},{},{},{:.4g},{:.3e},{:.3e},{:.3e},{:.3e},{:.3e},{:.3e},{}\n",
                        formulation_name(r.which.method), integrator_name(r.which.integrator), r.solve_ns, s.stats.steps,
                        s.stats.rhs_evaluations, s.wall_time, s.residuals.position, s.residuals.velocity,
                        s.residuals.acceleration, energy_error(s), r.max_error_q, r.max_error_v,
                        format_status(s));
  }
  return text;
}

void write_series(CsvWriter& series, const Model& model, const Comparison& result) {
  std::vector<double> row;
  for (std::size_t k = 0; k < result.times.size(); ++k) {
    row.assign(1, result.times[k]);
    for (const ComparisonResult& r : result.results) {
      row.push_back(r.error[k]);
      if (model.position_constraints() > 0) row.push_back(r.position_residual[k]);
      if (model.velocity_constraints() > 0) row.push_back(r.velocity_residual[k]);
    }
    series.write_row(row);
  }
}

// --plot: the error and the residuals against time, one panel per method or integrator.
void plot_comparison(const CompareArgs& args, const Model& model, const ComparisonOptions& options,
                     const std::filesystem::path& series_path) {
  PanelPlotRequest request;
  request.title = fmt::format("{}: |error| against the reference and constraint residuals", model.name);
  request.csv = series_path;
  std::vector<std::string> methods, integrators, quantities{"error"};
  for (const ComparisonCase& c : options.cases) {
    const std::string m(formulation_name(c.method)), i(integrator_name(c.integrator));
    if (std::find(methods.begin(), methods.end(), m) == methods.end()) methods.push_back(m);
    if (std::find(integrators.begin(), integrators.end(), i) == integrators.end()) integrators.push_back(i);
  }
  if (model.position_constraints() > 0) quantities.push_back("residual_pos");
  if (model.velocity_constraints() > 0) quantities.push_back("residual_vel");
  request.panels = calc_comparison_panels(methods, integrators, quantities);
  if (methods.size() > 1 && integrators.size() > 1) request.layout_columns = static_cast<int>(methods.size());
  select_panel_columns(request.panels, args.plot_columns);
  request.same_log_range = true;  // heights compare across panels
  write_panel_plot(request, args.plot);
}

// The table on standard output, and where the files went.
void print_comparison(const CompareArgs& args, const Model& model, const ComparisonOptions& options,
                      const Comparison& result, const std::filesystem::path& table_path,
                      const std::filesystem::path& series_path) {
  fmt::print("nhdyn compare {}: t = {:g} .. {:g} s, D: {}, rtol {:g}, atol {:g}, stabilization {}\n", model.name,
             model.t0, options.run.t_end, args.complement, options.run.integrator.rtol, options.run.integrator.atol, args.stabilize);
  if (options.reference == Reference::analytic)
    fmt::print("reference: the model's exact solution\n");
  else
    fmt::print("reference: sanh, dopri5, rtol 1e-13, atol 1e-15 ({} steps)\n", result.reference.stats.steps);
  auto level = [](double value, bool defined) { return defined ? fmt::format("{:.2e}", value) : std::string("-"); };
  fmt::print("{:<15} {:<12} {:>9} {:>8} {:>9} {:>9} {:>9} {:>9} {:>9} {:>9} {:>9}\n", "method", "integrator",
             "solve ns", "steps", "rhs", "wall ms", "res pos", "res vel", "energy", "err q", "err q'");
  for (const ComparisonResult& r : result.results) {
    const SimulationSummary& s = r.summary;
    fmt::print("{:<15} {:<12} {:>9.1f} {:>8} {:>9} {:>9.3g} {:>9} {:>9} {:>9.2e} {:>9.2e} {:>9.2e}{}\n",
               formulation_name(r.which.method), integrator_name(r.which.integrator), r.solve_ns, s.stats.steps,
               s.stats.rhs_evaluations, s.wall_time * 1e3,
               level(s.residuals.position, model.position_constraints() > 0),
               level(s.residuals.velocity, model.velocity_constraints() > 0),
               energy_error(s), r.max_error_q, r.max_error_v,
               format_failure_note(s));
  }
  fmt::print("table -> {}\nseries -> {}\n", shown_text(table_path.string()), shown_text(series_path.string()));
  if (!args.plot.empty()) fmt::print("plot -> {}\n", shown_text(args.plot));
}

int run_compare(const CompareArgs& args) {
  RunFiles files(args.model);
  const ModelSource source = read_model_source(args.model);
  const LoadedModel resolved = load_model_described(source, parse_parameter_sets(args.sets));
  std::string notice;
  const Model model = jit::with_evaluator(resolved.model, jit::parse_evaluator_choice(args.evaluator), &notice);
  if (!notice.empty()) fmt::print(stderr, "{}\n", notice);
  if (args.reference != "tight" && args.reference != "analytic")
    throw InputError(fmt::format("unknown reference '{}'; choose one of: tight, analytic", args.reference));
  ComparisonOptions options = make_comparison_options(model, args);
  const std::vector<std::string> methods = compared_methods(model, args);
  for (const std::string& m : methods)
    for (const std::string& i : args.integrators) options.cases.push_back({parse_formulation(m), parse_integrator(i)});

  namespace fs = std::filesystem;
  const fs::path table_path = args.output.empty() ? fs::path("results") / (make_file_name(model.name) + "-compare.csv") : fs::path(args.output);
  fs::path series_path = table_path;
  series_path.replace_filename(table_path.stem().string() + "-series.csv");
  files.output(table_path, "the table CSV", args.output.empty() ? Folder::make : Folder::must_exist);
  files.output(series_path, "the series CSV");
  files.plot(args.plot);
  files.check();
  const std::vector<std::string> columns = series_columns(model, options);
  check_plot_columns(args.plot, columns, args.plot_columns);
  const std::string provenance = compare_provenance(model, source, args, methods, options);
  // Both opened (so both paths proved writable) before any run; they appear only on commit.
  CsvWriter& series = files.open_csv(series_path, columns, provenance);
  AtomicFile& table = files.open(table_path);

  warn_stop_events(model, options.run.t_end);
  const Comparison result = compare_formulations(model, options);
  // The constraint watch's warnings (analysis/constraint_watch.hpp), per case, whatever -q says.
  for (const ComparisonResult& r : result.results) {
    for (const std::string& w : r.summary.warnings)
      fmt::print(stderr, "nhdyn: warning ({}, {}): {}\n", formulation_name(r.which.method), integrator_name(r.which.integrator), w);
    if (!r.summary.stiffness.empty())
      fmt::print(stderr, "nhdyn: warning ({}, {}): {}\n", formulation_name(r.which.method),
                 integrator_name(r.which.integrator), r.summary.stiffness);
  }
  table.write(format_table(provenance, result));
  write_series(series, model, result);
  files.commit();  // a case that failed is a row of the table: the files are kept, and the exit code says it
  if (!args.plot.empty()) plot_comparison(args, model, options, series_path);
  if (!args.quiet) print_comparison(args, model, options, result, table_path, series_path);
  for (const ComparisonResult& r : result.results)
    if (r.summary.status != Status::ok) return 1;
  return 0;
}

}  // namespace

std::function<int()> add_compare_command(CLI::App& app) {
  auto args = std::make_shared<CompareArgs>();
  CLI::App* cmd = app.add_subcommand("compare", "Run formulations and integrators side by side against a reference");
  cmd->add_option("MODEL", args->model, "A model file (.toml) or a built-in model (see `nhdyn list`)")->required();
  cmd->add_option("--reference", args->reference, "tight (a run at rtol 1e-13) | analytic (the model's)")
      ->capture_default_str();
  cmd->add_option("--methods", args->methods, "Formulations, comma-separated (a model with programs: sanh alone)")
      ->delimiter(',')
      ->capture_default_str()
      ->each([args](const std::string&) { args->methods_given = true; });
  cmd->add_option("--integrators", args->integrators,
                  "Integrators, comma-separated: " + list_names(kIntegrators))
      ->delimiter(',')
      ->capture_default_str();
  cmd->add_option("--complement", args->complement, "Where D comes from: " + list_names(kComplements, " | "))
      ->capture_default_str();
  cmd->add_option("--t-end", args->t_end, "End time [s] (default: the model's)");
  cmd->add_option("--output-step", args->output_step, "Time between compared outputs [s] (default: the model's)");
  cmd->add_option("--rtol", args->rtol, "Relative tolerance of every case (default: the model's, else 1e-8)");
  cmd->add_option("--atol", args->atol, "Absolute tolerance of every case (default: the model's, else 1e-10)");
  cmd->add_option("--stabilize", args->stabilize, list_names(kStabilizations, " | "))->capture_default_str();
  cmd->add_option("--set", args->sets, "Set a parameter, NAME=EXPR: a number or an expression in numbers, pi, e and the other parameters (repeatable)");
  cmd->add_option("--evaluator", args->evaluator, help_choices(jit::kEvaluatorChoices, jit::EvaluatorChoice::interpreted) + ", as for simulate");
  cmd->add_option("-o,--output", args->output, "Table CSV (default results/MODEL-compare.csv); the series "
                                                "goes next to it as ...-series.csv");
  cmd->add_option("--plot", args->plot,
                  "PNG of the error and the residuals against time, one panel per method or integrator");
  cmd->add_option("--plot-columns", args->plot_columns, "The series columns --plot draws, comma-separated (default: all)")
      ->delimiter(',');
  cmd->add_flag("-q,--quiet", args->quiet, "Print no table");
  return [args] { return run_compare(*args); };
}

}  // namespace nhdyn::cli
