#include "nhdyn/model/appell.hpp"

#include <fmt/format.h>

#include <cmath>
#include <memory>

#include "nhdyn/core/error.hpp"

namespace nhdyn {
namespace {

// The initial velocity (1, 0.5, z'), z' = a |(x', y')| on the constraint's falling branch.
void appell_initial_state(const AppellParameters& p, double* q0, double* v0) {
  q0[0] = q0[1] = q0[2] = 0.0;
  v0[0] = 1.0;
  v0[1] = 0.5;
  v0[2] = p.a * std::sqrt(1.0 + 0.25);
}

class AppellEvaluator final : public Evaluator {
 public:
  AppellEvaluator(const AppellParameters& p, double t0, const Vector& q0, const Vector& v0) : p_(p), t0_(t0) {
    for (int i = 0; i < 3; ++i) {
      q0_[i] = q0[i];
      v0_[i] = v0[i];
    }
  }

  // The values in the order of Model::parameters: m, g, a. The exact solution starts from the
  // initial state of these values.
  std::shared_ptr<const Evaluator> with_parameters(const double* values, std::size_t count) const override {
    if (count != 3) throw InputError("appell: 3 parameter values expected (m, g, a)");
    const AppellParameters p{values[0], values[1], values[2]};
    if (!(p.m > 0.0) || !(p.a > 0.0))
      throw InputError(fmt::format("appell: the mass must be positive (m = {:g}), or the inertia matrix is not "
                                   "positive definite, and so must a (a = {:g}): the model follows the falling "
                                   "branch z' = a |(x', y')| > 0 and divides by z'",
                                   p.m, p.a));
    Vector q0(3), v0(3);
    appell_initial_state(p, q0.data(), v0.data());
    return std::make_shared<AppellEvaluator>(p, t0_, q0, v0);
  }
  bool has_initial_state() const override { return true; }
  void initial_state(double*, double* q0, double* v0) const override { appell_initial_state(p_, q0, v0); }

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

  // docs/derivations/appell.md section 3.1 (falling branch, z' > 0): the horizontal velocity keeps
  // its direction e and its length grows at c = g a / (1 + a^2); z' = a u throughout.
  bool has_solution() const override { return true; }
  void solution(double t, double*, double* qva) const override {
    const double u0 = std::hypot(v0_[0], v0_[1]);
    const double c = p_.g * p_.a / (1.0 + p_.a * p_.a);
    const double e[2] = {v0_[0] / u0, v0_[1] / u0};
    const double tau = t - t0_;
    const double s = u0 * tau + 0.5 * c * tau * tau;  // horizontal distance travelled
    const double u = u0 + c * tau;
    const double direction[3] = {e[0], e[1], p_.a};
    for (int i = 0; i < 3; ++i) {
      qva[i] = q0_[i] + direction[i] * s;
      qva[3 + i] = direction[i] * u;
      qva[6 + i] = direction[i] * c;
    }
  }

 private:
  AppellParameters p_;
  double t0_;
  double q0_[3], v0_[3];  // the initial state the solution starts from
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
  model.q0 = Vector(3);
  model.v0 = Vector(3);
  appell_initial_state(p, model.q0.data(), model.v0.data());
  model.defaults = {10.0, 0.01};
  model.path = PlanarPath{0, 1};
  model.evaluator = std::make_shared<AppellEvaluator>(p, model.t0, model.q0, model.v0);
  return model;
}

}  // namespace nhdyn
