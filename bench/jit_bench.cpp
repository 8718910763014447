// The compiled evaluator (jit/compiled_evaluator.hpp) against the interpreter, on the Whipple
// bicycle (examples/whipple_bicycle.toml, n = 8, s = 5, a terms tape of about 3900 operations):
//   jit/whipple_bicycle/terms/<evaluator>        one Evaluator::terms call (A, Q, G, b, b0)
//   jit/whipple_bicycle/rhs/<evaluator>          one right-hand side: terms, then q'' by sanh with
//                                                D from QR (compute_dynamics)
//   jit/whipple_bicycle/simulate_10s/<evaluator> simulate() 10 s with dopri5 at rtol 1e-10, atol
//                                                1e-12 from upright at 5 m/s with a roll-rate kick of
//                                                0.5 rad/s, 1000 outputs (as multibody_bench.cpp)
//   jit/whipple_bicycle/compile                  make_compiled with an empty cache: the system
//                                                compiler's time (the C++ source, the compile, dlopen)
//   jit/whipple_bicycle/load_cached              make_compiled with the object in the cache
// The cache is a directory of its own under the system's temporary directory. Results:
// docs/design.md ("Compiled evaluator").
#include <benchmark/benchmark.h>
#include <unistd.h>

#include <algorithm>
#include <filesystem>
#include <string>

#include "nhdyn/analysis/simulation.hpp"
#include "nhdyn/formulation/formulation.hpp"
#include "nhdyn/frontend/load_model.hpp"
#include "nhdyn/jit/compiled_evaluator.hpp"
#include "nhdyn/model/data.hpp"
#include "nhdyn/model/parameters.hpp"

namespace nhdyn::bench {
namespace {

namespace fs = std::filesystem;

fs::path cache() {
  // Removed when the program ends.
  struct Directory {
    fs::path path = fs::temp_directory_path() / ("nhdyn-jit-bench-" + std::to_string(::getpid()));
    ~Directory() {
      std::error_code ec;
      fs::remove_all(path, ec);
    }
  };
  static const Directory directory;
  return directory.path;
}

const Model& bicycle(bool compiled) {
  static const Model interpreted = [] {
    Model m = load_model((fs::path(NHDYN_SOURCE_DIR) / "examples" / "whipple_bicycle.toml").string());
    return m;
  }();
  static const Model jit = [] {
    jit::JitOptions options;
    options.cache_dir = cache().string();
    return jit::make_compiled(interpreted, options);
  }();
  return compiled ? jit : interpreted;
}

void terms(benchmark::State& state, bool compiled) {
  const Model& model = bicycle(compiled);
  Data data = make_data(model);
  std::vector<double> scratch(model.evaluator->scratch_size());
  const int n = model.n(), s = model.s();
  std::vector<double> out(static_cast<std::size_t>(n * n + 2 * n + s * n + s));
  double* p = out.data();
  const TermsOut to{p, p + n * n, p + n * n + n, p + n * n + 2 * n, p + n * n + 2 * n + s * n};
  for (auto _ : state) {
    model.evaluator->terms(0.0, model.q0.data(), model.v0.data(), scratch.data(), to);
    benchmark::DoNotOptimize(out.data());
    benchmark::ClobberMemory();
  }
}

void rhs(benchmark::State& state, bool compiled) {
  const Model& model = bicycle(compiled);
  Data data = make_data(model);
  FormulationOptions options;
  for (auto _ : state) {
    if (compute_dynamics(model, data, options, 0.0, model.q0.data(), model.v0.data()) != Status::ok) {
      state.SkipWithError("compute_dynamics failed");
      return;
    }
    benchmark::DoNotOptimize(data.qdd.data());
  }
}

void simulate_10s(benchmark::State& state, bool compiled) {
  Model model = bicycle(compiled);
  const auto phi = std::find(model.coordinates.begin(), model.coordinates.end(), "phi") - model.coordinates.begin();
  model.v0[phi] = 0.5;
  SimulationOptions options;
  options.t_end = 10.0;
  options.output_step = 0.01;
  options.formulation = {Formulation::sanh, Complement::qr};
  options.integrator.kind = IntegratorKind::dopri5;
  options.integrator.rtol = 1e-10;
  options.integrator.atol = 1e-12;
  long evaluations = 0;
  for (auto _ : state) {
    const SimulationSummary summary = simulate(model, options, [](const Data&) {});
    if (summary.status != Status::ok) {
      state.SkipWithError("the bicycle run failed");
      return;
    }
    evaluations = summary.stats.rhs_evaluations;
  }
  state.counters["rhs"] = static_cast<double>(evaluations);
  state.counters["per_rhs_us"] = benchmark::Counter(static_cast<double>(evaluations) * 1e-6,
                                                    benchmark::Counter::kIsIterationInvariantRate |
                                                        benchmark::Counter::kInvert);
}

void compile(benchmark::State& state) {
  const Model& model = bicycle(false);
  jit::JitOptions options;
  options.cache_dir = (cache() / "compile").string();
  for (auto _ : state) {
    fs::remove_all(options.cache_dir);
    benchmark::DoNotOptimize(jit::make_compiled(model, options));
  }
  fs::remove_all(options.cache_dir);
}

void load_cached(benchmark::State& state) {
  const Model& model = bicycle(true);  // compiles into cache() once
  jit::JitOptions options;
  options.cache_dir = cache().string();
  for (auto _ : state) benchmark::DoNotOptimize(jit::make_compiled(bicycle(false), options));
  (void)model;
}

BENCHMARK_CAPTURE(terms, interpreted, false)->Name("jit/whipple_bicycle/terms/interpreted");
BENCHMARK_CAPTURE(terms, compiled, true)->Name("jit/whipple_bicycle/terms/compiled");
BENCHMARK_CAPTURE(rhs, interpreted, false)->Name("jit/whipple_bicycle/rhs/interpreted");
BENCHMARK_CAPTURE(rhs, compiled, true)->Name("jit/whipple_bicycle/rhs/compiled");
BENCHMARK_CAPTURE(simulate_10s, interpreted, false)
    ->Name("jit/whipple_bicycle/simulate_10s/interpreted")->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(simulate_10s, compiled, true)
    ->Name("jit/whipple_bicycle/simulate_10s/compiled")->Unit(benchmark::kMillisecond);
BENCHMARK(compile)->Name("jit/whipple_bicycle/compile")->Unit(benchmark::kMillisecond)->Iterations(2);
BENCHMARK(load_cached)->Name("jit/whipple_bicycle/load_cached")->Unit(benchmark::kMillisecond);

}  // namespace
}  // namespace nhdyn::bench
