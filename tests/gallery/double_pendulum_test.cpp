// Exam: the double pendulum of examples/double_pendulum.toml (Cartesian x1, y1, x2, y2; two rods
// as holonomic constraints) against the classical equations in the angles theta1, theta2 derived
// in docs/gallery/double_pendulum.md (Delta = theta1 - theta2):
//
//     (m1 + m2) l1 theta1'' + m2 l2 cos(Delta) theta2'' = -m2 l2 sin(Delta) theta2'^2 - (m1 + m2) g sin(theta1)
//     l1 cos(Delta) theta1'' + l2 theta2''             =  l1 sin(Delta) theta1'^2 - g sin(theta2)
//
// pointwise (the accelerations at random states) and along the file's motion (integrated here with
// a classical RK4 of small step, independent of the library), and T + V conserved.
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <numbers>
#include <random>
#include <vector>

#include "gallery/gallery.hpp"

namespace nhdyn::gallery {
namespace {

struct Pendulum2 {
  double m1 = 0.0, m2 = 0.0, l1 = 0.0, l2 = 0.0, g = 0.0;
};

Pendulum2 parameters_of(const Model& model) {
  return {parameter(model, "m1"), parameter(model, "m2"), parameter(model, "l1"), parameter(model, "l2"),
          parameter(model, "g")};
}

// (theta1'', theta2'') from the minimal-coordinate equations above, by Cramer's rule.
std::array<double, 2> minimal_accelerations(const Pendulum2& p, double th1, double th2, double w1, double w2) {
  const double d = th1 - th2, c = std::cos(d), s = std::sin(d);
  const double a11 = (p.m1 + p.m2) * p.l1, a12 = p.m2 * p.l2 * c, a21 = p.l1 * c, a22 = p.l2;
  const double f1 = -p.m2 * p.l2 * s * w2 * w2 - (p.m1 + p.m2) * p.g * std::sin(th1);
  const double f2 = p.l1 * s * w1 * w1 - p.g * std::sin(th2);
  const double det = a11 * a22 - a12 * a21;
  return {(f1 * a22 - a12 * f2) / det, (a11 * f2 - a21 * f1) / det};
}

// The Cartesian state of the angles and their rates.
void cartesian_state(const Pendulum2& p, double th1, double th2, double w1, double w2, Vector& q, Vector& v) {
  q.resize(4);
  v.resize(4);
  q << p.l1 * std::sin(th1), -p.l1 * std::cos(th1), p.l1 * std::sin(th1) + p.l2 * std::sin(th2),
      -p.l1 * std::cos(th1) - p.l2 * std::cos(th2);
  v << p.l1 * w1 * std::cos(th1), p.l1 * w1 * std::sin(th1), p.l1 * w1 * std::cos(th1) + p.l2 * w2 * std::cos(th2),
      p.l1 * w1 * std::sin(th1) + p.l2 * w2 * std::sin(th2);
}

// max over random states of |theta'' (Cartesian model) - theta'' (minimal)| / (g / l1).
double pointwise_error(const Model& model, Formulation method) {
  const Pendulum2 p = parameters_of(model);
  Data data = make_data(model);
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> angle(-3.0, 3.0), rate(-4.0, 4.0);
  double err = 0.0;
  for (int trial = 0; trial < 50; ++trial) {
    const double th1 = angle(rng), th2 = angle(rng), w1 = rate(rng), w2 = rate(rng);
    Vector q, v;
    cartesian_state(p, th1, th2, w1, w2, q, v);
    EXPECT_EQ(compute_dynamics(model, data, {method, Complement::qr}, 0.0, q.data(), v.data()), Status::ok);
    const Vector& a = data.qdd;
    const double th1dd = (std::cos(th1) * a(0) + std::sin(th1) * a(1)) / p.l1;
    const double th2dd = (std::cos(th2) * (a(2) - a(0)) + std::sin(th2) * (a(3) - a(1))) / p.l2;
    const std::array<double, 2> ref = minimal_accelerations(p, th1, th2, w1, w2);
    err = std::max({err, std::abs(th1dd - ref[0]) / (p.g / p.l1), std::abs(th2dd - ref[1]) / (p.g / p.l1)});
  }
  return err;
}

TEST(DoublePendulum, AccelerationsAgreeWithTheMinimalCoordinateEquationsEverywhere) {
  const Model model = load_example("double_pendulum.toml");
  for (Formulation method : {Formulation::sanh, Formulation::lagrange, Formulation::udwadia_kalaba, Formulation::nullspace}) {
    const double err = pointwise_error(model, method);
    EXPECT_LT(err, 1e-12) << formulation_name(method);
  }
}

// The file's motion for 3 s against the minimal equations integrated by RK4 with h = 1e-4 s
// (its error, ~h^4, is far below the tolerance). The motion is chaotic: differences grow
// exponentially, so the comparison stops at 3 s.
TEST(DoublePendulum, MotionAgreesWithTheMinimalCoordinateEquations) {
  const Model model = load_example("double_pendulum.toml");
  const Pendulum2 p = parameters_of(model);
  std::array<double, 4> y = {parameter(model, "theta1"), parameter(model, "theta2"), parameter(model, "omega1"),
                             parameter(model, "omega2")};
  const auto f = [&](const std::array<double, 4>& s) {
    const std::array<double, 2> a = minimal_accelerations(p, s[0], s[1], s[2], s[3]);
    return std::array<double, 4>{s[2], s[3], a[0], a[1]};
  };
  const double h = 1e-4;
  double t = 0.0, err = 0.0;
  for (const Row& row : run_rows(model, tight_options(3.0, 0.01))) {
    while (t < row.t - 0.5 * h) {
      std::array<double, 4> k1 = f(y), k2, k3, k4, tmp;
      for (int i = 0; i < 4; ++i) tmp[i] = y[i] + 0.5 * h * k1[i];
      k2 = f(tmp);
      for (int i = 0; i < 4; ++i) tmp[i] = y[i] + 0.5 * h * k2[i];
      k3 = f(tmp);
      for (int i = 0; i < 4; ++i) tmp[i] = y[i] + h * k3[i];
      k4 = f(tmp);
      for (int i = 0; i < 4; ++i) y[i] += h / 6 * (k1[i] + 2 * k2[i] + 2 * k3[i] + k4[i]);
      t += h;
    }
    const double th1 = std::atan2(row.q(0), -row.q(1));
    const double th2 = std::atan2(row.q(2) - row.q(0), -(row.q(3) - row.q(1)));
    // Compare angles modulo 2 pi (the RK4 angles are unwrapped).
    err = std::max({err, std::abs(std::remainder(th1 - y[0], 2 * std::numbers::pi)),
                    std::abs(std::remainder(th2 - y[1], 2 * std::numbers::pi))});
  }
  EXPECT_LT(err, 1e-7);
}

TEST(DoublePendulum, EnergyIsConserved) {
  const Model model = load_example("double_pendulum.toml");
  const Pendulum2 p = parameters_of(model);
  SimulationSummary summary;
  run_rows(model, tight_options(10.0, 0.005), &summary);
  ASSERT_TRUE(summary.energy.has_energy);
  EXPECT_LT(summary.energy.drift / ((p.m1 + p.m2) * p.g * (p.l1 + p.l2)), 1e-8);
}

// Negative controls: the lower mass given the upper one's in T, or in V, fails the pointwise exam.
TEST(DoublePendulum, TheExamRejectsWrongModels) {
  const Model wrong_mass = load_altered_example("double_pendulum.toml", "m2/2 * (x2'^2", "m1/2 * (x2'^2");
  EXPECT_GT(pointwise_error(wrong_mass, Formulation::sanh), 1e-2);
  const Model wrong_gravity = load_altered_example("double_pendulum.toml", "m2*g*y2", "m1*g*y2");
  EXPECT_GT(pointwise_error(wrong_gravity, Formulation::sanh), 1e-2);
}

}  // namespace
}  // namespace nhdyn::gallery
