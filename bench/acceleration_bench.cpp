// Cost of one acceleration solve, for every formulation and choice of D on every built-in model,
// at the fixed state of bench_cases.hpp:
//   acceleration/<model>/<method>/<complement>       compute_dynamics = compute_terms + compute_acceleration
//   acceleration_only/<model>/<method>/<complement>  compute_acceleration alone (terms already computed)
// lagrange and udwadia-kalaba do not use D, so they run with qr only. Together with terms_bench.cpp
// (compute_terms alone) this separates the linear algebra of a formulation from the model's
// evaluation. Results: docs/performance.md.
#include <benchmark/benchmark.h>

#include <string>
#include <utility>
#include <vector>

#include "bench_cases.hpp"
#include "nhdyn/formulation/formulation.hpp"
#include "nhdyn/model/data.hpp"
#include "nhdyn/model/terms.hpp"

namespace nhdyn::bench {
namespace {

std::vector<FormulationOptions> all_formulations() {
  return {{Formulation::sanh, Complement::qr},
          {Formulation::sanh, Complement::partition},
          {Formulation::sanh, Complement::analytic},
          {Formulation::lagrange, Complement::qr},
          {Formulation::udwadia_kalaba, Complement::qr},
          {Formulation::nullspace, Complement::qr},
          {Formulation::nullspace, Complement::partition},
          {Formulation::nullspace, Complement::analytic}};
}

void bench_dynamics(benchmark::State& state, ModelId id, FormulationOptions options) {
  const Model model = make_bench_model(id);
  Data data = make_data(model);
  const State x = bench_state(id);
  if (compute_dynamics(model, data, options, 0.0, x.q.data(), x.v.data()) != Status::ok) {
    state.SkipWithError("compute_dynamics failed at the benchmark state");
    return;
  }
  for (auto _ : state) {
    Status status = compute_dynamics(model, data, options, 0.0, x.q.data(), x.v.data());
    benchmark::DoNotOptimize(status);
    benchmark::DoNotOptimize(data.qdd);
    benchmark::ClobberMemory();
  }
}

void bench_acceleration_only(benchmark::State& state, ModelId id, FormulationOptions options) {
  const Model model = make_bench_model(id);
  Data data = make_data(model);
  const State x = bench_state(id);
  if (compute_terms(model, data, 0.0, x.q.data(), x.v.data()) != Status::ok ||
      compute_acceleration(model, data, options) != Status::ok) {
    state.SkipWithError("compute_acceleration failed at the benchmark state");
    return;
  }
  // A successful compute_acceleration leaves Stage::acceleration, so the terms stay valid and
  // the kernel may be called again on the same state.
  for (auto _ : state) {
    Status status = compute_acceleration(model, data, options);
    benchmark::DoNotOptimize(status);
    benchmark::DoNotOptimize(data.qdd);
    benchmark::ClobberMemory();
  }
}

const bool registered = [] {
  for (ModelId id : all_models()) {
    for (const FormulationOptions& options : all_formulations()) {
      const std::string suffix = model_name(id) + "/" + std::string(formulation_name(options.method)) + "/" +
                                 std::string(complement_name(options.complement));
      benchmark::RegisterBenchmark(("acceleration/" + suffix).c_str(), bench_dynamics, id, options);
    }
  }
  for (ModelId id : all_models()) {
    for (const FormulationOptions& options : all_formulations()) {
      const std::string suffix = model_name(id) + "/" + std::string(formulation_name(options.method)) + "/" +
                                 std::string(complement_name(options.complement));
      benchmark::RegisterBenchmark(("acceleration_only/" + suffix).c_str(), bench_acceleration_only, id,
                                   options);
    }
  }
  return true;
}();

}  // namespace
}  // namespace nhdyn::bench
