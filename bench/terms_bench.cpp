// Cost of compute_terms alone (the model's evaluation: A, Q, G, b, b0 through the Evaluator, plus
// the copy of the state and the finiteness checks) at the fixed state of bench_cases.hpp:
//   terms/<model>
// Subtracted from acceleration/... (acceleration_bench.cpp) it leaves the formulation's own cost.
// Results: docs/performance.md.
#include <benchmark/benchmark.h>

#include "bench_cases.hpp"
#include "nhdyn/model/data.hpp"
#include "nhdyn/model/terms.hpp"

namespace nhdyn::bench {
namespace {

void bench_terms(benchmark::State& state, ModelId id) {
  const Model model = make_bench_model(id);
  Data data = make_data(model);
  const State x = bench_state(id);
  for (auto _ : state) {
    Status status = compute_terms(model, data, 0.0, x.q.data(), x.v.data());
    benchmark::DoNotOptimize(status);
    benchmark::DoNotOptimize(data.A);
    benchmark::ClobberMemory();
  }
}

const bool registered = [] {
  for (ModelId id : all_models()) benchmark::RegisterBenchmark(("terms/" + model_name(id)).c_str(), bench_terms, id);
  return true;
}();

}  // namespace
}  // namespace nhdyn::bench
