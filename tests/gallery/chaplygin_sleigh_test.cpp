// Exam: the Chaplygin sleigh of examples/chaplygin_sleigh.toml against the closed form derived in
// docs/gallery/chaplygin_sleigh.md: with v the speed of the contact point along the blade,
// w = phi', V = sqrt(v0^2 + rho^2 w0^2), k = a V / rho^2, u = k t + c0, tanh(c0) = v0 / V,
//
//     v = V tanh(u),   w = (V/rho) sech(u),   phi = phi0 + (rho/a) (gd(u) - gd(c0)),
//
// the blade's reaction lambda = m (rho^2 - a^2)/rho^2 v w, R = lambda (-sin(phi), cos(phi), 0),
// the conserved T = m/2 (v^2 + rho^2 w^2), and the limit motion v -> V, w -> 0,
// phi -> phi0 + (rho/a) (pi/2 - gd(c0)).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <numbers>
#include <vector>

#include "gallery/gallery.hpp"

namespace nhdyn::gallery {
namespace {

struct SleighErrors {
  double w = 0.0;         // max |w - w_exact| / |w_exact|
  double v = 0.0;         // max |v - v_exact| / V
  double phi = 0.0;       // max |phi - phi_exact| [rad]
  double reaction = 0.0;  // max |R - R_exact| / (m V^2 / rho)
  double energy = 0.0;    // max |T - T0| / T0
};

double gd(double u) { return std::atan(std::sinh(u)); }  // Gudermann's function

SleighErrors measure_sleigh(const Model& model, double t_end) {
  const double m = parameter(model, "m"), a = parameter(model, "a"), rho = parameter(model, "rho");
  const double phi0 = model.q0(2), w0 = model.v0(2);
  const double v0 = std::cos(phi0) * model.v0(0) + std::sin(phi0) * model.v0(1);
  const double V = std::sqrt(v0 * v0 + rho * rho * w0 * w0), k = a * V / (rho * rho);
  const double c0 = std::atanh(v0 / V), sign = w0 > 0 ? 1.0 : -1.0;
  SleighErrors err;
  for (const Row& r : run_rows(model, tight_options(t_end, 0.01))) {
    const double phi = r.q(2), c = std::cos(phi), s = std::sin(phi);
    const double v = c * r.v(0) + s * r.v(1), w = r.v(2);
    const double u = k * r.t + c0;
    const double v_exact = V * std::tanh(u), w_exact = sign * V / rho / std::cosh(u);
    const double phi_exact = phi0 + sign * rho / a * (gd(u) - gd(c0));
    err.w = std::max(err.w, std::abs(w - w_exact) / std::abs(w_exact));
    err.v = std::max(err.v, std::abs(v - v_exact) / V);
    err.phi = std::max(err.phi, std::abs(phi - phi_exact));
    // The reaction at the row's own state: an identity on the constraint manifold.
    const double lambda = m * (rho * rho - a * a) / (rho * rho) * v * w;
    const double R_scale = m * V * V / rho;
    err.reaction = std::max({err.reaction, std::abs(r.R(0) + lambda * s) / R_scale,
                             std::abs(r.R(1) - lambda * c) / R_scale, std::abs(r.R(2)) / R_scale});
    const double T0 = 0.5 * m * V * V;
    err.energy = std::max(err.energy, std::abs(r.energy - T0) / T0);
  }
  return err;
}

TEST(ChaplyginSleigh, MatchesTheClosedForm) {
  const Model model = load_example("chaplygin_sleigh.toml");
  const SleighErrors err = measure_sleigh(model, 8.0);
  EXPECT_LT(err.w, 1e-7);
  EXPECT_LT(err.v, 1e-9);
  EXPECT_LT(err.phi, 1e-9);
  EXPECT_LT(err.reaction, 1e-12);
  EXPECT_LT(err.energy, 1e-9);
}

// The limit motion: a straight line at the speed V with the centre of mass ahead, heading
// phi_inf = phi0 + (rho/a) (pi/2 - gd(c0)). At t = 25 s, k t + c0 = 32: the tails of the closed
// form (1 - tanh(u) < 2 e^-2u, pi/2 - gd(u) < 2 e^-u) are below 1e-13.
TEST(ChaplyginSleigh, TendsToStraightMotionWithTheCentreOfMassAhead) {
  const Model model = load_example("chaplygin_sleigh.toml");
  const double a = parameter(model, "a"), rho = parameter(model, "rho");
  const double v0 = model.v0(0), w0 = model.v0(2);
  const double V = std::sqrt(v0 * v0 + rho * rho * w0 * w0), c0 = std::atanh(v0 / V);
  ASSERT_LT(v0, 0.0);  // the file starts the sleigh backwards: the limit reverses its motion
  const std::vector<Row> rows = run_rows(model, tight_options(25.0, 1.0));
  ASSERT_FALSE(rows.empty());
  const Row& end = rows.back();
  const double phi = end.q(2), v = std::cos(phi) * end.v(0) + std::sin(phi) * end.v(1);
  EXPECT_NEAR(v, V, 1e-9 * V);
  EXPECT_LT(std::abs(end.v(2)), 1e-11 * w0);
  EXPECT_NEAR(phi, rho / a * (std::numbers::pi / 2 - gd(c0)), 1e-8);
}

// Negative controls: the same file with the blade's sign flipped (the blade at -phi), or with the
// centre of mass behind the contact point (a -> -a in T only), is caught by the exam.
TEST(ChaplyginSleigh, TheExamRejectsWrongModels) {
  const Model flipped = load_altered_example("chaplygin_sleigh.toml", "velocity = \"-sin(phi)*x' + cos(phi)*y'\"",
                                             "velocity = \"sin(phi)*x' + cos(phi)*y'\"");
  EXPECT_GT(measure_sleigh(flipped, 8.0).w, 1e-2);
  const Model behind = load_altered_example("chaplygin_sleigh.toml", "+ m*a*phi' *", "- m*a*phi' *");
  EXPECT_GT(measure_sleigh(behind, 8.0).w, 1e-2);
}

}  // namespace
}  // namespace nhdyn::gallery
