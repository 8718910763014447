// Cost of compute_complement alone (D from a QR of b^T, from coordinate partitioning, or the
// model's analytic D) at the fixed state of bench_cases.hpp, terms already computed:
//   complement/<model>/<complement>
// It is the first step of sanh and nullspace; subtracted from acceleration_only/... it leaves the
// stacking, the LU factorization and the solve. Results: docs/performance.md.
#include <benchmark/benchmark.h>

#include <string>

#include "bench_cases.hpp"
#include "nhdyn/formulation/complement.hpp"
#include "nhdyn/model/data.hpp"
#include "nhdyn/model/terms.hpp"

namespace nhdyn::bench {
namespace {

void bench_complement(benchmark::State& state, ModelId id, Complement complement) {
  const Model model = make_bench_model(id);
  Data data = make_data(model);
  const State x = bench_state(id);
  if (compute_terms(model, data, 0.0, x.q.data(), x.v.data()) != Status::ok ||
      compute_complement(model, data, complement) != Status::ok) {
    state.SkipWithError("compute_complement failed at the benchmark state");
    return;
  }
  for (auto _ : state) {
    Status status = compute_complement(model, data, complement);
    benchmark::DoNotOptimize(status);
    benchmark::DoNotOptimize(data.D);
    benchmark::ClobberMemory();
  }
}

const bool registered = [] {
  for (ModelId id : all_models())
    for (Complement complement : {Complement::qr, Complement::partition, Complement::analytic})
      benchmark::RegisterBenchmark(
          ("complement/" + model_name(id) + "/" + std::string(complement_name(complement))).c_str(),
          bench_complement, id, complement);
  return true;
}();

}  // namespace
}  // namespace nhdyn::bench
