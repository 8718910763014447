// `nhdyn simulate MODEL`: integrate a model, write one CSV row per output time, optionally plot,
// and print a short summary. Every check of the user's input (model, times, tolerances, output
// paths) happens before the first step, so a bad option never costs a run.
#include <fmt/format.h>

#include <filesystem>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "commands.hpp"
#include "model_source.hpp"
#include "nhdyn/analysis/simulation.hpp"
#include "nhdyn/core/error.hpp"
#include "nhdyn/io/csv.hpp"
#include "nhdyn/io/plot.hpp"
#include "nhdyn/io/results.hpp"
#include "progress.hpp"

namespace nhdyn::cli {
namespace {

struct SimulateArgs {
  std::string model;
  std::optional<double> t_end;
  std::optional<double> output_step;
  std::string method = "sanh";
  std::string complement = "qr";
  std::string integrator = "dopri5";
  double rtol = 1e-8;
  double atol = 1e-10;
  double step = 0.0;
  std::string output;
  std::string plot;
  bool quiet = false;
};

std::string format_residual(double value, bool defined) { return defined ? fmt::format("{:.3g}", value) : "-"; }

int run_simulate(const SimulateArgs& args) {
  const Model model = resolve_model(args.model);
  SimulationOptions options;
  options.t_end = args.t_end.value_or(model.defaults.t_end);
  options.output_step = args.output_step.value_or(model.defaults.output_step);
  options.formulation.method = parse_method(args.method);
  options.formulation.complement = parse_complement(args.complement);
  options.integrator.kind = parse_integrator(args.integrator);
  options.integrator.rtol = args.rtol;
  options.integrator.atol = args.atol;
  options.integrator.step = args.step;
  check_simulation_options(model, options);

  std::filesystem::path csv_path = args.output;
  if (csv_path.empty()) {
    // The default place is ours to create; a path the user names must already be writable.
    csv_path = std::filesystem::path("results") / (model.name + ".csv");
    std::filesystem::create_directories(csv_path.parent_path());
  }
  const ResultColumns columns = make_result_columns(model);
  CsvWriter writer(csv_path, columns.all);  // refuses an unwritable path before any step
  std::optional<AtomicFile> plot_probe;
  if (!args.plot.empty()) {
    if (!gnuplot_available())
      throw FileError("--plot needs gnuplot, which is not installed: install it (apt-get install gnuplot-nox) "
                      "or run without --plot");
    plot_probe.emplace(args.plot);  // checks the plot's directory now; removed unused
  }

  std::vector<double> row;
  row.reserve(columns.all.size());
  ProgressBar progress(model.t0, options.t_end);
  const SimulationSummary summary = simulate(model, options, [&](const Data& data) {
    fill_result_row(model, data, row);
    writer.write_row(row);
    progress.update(data.t);
  });
  progress.finish();
  if (summary.status != Status::ok) {
    fmt::print(stderr, "nhdyn: simulation of '{}' failed at t = {:.6g}: {}\n", model.name, summary.t_reached,
               summary.message);
    fmt::print(stderr, "nhdyn: no results written ({} is left as it was)\n", csv_path.string());
    return 1;
  }
  writer.commit();
  plot_probe.reset();
  if (!args.plot.empty()) {
    PlotRequest request;
    request.title = fmt::format("{}: {}, {}", model.name, method_name(options.formulation.method),
                                integrator_name(options.integrator.kind));
    request.csv = csv_path;
    request.coordinates = columns.coordinates;
    request.reactions = columns.reactions;
    request.residuals = columns.residuals;
    if (model.path)
      request.path = std::make_pair(model.coordinates[static_cast<std::size_t>(model.path->x)],
                                    model.coordinates[static_cast<std::size_t>(model.path->y)]);
    if (!columns.energy.empty()) request.energy = columns.energy;
    write_plot(request, args.plot);
  }

  if (!args.quiet) {
    const bool adaptive = options.integrator.kind != IntegratorKind::rk4;
    fmt::print("nhdyn simulate {}: method {} (D: {}), integrator {}{}\n", model.name,
               method_name(options.formulation.method), complement_name(options.formulation.complement),
               integrator_name(options.integrator.kind),
               adaptive ? fmt::format(" (rtol {:g}, atol {:g})", options.integrator.rtol, options.integrator.atol) : "");
    fmt::print("  t = {:g} .. {:g} s, {} rows -> {}\n", model.t0, options.t_end, summary.outputs, csv_path.string());
    fmt::print("  steps {} (rejected {}), right-hand-side evaluations {}, wall time {:.3g} ms\n",
               summary.stats.steps, summary.stats.rejected_steps, summary.stats.rhs_evaluations,
               summary.wall_time * 1e3);
    fmt::print("  max residual: position {}, velocity {}, acceleration {}\n",
               format_residual(summary.max_position_residual, model.position_constraints() > 0),
               format_residual(summary.max_velocity_residual, model.velocity_constraints() > 0),
               format_residual(summary.max_acceleration_residual, model.s() > 0));
    if (summary.has_energy)
      fmt::print("  energy drift: {:.3g} (E0 = {:.10g})\n", summary.energy_drift, summary.energy_initial);
    if (!args.plot.empty()) fmt::print("  plot -> {}\n", args.plot);
  }
  return 0;
}

}  // namespace

std::function<int()> add_simulate_command(CLI::App& app) {
  auto args = std::make_shared<SimulateArgs>();
  CLI::App* cmd = app.add_subcommand("simulate", "Simulate a model and write its results as CSV");
  cmd->add_option("MODEL", args->model, "A built-in model (see `nhdyn list`)")->required();
  cmd->add_option("--t-end", args->t_end, "End time [s] (default: the model's)");
  cmd->add_option("--output-step", args->output_step, "Time between output rows [s] (default: the model's)");
  cmd->add_option("--method", args->method, "Formulation: sanh | lagrange | udwadia-kalaba | nullspace")
      ->capture_default_str();
  cmd->add_option("--complement", args->complement, "Where D comes from (sanh, nullspace): qr | partition | analytic")
      ->capture_default_str();
  cmd->add_option("--integrator", args->integrator, "rk4 | dopri5 | cvode-bdf | cvode-adams")->capture_default_str();
  cmd->add_option("--rtol", args->rtol, "Relative tolerance (adaptive integrators)")->capture_default_str();
  cmd->add_option("--atol", args->atol, "Absolute tolerance (adaptive integrators)")->capture_default_str();
  cmd->add_option("--step", args->step, "rk4: step size [s] (default output step / 10); adaptive: first step");
  cmd->add_option("-o,--output", args->output, "CSV file to write (default results/MODEL.csv)");
  cmd->add_option("--plot", args->plot, "PNG file to draw with gnuplot");
  cmd->add_flag("-q,--quiet", args->quiet, "Print no summary");
  return [args] { return run_simulate(*args); };
}

}  // namespace nhdyn::cli
