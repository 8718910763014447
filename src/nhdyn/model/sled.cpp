#include "nhdyn/model/sled.hpp"

#include <fmt/format.h>

#include <cmath>
#include <memory>

#include "nhdyn/core/error.hpp"

namespace nhdyn {
namespace {

void check_sled_parameters(const SledParameters& p) {
  if (!(p.rho > p.a) || !(p.m > 0.0))
    throw InputError(fmt::format("sled: the radius of gyration about the contact point must exceed the distance to "
                                 "the centre of mass (rho > a; here rho = {:g}, a = {:g}) and the mass must be "
                                 "positive (m = {:g}), or the inertia matrix is not positive definite",
                                 p.rho, p.a, p.m));
}

class SledEvaluator final : public Evaluator {
 public:
  // m g sin(alpha) is a constant of the model: computed once, not at every evaluation.
  SledEvaluator(SledVariant variant, const SledParameters& p)
      : variant_(variant), p_(p), mg_sin_alpha_(p.m * p.g * std::sin(p.alpha)) {}

  // The values in the order of Model::parameters: m, a, rho, alpha, g.
  std::shared_ptr<const Evaluator> with_parameters(const double* values, std::size_t count) const override {
    if (count != 5) throw InputError("sled: 5 parameter values expected (m, a, rho, alpha, g)");
    const SledParameters p{values[0], values[1], values[2], values[3], values[4]};
    check_sled_parameters(p);
    return std::make_shared<SledEvaluator>(variant_, p);
  }

  void terms(double, const double* q, const double* v, double*, const TermsOut& out) const override {
    const double m = p_.m, a = p_.a;
    const double s = std::sin(q[2]), c = std::cos(q[2]);
    const double w = v[2];
    // A, column-major 3 x 3 (symmetric).
    out.A[0] = m;          out.A[3] = 0.0;        out.A[6] = -m * a * s;
    out.A[1] = 0.0;        out.A[4] = m;          out.A[7] = m * a * c;
    out.A[2] = -m * a * s; out.A[5] = m * a * c;  out.A[8] = m * p_.rho * p_.rho;
    const double mgs = mg_sin_alpha_;
    out.Q[0] = mgs;
    out.Q[1] = 0.0;
    out.Q[2] = variant_ == SledVariant::centre_of_mass ? -mgs * a * s : 0.0;
    out.G[0] = m * a * c * w * w;
    out.G[1] = m * a * s * w * w;
    out.G[2] = 0.0;
    if (variant_ == SledVariant::centre_of_mass) {
      // f = -sin(phi) x' + cos(phi) y'
      out.b[0] = -s;
      out.b[1] = c;
      out.b[2] = 0.0;
      out.b0[0] = -(c * v[0] + s * v[1]) * w;
    } else {
      // f = y' - tan(phi) x'
      out.b[0] = -s / c;
      out.b[1] = 1.0;
      out.b[2] = 0.0;
      out.b0[0] = -v[0] * w / (c * c);
    }
  }

  bool has_complement() const override { return true; }
  void complement(double, const double* q, const double*, double*, double* D) const override {
    const double s = std::sin(q[2]), c = std::cos(q[2]);
    // Column-major 2 x 3.
    if (variant_ == SledVariant::centre_of_mass) {
      D[0] = c;   D[2] = s;   D[4] = 0.0;
      D[1] = 0.0; D[3] = 0.0; D[5] = 1.0;
    } else {
      D[0] = 1.0; D[2] = s / c; D[4] = 0.0;
      D[1] = 0.0; D[3] = 0.0;   D[5] = 1.0;
    }
  }

  void velocity_residual(double, const double* q, const double* v, double*, double* f) const override {
    const double s = std::sin(q[2]), c = std::cos(q[2]);
    f[0] = variant_ == SledVariant::centre_of_mass ? -s * v[0] + c * v[1] : v[1] - (s / c) * v[0];
  }

  bool has_energy() const override { return true; }
  double energy(double, const double* q, const double* v, double*) const override {
    const double m = p_.m, a = p_.a;
    const double s = std::sin(q[2]), c = std::cos(q[2]);
    const double T = 0.5 * m * (v[0] * v[0] + v[1] * v[1]) + m * a * v[2] * (-s * v[0] + c * v[1]) +
                     0.5 * m * p_.rho * p_.rho * v[2] * v[2];
    const double height = variant_ == SledVariant::centre_of_mass ? q[0] + a * c : q[0];
    return T - mg_sin_alpha_ * height;
  }

 private:
  SledVariant variant_;
  SledParameters p_;
  double mg_sin_alpha_;
};

}  // namespace

Model make_sled_model(SledVariant variant, const SledParameters& p) {
  check_sled_parameters(p);
  const bool paper = variant == SledVariant::paper;
  Model model;
  model.name = paper ? "sled-paper" : "sled";
  model.description = paper ? "Sled on an inclined plane, the paper's potential -m g sin(alpha) x"
                            : "Sled on an inclined plane, centre-of-mass potential";
  model.coordinates = {"x", "y", "phi"};
  model.constraints = {{"blade", ConstraintLevel::velocity,
                        paper ? "y' - tan(phi) x' = 0" : "-sin(phi) x' + cos(phi) y' = 0"}};
  model.parameters = {{"m", p.m, "kg"},
                      {"a", p.a, "m"},
                      {"rho", p.rho, "m"},
                      {"alpha", p.alpha, "rad"},
                      {"g", p.g, "m/s^2"}};
  model.q0 = Vector::Zero(3);
  model.v0 = Vector(3);
  // Moving down the slope while turning; the paper's variant turns gently so that phi stays
  // inside (-pi/2, pi/2), where its tan(phi) form is regular.
  model.v0 << 1.0, 0.0, paper ? 0.2 : 1.0;
  model.defaults = {10.0, 0.01};
  model.path = PlanarPath{0, 1};
  model.evaluator = std::make_shared<SledEvaluator>(variant, p);
  return model;
}

}  // namespace nhdyn
