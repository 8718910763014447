// Exam: the slider-crank of examples/slider_crank.toml (crank angle alpha, rod angle beta, slider
// position x; two holonomic loop constraints) against the one-coordinate description derived in
// docs/gallery/slider_crank.md:
//
//     sin(beta) = (a/l) sin(alpha),   x = a cos(alpha) + l cos(beta),
//     E(alpha, alpha') = J(alpha) alpha'^2 / 2 + V(alpha) conserved,
//     J(alpha) alpha'' = -J'(alpha) alpha'^2 / 2 - V'(alpha),
//
// and the loop's reactions R = b^T lambda, with lambda the force of the slider on the rod at B:
// lambda_x = -m3 x'' (the slider's own equation) and lambda_y from the moment about O of crank and
// rod, x lambda_y = dH_O/dt + g (m1 a/2 cos(alpha) + m2 x_G).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <numbers>
#include <random>
#include <vector>

#include "gallery/gallery.hpp"

namespace nhdyn::gallery {
namespace {

struct Crank {
  double a = 0.0, l = 0.0, m1 = 0.0, m2 = 0.0, m3 = 0.0, g = 0.0;
};

Crank parameters_of(const Model& model) {
  return {parameter(model, "a"),  parameter(model, "l"),  parameter(model, "m1"),
          parameter(model, "m2"), parameter(model, "m3"), parameter(model, "g")};
}

double rod_angle(const Crank& p, double alpha) { return std::asin(p.a / p.l * std::sin(alpha)); }
double slider(const Crank& p, double alpha) {
  const double s = std::sin(alpha);
  return p.a * std::cos(alpha) + std::sqrt(p.l * p.l - p.a * p.a * s * s);
}

// The generalized inertia J(alpha) = 2 T / alpha'^2 on the loop, and the potential V(alpha).
double inertia(const Crank& p, double alpha) {
  const double beta = rod_angle(p, alpha), ba = p.a * std::cos(alpha) / (p.l * std::cos(beta));  // dbeta/dalpha
  const double xa = -p.a * std::sin(alpha) - p.l * std::sin(beta) * ba;                            // dx/dalpha
  const double gx = -p.a * std::sin(alpha) - p.l / 2 * std::sin(beta) * ba;                        // dG/dalpha
  const double gy = p.a * std::cos(alpha) - p.l / 2 * std::cos(beta) * ba;
  return p.m1 * p.a * p.a / 3 + p.m2 * (gx * gx + gy * gy) + p.m2 * p.l * p.l / 12 * ba * ba + p.m3 * xa * xa;
}
double potential(const Crank& p, double alpha) { return p.g * (p.m1 + p.m2) * p.a / 2 * std::sin(alpha); }

// alpha'' of the one-coordinate equation (J' and V' by central differences: error ~1e-10).
double minimal_acceleration(const Crank& p, double alpha, double w) {
  const double h = 1e-5;
  const double dJ = (inertia(p, alpha + h) - inertia(p, alpha - h)) / (2 * h);
  const double dV = (potential(p, alpha + h) - potential(p, alpha - h)) / (2 * h);
  return (-0.5 * dJ * w * w - dV) / inertia(p, alpha);
}

// max over random states on the loop of |alpha'' - alpha''_minimal| / (w_max^2).
double pointwise_error(const Model& model, Formulation method) {
  const Crank p = parameters_of(model);
  Data data = make_data(model);
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> angle(-std::numbers::pi, std::numbers::pi), rate(-20.0, 20.0);
  double err = 0.0;
  for (int trial = 0; trial < 50; ++trial) {
    const double alpha = angle(rng), w = rate(rng), beta = rod_angle(p, alpha);
    const double bw = p.a * std::cos(alpha) * w / (p.l * std::cos(beta));
    Vector q(3), v(3);
    q << alpha, beta, slider(p, alpha);
    v << w, bw, -p.a * std::sin(alpha) * w - p.l * std::sin(beta) * bw;
    EXPECT_EQ(compute_dynamics(model, data, {method, Complement::qr}, 0.0, q.data(), v.data()), Status::ok);
    err = std::max(err, std::abs(data.qdd(0) - minimal_acceleration(p, alpha, w)) / 400.0);
  }
  return err;
}

struct MotionErrors {
  double kinematics = 0.0;  // max |beta - beta(alpha)|, |x - x(alpha)| / l
  double energy = 0.0;      // max |J alpha'^2/2 + V - E0| / E0, with J and V of the minimal form
  double lambda_x = 0.0;    // max |lambda_x - (-m3 x'')| / (m3 a w0^2)
  double lambda_y = 0.0;    // max |lambda_y - lambda_y(moments)| / (m3 a w0^2)
  double work = 0.0;        // max |R . q'| / (m3 a^2 w0^3): the reactions do no work
};

MotionErrors measure_crank(const Model& model) {
  const Crank p = parameters_of(model);
  const double w0 = model.v0(0), scale = p.m3 * p.a * w0 * w0;
  const double E0 = 0.5 * inertia(p, model.q0(0)) * w0 * w0 + potential(p, model.q0(0));
  MotionErrors err;
  for (const Row& row : run_rows(model, tight_options(3.0, 0.005))) {
    const double alpha = row.q(0), beta = row.q(1), x = row.q(2);
    err.kinematics = std::max({err.kinematics, std::abs(std::remainder(beta - rod_angle(p, alpha), 2 * std::numbers::pi)),
                               std::abs(x - slider(p, alpha)) / p.l});
    const double E = 0.5 * inertia(p, alpha) * row.v(0) * row.v(0) + potential(p, alpha);
    err.energy = std::max(err.energy, std::abs(E - E0) / E0);
    // lambda from the generalized reactions: R_x = -lambda_x, R_beta = -l (sin(beta) lambda_x + cos(beta) lambda_y).
    const double lx = -row.R(2), ly = -(row.R(1) / p.l + std::sin(beta) * lx) / std::cos(beta);
    err.lambda_x = std::max(err.lambda_x, std::abs(lx + p.m3 * row.qdd(2)) / scale);
    // Moments about O of crank and rod: dH_O/dt = -g (m1 a/2 cos(alpha) + m2 x_G) + x lambda_y.
    const double ad = row.v(0), bd = row.v(1), add = row.qdd(0), bdd = row.qdd(1);
    const double gx = p.a * std::cos(alpha) + p.l / 2 * std::cos(beta), gy = p.a * std::sin(alpha) - p.l / 2 * std::sin(beta);
    const double ax = -p.a * (std::cos(alpha) * ad * ad + std::sin(alpha) * add) -
                      p.l / 2 * (std::cos(beta) * bd * bd + std::sin(beta) * bdd);
    const double ay = p.a * (-std::sin(alpha) * ad * ad + std::cos(alpha) * add) -
                      p.l / 2 * (-std::sin(beta) * bd * bd + std::cos(beta) * bdd);
    const double dH = p.m1 * p.a * p.a / 3 * add + p.m2 * (gx * ay - gy * ax) - p.m2 * p.l * p.l / 12 * bdd;
    const double ly_moments = (dH + p.g * (p.m1 * p.a / 2 * std::cos(alpha) + p.m2 * gx)) / x;
    err.lambda_y = std::max(err.lambda_y, std::abs(ly - ly_moments) / scale);
    err.work = std::max(err.work, std::abs(row.R.dot(row.v)) / (scale * p.a * w0));
  }
  return err;
}

TEST(SliderCrank, AccelerationsAgreeWithTheOneCoordinateEquationEverywhere) {
  const Model model = load_example("slider_crank.toml");
  for (Formulation method : {Formulation::sanh, Formulation::lagrange, Formulation::udwadia_kalaba, Formulation::nullspace})
    EXPECT_LT(pointwise_error(model, method), 1e-8) << formulation_name(method);
}

TEST(SliderCrank, MotionFollowsTheLoopKinematicsAndConservesEnergy) {
  const MotionErrors err = measure_crank(load_example("slider_crank.toml"));
  EXPECT_LT(err.kinematics, 5e-9);
  EXPECT_LT(err.energy, 5e-9);
  EXPECT_LT(err.lambda_x, 1e-10);
  EXPECT_LT(err.lambda_y, 5e-9);
  EXPECT_LT(err.work, 1e-8);
}

// Negative controls: the rod's moment of inertia about its centre forgotten in T, or the rod's
// centre put at B in V, fail the exam.
TEST(SliderCrank, TheExamRejectsWrongModels) {
  const Model no_rod_inertia = load_altered_example("slider_crank.toml", "+ m2*l^2/24 * beta'^2", "");
  EXPECT_GT(pointwise_error(no_rod_inertia, Formulation::sanh), 1e-3);
  EXPECT_GT(measure_crank(no_rod_inertia).energy, 1e-3);
  const Model wrong_potential = load_altered_example("slider_crank.toml", "m2*(a*sin(alpha) - l/2*sin(beta))",
                                                     "m2*(a*sin(alpha) - l*sin(beta))");
  EXPECT_GT(pointwise_error(wrong_potential, Formulation::sanh), 1e-3);
}

}  // namespace
}  // namespace nhdyn::gallery
