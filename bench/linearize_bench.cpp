// Cost of the linearization about a steady motion (analysis/linearization.hpp) on the upright
// rolling disk (examples/rolling_disk_upright.toml, n = 5, s = 2, psi named cyclic):
//   linearize/rolling_disk/tangent     derivatives by the tangent mode of the compiled tapes
//   linearize/rolling_disk/richardson  the same model behind a forwarding Evaluator (no tapes),
//                                      so that Richardson-extrapolated central differences are used
// and of one point of a sweep, which also recompiles the model from its derivation:
//   sweep_point/bicycle_linear         compile_model + linearize of examples/bicycle_linear.toml
// Results: docs/linearization.md ("Cost").
#include <benchmark/benchmark.h>

#include <memory>
#include <string>

#include "nhdyn/analysis/linearization.hpp"
#include "nhdyn/frontend/model_file.hpp"
#include "nhdyn/symbolic/compile.hpp"
#include "nhdyn/symbolic/derivation.hpp"

namespace nhdyn::bench {
namespace {

std::string example(const std::string& file) { return std::string(NHDYN_SOURCE_DIR) + "/examples/" + file; }

// Hides the TapeEvaluator behind the plain Evaluator interface.
class Forwarding final : public Evaluator {
 public:
  explicit Forwarding(std::shared_ptr<const Evaluator> inner) : inner_(std::move(inner)) {}
  std::size_t scratch_size() const override { return inner_->scratch_size(); }
  void terms(double t, const double* q, const double* v, double* s, const TermsOut& out) const override {
    inner_->terms(t, q, v, s, out);
  }
  void position_residual(double t, const double* q, double* s, double* phi) const override {
    inner_->position_residual(t, q, s, phi);
  }
  void velocity_residual(double t, const double* q, const double* v, double* s, double* f) const override {
    inner_->velocity_residual(t, q, v, s, f);
  }

 private:
  std::shared_ptr<const Evaluator> inner_;
};

void linearize_disk(benchmark::State& state, bool richardson) {
  Model model = symbolic::compile_model(load_model_file(example("rolling_disk_upright.toml")));
  if (richardson) model.evaluator = std::make_shared<Forwarding>(model.evaluator);
  LinearizationOptions options;
  options.cyclic = {"psi"};
  for (auto _ : state) {
    Linearization l = calc_linearization(model, options);
    benchmark::DoNotOptimize(l.eigenvalues.data());
  }
}
BENCHMARK_CAPTURE(linearize_disk, tangent, false)->Name("linearize/rolling_disk/tangent");
BENCHMARK_CAPTURE(linearize_disk, richardson, true)->Name("linearize/rolling_disk/richardson");

void sweep_point(benchmark::State& state) {
  symbolic::Spec spec = load_model_file(example("bicycle_linear.toml"));
  const symbolic::Derivation derivation = symbolic::derive(spec);
  double v = 0.0;
  for (auto _ : state) {
    spec.set_parameter("v", v);
    v = v < 10.0 ? v + 0.1 : 0.0;
    Linearization l = calc_linearization(symbolic::compile_model(spec, derivation));
    benchmark::DoNotOptimize(l.eigenvalues.data());
  }
}
BENCHMARK(sweep_point)->Name("sweep_point/bicycle_linear");

}  // namespace
}  // namespace nhdyn::bench
