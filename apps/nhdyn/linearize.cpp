// `nhdyn linearize MODEL`: the linearization about the steady motion the model starts on
// (analysis/linearization.hpp, docs/linearization.md) — the state chosen, the state matrix and its
// eigenvalues on stdout, the eigenvalues optionally as CSV.
#include <fmt/format.h>

#include <memory>
#include <string>
#include <utility>
#include <vector>

#include "commands.hpp"
#include "nhdyn/analysis/linearization.hpp"
#include "nhdyn/core/error.hpp"
#include "nhdyn/core/join.hpp"
#include "nhdyn/core/shown_text.hpp"
#include "nhdyn/frontend/load_model.hpp"
#include "nhdyn/frontend/provenance.hpp"
#include "nhdyn/io/atomic_file.hpp"
#include "run_files.hpp"

namespace nhdyn::cli {
namespace {

struct LinearizeArgs {
  std::string model;
  std::vector<std::string> sets;
  std::vector<std::string> cyclic, independent, speeds;
  double tolerance = 1e-9;
  std::string output;
};

std::string join_names(const std::vector<std::string>& names) {
  std::string out;
  for (const std::string& s : names) out += (out.empty() ? "" : ", ") + s;
  return out.empty() ? "(none)" : out;
}

int run_linearize(const LinearizeArgs& args) {
  RunFiles files(args.model);
  const ModelSource source = read_model_source(args.model);
  const LoadedModel resolved = load_model_described(source, parse_parameter_sets(args.sets));
  const Model& model = resolved.model;
  files.output(args.output, "-o", Folder::make);
  files.check();
  AtomicFile* file = args.output.empty() ? nullptr : &files.open(args.output);  // writable: checked before any work
  LinearizationOptions options;
  options.cyclic = args.cyclic;
  options.independent = args.independent;
  options.speeds = args.speeds;
  options.steady_tolerance = args.tolerance;
  const Linearization l = calc_linearization(model, options);

  if (file) {
    std::vector<std::pair<std::string, std::string>> given;
    if (!args.cyclic.empty()) given.emplace_back("cyclic", join(args.cyclic, ","));
    if (!args.independent.empty()) given.emplace_back("independent", join(args.independent, ","));
    if (!args.speeds.empty()) given.emplace_back("speeds", join(args.speeds, ","));
    given.emplace_back("tolerance", fmt::format("{}", args.tolerance));
    std::string text = format_provenance(make_command_provenance(model, source, "linearize", std::move(given)));
    text += "index,real,imag\n";
    for (std::size_t i = 0; i < l.eigenvalues.size(); ++i)
      text += fmt::format("{},{:.17g},{:.17g}\n", i + 1, l.eigenvalues[i].real(), l.eigenvalues[i].imag());
    file->write(text);
    files.commit();
  }

  fmt::print("nhdyn linearize {}: about the steady motion at t0 = {:g}\n", model.name, model.t0);
  std::string state;
  for (int i = 0; i < model.n(); ++i)
    state += fmt::format("{}{} = {:.10g}, {}' = {:.10g}", i == 0 ? "" : "; ", model.coordinates[static_cast<std::size_t>(i)],
                         model.q0(i), model.coordinates[static_cast<std::size_t>(i)], model.v0(i));
  fmt::print("state: {}\n", state);
  fmt::print("cyclic coordinates: {}\n", join_names(l.cyclic));
  fmt::print("independent coordinates: {}; independent speeds: {}\n", join_names(l.independent),
             join_names(l.speeds.empty() ? l.speeds : [&] {
               std::vector<std::string> primed;
               for (const std::string& s : l.speeds) primed.push_back(s + "'");
               return primed;
             }()));
  fmt::print("derivatives: {}\n", derivative_method_name(l.derivatives));
  fmt::print("steady-motion residual: {:.3e} (tolerance {:g})\n", l.steady_residual, args.tolerance);
  const std::size_t k = l.state.size();
  fmt::print("state matrix S ({} x {}), d/dt x = S x with x = ({}):\n", k, k, join_names(l.state));
  std::size_t width = 8;
  for (const std::string& s : l.state) width = std::max(width, s.size());
  const std::size_t label = width + 5;  // "d/dt " and the longest name
  fmt::print("{:<{}}", "", label);
  for (const std::string& s : l.state) fmt::print(" {:>20}", s);
  fmt::print("\n");
  for (std::size_t i = 0; i < k; ++i) {
    fmt::print("{:<{}}", "d/dt " + l.state[i], label);
    for (std::size_t j = 0; j < k; ++j)
      fmt::print(" {:>20.13g}", l.state_matrix(static_cast<Eigen::Index>(i), static_cast<Eigen::Index>(j)));
    fmt::print("\n");
  }
  fmt::print("eigenvalues (by decreasing real part):\n");
  fmt::print("{:>4} {:>24} {:>24}\n", "#", "real", "imag");
  for (std::size_t i = 0; i < l.eigenvalues.size(); ++i)
    fmt::print("{:>4} {:>24.16g} {:>24.16g}\n", i + 1, l.eigenvalues[i].real(), l.eigenvalues[i].imag());
  if (!args.output.empty()) fmt::print("eigenvalues -> {}\n", shown_text(args.output));
  return 0;
}

}  // namespace

std::function<int()> add_linearize_command(CLI::App& app) {
  auto args = std::make_shared<LinearizeArgs>();
  CLI::App* cmd = app.add_subcommand("linearize", "Linearize about the steady motion the model starts on: state "
                                                  "matrix and eigenvalues");
  cmd->add_option("MODEL", args->model, "A model file (.toml) or a built-in model (see `nhdyn list`)")->required();
  cmd->add_option("--set", args->sets, "Set a parameter, NAME=EXPR: a number or an expression in numbers, pi, e and the other parameters (repeatable)");
  cmd->add_option("--cyclic", args->cyclic, "Coordinates to treat as cyclic besides those found, comma-separated")
      ->delimiter(',');
  cmd->add_option("--independent", args->independent, "Independent coordinates of the state, comma-separated "
                                                       "(default: chosen by pivoted QR)")
      ->delimiter(',');
  cmd->add_option("--speeds", args->speeds, "Coordinates whose velocities are the independent speeds, "
                                            "comma-separated (default: chosen by pivoted QR)")
      ->delimiter(',');
  cmd->add_option("--tolerance", args->tolerance, "Tolerance of the steady-motion test (scaled)")->capture_default_str();
  cmd->add_option("-o,--output", args->output, "CSV of the eigenvalues (index,real,imag)");
  return [args] { return run_linearize(*args); };
}

}  // namespace nhdyn::cli
