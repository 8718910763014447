// DOP853 against dopri5 (integrators/detail/explicit_rk.hpp) on whole simulations, at the tolerances
// where an 8th-order pair should pay:
//   integrators/<model>/<integrator>/rtol_<r>/outputs_<k>
// simulate() of <model> for 10 s, sanh with D from QR, atol = rtol / 100, k outputs (every
// 0.01 s: most steps hold an output, so DOP853 pays 3 extra stages in each; every 1 s: almost
// none do), an empty observer. Models: the built-in sled (bench_cases.hpp's parameters, its
// default initial state) and examples/whipple_bicycle.toml (upright at 5 m/s with a roll-rate
// kick of 0.5 rad/s, as in multibody_bench.cpp). Counters: accepted steps, rhs evaluations, and
// error = the largest |q - q_ref| at t = 10 s against a dop853 run at rtol 1e-13, atol 1e-15
// (so the costs compare at the accuracy each run actually reaches). Results: docs/performance.md.
#include <benchmark/benchmark.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <string>

#include "bench_cases.hpp"
#include "nhdyn/analysis/simulation.hpp"
#include "nhdyn/frontend/model_file.hpp"
#include "nhdyn/symbolic/compile.hpp"

namespace nhdyn::bench {
namespace {

enum class Case { sled, bicycle };

const Model& case_model(Case c) {
  static const Model sled = make_bench_model(ModelId::sled);
  static const Model bicycle = [] {
    symbolic::Spec spec = load_model_file(std::filesystem::path(NHDYN_SOURCE_DIR) / "examples" /
                                          "whipple_bicycle.toml");
    const auto phi =
        std::find(spec.coordinates.begin(), spec.coordinates.end(), "phi") - spec.coordinates.begin();
    spec.v0[static_cast<std::size_t>(phi)] = GiNaC::numeric(1, 2);
    return symbolic::compile_model(spec);
  }();
  return c == Case::sled ? sled : bicycle;
}

SimulationOptions options_for(IntegratorKind kind, double rtol, double output_step) {
  SimulationOptions options;
  options.t_end = 10.0;
  options.output_step = output_step;
  options.formulation = {Formulation::sanh, Complement::qr};
  options.integrator.kind = kind;
  options.integrator.rtol = rtol;
  options.integrator.atol = rtol / 100.0;
  return options;
}

// q at t_end of one run.
Vector final_q(const Model& model, const SimulationOptions& options, SimulationSummary& summary) {
  Vector q;
  summary = simulate(model, options, [&](const Data& data) { q = data.q; });
  return q;
}

void run(benchmark::State& state, Case c, IntegratorKind kind, double rtol, double output_step) {
  const Model& model = case_model(c);
  SimulationSummary reference_summary;
  const Vector q_ref =
      final_q(model, options_for(IntegratorKind::dop853, 1e-13, output_step), reference_summary);
  if (reference_summary.status != Status::ok) {
    state.SkipWithError("the reference run failed");
    return;
  }
  const SimulationOptions options = options_for(kind, rtol, output_step);
  SimulationSummary summary;
  Vector q;
  for (auto _ : state) {
    q = final_q(model, options, summary);
    if (summary.status != Status::ok) {
      state.SkipWithError("the run failed");
      return;
    }
  }
  state.counters["steps"] = static_cast<double>(summary.stats.steps);
  state.counters["rhs"] = static_cast<double>(summary.stats.rhs_evaluations);
  state.counters["error"] = (q - q_ref).cwiseAbs().maxCoeff();
}

void register_all() {
  for (Case c : {Case::sled, Case::bicycle}) {
    for (double rtol : {1e-8, 1e-10, 1e-12}) {
      for (double output_step : {0.01, 1.0}) {
        for (IntegratorKind kind : {IntegratorKind::dopri5, IntegratorKind::dop853}) {
          const std::string name = std::string("integrators/") +
                                   (c == Case::sled ? "sled" : "whipple_bicycle") + "/" +
                                   std::string(integrator_name(kind)) + "/rtol_" +
                                   (rtol == 1e-8 ? "1e-8" : rtol == 1e-10 ? "1e-10" : "1e-12") +
                                   "/outputs_" + (output_step == 0.01 ? "1000" : "10");
          benchmark::RegisterBenchmark(name.c_str(), [=](benchmark::State& state) {
            run(state, c, kind, rtol, output_step);
          })->Unit(benchmark::kMillisecond);
        }
      }
    }
  }
}

const int registered = (register_all(), 0);

}  // namespace
}  // namespace nhdyn::bench
