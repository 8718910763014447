// Scaling with the size of the model (issue 5): the N-trailer chain of docs/gallery/chain.md
// (symbolic/chain.hpp), n = 3N coordinates, s = 3N - 2 constraints, k = 2.
//   chain/derive_and_compile/N         make_chain_spec, derive() and compile_model(): the symbolic
//                                      front end from nothing to a frozen Model (compiled sparse
//                                      from N = 22 on, TermsLayout::automatic)
//   chain/terms/dense/N                compute_terms into the dense Data (A and b written whole)
//   chain/terms/sparse/N               compute_terms on a sparse Data (only the nonzeros of A and b)
//   chain/solve/dense/<form>/N         one acceleration solve (compute_acceleration) with the
//                                      terms already computed: sanh/qr, sanh/partition, lagrange,
//                                      udwadia-kalaba, nullspace/qr
//   chain/solve/sparse/<form>/N        the same on the sparse path: sanh (block elimination on
//                                      the partition, formulation/sparse_sanh.hpp) and lagrange
//                                      (one LU of the KKT matrix), KLU both (model/sparse_lu.hpp)
//   chain/rhs/sparse/<form>/N          one whole right-hand side (compute_dynamics: terms and
//                                      solve) at the initial state, what an integrator pays per
//                                      stage; its growth from N = 100 to 1000 is the n^1.1 target
// Dense for N = 1 .. 100 (one dense solve at N = 1000 takes seconds and its Data a gigabyte);
// sparse for N = 1 .. 1000. Results, plot and fitted exponents: docs/performance.md.
#include <benchmark/benchmark.h>

#include <string>
#include <vector>

#include "nhdyn/formulation/formulation.hpp"
#include "nhdyn/model/data.hpp"
#include "nhdyn/model/terms.hpp"
#include "nhdyn/symbolic/chain.hpp"
#include "nhdyn/symbolic/compile.hpp"

namespace nhdyn::bench {
namespace {

Model make_chain_model(int bodies, symbolic::TermsLayout layout = symbolic::TermsLayout::automatic) {
  symbolic::ChainParameters p;
  p.bodies = bodies;
  return symbolic::compile_model(symbolic::make_chain_spec(p), symbolic::CompileOptions{layout});
}

void bench_derive_and_compile(benchmark::State& state) {
  const int bodies = static_cast<int>(state.range(0));
  for (auto _ : state) {
    Model model = make_chain_model(bodies);
    benchmark::DoNotOptimize(model.evaluator);
  }
  state.counters["n"] = 3.0 * bodies;
}

void bench_dense_terms(benchmark::State& state) {
  const Model model = make_chain_model(static_cast<int>(state.range(0)), symbolic::TermsLayout::dense);
  Data data = make_data(model, DataOptions{Path::dense, Formulation::sanh, false});
  for (auto _ : state) {
    compute_terms(model, data, model.t0, model.q0.data(), model.v0.data());
    benchmark::DoNotOptimize(data.A.data());
    benchmark::ClobberMemory();
  }
  state.counters["n"] = model.n();
}

void bench_sparse_terms(benchmark::State& state) {
  const Model model = make_chain_model(static_cast<int>(state.range(0)), symbolic::TermsLayout::sparse);
  Data data = make_data(model, DataOptions{Path::sparse, Formulation::sanh, false});
  for (auto _ : state) {
    compute_terms(model, data, model.t0, model.q0.data(), model.v0.data());
    benchmark::DoNotOptimize(data.A_sparse.valuePtr());
    benchmark::ClobberMemory();
  }
  state.counters["n"] = model.n();
}

void bench_dense_solve(benchmark::State& state, FormulationOptions options) {
  const Model model = make_chain_model(static_cast<int>(state.range(0)), symbolic::TermsLayout::dense);
  Data data = make_data(model, DataOptions{Path::dense, options.method, false});
  if (compute_dynamics(model, data, options, model.t0, model.q0.data(), model.v0.data()) != Status::ok) {
    state.SkipWithError("compute_dynamics failed at the chain's initial state");
    return;
  }
  for (auto _ : state) {
    Status status = compute_acceleration(model, data, options);
    benchmark::DoNotOptimize(status);
    benchmark::DoNotOptimize(data.qdd.data());
    benchmark::ClobberMemory();
  }
  state.counters["n"] = model.n();
}

void bench_sparse_solve(benchmark::State& state, FormulationOptions options) {
  const Model model = make_chain_model(static_cast<int>(state.range(0)), symbolic::TermsLayout::sparse);
  Data data = make_data(model, DataOptions{Path::sparse, options.method, false});
  if (compute_dynamics(model, data, options, model.t0, model.q0.data(), model.v0.data()) != Status::ok) {
    state.SkipWithError("the sparse solve failed at the chain's initial state");
    return;
  }
  for (auto _ : state) {
    Status status = compute_acceleration(model, data, options);
    benchmark::DoNotOptimize(status);
    benchmark::DoNotOptimize(data.qdd.data());
    benchmark::ClobberMemory();
  }
  state.counters["n"] = model.n();
}

void bench_sparse_rhs(benchmark::State& state, FormulationOptions options) {
  const Model model = make_chain_model(static_cast<int>(state.range(0)), symbolic::TermsLayout::sparse);
  Data data = make_data(model, DataOptions{Path::sparse, options.method, false});
  for (auto _ : state) {
    Status status = compute_dynamics(model, data, options, model.t0, model.q0.data(), model.v0.data());
    benchmark::DoNotOptimize(status);
    benchmark::DoNotOptimize(data.qdd.data());
    benchmark::ClobberMemory();
  }
  state.counters["n"] = model.n();
}

const std::vector<long> dense_sizes{1, 3, 10, 30, 100};
const std::vector<long> sparse_sizes{1, 3, 10, 30, 100, 300, 1000};

const bool registered = [] {
  auto* compile = benchmark::RegisterBenchmark("chain/derive_and_compile", bench_derive_and_compile);
  for (long n : sparse_sizes) compile->Arg(n);
  compile->Unit(benchmark::kMillisecond);
  auto* dense_terms = benchmark::RegisterBenchmark("chain/terms/dense", bench_dense_terms);
  for (long n : dense_sizes) dense_terms->Arg(n);
  dense_terms->Unit(benchmark::kMicrosecond);
  auto* sparse_terms = benchmark::RegisterBenchmark("chain/terms/sparse", bench_sparse_terms);
  for (long n : sparse_sizes) sparse_terms->Arg(n);
  sparse_terms->Unit(benchmark::kMicrosecond);

  const std::vector<std::pair<std::string, FormulationOptions>> dense{
      {"sanh/qr", {Formulation::sanh, Complement::qr}},
      {"sanh/partition", {Formulation::sanh, Complement::partition}},
      {"lagrange", {Formulation::lagrange, Complement::qr}},
      {"udwadia-kalaba", {Formulation::udwadia_kalaba, Complement::qr}},
      {"nullspace/qr", {Formulation::nullspace, Complement::qr}}};
  for (const auto& [name, options] : dense) {
    auto* b = benchmark::RegisterBenchmark(("chain/solve/dense/" + name).c_str(), bench_dense_solve, options);
    for (long n : dense_sizes) b->Arg(n);
    b->Unit(benchmark::kMicrosecond);
  }
  const std::vector<std::pair<std::string, FormulationOptions>> sparse{{"sanh", FormulationOptions(Formulation::sanh)},
                                                                       {"lagrange", FormulationOptions(Formulation::lagrange)}};
  for (const auto& [name, options] : sparse) {
    auto* b = benchmark::RegisterBenchmark(("chain/solve/sparse/" + name).c_str(), bench_sparse_solve, options);
    for (long n : sparse_sizes) b->Arg(n);
    b->Unit(benchmark::kMicrosecond);
    auto* r = benchmark::RegisterBenchmark(("chain/rhs/sparse/" + name).c_str(), bench_sparse_rhs, options);
    for (long n : sparse_sizes) r->Arg(n);
    r->Unit(benchmark::kMicrosecond);
  }
  return true;
}();

}  // namespace
}  // namespace nhdyn::bench
