#include "nhdyn/model/appell.hpp"

#include <cmath>

namespace nhdyn {
namespace {

class AppellEvaluator final : public Evaluator {
 public:
  explicit AppellEvaluator(const AppellParameters& p) : p_(p) {}

  void terms(double, const double*, const double* v, double*, const TermsOut& out) const override {
    const double m = p_.m;
    for (int i = 0; i < 9; ++i) out.A[i] = 0.0;
    out.A[0] = out.A[4] = out.A[8] = m;
    out.Q[0] = 0.0;
    out.Q[1] = 0.0;
    out.Q[2] = m * p_.g;
    out.G[0] = out.G[1] = out.G[2] = 0.0;
    // The paper's acceleration form: z'' - (a^2 / z') (x' x'' + y' y'') = 0.
    const double r = p_.a * p_.a / v[2];
    out.b[0] = -r * v[0];
    out.b[1] = -r * v[1];
    out.b[2] = 1.0;
    out.b0[0] = 0.0;
  }

  bool has_complement() const override { return true; }
  void complement(double, const double*, const double* v, double*, double* D) const override {
    // D = [[1, 0, a^2 x'/z'], [0, 1, a^2 y'/z']], column-major 2 x 3.
    const double r = p_.a * p_.a / v[2];
    D[0] = 1.0;
    D[1] = 0.0;
    D[2] = 0.0;
    D[3] = 1.0;
    D[4] = r * v[0];
    D[5] = r * v[1];
  }

  void velocity_residual(double, const double*, const double* v, double*, double* f) const override {
    f[0] = v[2] * v[2] - p_.a * p_.a * (v[0] * v[0] + v[1] * v[1]);
  }

  bool has_energy() const override { return true; }
  double energy(double, const double* q, const double* v, double*) const override {
    return 0.5 * p_.m * (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]) - p_.m * p_.g * q[2];
  }

 private:
  AppellParameters p_;
};

}  // namespace

Model make_appell_model(const AppellParameters& p) {
  Model model;
  model.name = "appell";
  model.description =
      "Appell's particle: nonlinear nonholonomic constraint z'^2 = a^2 (x'^2 + y'^2), z down";
  model.coordinates = {"x", "y", "z"};
  model.constraints = {{"appell", ConstraintLevel::velocity, "z'^2 - a^2 (x'^2 + y'^2) = 0"}};
  model.parameters = {{"m", p.m, "kg"}, {"g", p.g, "m/s^2"}, {"a", p.a, ""}};
  model.q0 = Vector::Zero(3);
  model.v0 = Vector(3);
  model.v0 << 1.0, 0.5, p.a * std::sqrt(1.0 + 0.25);
  model.defaults = {10.0, 0.01};
  model.path = PlanarPath{0, 1};
  model.evaluator = std::make_shared<AppellEvaluator>(p);
  return model;
}

}  // namespace nhdyn
