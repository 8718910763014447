// Exam: the thin disk rolling without slipping of examples/rolling_disk.toml (x, y, heading psi,
// tilt theta, spin phi) against the steady circular motions derived in docs/gallery/rolling_disk.md:
// theta = theta0, psi' = Omega, phi' = w stay constant when
//
//     w = -(5/6) Omega sin(theta0) - 2 g tan(theta0) / (3 r Omega),
//
// the contact point runs on the circle of radius |r w / Omega| about (0, r w / Omega), and the
// friction force at the contact is F e_n with F = m r Omega (w + Omega sin(theta0)), so
// R = (-F sin(psi), F cos(psi), 0, 0, 0). On every motion T + V is conserved.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <numbers>
#include <utility>
#include <vector>

#include "gallery/gallery.hpp"

namespace nhdyn::gallery {
namespace {

struct SteadyErrors {
  double theta = 0.0;     // max |theta - theta0| [rad]
  double rates = 0.0;     // max of |psi' - Omega| / |Omega|, |phi' - w| / |w|, |theta'| / |Omega|
  double phase = 0.0;     // max |psi - Omega t|, |phi - w t| [rad]
  double radius = 0.0;    // max ||P - centre| - R| / R, R = |r w / Omega|
  double reaction = 0.0;  // max |R - R_exact| / |F|
  double energy = 0.0;    // max |E - E0| / |E0|
};

// The steady motion of the file's parameters: the relation is evaluated here, not read from the
// file, so a file whose initial spin breaks it is measured against the motion it should have had.
SteadyErrors measure_steady(const Model& model, double t_end) {
  const double m = parameter(model, "m"), r = parameter(model, "r"), g = parameter(model, "g");
  const double theta0 = parameter(model, "theta0"), Omega = parameter(model, "Omega");
  const double w = -5.0 / 6.0 * Omega * std::sin(theta0) - 2.0 * g * std::tan(theta0) / (3.0 * r * Omega);
  const double R = std::abs(r * w / Omega), yc = r * w / Omega;
  const double F = m * r * Omega * (w + Omega * std::sin(theta0));
  SteadyErrors err;
  double E0 = 0.0;
  for (const Row& row : run_rows(model, tight_options(t_end, 0.01))) {
    if (row.t == 0.0) E0 = row.energy;
    err.theta = std::max(err.theta, std::abs(row.q(3) - theta0));
    err.rates = std::max({err.rates, std::abs(row.v(2) - Omega) / std::abs(Omega), std::abs(row.v(4) - w) / std::abs(w),
                          std::abs(row.v(3)) / std::abs(Omega)});
    err.phase = std::max({err.phase, std::abs(row.q(2) - Omega * row.t), std::abs(row.q(4) - w * row.t)});
    err.radius = std::max(err.radius, std::abs(std::hypot(row.q(0), row.q(1) - yc) - R) / R);
    const double psi = row.q(2);
    err.reaction = std::max({err.reaction, std::abs(row.R(0) + F * std::sin(psi)) / std::abs(F),
                             std::abs(row.R(1) - F * std::cos(psi)) / std::abs(F), std::abs(row.R(2)) / std::abs(F),
                             std::abs(row.R(3)) / std::abs(F), std::abs(row.R(4)) / (r * std::abs(F))});
    err.energy = std::max(err.energy, std::abs(row.energy - E0) / std::abs(E0));
  }
  return err;
}

TEST(RollingDisk, TheSteadyCircularMotionStaysSteadyForTenTurns) {
  const Model model = load_example("rolling_disk.toml");
  const double Omega = parameter(model, "Omega");
  const double t_end = 10.0 * 2.0 * std::numbers::pi / Omega;
  const SteadyErrors err = measure_steady(model, t_end);
  EXPECT_LT(err.theta, 1e-9);
  EXPECT_LT(err.rates, 1e-9);
  EXPECT_LT(err.phase, 1e-8);
  EXPECT_LT(err.radius, 1e-9);
  EXPECT_LT(err.reaction, 1e-8);
  EXPECT_LT(err.energy, 1e-10);
}

// Other steady motions of the same family (another tilt, another heading rate, the other sense of
// turning) are steady as well: the relation, not one lucky point.
TEST(RollingDisk, EveryPointOfTheRelationIsSteady) {
  for (const auto& [theta0, Omega] : {std::pair{0.6, 3.0}, std::pair{-0.2, 1.5}, std::pair{0.4, -2.5}}) {
    const Model model = load_example("rolling_disk.toml", {{"theta0", theta0}, {"Omega", Omega}});
    const SteadyErrors err = measure_steady(model, 4.0 * 2.0 * std::numbers::pi / std::abs(Omega));
    EXPECT_LT(err.theta, 1e-9) << theta0 << ", " << Omega;
    EXPECT_LT(err.rates, 1e-9) << theta0 << ", " << Omega;
    EXPECT_LT(err.radius, 1e-9) << theta0 << ", " << Omega;
  }
}

// From a general state (the disk nutates: theta swings, the rates vary), T + V is conserved and the
// contact point still rolls: the velocity residuals stay at the integration error.
TEST(RollingDisk, ConservesEnergyFromAGeneralState) {
  Model model = load_example("rolling_disk.toml");
  const double r = parameter(model, "r");
  const double psi0 = 0.4, phi_rate = -9.0;
  model.q0 << 0.1, -0.2, psi0, 0.25, 0.0;
  model.v0 << r * phi_rate * std::cos(psi0), r * phi_rate * std::sin(psi0), 1.5, 0.8, phi_rate;
  const std::vector<Row> rows = run_rows(model, tight_options(10.0, 0.01));
  ASSERT_FALSE(rows.empty());
  double drift = 0.0, theta_min = rows.front().q(3), theta_max = theta_min, roll = 0.0;
  for (const Row& row : rows) {
    drift = std::max(drift, std::abs(row.energy - rows.front().energy) / std::abs(rows.front().energy));
    theta_min = std::min(theta_min, row.q(3));
    theta_max = std::max(theta_max, row.q(3));
    roll = std::max({roll, std::abs(row.v(0) - r * row.v(4) * std::cos(row.q(2))),
                     std::abs(row.v(1) - r * row.v(4) * std::sin(row.q(2)))});
  }
  EXPECT_GT(theta_max - theta_min, 0.05);  // a general motion, not a steady one
  EXPECT_LT(drift, 1e-9);
  EXPECT_LT(roll, 1e-8);
}

// Negative controls: a start off the relation (the spin of a wrong relation, 1/2 for 5/6), or the
// right start for a disk with the wrong axial inertia (m r^2/4 instead of m r^2/2), does not stay
// steady.
TEST(RollingDisk, TheExamRejectsWrongModels) {
  Model wrong_relation = load_example("rolling_disk.toml");
  const double r = parameter(wrong_relation, "r"), g = parameter(wrong_relation, "g");
  const double theta0 = parameter(wrong_relation, "theta0"), Omega = parameter(wrong_relation, "Omega");
  const double w_wrong = -0.5 * Omega * std::sin(theta0) - 2.0 * g * std::tan(theta0) / (3.0 * r * Omega);
  wrong_relation.v0(0) = r * w_wrong;
  wrong_relation.v0(4) = w_wrong;
  const SteadyErrors a = measure_steady(wrong_relation, 10.0 * std::numbers::pi);
  EXPECT_GT(a.theta, 1e-3);
  EXPECT_GT(a.rates, 1e-2);
  const Model wrong_inertia = load_altered_example("rolling_disk.toml", "m*r^2/4 * (psi'", "m*r^2/8 * (psi'");
  const SteadyErrors b = measure_steady(wrong_inertia, 10.0 * std::numbers::pi);
  EXPECT_GT(b.theta, 1e-3);
  EXPECT_GT(b.rates, 1e-2);
}

}  // namespace
}  // namespace nhdyn::gallery
