// `nhdyn optimize MODEL -o out.csv [--plot out.png] [--html out.html] [--guess FILE.csv]`: the
// optimal program of the model's [optimize] section by direct collocation with IPOPT
// (docs/optimize.md, optimize/solve.hpp) — the summary lines on stdout, the motion with its
// controls (u_NAME) as CSV, and the HTML report of the optimal motion (the page `simulate --html`
// writes, its rows the optimized points). A solve that does not converge exits 1 and leaves its
// last iterate in FILE.partial.csv.
#include <fmt/format.h>

#include <filesystem>
#include <memory>
#include <string>
#include <vector>

#include "commands.hpp"
#include "nhdyn/analysis/residuals.hpp"
#include "nhdyn/core/error.hpp"
#include "nhdyn/core/shown_text.hpp"
#include "nhdyn/frontend/load_model.hpp"
#include "nhdyn/frontend/optimize_problem.hpp"
#include "nhdyn/io/atomic_file.hpp"
#include "nhdyn/io/csv.hpp"
#include "nhdyn/io/plot.hpp"
#include "nhdyn/io/report.hpp"
#include "nhdyn/io/results.hpp"
#include "nhdyn/model/output.hpp"
#include "nhdyn/model/terms.hpp"
#include "nhdyn/optimize/solve.hpp"
#include "run_files.hpp"

namespace nhdyn::cli {
namespace {

namespace fs = std::filesystem;

struct OptimizeArgs {
  std::string model;
  std::vector<std::string> sets;
  std::string output;
  std::string plot;
  std::string guess;
  std::string html;
  double tolerance = 1e-8;
  int max_iterations = 3000;
};

std::string format_table(const std::vector<std::string>& columns, const std::vector<std::vector<double>>& rows) {
  std::string out;
  for (std::size_t i = 0; i < columns.size(); ++i) out += (i ? "," : "") + columns[i];
  out += "\n";
  for (const std::vector<double>& row : rows) {
    for (std::size_t i = 0; i < row.size(); ++i) out += fmt::format("{}{}", i ? "," : "", row[i]);
    out += "\n";
  }
  return out;
}

fs::path partial_path(const fs::path& csv) {
  std::string base = csv.string();
  if (csv.extension() == ".csv") base.resize(base.size() - 4);
  return base + ".partial.csv";
}

void write_plot_of(const OptimalControlProblem& problem, const fs::path& csv, const fs::path& png) {
  PlotRequest request;
  request.title = fmt::format("{} — optimal program, {} nodes, {}", problem.model.name, problem.nodes,
                              collocation_method_name(problem.method));
  request.csv = csv;
  request.coordinates = problem.model.coordinates;
  for (const std::string& c : problem.model.coordinates) request.velocities.push_back(c + "'");
  for (const OptimizeControl& c : problem.controls) request.actuators.push_back("u_" + c.name);
  if (problem.model.path)
    request.path = std::pair{problem.model.coordinates[static_cast<std::size_t>(problem.model.path->x)],
                             problem.model.coordinates[static_cast<std::size_t>(problem.model.path->y)]};
  write_plot(request, png);
}

// The optimized points in the columns of a simulation (io/results.hpp), for the report: q, q', q''
// from the optimum; R = A q'' - Q - G - B u, the constraints' reactions with the controls' force
// taken out (an applied force, as the actuators of program motion); the residuals, energy and
// outputs from the model's kernels at each point; the energy balance with the controls' work
// booked with the forces (as for program motion) and the works by the trapezoidal rule over the
// points, so that its error column shows the quadrature's error.
// The report's columns are a simulation's without contact forces or programs (optimum_table):
// --html on another model is refused before any work, so that the refusal costs no solve and
// leaves no file.
void require_optimum_report(const Model& model) {
  if (!make_result_columns(model).contact_forces.empty() || model.m() > 0)
    throw InputError(fmt::format("--html: the report of an optimum is for models without contacts and [[programs]], "
                                 "and {} has {}; leave --html out (-o and --plot take this model)",
                                 model.name, model.m() > 0 ? "[[programs]]" : "contacts"));
}

CsvTable optimum_table(const OptimalControlProblem& problem, const OptimizeResult& result) {
  const Model& model = problem.model;
  const ResultColumns columns = make_result_columns(model);
  const int n = model.n(), m = problem.m();
  Data data = make_data(model);
  std::vector<double> registers(static_cast<std::size_t>(problem.force.registers())), layout_q(static_cast<std::size_t>(n + m)),
      layout_v(layout_q.size(), 0.0), force(static_cast<std::size_t>(n));
  CsvTable table;
  table.header = columns.all;
  for (const OptimizeControl& c : problem.controls) table.header.push_back("u_" + c.name);
  double h0 = 0.0, previous_t = 0.0, previous_power[3] = {0.0, 0.0, 0.0};
  std::vector<double> row;
  for (int p = 0; p < result.points; ++p) {
    const double t = result.times[static_cast<std::size_t>(p)];
    const double* q = result.q.data() + static_cast<std::ptrdiff_t>(p) * n;
    const double* v = result.v.data() + static_cast<std::ptrdiff_t>(p) * n;
    const double* u = result.u.data() + static_cast<std::ptrdiff_t>(p) * m;
    if (compute_terms(model, data, t, q, v) != Status::ok)
      throw InputError(fmt::format("--html: the model's terms cannot be evaluated at t = {}", t));
    std::copy(q, q + n, layout_q.begin());
    std::copy(v, v + n, layout_v.begin());
    std::copy(u, u + m, layout_q.begin() + n);
    problem.force.run(t, layout_q.data(), layout_v.data(), registers.data(), force.data());
    for (int i = 0; i < n; ++i) data.qdd(i) = result.a[static_cast<std::size_t>(p * n + i)];
    data.R = data.A * data.qdd - data.Q - data.G;
    for (int i = 0; i < n; ++i) data.R(i) -= force[static_cast<std::size_t>(i)];
    data.stage = Stage::acceleration;
    compute_residuals(model, data);
    compute_energy(model, data);
    if (model.evaluator->has_energy_balance()) {
      compute_power(model, data);
      for (int i = 0; i < n; ++i) data.power_forces += force[static_cast<std::size_t>(i)] * v[i];
      const double power[3] = {data.power_forces, data.power_reactions, data.power_time};
      if (p == 0) {
        h0 = data.energy_function;
      } else {
        const double dt = 0.5 * (t - previous_t);
        data.work_forces += dt * (power[0] + previous_power[0]);
        data.work_reactions += dt * (power[1] + previous_power[1]);
        data.work_time += dt * (power[2] + previous_power[2]);
      }
      std::copy(power, power + 3, previous_power);
      data.balance_error = data.energy_function - h0 - (data.work_forces + data.work_reactions + data.work_time);
    }
    previous_t = t;
    compute_outputs(model, data);
    fill_result_row(model, data, row);
    row.insert(row.end(), u, u + m);  // the controls, after the model's columns (ReportOptions::controls)
    table.rows.push_back(row);
  }
  return table;
}

// The report of the optimal motion (--html), from the optimum's points in a simulation's columns.
std::string write_optimum_report(const OptimizeArgs& args, const LoadedModel& loaded,
                                 const OptimalControlProblem& problem, const OptimizeResult& result) {
  ReportOptions report_options;
  for (const OptimizeControl& c : problem.controls) report_options.controls.push_back("u_" + c.name);
  return write_model_report(
      problem.model, loaded.description.get(), optimum_table(problem, result),
      fmt::format("{}: optimal program, {} nodes, {}", problem.model.name, problem.nodes,
                  collocation_method_name(problem.method)),
      {{"status", fmt::format("{} ({})", optimize_status_name(result), result.solver.message)},
       {"iterations", fmt::format("{}", result.solver.iterations)},
       {"objective", fmt::format("{:.10g}", result.objective)},
       {"replay difference", result.replayed ? fmt::format("{:.3e}", result.replay_difference) : "none"},
       {"results", args.output}},
      args.html, report_options);
}

int run_optimize(const OptimizeArgs& args) {
  RunFiles files(args.model);
  const ModelSource source = read_model_source(args.model);
  const LoadedModel loaded = load_model_described(source, parse_parameter_sets(args.sets));
  if (!args.html.empty() && args.output.empty())
    throw InputError("--html reports the CSV of -o: give -o FILE.csv too");
  if (!args.plot.empty() && args.output.empty()) throw InputError("--plot draws the CSV of -o: give -o FILE.csv too");
  const OptimalControlProblem problem = load_optimal_control_problem(source, loaded);
  if (!args.html.empty()) require_optimum_report(problem.model);
  // Every file of the command, checked together before the solve (run_files.hpp); their folders
  // are made, and -o opened, so that an unwritable path never costs a solve. The first guess is
  // an input: no output may replace it (a failed solve's FILE.partial.csv given back as --guess
  // included).
  if (!args.guess.empty())
    files.input(args.guess, "--guess");
  else
    files.input(problem.guess, "the first guess (guess = in [optimize])");
  files.output(args.output, "-o", Folder::make);
  if (!args.output.empty()) files.output(partial_path(args.output), "the partial-results file", Folder::make);
  files.plot(args.plot, "--plot");  // in a folder that exists, or the one made for -o
  files.page(args.html, "--html");
  files.check();
  AtomicFile* csv = args.output.empty() ? nullptr : &files.open(args.output);
  OptimizeOptions options;
  options.nlp.tolerance = args.tolerance;
  options.nlp.constraint_tolerance = args.tolerance;
  options.nlp.max_iterations = args.max_iterations;
  options.guess = args.guess;
  const OptimizeResult result = solve_optimal_control(problem, options);
  // A build without IPOPT: bad input is still reported as such (the transcription checks it
  // before the solver is called), then the command says how to get IPOPT.
  if (result.solver.status == NlpStatus::unavailable) throw InputError(result.solver.message);
  fmt::print("{}", format_optimize_summary(problem, result));
  const std::string table = format_table(optimize_columns(problem), optimize_rows(problem, result));
  if (!result.solved()) {
    // -o is left as it was; the last iterate (or the discrete optimum the replay rejects) goes
    // beside it.
    if (csv) {
      files.write_now(partial_path(args.output),
                      (result.replay_rejected
                           ? fmt::format("# nhdyn optimize: not a motion of the model (interval replay {:.3e} in {}, "
                                         "limit {:.3e}); the discrete optimum\n",
                                         result.local_difference, result.replay_coordinate, result.replay_limit)
                           : fmt::format("# nhdyn optimize: IPOPT stopped ({}: {}); the last iterate\n",
                                         nlp_status_name(result.solver.status), result.solver.message)) +
                          table);
      fmt::print("{} -> {}\n", result.replay_rejected ? "discrete optimum" : "last iterate",
                 shown_text(partial_path(args.output).string()));
    }
    if (result.replay_rejected)
      fmt::print(stderr, "nhdyn: error: {}\n", result.replay_verdict);
    else
      fmt::print(stderr, "nhdyn: error: IPOPT did not converge: {} ({})\n", nlp_status_name(result.solver.status),
                 result.solver.message);
    return 1;
  }
  if (csv) csv->write(table);
  files.commit();
  if (csv) fmt::print("results -> {}\n", shown_text(args.output));
  if (!args.plot.empty()) {
    write_plot_of(problem, args.output, args.plot);
    fmt::print("plot -> {}\n", shown_text(args.plot));
  }
  if (!args.html.empty()) {
    const std::string notice = write_optimum_report(args, loaded, problem, result);
    fmt::print("report -> {}{}\n", shown_text(args.html), notice.empty() ? "" : "\nnote: " + notice);
  }
  return 0;
}

}  // namespace

std::function<int()> add_optimize_command(CLI::App& app) {
  auto args = std::make_shared<OptimizeArgs>();
  CLI::App* cmd = app.add_subcommand("optimize", "Find the optimal program of the model file's [optimize] section "
                                                 "(direct collocation with IPOPT)");
  cmd->add_option("MODEL", args->model, "A model file (.toml) with an [optimize] section")->required();
  cmd->add_option("--set", args->sets, "Set a parameter, NAME=EXPR: a number or an expression in numbers, pi, e and the other parameters (repeatable)");
  cmd->add_option("-o,--output", args->output, "CSV of the motion and the controls (t, q, q', q'', u_NAME)");
  cmd->add_option("--plot", args->plot, "PNG of the coordinates, velocities and controls (needs -o)");
  cmd->add_option("--html", args->html, "HTML report of the optimal motion (needs -o): animation, plots, equations "
                                        "(docs/report.md)");
  cmd->add_option("--guess", args->guess, "CSV of a first guess (t, q, q', optionally q'' and u_NAME), e.g. a "
                                          "previous result");
  cmd->add_option("--tolerance", args->tolerance, "IPOPT's tolerance (tol and constr_viol_tol)")->capture_default_str();
  cmd->add_option("--max-iterations", args->max_iterations, "IPOPT's iteration limit")->capture_default_str();
  return [args] { return run_optimize(*args); };
}

}  // namespace nhdyn::cli
