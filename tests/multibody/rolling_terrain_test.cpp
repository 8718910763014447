// Bodies rolling on terrain Z = h(X, Y) ([[contacts]] with ground = { terrain = ... }): the contact
// point's X and Y are coordinates without inertia of their own (A singular, [D A; b] regular,
// docs/derivations/rolling-bodies.md section 8). An inclined plane written as terrain against the
// plane's closed form; a ball over a bump against the invariants (energy, the contact geometry).
#include <gtest/gtest.h>

#include <cmath>
#include <string>
#include <vector>

#include "nhdyn/analysis/simulation.hpp"
#include "nhdyn/frontend/load_model.hpp"
#include "nhdyn/io/results.hpp"
#include "support/models.hpp"

namespace nhdyn {
namespace {

int terrain_column(const ResultColumns& columns, const std::string& name) {
  for (std::size_t i = 0; i < columns.all.size(); ++i)
    if (columns.all[i] == name) return static_cast<int>(i);
  ADD_FAILURE() << "no column " << name;
  return 0;
}

// The terrain h = X tan(alpha) is the plane through the origin inclined by alpha: a solid ball
// released on it rolls down at a = 5/7 g sin(alpha) (rolling-bodies.md (6.8) with J = 2/5 m r^2),
// pressed by N = m g cos(alpha), its contact point straight below the centre along the normal.
TEST(RollingTerrain, BallOnAnInclinedTerrainRollsAtFiveSevenths) {
  const Model model = load_model_text(test::ball_on_terrain("X*tan(alpha)", R"toml([initial]
position = { x = "-r*sin(alpha)", y = 0, z = "r*cos(alpha)", u = 0, v = 0, psi = 0, theta = 0, phi = 0 }
)toml"));
  const double m = 1.5, r = 0.1, g = 9.81, alpha = 0.3, a = 5.0 / 7.0 * g * std::sin(alpha);
  const ResultColumns columns = make_result_columns(model);
  const int N = terrain_column(columns, "ball_N"), X = terrain_column(columns, "ball_X"), Z = terrain_column(columns, "ball_Z");
  const int Fx = terrain_column(columns, "ball_Fx"), Fz = terrain_column(columns, "ball_Fz");
  SimulationOptions options;
  options.t_end = 1.0;
  options.output_step = 0.05;
  options.integrator.rtol = 1e-11;
  options.integrator.atol = 1e-13;
  std::vector<double> row;
  int rows = 0;
  const SimulationSummary summary = simulate(model, options, [&](const Data& data) {
    fill_result_row(model, data, row);
    const auto at = [&](int i) { return row[static_cast<std::size_t>(i)]; };
    const double t = data.t, s = a * t * t / 2;  // down the slope, d = -(cos(alpha), 0, sin(alpha))
    EXPECT_NEAR(data.q(0), -r * std::sin(alpha) - s * std::cos(alpha), 1e-10) << t;
    EXPECT_NEAR(data.q(1), 0.0, 1e-12);
    EXPECT_NEAR(data.q(2), r * std::cos(alpha) - s * std::sin(alpha), 1e-10) << t;
    EXPECT_NEAR(data.q(3), -s * std::cos(alpha), 1e-10) << t;  // the contact point's X
    EXPECT_NEAR(data.v(7), -a * t / r, 1e-9) << t;             // rolling about y
    EXPECT_NEAR(at(N), m * g * std::cos(alpha), 1e-10 * m * g);
    EXPECT_NEAR(at(Fx), -m * a * std::cos(alpha), 1e-10 * m * g);
    EXPECT_NEAR(at(Fz), m * (g - a * std::sin(alpha)), 1e-10 * m * g);
    EXPECT_NEAR(at(Z), at(X) * std::tan(alpha), 1e-12);
    ++rows;
  });
  EXPECT_EQ(rows, 21);
  EXPECT_LT(summary.energy.drift, 1e-12);
}

// Over a Gaussian bump, started off its axis with a velocity across it: the energy stays, the
// contact point is on the terrain, at the distance r from the centre, along the terrain's normal.
TEST(RollingTerrain, BallOverABumpKeepsItsEnergyAndTouchesTheTerrain) {
  const Model model = load_model_text(test::ball_on_terrain("H*exp(-(X^2 + Y^2)/w^2)", R"toml([initial]
position = { x = -0.6, y = 0.08, psi = 0, theta = 0, phi = 0 }
velocity = { x = 1.2, y = 0, phi = 12 }
)toml"));
  const double r = 0.1, H = 0.05, w = 0.3;
  const auto h = [&](double X, double Y) { return H * std::exp(-(X * X + Y * Y) / (w * w)); };
  const ResultColumns columns = make_result_columns(model);
  const int X = terrain_column(columns, "ball_X"), Y = terrain_column(columns, "ball_Y"), Z = terrain_column(columns, "ball_Z");
  SimulationOptions options;
  options.t_end = 1.0;
  options.output_step = 0.01;
  options.integrator.rtol = 1e-11;
  options.integrator.atol = 1e-13;
  options.fix_initial = true;  // the centre's height, u, v and the rolling velocities, left free, from the rest
  std::vector<double> row;
  double highest = 0.0, farthest_y = 0.0;
  const SimulationSummary summary = simulate(model, options, [&](const Data& data) {
    fill_result_row(model, data, row);
    const auto at = [&](int i) { return row[static_cast<std::size_t>(i)]; };
    const double px = at(X), py = at(Y), pz = at(Z);
    EXPECT_NEAR(pz, h(px, py), 1e-11);
    EXPECT_NEAR(px, data.q(3), 1e-11);
    EXPECT_NEAR(py, data.q(4), 1e-11);
    // C - P = r n, n = (-h_X, -h_Y, 1) / |...|.
    const double hx = -2 * px / (w * w) * h(px, py), hy = -2 * py / (w * w) * h(px, py);
    const double length = std::sqrt(1 + hx * hx + hy * hy);
    EXPECT_NEAR(data.q(0) - px, -r * hx / length, 1e-11);
    EXPECT_NEAR(data.q(1) - py, -r * hy / length, 1e-11);
    EXPECT_NEAR(data.q(2) - pz, r / length, 1e-11);
    highest = std::max(highest, pz);
    farthest_y = std::max(farthest_y, std::abs(data.q(1)));
  });
  ASSERT_TRUE(summary.initial_fix.has_value());
  EXPECT_GT(highest, 0.6 * H);     // it went over the bump, not around it
  EXPECT_GT(farthest_y, 0.1);      // and was deflected sideways
  EXPECT_LT(summary.energy.drift, 1e-10);
}

}  // namespace
}  // namespace nhdyn
