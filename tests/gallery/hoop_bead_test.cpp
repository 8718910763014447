// Exam: the bead on a rotating hoop of examples/hoop_bead.toml (Cartesian x, y, z; the hoop's
// sphere and its plane turning at the prescribed rate Omega, a time-dependent constraint) against
// docs/gallery/hoop_bead.md. With theta the angle from the bottom,
//
//     theta'' = sin(theta) (Omega^2 cos(theta) - g/r)
//
// - below Omega_c = sqrt(g/r) the bottom is stable: small oscillations at sqrt(g/r - Omega^2);
// - above it the bottom is unstable (growth rate sqrt(Omega^2 - g/r)) and the bead rests relative to
//   the hoop at theta* = acos(g/(r Omega^2)), with small oscillations at Omega sin(theta*);
// - the Jacobi integral h = m/2 |v|^2 - m Omega^2 (x^2 + y^2) + m g z is conserved (T + V is not).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <numbers>
#include <string>
#include <utility>
#include <vector>

#include "gallery/gallery.hpp"

namespace nhdyn::gallery {
namespace {

struct HoopState {
  double theta = 0.0, theta_dot = 0.0;
};

// theta and theta' of a row: s is the bead's distance from the axis, signed, in the hoop's plane.
HoopState hoop_state(const Row& r, double Omega, double radius) {
  const double c = std::cos(Omega * r.t), s_ = std::sin(Omega * r.t);
  const double s = c * r.q(0) + s_ * r.q(1);
  const double s_dot = c * r.v(0) + s_ * r.v(1) + Omega * (-s_ * r.q(0) + c * r.q(1));
  return {std::atan2(s, -r.q(2)), (s * r.v(2) - s_dot * r.q(2)) / (radius * radius)};
}

struct Hoop {
  Model model;
  double g = 0.0, r = 0.0, m = 0.0, Omega = 0.0;
};

Hoop load_hoop(double Omega, double theta0, double thetadot0 = 0.0) {
  Hoop h{load_example("hoop_bead.toml", {{"Omega", Omega}, {"theta0", theta0}, {"thetadot0", thetadot0}})};
  h.g = parameter(h.model, "g");
  h.r = parameter(h.model, "r");
  h.m = parameter(h.model, "m");
  h.Omega = Omega;
  return h;
}

// The period of small oscillations about theta_eq, from the crossings of
// theta = theta_eq, each located on the cubic Hermite interpolant of theta - theta_eq and theta'.
// rtol 1e-12: the oscillation (1e-4 rad) rides on the hoop's rotation, which sets the scale of
// the integrator's error control.
double oscillation_period(const Hoop& h, double theta_eq, double t_end, int* crossings) {
  SimulationOptions options = tight_options(t_end, 0.005);
  options.integrator.rtol = 1e-12;
  options.integrator.atol = 1e-14;
  const std::vector<Row> rows = run_rows(h.model, options);
  const std::vector<double> times = sign_changes(
      rows, [&](const Row& row) { return hoop_state(row, h.Omega, h.r).theta - theta_eq; },
      [&](const Row& row) { return hoop_state(row, h.Omega, h.r).theta_dot; });
  *crossings = static_cast<int>(times.size());
  // Whole periods only, from crossings in the same direction: about theta* the quadratic term of
  // the force makes the half-periods above and below theta_eq differ at first order in the amplitude.
  const std::size_t last = (times.size() - 1) / 2 * 2;
  if (last == 0) return 0.0;
  return 2.0 * (times[last] - times.front()) / static_cast<double>(last);
}

TEST(HoopBead, AboveTheCriticalRateTheBeadRestsAtTheAngleAcosOfGOverROmegaSquared) {
  for (const double Omega : {6.0, 8.0, 12.0}) {
    const double g = 9.81, r = 0.5;  // the file's values, checked against the model below
    const double theta_star = std::acos(g / (r * Omega * Omega));
    const Hoop h = load_hoop(Omega, theta_star);
    ASSERT_EQ(h.g, g);
    ASSERT_EQ(h.r, r);
    double drift = 0.0;
    for (const Row& row : run_rows(h.model, tight_options(5.0, 0.01)))
      drift = std::max(drift, std::abs(hoop_state(row, Omega, r).theta - theta_star));
    EXPECT_LT(drift, 1e-8) << "Omega = " << Omega;
  }
}

TEST(HoopBead, SmallOscillationsAboutTheRelativeEquilibriumAtOmegaSinThetaStar) {
  for (const double Omega : {6.0, 12.0}) {
    const Hoop h = load_hoop(Omega, 0.0);
    const double theta_star = std::acos(h.g / (h.r * Omega * Omega));
    const Hoop near = load_hoop(Omega, theta_star + 1e-4);
    int crossings = 0;
    const double P = oscillation_period(near, theta_star, 10.0, &crossings);
    EXPECT_GT(crossings, 10) << "Omega = " << Omega;
    const double P_exact = 2 * std::numbers::pi / (Omega * std::sin(theta_star));
    EXPECT_LT(std::abs(P / P_exact - 1.0), 1e-6) << "Omega = " << Omega;
  }
}

TEST(HoopBead, BelowTheCriticalRateTheBottomIsStableWithFrequencySqrtOfGOverRMinusOmegaSquared) {
  for (const double Omega : {0.0, 3.0, 4.0}) {
    const Hoop h = load_hoop(Omega, 1e-4);
    int crossings = 0;
    const double P = oscillation_period(h, 0.0, 10.0, &crossings);
    EXPECT_GT(crossings, 4) << "Omega = " << Omega;
    const double P_exact = 2 * std::numbers::pi / std::sqrt(h.g / h.r - Omega * Omega);
    EXPECT_LT(std::abs(P / P_exact - 1.0), 1e-6) << "Omega = " << Omega;
  }
}

// Above the critical rate the bottom is unstable: from theta0 = 1e-6 at rest relative to the hoop,
// the linearized motion is theta0 cosh(lambda t), lambda = sqrt(Omega^2 - g/r); followed until
// theta = 1e-3, where the neglected cubic terms are ~1e-6 of theta.
TEST(HoopBead, AboveTheCriticalRateTheBottomIsUnstableWithGrowthRateSqrtOfOmegaSquaredMinusGOverR) {
  const double Omega = 6.0, theta0 = 1e-6;
  const Hoop h = load_hoop(Omega, theta0);
  const double lambda = std::sqrt(Omega * Omega - h.g / h.r);
  const double t_end = std::acosh(1e-3 / theta0) / lambda;
  double err = 0.0;
  for (const Row& row : run_rows(h.model, tight_options(t_end, 0.01))) {
    const double linear = theta0 * std::cosh(lambda * row.t);
    err = std::max(err, std::abs(hoop_state(row, Omega, h.r).theta / linear - 1.0));
  }
  EXPECT_LT(err, 1e-5);
}

// The file's run: released near the bottom above the critical rate, the bead swings widely; the
// Jacobi integral holds while T + V changes by the work of the motor.
TEST(HoopBead, TheJacobiIntegralIsConservedAndTheEnergyIsNot) {
  const Model model = load_example("hoop_bead.toml");
  const double m = parameter(model, "m"), g = parameter(model, "g"), r = parameter(model, "r");
  const double Omega = parameter(model, "Omega");
  double h0 = 0.0, h_err = 0.0, E0 = 0.0, E_change = 0.0, theta_max = 0.0;
  bool first = true;
  for (const Row& row : run_rows(model, tight_options(6.0, 0.005))) {
    const Vector& q = row.q;
    const double h = 0.5 * m * row.v.squaredNorm() - m * Omega * Omega * (q(0) * q(0) + q(1) * q(1)) + m * g * q(2);
    if (first) {
      h0 = h;
      E0 = row.energy;
      first = false;
    }
    h_err = std::max(h_err, std::abs(h - h0) / (m * g * r));
    E_change = std::max(E_change, std::abs(row.energy - E0) / (m * g * r));
    theta_max = std::max(theta_max, hoop_state(row, Omega, r).theta);
  }
  EXPECT_LT(h_err, 1e-8);
  EXPECT_GT(E_change, 0.1);  // the motor's work: T + V is no invariant here
  EXPECT_GT(theta_max, std::acos(g / (r * Omega * Omega)));  // the bead climbs past theta*
}

// Negative controls: started at theta* (written in the file as the expression
// acos(g/(r*Omega^2))), the file with gravity reversed, or with the bead 20 % heavier along y
// in T, leaves it.
TEST(HoopBead, TheExamRejectsWrongModels) {
  const std::pair<std::string, std::string> at_theta_star{"theta0 = { value = 0.1,",
                                                          "theta0 = { value = \"acos(g/(r*Omega^2))\","};
  const std::pair<std::string, std::string> wrongs[] = {{"\"m*g*z\"", "\"-m*g*z\""}, {"y'^2 + z'^2)", "1.2*y'^2 + z'^2)"}};
  for (const auto& wrong : wrongs) {
    const Model model = load_altered_example("hoop_bead.toml", {at_theta_star, wrong});
    const double g = parameter(model, "g"), r = parameter(model, "r"), Omega = parameter(model, "Omega");
    const double theta_star = std::acos(g / (r * Omega * Omega));
    double drift = 0.0;
    for (const Row& row : run_rows(model, tight_options(5.0, 0.01)))
      drift = std::max(drift, std::abs(hoop_state(row, Omega, r).theta - theta_star));
    EXPECT_GT(drift, 1e-2) << wrong.first << " -> " << wrong.second;
  }
  // The same start in the right model stays there (the exam above, through the file's expression).
  const Model right = load_altered_example("hoop_bead.toml", {at_theta_star});
  double drift = 0.0;
  for (const Row& row : run_rows(right, tight_options(5.0, 0.01)))
    drift = std::max(drift, std::abs(hoop_state(row, 6.0, 0.5).theta - std::acos(9.81 / (0.5 * 36.0))));
  EXPECT_LT(drift, 1e-8);
}

}  // namespace
}  // namespace nhdyn::gallery
