// Cost of building a model from its multibody description (symbolic/multibody.hpp, docs/multibody.md):
//   multibody/<example>/load               the model file read: bodies -> T, V, wheel constraints
//   multibody/<example>/derive_and_compile derive() then compile_model() of the loaded Spec
//   multibody/whipple_bicycle/simulate_10s  simulate() of the compiled model from its initial
//                                          state (upright at 5 m/s, a roll-rate kick of 0.5 rad/s),
//                                          10 s with dopri5, cvode-adams or cvode-bdf at rtol 1e-10, atol 1e-12, sanh with D
//                                          from QR, an empty observer
//                                          (issue 6 asks for under 20 ms); outputs every
//                                          0.01 s (1000, the default) or 0.1 s (100)
// for examples/rolling_disk_bodies.toml (n = 5, s = 2) and examples/whipple_bicycle.toml (n = 8,
// s = 5; issue 6 asks for derivation + compilation under 1 s). Results: docs/performance.md.
#include <benchmark/benchmark.h>

#include <algorithm>
#include <filesystem>
#include <string>

#include "nhdyn/analysis/simulation.hpp"
#include "nhdyn/frontend/model_file.hpp"
#include "nhdyn/symbolic/compile.hpp"
#include "nhdyn/symbolic/derivation.hpp"

namespace nhdyn::bench {
namespace {

std::filesystem::path example(const std::string& file) {
  // Not __FILE__: a compiler cache may make it relative to the build folder.
  return std::filesystem::path(NHDYN_SOURCE_DIR) / "examples" / file;
}

void load(benchmark::State& state, const std::string& file) {
  for (auto _ : state) benchmark::DoNotOptimize(load_model_file(example(file)));
}

void derive_and_compile(benchmark::State& state, const std::string& file) {
  const symbolic::Spec spec = load_model_file(example(file));
  for (auto _ : state) benchmark::DoNotOptimize(symbolic::compile_model(spec, symbolic::derive(spec)));
}

void simulate_bicycle(benchmark::State& state, IntegratorKind integrator, double output_step) {
  symbolic::Spec spec = load_model_file(example("whipple_bicycle.toml"));
  const auto phi = std::find(spec.coordinates.begin(), spec.coordinates.end(), "phi") - spec.coordinates.begin();
  spec.v0[static_cast<std::size_t>(phi)] = GiNaC::numeric(1, 2);
  const Model model = symbolic::compile_model(spec);
  SimulationOptions options;
  options.t_end = 10.0;
  options.output_step = output_step;
  options.formulation = {Formulation::sanh, Complement::qr};
  options.integrator.kind = integrator;
  options.integrator.rtol = 1e-10;
  options.integrator.atol = 1e-12;
  long steps = 0, evaluations = 0;
  for (auto _ : state) {
    const SimulationSummary summary = simulate(model, options, [](const Data&) {});
    if (summary.status != Status::ok) {
      state.SkipWithError("the bicycle run failed");
      return;
    }
    steps = summary.stats.steps;
    evaluations = summary.stats.rhs_evaluations;
  }
  state.counters["steps"] = static_cast<double>(steps);
  state.counters["rhs"] = static_cast<double>(evaluations);
}

BENCHMARK_CAPTURE(load, rolling_disk_bodies, std::string("rolling_disk_bodies.toml"))
    ->Name("multibody/rolling_disk_bodies/load")->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(derive_and_compile, rolling_disk_bodies, std::string("rolling_disk_bodies.toml"))
    ->Name("multibody/rolling_disk_bodies/derive_and_compile")->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(load, whipple_bicycle, std::string("whipple_bicycle.toml"))
    ->Name("multibody/whipple_bicycle/load")->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(derive_and_compile, whipple_bicycle, std::string("whipple_bicycle.toml"))
    ->Name("multibody/whipple_bicycle/derive_and_compile")->Unit(benchmark::kMillisecond)->Iterations(3);
BENCHMARK_CAPTURE(simulate_bicycle, dopri5, IntegratorKind::dopri5, 0.01)
    ->Name("multibody/whipple_bicycle/simulate_10s/dopri5/outputs_1000")->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(simulate_bicycle, cvode_adams, IntegratorKind::cvode_adams, 0.01)
    ->Name("multibody/whipple_bicycle/simulate_10s/cvode-adams/outputs_1000")->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(simulate_bicycle, cvode_bdf, IntegratorKind::cvode_bdf, 0.01)
    ->Name("multibody/whipple_bicycle/simulate_10s/cvode-bdf/outputs_1000")->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(simulate_bicycle, dopri5_100, IntegratorKind::dopri5, 0.1)
    ->Name("multibody/whipple_bicycle/simulate_10s/dopri5/outputs_100")->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(simulate_bicycle, cvode_adams_100, IntegratorKind::cvode_adams, 0.1)
    ->Name("multibody/whipple_bicycle/simulate_10s/cvode-adams/outputs_100")->Unit(benchmark::kMillisecond);

}  // namespace
}  // namespace nhdyn::bench
