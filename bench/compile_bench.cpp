// Cost of the terms of a compiled model (symbolic/compile.hpp) against the hand-written Evaluator
// of the same system, on the models and states of bench_cases.hpp:
//   compiled_terms/<model>/hand_written  Evaluator::terms of make_sled_model / make_appell_model
//   compiled_terms/<model>/interpreted   the same call on the TapeEvaluator that compile_model
//                                        makes from the hand-built Spec and Derivation
//                                        (tests/codegen/hand_built_specs.hpp): one straight-line
//                                        tape for A, Q, G, b, b0, run by the interpreter
//   compiled_terms/<model>/generated     the generated C++ of the same tapes (tests/codegen/),
//                                        when its headers are on the include path; they carry the
//                                        models' default parameter values, which change no
//                                        operation count
// and the cost of building the model from symbols:
//   compile/<model>/compile_model        parameter substitution, CSE, tapes, Model
//   compile/<model>/generate_code        the same, then printed as C++
//   compile/<model>/derive_and_compile   from the Spec (SpecBuilder, as a model file makes it):
//                                        derive() then compile_model()
// Targets: interpreted <= 3x hand-written, generated <= 1.2x. Appell's hand-written row is
// df/dq' / (2 z') where the compiled one is df/dq': the same operation count within one division.
// Before timing, the interpreted terms are checked against the hand-written ones (1e-13); a
// disagreement aborts the program. Results: docs/performance.md.
#include <benchmark/benchmark.h>

#include <array>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <memory>
#include <string>
#include <vector>

#include "../tests/codegen/hand_built_specs.hpp"
#include "bench_cases.hpp"
#include "nhdyn/model/tape.hpp"
#include "nhdyn/symbolic/codegen.hpp"
#include "nhdyn/symbolic/compile.hpp"
#include "nhdyn/symbolic/spec_builder.hpp"

#if __has_include("sled_model.hpp") && __has_include("appell_model.hpp")
#include "appell_model.hpp"
#include "sled_model.hpp"
#define NHDYN_BENCH_GENERATED 1
#endif

namespace nhdyn::bench {
namespace {

testing::HandBuilt hand_built(ModelId id) {
  return id == ModelId::appell ? testing::make_hand_built_appell(appell_parameters())
                               : testing::make_hand_built_sled(sled_parameters());
}

// Storage for one evaluation of the terms (n = 3, s = 1).
struct Terms {
  std::array<double, 9> A{};
  std::array<double, 3> Q{}, G{}, b{};
  std::array<double, 1> b0{};
  TermsOut out() { return TermsOut{A.data(), Q.data(), G.data(), b.data(), b0.data()}; }
};

void check_or_abort(const Model& compiled, const Model& hand, ModelId id) {
  const State x = bench_state(id);
  std::vector<double> scratch(compiled.evaluator->scratch_size());
  Terms c, h;
  compiled.evaluator->terms(0.0, x.q.data(), x.v.data(), scratch.data(), c.out());
  hand.evaluator->terms(0.0, x.q.data(), x.v.data(), nullptr, h.out());
  const double scale = id == ModelId::appell ? 2.0 * x.v[2] : 1.0;  // see the header comment
  double worst = 0.0;
  for (int i = 0; i < 9; ++i) worst = std::max(worst, std::abs(c.A[i] - h.A[i]));
  for (int i = 0; i < 3; ++i) {
    worst = std::max(worst, std::abs(c.Q[i] - h.Q[i]));
    worst = std::max(worst, std::abs(c.G[i] - h.G[i]));
    worst = std::max(worst, std::abs(c.b[i] / scale - h.b[i]));
  }
  worst = std::max(worst, std::abs(c.b0[0] / scale - h.b0[0]));
  if (!(worst <= 1e-13)) {
    std::fprintf(stderr, "compile_bench: compiled %s differs from the hand-written model by %g\n",
                 model_name(id).c_str(), worst);
    std::abort();
  }
}

void bench_terms(benchmark::State& state, const Model& model, ModelId id) {
  const Evaluator& evaluator = *model.evaluator;
  const State x = bench_state(id);
  std::vector<double> scratch(evaluator.scratch_size() + 1);
  Terms terms;
  const TermsOut out = terms.out();
  for (auto _ : state) {
    evaluator.terms(0.0, x.q.data(), x.v.data(), scratch.data(), out);
    benchmark::DoNotOptimize(terms.A.data());
    benchmark::ClobberMemory();
  }
}

void bench_compile(benchmark::State& state, ModelId id) {
  const testing::HandBuilt built = hand_built(id);
  for (auto _ : state) {
    Model model = symbolic::compile_model(built.spec, built.derivation);
    benchmark::DoNotOptimize(model.evaluator.get());
  }
}

void bench_generate(benchmark::State& state, ModelId id) {
  const testing::HandBuilt built = hand_built(id);
  for (auto _ : state) {
    std::string code = symbolic::generate_code(built.spec, built.derivation);
    benchmark::DoNotOptimize(code.data());
  }
}

// The Spec as the model-file loader builds it (examples/sled.toml, appell.toml), with the
// parameters of bench_cases.hpp.
symbolic::Spec built_spec(ModelId id) {
  if (id == ModelId::appell) {
    const AppellParameters p = appell_parameters();
    symbolic::SpecBuilder b("appell");
    b.coordinate("x").coordinate("y").coordinate("z");
    b.parameter("m", p.m, "kg").parameter("g", p.g, "m/s^2").parameter("a", p.a);
    b.kinetic_energy("m/2*(x'^2 + y'^2 + z'^2)");
    b.potential_energy("-m*g*z");
    b.constraint("appell", ConstraintLevel::velocity, "z'^2 - a^2*(x'^2 + y'^2)");
    b.independent({"x", "y"});
    return b.build();
  }
  const SledParameters p = sled_parameters();
  symbolic::SpecBuilder b("sled");
  b.coordinate("x").coordinate("y").coordinate("phi");
  b.parameter("m", p.m, "kg").parameter("a", p.a, "m").parameter("rho", p.rho, "m");
  b.parameter("alpha", p.alpha, "rad").parameter("g", p.g, "m/s^2");
  b.kinetic_energy("m/2*(x'^2 + y'^2) + m*a*phi'*(cos(phi)*y' - sin(phi)*x') + m*rho^2/2*phi'^2");
  b.potential_energy("-m*g*sin(alpha)*(x + a*cos(phi))");
  b.constraint("blade", ConstraintLevel::velocity, "-sin(phi)*x' + cos(phi)*y'");
  b.independent({"x", "phi"});
  return b.build();
}

void bench_derive_and_compile(benchmark::State& state, ModelId id) {
  const symbolic::Spec spec = built_spec(id);
  for (auto _ : state) {
    Model model = symbolic::compile_model(spec);
    benchmark::DoNotOptimize(model.evaluator.get());
  }
}

const bool registered = [] {
  for (ModelId id : {ModelId::sled, ModelId::appell}) {
    const std::string name = model_name(id);
    const testing::HandBuilt built = hand_built(id);
    // Models live as long as the program: benchmarks hold references to them.
    static std::vector<std::unique_ptr<Model>> models;
    models.push_back(std::make_unique<Model>(make_bench_model(id)));
    const Model& hand = *models.back();
    models.push_back(std::make_unique<Model>(symbolic::compile_model(built.spec, built.derivation)));
    const Model& compiled = *models.back();
    check_or_abort(compiled, hand, id);
    benchmark::RegisterBenchmark(("compiled_terms/" + name + "/hand_written").c_str(),
                                 [&hand, id](benchmark::State& s) { bench_terms(s, hand, id); });
    benchmark::RegisterBenchmark(("compiled_terms/" + name + "/interpreted").c_str(),
                                 [&compiled, id](benchmark::State& s) { bench_terms(s, compiled, id); });
#ifdef NHDYN_BENCH_GENERATED
    models.push_back(std::make_unique<Model>(id == ModelId::appell ? generated::make_appell_model()
                                                                   : generated::make_sled_model()));
    const Model& generated_model = *models.back();
    benchmark::RegisterBenchmark(("compiled_terms/" + name + "/generated").c_str(),
                                 [&generated_model, id](benchmark::State& s) { bench_terms(s, generated_model, id); });
#endif
    benchmark::RegisterBenchmark(("compile/" + name + "/compile_model").c_str(), bench_compile, id);
    benchmark::RegisterBenchmark(("compile/" + name + "/generate_code").c_str(), bench_generate, id);
    benchmark::RegisterBenchmark(("compile/" + name + "/derive_and_compile").c_str(), bench_derive_and_compile, id);
  }
  return true;
}();

}  // namespace
}  // namespace nhdyn::bench
