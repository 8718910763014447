// `nhdyn optimize MODEL -o out.csv [--plot out.png] [--guess FILE.csv]`: the optimal program of
// the model's [optimize] section by direct collocation with IPOPT (docs/optimize.md,
// optimize/solve.hpp) — the summary lines on stdout and the motion with its controls (u_NAME) as
// CSV. A solve that does not converge exits 1 and leaves its last iterate in FILE.partial.csv.
#include <fmt/format.h>

#include <filesystem>
#include <memory>
#include <string>
#include <vector>

#include "commands.hpp"
#include "outputs.hpp"
#include "nhdyn/core/error.hpp"
#include "nhdyn/frontend/load_model.hpp"
#include "nhdyn/frontend/optimize_problem.hpp"
#include "nhdyn/io/atomic_file.hpp"
#include "nhdyn/io/csv.hpp"
#include "nhdyn/io/plot.hpp"
#include "nhdyn/optimize/solve.hpp"

namespace nhdyn::cli {
namespace {

namespace fs = std::filesystem;

struct OptimizeArgs {
  std::string model;
  std::vector<std::string> sets;
  std::string output;
  std::string plot;
  std::string guess;
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

int run_optimize(const OptimizeArgs& args) {
  protect_model_file(args.model);
  const ModelSource source = read_model_source(args.model);
  const LoadedModel loaded = load_model_described(source, parse_parameter_sets(args.sets));
  const OptimalControlProblem problem = load_optimal_control_problem(source, loaded);
  OptimizeOptions options;
  options.nlp.tolerance = args.tolerance;
  options.nlp.constraint_tolerance = args.tolerance;
  options.nlp.max_iterations = args.max_iterations;
  options.guess = args.guess;
  if (!args.output.empty()) make_parent_directory(args.output);
  if (!args.plot.empty()) make_parent_directory(args.plot);
  const OptimizeResult result = solve_optimal_control(problem, options);
  // A build without IPOPT: bad input is still reported as such (the transcription checks it
  // before the solver is called), then the command says how to get IPOPT.
  if (result.solver.status == NlpStatus::unavailable) throw InputError(result.solver.message);
  fmt::print("{}", format_optimize_summary(problem, result));
  const std::string table = format_table(optimize_columns(problem), optimize_rows(problem, result));
  if (!result.converged()) {
    if (!args.output.empty()) {
      const fs::path partial = partial_path(args.output);
      AtomicFile file(partial);
      file.write(fmt::format("# nhdyn optimize: IPOPT stopped ({}: {}); the last iterate\n",
                             nlp_status_name(result.solver.status), result.solver.message) +
                 table);
      file.commit();
      fmt::print("last iterate -> {}\n", partial.string());
    }
    fmt::print(stderr, "nhdyn: error: IPOPT did not converge: {} ({})\n", nlp_status_name(result.solver.status),
               result.solver.message);
    return 1;
  }
  if (!args.output.empty()) {
    AtomicFile file(args.output);
    file.write(table);
    file.commit();
    fmt::print("results -> {}\n", args.output);
  }
  if (!args.plot.empty()) {
    if (args.output.empty()) throw InputError("--plot draws the CSV of -o: give -o FILE.csv too");
    write_plot_of(problem, args.output, args.plot);
    fmt::print("plot -> {}\n", args.plot);
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
  cmd->add_option("--guess", args->guess, "CSV of a first guess (t, q, q', optionally q'' and u_NAME), e.g. a "
                                          "previous result");
  cmd->add_option("--tolerance", args->tolerance, "IPOPT's tolerance (tol and constr_viol_tol)")->capture_default_str();
  cmd->add_option("--max-iterations", args->max_iterations, "IPOPT's iteration limit")->capture_default_str();
  return [args] { return run_optimize(*args); };
}

}  // namespace nhdyn::cli
