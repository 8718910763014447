// `nhdyn sweep MODEL --param P --from A --to B --steps N --eigenvalues`: the eigenvalues of the
// linearization about the model's steady motion against one parameter (analysis/sweep.hpp) as
// CSV, the values where a real part crosses zero (found by bisection) on stdout and as a second
// CSV, and optionally the classical plot of real and imaginary parts against the parameter.
#include <fmt/format.h>

#include <unistd.h>

#include <algorithm>
#include <filesystem>
#include <memory>
#include <string>
#include <utility>
#include <vector>

#include "commands.hpp"
#include "nhdyn/analysis/sweep.hpp"
#include "nhdyn/core/error.hpp"
#include "nhdyn/core/join.hpp"
#include "nhdyn/core/shown_text.hpp"
#include "nhdyn/frontend/load_model.hpp"
#include "nhdyn/frontend/provenance.hpp"
#include "nhdyn/io/atomic_file.hpp"
#include "nhdyn/io/xy_plot.hpp"
#include "nhdyn/model/parameters.hpp"
#include "run_files.hpp"

namespace nhdyn::cli {
namespace {

struct SweepArgs {
  std::string model;
  std::string param;
  double from = 0.0;
  double to = 0.0;
  int steps = 101;
  bool eigenvalues = false;
  std::vector<std::string> sets;
  std::vector<std::string> cyclic, independent, speeds;
  double tolerance = 1e-9;
  std::string output;
  std::string plot;
  bool quiet = false;
};

// --param must name one of the model's parameters.
void check_swept_parameter(const Model& base, const SweepArgs& args) {
  std::string names;
  bool known = false;
  for (const Parameter& p : base.parameters) {
    names += (names.empty() ? "" : ", ") + p.name;
    known = known || p.name == args.param;
  }
  if (!known)
    throw InputError(fmt::format("--param {}: model '{}' ({}) has no parameter '{}'; its parameters are: {}",
                                 args.param, base.name, args.model, args.param, names.empty() ? "(none)" : names));
}

// The eigenvalue table and the crossings, each after the same provenance header.
void write_sweep_tables(const Sweep& sweep, const Model& base, const ModelSource& source, const SweepArgs& args,
                        AtomicFile& table, AtomicFile& crossings_file) {
  const std::size_t k = sweep.state.size();
  std::vector<std::string> columns{args.param};
  for (std::size_t i = 1; i <= k; ++i) {
    columns.push_back(fmt::format("re_{}", i));
    columns.push_back(fmt::format("im_{}", i));
  }
  // Both files say what made them (io/provenance.hpp): the model as loaded and the sweep's options.
  std::vector<std::pair<std::string, std::string>> given{{"param", args.param},
                                                         {"from", fmt::format("{}", args.from)},
                                                         {"to", fmt::format("{}", args.to)},
                                                         {"steps", fmt::format("{}", args.steps)}};
  if (!args.cyclic.empty()) given.emplace_back("cyclic", join(args.cyclic, ","));
  if (!args.independent.empty()) given.emplace_back("independent", join(args.independent, ","));
  if (!args.speeds.empty()) given.emplace_back("speeds", join(args.speeds, ","));
  given.emplace_back("tolerance", fmt::format("{}", args.tolerance));
  const std::string provenance = format_provenance(make_command_provenance(base, source, "sweep", std::move(given)));
  std::string text = provenance;
  for (std::size_t c = 0; c < columns.size(); ++c) text += (c ? "," : "") + columns[c];
  text += "\n";
  for (const SweepPoint& p : sweep.points) {
    text += fmt::format("{:.17g}", p.value);
    for (const std::complex<double>& e : p.eigenvalues) text += fmt::format(",{:.17g},{:.17g}", e.real(), e.imag());
    text += "\n";
  }
  table.write(text);
  std::string ctext = provenance + "parameter,value,kind,frequency,unstable_before,unstable_after,bracket\n";
  for (const StabilityCrossing& c : sweep.crossings)
    ctext += fmt::format("{},{:.17g},{},{:.17g},{},{},{:.3g}\n", args.param, c.value,
                         c.oscillatory ? "complex-pair" : "real", c.frequency, c.unstable_before, c.unstable_after,
                         c.bracket);
  crossings_file.write(ctext);
}

// --plot: the real parts and the |imaginary parts| each sorted at every value: the k-th largest of
// continuous functions is continuous, so the curves have no jumps where the CSV's order (by real
// part) swaps the imaginary parts. Its data go to a scratch file of the run's (run_files.hpp).
void plot_sweep(const Sweep& sweep, const Model& base, const SweepArgs& args, RunFiles& files) {
  const std::size_t k = sweep.state.size();
  std::string plot_text = args.param;
  for (std::size_t i = 1; i <= k; ++i) plot_text += fmt::format(",re_{}", i);
  for (std::size_t i = 1; i <= k; ++i) plot_text += fmt::format(",absim_{}", i);
  plot_text += "\n";
  for (const SweepPoint& p : sweep.points) {
    std::vector<double> re, im;
    for (const std::complex<double>& e : p.eigenvalues) {
      re.push_back(e.real());
      im.push_back(std::abs(e.imag()));
    }
    std::sort(re.rbegin(), re.rend());
    std::sort(im.rbegin(), im.rend());
    plot_text += fmt::format("{:.17g}", p.value);
    for (double x : re) plot_text += fmt::format(",{:.17g}", x);
    for (double x : im) plot_text += fmt::format(",{:.17g}", x);
    plot_text += "\n";
  }
  XyPlotRequest request;
  request.title = fmt::format("{}: eigenvalues of the linearization against {}", base.name, args.param);
  request.csv = files.write_scratch(
      fmt::format(".nhdyn-sweep-{}-{}.csv", ::getpid(), std::filesystem::path(args.plot).stem().string()), plot_text);
  request.x = args.param;
  for (std::size_t i = 1; i <= k; ++i) {
    request.y.push_back(fmt::format("re_{}", i));
    request.titles.push_back(fmt::format("Re, {}. largest", i));
  }
  for (std::size_t i = 1; i <= k; ++i) {
    request.y.push_back(fmt::format("absim_{}", i));
    request.titles.push_back(fmt::format("|Im|, {}. largest", i));
  }
  request.x_label = args.param;
  request.y_label = "eigenvalues [1/s]: real parts and |imaginary parts|";
  request.log_x = false;
  request.log_y = false;
  write_xy_plot(request, args.plot);
}

// The summary on standard output: the range, each crossing, and where the files went.
void print_sweep(const Sweep& sweep, const Model& base, const SweepArgs& args, const std::filesystem::path& table_path,
                 const std::filesystem::path& crossings_path) {
  std::string state;
  for (const std::string& s : sweep.state) state += (state.empty() ? "" : ", ") + s;
  fmt::print("nhdyn sweep {}: eigenvalues of the linearization for {} = {:g} .. {:g} ({} points), state ({})\n",
             base.name, args.param, args.from, args.to, args.steps, state);
  if (sweep.crossings.empty())
    fmt::print("no real part crosses zero in the range\n");
  int undecided = 0;
  for (const SweepPoint& p : sweep.points) undecided = std::max(undecided, p.undecided);
  if (undecided > 0)
    fmt::print("undecided: up to {} eigenvalues per value have a real part within their round-off uncertainty "
                "(zero, on the imaginary axis, or a multiple eigenvalue split by round-off); they are never "
                "counted unstable\n",
                undecided);
  for (const StabilityCrossing& c : sweep.crossings)
    fmt::print("crossing: {} = {:.15g}  {} ({}), unstable eigenvalues {} -> {}\n", args.param, c.value,
               c.oscillatory ? "a complex pair crosses the imaginary axis" : "a real eigenvalue crosses zero",
               c.oscillatory ? fmt::format("frequency {:.6g} rad/s", c.frequency) : std::string("divergence"),
               c.unstable_before, c.unstable_after);
  fmt::print("eigenvalues -> {}\ncrossings -> {}\n", shown_text(table_path.string()), shown_text(crossings_path.string()));
  if (!args.plot.empty()) fmt::print("plot -> {}\n", shown_text(args.plot));
}

int run_sweep(const SweepArgs& args) {
  RunFiles files(args.model);
  SweepOptions options;
  options.parameter = args.param;
  options.from = args.from;
  options.to = args.to;
  options.steps = args.steps;
  options.linearization.cyclic = args.cyclic;
  options.linearization.independent = args.independent;
  options.linearization.speeds = args.speeds;
  options.linearization.steady_tolerance = args.tolerance;
  check_sweep_options(options);
  // Compiled once: each grid point and bisection step only sets the parameter (parameters as
  // data, model/parameters.hpp), which re-binds the evaluator without symbolic work.
  const ModelSource source = read_model_source(args.model);
  const Model base = load_model_described(source, parse_parameter_sets(args.sets)).model;
  check_swept_parameter(base, args);
  const ModelAtValue model_at = make_model_at_value(base, args.param);

  // The first point linearized before any file is made: a model that is not steady, or a bad
  // --cyclic or --independent, is refused with nothing written.
  try {
    calc_linearization(model_at(args.from), options.linearization);
  } catch (const InputError& e) {
    throw InputError(fmt::format("at {} = {:g}: {}", args.param, args.from, e.what()));
  } catch (const ModelError& e) {
    throw ModelError(fmt::format("at {} = {:g}: {}", args.param, args.from, e.what()));
  }

  namespace fs = std::filesystem;
  const fs::path table_path =
      args.output.empty() ? fs::path("results") / (make_file_name(base.name + "-sweep-" + args.param) + ".csv") : fs::path(args.output);
  fs::path crossings_path = table_path;
  crossings_path.replace_filename(table_path.stem().string() + "-crossings.csv");
  files.output(table_path, "the eigenvalue CSV", Folder::make);
  files.output(crossings_path, "the crossings CSV");
  files.plot(args.plot);
  files.check();
  AtomicFile& table = files.open(table_path);  // both files can be written: checked before any work
  AtomicFile& crossings_file = files.open(crossings_path);

  const Sweep sweep = calc_eigenvalue_sweep(model_at, options);

  write_sweep_tables(sweep, base, source, args, table, crossings_file);
  files.commit();

  if (!args.plot.empty()) plot_sweep(sweep, base, args, files);
  if (!args.quiet) print_sweep(sweep, base, args, table_path, crossings_path);
  return 0;
}

}  // namespace

std::function<int()> add_sweep_command(CLI::App& app) {
  auto args = std::make_shared<SweepArgs>();
  CLI::App* cmd = app.add_subcommand("sweep", "Eigenvalues of the linearization against a parameter, with the "
                                              "values where the stability changes");
  cmd->add_option("MODEL", args->model, "A model file (.toml) or a built-in model")->required();
  cmd->add_option("--param", args->param, "The parameter to vary")->required();
  cmd->add_option("--from", args->from, "First value")->required();
  cmd->add_option("--to", args->to, "Last value")->required();
  cmd->add_option("--steps", args->steps, "Number of grid points, both ends included")->capture_default_str();
  cmd->add_flag("--eigenvalues", args->eigenvalues, "Sweep the eigenvalues (the default and, so far, only quantity)");
  cmd->add_option("--set", args->sets, "Override another parameter, NAME=EXPR (repeatable)");
  cmd->add_option("--cyclic", args->cyclic, "Coordinates to treat as cyclic besides those found, comma-separated")
      ->delimiter(',');
  cmd->add_option("--independent", args->independent, "Independent coordinates, comma-separated")->delimiter(',');
  cmd->add_option("--speeds", args->speeds, "Coordinates whose velocities are independent speeds, comma-separated")
      ->delimiter(',');
  cmd->add_option("--tolerance", args->tolerance, "Tolerance of the steady-motion test (scaled)")->capture_default_str();
  cmd->add_option("-o,--output", args->output, "Eigenvalue CSV (default results/MODEL-sweep-PARAM.csv); the "
                                               "crossings go next to it as ...-crossings.csv");
  cmd->add_option("--plot", args->plot, "PNG of the real and imaginary parts against the parameter");
  cmd->add_flag("-q,--quiet", args->quiet, "Print nothing");
  return [args] { return run_sweep(*args); };
}

}  // namespace nhdyn::cli
