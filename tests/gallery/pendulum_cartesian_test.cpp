// Exam: the pendulum of examples/pendulum_cartesian.toml (Cartesian x, y, the rod as a holonomic
// constraint) against docs/gallery/pendulum_cartesian.md: released at rest at theta0 it turns
// back at the times n P/2, P = 4 sqrt(l/g) K(sin(theta0/2)); the rod's tension from the
// reactions, N = -(R_x x + R_y y)/l, is m g (3 cos(theta) - 2 cos(theta0)) = m (g cos(theta) + l theta'^2)
// at every row, and R has no component along the arc; T + V is conserved.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <vector>

#include "gallery/gallery.hpp"

namespace nhdyn::gallery {
namespace {

struct PendulumErrors {
  double period = 0.0;      // max over the turning points n of |t_n - n P/2| / P
  int turning_points = 0;   // how many were found
  double tension = 0.0;     // max |N - m g (3 cos(theta) - 2 cos(theta0))| / (m g)
  double tension_v = 0.0;   // max |N - m (g cos(theta) + l theta'^2)| / (m g)
  double tangential = 0.0;  // max |R_x y - R_y x| / (m g l)
  double energy = 0.0;      // max |E - E0| / (m g l)
};

double period_exact(double l, double g, double theta0) {
  return 4.0 * std::sqrt(l / g) * std::comp_ellint_1(std::sin(theta0 / 2));
}

PendulumErrors measure_pendulum(const Model& model, double theta0, double periods) {
  const double m = parameter(model, "m"), g = parameter(model, "g"), l = parameter(model, "l");
  const double P = period_exact(l, g, theta0);
  // rtol 1e-12: near the top (theta0 = 3) the period is so sensitive to the energy that the drift
  // allowed by rtol 1e-10 moves it by 1e-7.
  SimulationOptions options = tight_options(periods * P, 0.01);
  options.integrator.rtol = 1e-12;
  options.integrator.atol = 1e-14;
  const std::vector<Row> rows = run_rows(model, options);
  PendulumErrors err;
  // Turning points: theta' changes sign, and with it l^2 theta' = x y' - y x', whose derivative
  // is x y'' - y x'' (x' alone also vanishes where the mass passes the horizontal).
  const std::vector<double> turns = sign_changes(
      rows, [](const Row& r) { return r.q(0) * r.v(1) - r.q(1) * r.v(0); },
      [](const Row& r) { return r.q(0) * r.qdd(1) - r.q(1) * r.qdd(0); });
  err.turning_points = static_cast<int>(turns.size());
  for (std::size_t n = 0; n < turns.size(); ++n)
    err.period = std::max(err.period, std::abs(turns[n] - (n + 1) * P / 2) / P);
  const double E0 = m * g * model.q0(1);
  for (const Row& r : rows) {
    const double x = r.q(0), y = r.q(1), cos_theta = -y / l;
    const double N = -(r.R(0) * x + r.R(1) * y) / l;
    const double l_thetadot2 = (r.v(0) * r.v(0) + r.v(1) * r.v(1)) / l;
    err.tension = std::max(err.tension, std::abs(N - m * g * (3 * cos_theta - 2 * std::cos(theta0))) / (m * g));
    err.tension_v = std::max(err.tension_v, std::abs(N - m * (g * cos_theta + l_thetadot2)) / (m * g));
    err.tangential = std::max(err.tangential, std::abs(r.R(0) * y - r.R(1) * x) / (m * g * l));
    err.energy = std::max(err.energy, std::abs(r.energy - E0) / (m * g * l));
  }
  return err;
}

TEST(PendulumCartesian, PeriodIsTheEllipticIntegralsAndTensionComesFromTheReactions) {
  // The file's amplitude (2 rad, above the horizontal) and two others: small, and near the top.
  // Even at 0.2 rad the small-angle period 2 pi sqrt(l/g) is 2.5e-3 too short (theta0^2/16).
  for (const double theta0 : {2.0, 0.2, 3.0}) {
    const Model model = load_example("pendulum_cartesian.toml", {{"theta0", theta0}});
    const PendulumErrors err = measure_pendulum(model, theta0, 3.2);
    EXPECT_EQ(err.turning_points, 6) << "theta0 = " << theta0;
    EXPECT_LT(err.period, 1e-8) << "theta0 = " << theta0;
    EXPECT_LT(err.tension, 1e-9) << "theta0 = " << theta0;
    EXPECT_LT(err.tension_v, 1e-12) << "theta0 = " << theta0;
    EXPECT_LT(err.tangential, 1e-12) << "theta0 = " << theta0;
    EXPECT_LT(err.energy, 1e-9) << "theta0 = " << theta0;
  }
}

// Negative controls: gravity reversed, or a kinetic energy that weighs y' twice, is caught.
TEST(PendulumCartesian, TheExamRejectsWrongModels) {
  const Model reversed = load_altered_example("pendulum_cartesian.toml", "\"m*g*y\"", "\"-m*g*y\"");
  EXPECT_GT(measure_pendulum(reversed, 2.0, 3.2).period, 1e-3);
  const Model heavy_y = load_altered_example("pendulum_cartesian.toml", "(x'^2 + y'^2)", "(x'^2 + 2*y'^2)");
  EXPECT_GT(measure_pendulum(heavy_y, 2.0, 3.2).period, 1e-3);
}

}  // namespace
}  // namespace nhdyn::gallery
