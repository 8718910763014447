// Small models for tests that need a property no built-in model has: a free particle with
// constraints given as fixed rows of b (dependent ones, say), or an inertia matrix chosen by the
// test (not positive definite, say). Header-only so that every test executable can use it.
#pragma once

#include <cmath>
#include <memory>
#include <string>
#include <vector>

#include "nhdyn/model/model.hpp"

namespace nhdyn::testing {

// A body with constant inertia matrix A, constant forces Q, and constraints b q'' + b0 = 0 with
// constant rows (given at acceleration level).
class ConstantEvaluator final : public Evaluator {
 public:
  ConstantEvaluator(Matrix A, Vector Q, Matrix b, Vector b0)
      : A_(std::move(A)), Q_(std::move(Q)), b_(std::move(b)), b0_(std::move(b0)) {}
  void terms(double, const double*, const double*, double*, const TermsOut& out) const override {
    const Eigen::Index n = A_.rows(), s = b_.rows();
    Eigen::Map<Matrix>(out.A, n, n) = A_;
    Eigen::Map<Vector>(out.Q, n) = Q_;
    Eigen::Map<Vector>(out.G, n).setZero();
    Eigen::Map<Matrix>(out.b, s, n) = b_;
    Eigen::Map<Vector>(out.b0, s) = b0_;
  }

 private:
  Matrix A_;
  Vector Q_;
  Matrix b_;
  Vector b0_;
};

inline Model make_constant_model(const Matrix& A, const Vector& Q, const Matrix& b, const Vector& b0) {
  Model m;
  m.name = "constant";
  for (Eigen::Index i = 0; i < A.rows(); ++i) m.coordinates.push_back("q" + std::to_string(i + 1));
  for (Eigen::Index i = 0; i < b.rows(); ++i)
    m.constraints.push_back({"c" + std::to_string(i + 1), ConstraintLevel::acceleration, ""});
  m.q0 = Vector::Zero(A.rows());
  m.v0 = Vector::Zero(A.rows());
  m.evaluator = std::make_shared<ConstantEvaluator>(A, Q, b, b0);
  return m;
}

// Two coordinates on a line x + y = 0 pushed by Q_x = sqrt(t_end - t): the force is NaN after
// t_end, so any run past it must stop there with a non-finite status.
class BlowupEvaluator final : public Evaluator {
 public:
  explicit BlowupEvaluator(double t_end) : t_end_(t_end) {}
  void terms(double t, const double*, const double*, double*, const TermsOut& out) const override {
    out.A[0] = 1.0;
    out.A[1] = 0.0;
    out.A[2] = 0.0;
    out.A[3] = 1.0;
    out.Q[0] = std::sqrt(t_end_ - t);
    out.Q[1] = 0.0;
    out.G[0] = out.G[1] = 0.0;
    out.b[0] = 1.0;
    out.b[1] = 1.0;
    out.b0[0] = 0.0;
  }

 private:
  double t_end_;
};

inline Model make_blowup_model(double t_end) {
  Model m;
  m.name = "blowup";
  m.coordinates = {"x", "y"};
  m.constraints = {{"line", ConstraintLevel::acceleration, "x'' + y'' = 0"}};
  m.q0 = Vector::Zero(2);
  m.v0 = Vector::Zero(2);
  m.evaluator = std::make_shared<BlowupEvaluator>(t_end);
  return m;
}

// A planar pendulum in Cartesian coordinates: mass m on a rod of length l, y up,
// phi = x^2 + y^2 - l^2 = 0 (position level).
class PendulumEvaluator final : public Evaluator {
 public:
  // l2 is the squared rod length; a negative one makes a constraint without solution.
  PendulumEvaluator(double m, double g, double l2) : m_(m), g_(g), l2_(l2) {}
  void terms(double, const double* q, const double* v, double*, const TermsOut& out) const override {
    out.A[0] = m_;
    out.A[1] = 0.0;
    out.A[2] = 0.0;
    out.A[3] = m_;
    out.Q[0] = 0.0;
    out.Q[1] = -m_ * g_;
    out.G[0] = out.G[1] = 0.0;
    out.b[0] = 2.0 * q[0];
    out.b[1] = 2.0 * q[1];
    out.b0[0] = 2.0 * (v[0] * v[0] + v[1] * v[1]);
  }
  void position_residual(double, const double* q, double*, double* phi) const override {
    phi[0] = q[0] * q[0] + q[1] * q[1] - l2_;
  }
  void velocity_residual(double, const double* q, const double* v, double*, double* f) const override {
    f[0] = 2.0 * (q[0] * v[0] + q[1] * v[1]);
  }
  bool has_energy() const override { return true; }
  double energy(double, const double* q, const double* v, double*) const override {
    return 0.5 * m_ * (v[0] * v[0] + v[1] * v[1]) + m_ * g_ * q[1];
  }

 private:
  double m_, g_, l2_;
};

inline Model make_pendulum_model(double m = 1.0, double g = 9.81, double l = 1.0) {
  Model model;
  model.name = "pendulum";
  model.coordinates = {"x", "y"};
  model.constraints = {{"rod", ConstraintLevel::position, "x^2 + y^2 - l^2 = 0"}};
  model.q0 = Vector(2);
  model.q0 << l, 0.0;
  model.v0 = Vector::Zero(2);
  model.evaluator = std::make_shared<PendulumEvaluator>(m, g, l * l);
  return model;
}

}  // namespace nhdyn::testing
