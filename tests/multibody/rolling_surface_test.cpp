// Bodies rolling on a fixed surface g(X, Y, Z) = 0 whose contact point is held by three
// coordinates (ground = { surface = ... } with any shape or any g, docs/derivations/rolling-bodies.md
// section 11): against the closed forms (a ball on a sphere, a ball on an incline, an ellipsoid on
// the plane), the elliptic paraboloid's two frequencies, the invariants in an ellipsoidal bowl,
// and the refusals.
#include <gtest/gtest.h>

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <complex>
#include <functional>
#include <string>
#include <vector>

#include "nhdyn/analysis/linearization.hpp"
#include "nhdyn/analysis/simulation.hpp"
#include "nhdyn/frontend/load_model.hpp"
#include "nhdyn/io/results.hpp"
#include "support/text.hpp"

namespace nhdyn {
namespace {

using test::example;
using test::replace_once;

int surface_column(const ResultColumns& columns, const std::string& name) {
  for (std::size_t i = 0; i < columns.all.size(); ++i)
    if (columns.all[i] == name) return static_cast<int>(i);
  ADD_FAILURE() << "no column " << name;
  return 0;
}

std::vector<std::vector<double>> surface_rows(const Model& model, const SimulationOptions& options,
                                              SimulationSummary* summary = nullptr) {
  std::vector<std::vector<double>> rows;
  std::vector<double> row;
  const SimulationSummary s = simulate(model, options, [&](const Data& data) {
    fill_result_row(model, data, row);
    rows.push_back(row);
  });
  if (summary) *summary = s;
  return rows;
}

std::string surface_error(const std::function<void()>& f) {
  try {
    f();
  } catch (const std::exception& e) {
    return e.what();
  }
  ADD_FAILURE() << "expected an error";
  return "";
}

// The largest difference of the columns both tables have, by name, row by row.
double largest_difference(const Model& a, const std::vector<std::vector<double>>& ra, const Model& b,
                          const std::vector<std::vector<double>>& rb, const std::vector<std::string>& names) {
  const ResultColumns ca = make_result_columns(a), cb = make_result_columns(b);
  EXPECT_EQ(ra.size(), rb.size());
  double worst = 0.0;
  for (const std::string& name : names) {
    const int i = surface_column(ca, name), j = surface_column(cb, name);
    for (std::size_t k = 0; k < std::min(ra.size(), rb.size()); ++k)
      worst = std::max(worst, std::abs(ra[k][static_cast<std::size_t>(i)] - rb[k][static_cast<std::size_t>(j)]));
  }
  return worst;
}

std::string text_of(const std::string& file) { return test::read_text(example(file)); }

// The bowl of examples/ball_in_bowl.toml with `coordinates` given: the contact point held by
// gx, gy, gz instead of the closed form. Every coordinate of the ball and its contact force agree.
TEST(RollingSurface, BallOnASphereHeldByCoordinatesFollowsTheClosedForm) {
  std::string text = text_of("ball_in_bowl.toml");
  replace_once(text, R"(coordinates = ["x", "y", "z", "a", "b", "c"])",
               R"(coordinates = ["x", "y", "z", "a", "b", "c", "gx", "gy", "gz"])");
  replace_once(text, R"(side = "inside" })", R"(side = "inside", coordinates = ["gx", "gy", "gz"] })");
  const Model closed = load_model(example("ball_in_bowl.toml"));
  const Model located = load_model_text(text);
  EXPECT_EQ(located.n(), closed.n() + 3);
  SimulationOptions options;
  options.t_end = 3.0;
  options.output_step = 0.05;
  options.integrator.rtol = 1e-11;
  options.integrator.atol = 1e-13;
  const auto a = surface_rows(closed, options);
  options.fix_initial = true;  // gx, gy, gz are written nowhere: moved onto the contact
  SimulationSummary summary;
  const auto b = surface_rows(located, options, &summary);
  EXPECT_LT(largest_difference(closed, a, located, b, {"x", "y", "z", "a", "b", "c", "x'", "b'"}), 1e-9);
  EXPECT_LT(largest_difference(closed, a, located, b, {"ball_N", "ball_Fx", "ball_Fz", "ball_X", "ball_Z"}), 1e-9);
  // The contact point's coordinates are the closed form's contact point.
  const ResultColumns columns = make_result_columns(located);
  for (const auto& row : b) {
    EXPECT_NEAR(row[static_cast<std::size_t>(surface_column(columns, "gx"))],
                row[static_cast<std::size_t>(surface_column(columns, "ball_X"))], 1e-11);
    EXPECT_NEAR(row[static_cast<std::size_t>(surface_column(columns, "gz"))],
                row[static_cast<std::size_t>(surface_column(columns, "ball_Z"))], 1e-11);
  }
  EXPECT_LT(summary.energy.drift, 1e-11);
}

// g = Z - X tan(alpha), the body where g > 0: the incline of rolling-bodies.md (6.8); the ball
// rolls down at 5/7 g sin(alpha), pressed by m g cos(alpha). nhdyn adds ball_gx, ball_gy, ball_gz.
TEST(RollingSurface, BallOnAnInclineWrittenAsASurfaceRollsAtFiveSevenths) {
  const Model model = load_model_text(R"toml(name = "ball-on-surface-incline"
coordinates = ["x", "y", "z", "psi", "theta", "phi"]
gravity = [0, 0, "-g"]

[parameters]
m = 1.5
r = 0.1
g = 9.81
alpha = 0.3

[[frames]]
name = "ball"
translation = ["x", "y", "z"]
rotations = [["z", "psi"], ["x", "theta"], ["y", "phi"]]

[[bodies]]
name = "ball"
frame = "ball"
mass = "m"
inertia = ["2/5*m*r^2", "2/5*m*r^2", "2/5*m*r^2"]

[[contacts]]
name = "ball"
body = "ball"
shape = { sphere = "r" }
ground = { surface = "Z - X*tan(alpha)", side = "outside" }

[initial]
position = { x = "-r*sin(alpha)", y = 0, z = "r*cos(alpha)", psi = 0, theta = 0, phi = 0 }
)toml");
  const double m = 1.5, r = 0.1, g = 9.81, alpha = 0.3, a = 5.0 / 7.0 * g * std::sin(alpha);
  ASSERT_EQ(model.n(), 9);
  EXPECT_EQ(model.coordinates[6], "ball_gx");
  const ResultColumns columns = make_result_columns(model);
  const int N = surface_column(columns, "ball_N"), X = surface_column(columns, "ball_X"),
            Z = surface_column(columns, "ball_Z"), Fx = surface_column(columns, "ball_Fx");
  SimulationOptions options;
  options.t_end = 1.0;
  options.output_step = 0.05;
  options.integrator.rtol = 1e-11;
  options.integrator.atol = 1e-13;
  std::vector<double> row;
  int rows = 0;
  simulate(model, options, [&](const Data& data) {
    fill_result_row(model, data, row);
    const auto at = [&](int i) { return row[static_cast<std::size_t>(i)]; };
    const double t = data.t, s = a * t * t / 2;
    EXPECT_NEAR(data.q(0), -r * std::sin(alpha) - s * std::cos(alpha), 1e-10) << t;
    EXPECT_NEAR(data.q(2), r * std::cos(alpha) - s * std::sin(alpha), 1e-10) << t;
    EXPECT_NEAR(data.q(6), -s * std::cos(alpha), 1e-10) << t;  // the contact point's X
    EXPECT_NEAR(data.q(8), data.q(6) * std::tan(alpha), 1e-12);  // on the incline
    EXPECT_NEAR(at(N), m * g * std::cos(alpha), 1e-10 * m * g);
    EXPECT_NEAR(at(Fx), -m * a * std::cos(alpha), 1e-10 * m * g);
    EXPECT_NEAR(at(Z), at(X) * std::tan(alpha), 1e-12);
    ++rows;
  });
  EXPECT_EQ(rows, 21);
}

// examples/ball_in_paraboloid.toml at rest at the bottom: two frequencies,
// omega_k^2 = g / ((1 + 2/5)(rho_k - r)) (rolling-bodies.md section 11, test iii); rolling in a
// sphere of radius rho_k would give the same.
TEST(RollingSurface, BallInAnEllipticParaboloidRocksAtItsTwoFrequencies) {
  const Model model = load_model(example("ball_in_paraboloid.toml"), {{"vx", 0.0}, {"vy", 0.0}});
  const double g = 9.81, r = 0.05, rho1 = 0.5, rho2 = 0.8;
  const double w1 = std::sqrt(g / (1.4 * (rho1 - r))), w2 = std::sqrt(g / (1.4 * (rho2 - r)));
  const Linearization l = calc_linearization(model);
  std::vector<double> w;
  for (const std::complex<double>& e : l.eigenvalues) {
    EXPECT_LT(std::abs(e.real()), 1e-9) << e;
    if (e.imag() > 1e-3) w.push_back(e.imag());
  }
  std::sort(w.begin(), w.end());
  ASSERT_EQ(w.size(), 2u);
  EXPECT_NEAR(w[0], w2, 1e-10 * w2);
  EXPECT_NEAR(w[1], w1, 1e-10 * w1);
}

// The example as shipped: the ball's energy, the contact point on the paraboloid, and the
// ball's centre at r along the bowl's normal from it.
TEST(RollingSurface, BallInAnEllipticParaboloidKeepsItsEnergyAndItsContact) {
  const Model model = load_model(example("ball_in_paraboloid.toml"));
  const double r = 0.05, rho1 = 0.5, rho2 = 0.8;
  const ResultColumns columns = make_result_columns(model);
  const int X = surface_column(columns, "ball_X"), Y = surface_column(columns, "ball_Y"),
            Z = surface_column(columns, "ball_Z"), N = surface_column(columns, "ball_N");
  SimulationOptions options;
  options.t_end = 6.0;
  options.output_step = 0.02;
  options.integrator.rtol = 1e-11;
  options.integrator.atol = 1e-13;
  SimulationSummary summary;
  double farthest_x = 0.0, farthest_y = 0.0;
  for (const auto& row : surface_rows(model, options, &summary)) {
    const double px = row[static_cast<std::size_t>(X)], py = row[static_cast<std::size_t>(Y)],
                 pz = row[static_cast<std::size_t>(Z)];
    EXPECT_NEAR(pz, px * px / (2 * rho1) + py * py / (2 * rho2), 1e-12);
    const double nx = -px / rho1, ny = -py / rho2, length = std::sqrt(nx * nx + ny * ny + 1);
    EXPECT_NEAR(row[1] - px, r * nx / length, 1e-11);
    EXPECT_NEAR(row[2] - py, r * ny / length, 1e-11);
    EXPECT_NEAR(row[3] - pz, r / length, 1e-11);
    EXPECT_GT(row[static_cast<std::size_t>(N)], 0.0);
    farthest_x = std::max(farthest_x, std::abs(px));
    farthest_y = std::max(farthest_y, std::abs(py));
  }
  // It went both ways: along X by about vx/omega_1, along Y by about vy/omega_2.
  EXPECT_GT(farthest_x, 0.015);
  EXPECT_GT(farthest_y, 0.012);
  EXPECT_LT(summary.energy.drift, 1e-11);
}

// examples/ellipsoid_rocking.toml on the surface Z = 0 (g = Z, the body where g > 0) instead of
// the plane: the same motion and contact force, the contact point held by coordinates.
TEST(RollingSurface, EllipsoidOnTheSurfaceZFollowsTheEllipsoidOnThePlane) {
  std::string text = text_of("ellipsoid_rocking.toml");
  replace_once(text, R"(shape = { ellipsoid = ["a", "b", "c"] })",
               "shape = { ellipsoid = [\"a\", \"b\", \"c\"] }\nground = { surface = \"Z\", side = \"outside\" }");
  const Model plane = load_model(example("ellipsoid_rocking.toml"));
  const Model surface = load_model_text(text);
  EXPECT_EQ(surface.n(), plane.n() + 3);
  SimulationOptions options;
  options.t_end = 2.0;
  options.output_step = 0.02;
  options.integrator.rtol = 1e-11;
  options.integrator.atol = 1e-13;
  const auto a = surface_rows(plane, options);
  const auto b = surface_rows(surface, options);
  EXPECT_LT(largest_difference(plane, a, surface, b, {"x", "y", "z", "psi", "theta", "phi", "phi'"}), 1e-9);
  EXPECT_LT(largest_difference(plane, a, surface, b, {"foot_N", "foot_Fx", "foot_Fy", "foot_X", "foot_Y"}), 1e-8);
}

// An ellipsoid rolling in an ellipsoidal bowl (no closed form on either side): the energy, the
// contact point on the bowl, and the body's touching point there.
TEST(RollingSurface, EllipsoidInAnEllipsoidalBowlKeepsItsEnergyAndItsContact) {
  std::string text = text_of("ellipsoid_rocking.toml");
  replace_once(text, R"(shape = { ellipsoid = ["a", "b", "c"] })",
               "shape = { ellipsoid = [\"a\", \"b\", \"c\"] }\n"
               "ground = { surface = \"X^2/A^2 + Y^2/B^2 + (Z - C)^2/C^2 - 1\", side = \"inside\" }");
  replace_once(text, "[parameters]\n", "[parameters]\nA = 1.2\nB = 0.9\nC = 0.7\n");
  replace_once(text, R"x(z = "sqrt(a^2*sin(tilt)^2 + c^2*cos(tilt)^2)", psi = 0, theta = 0,)x", "psi = 0.2, theta = 0.05,");
  const Model model = load_model_text(text);
  const ResultColumns columns = make_result_columns(model);
  const int X = surface_column(columns, "foot_X"), Y = surface_column(columns, "foot_Y"),
            Z = surface_column(columns, "foot_Z"), gx = surface_column(columns, "foot_gx"),
            gz = surface_column(columns, "foot_gz");
  SimulationOptions options;
  options.t_end = 2.0;
  options.output_step = 0.02;
  options.integrator.rtol = 1e-11;
  options.integrator.atol = 1e-13;
  options.fix_initial = true;  // z left out: put onto the bowl
  SimulationSummary summary;
  double farthest = 0.0;
  for (const auto& row : surface_rows(model, options, &summary)) {
    const auto at = [&](int i) { return row[static_cast<std::size_t>(i)]; };
    const double A = 1.2, B = 0.9, C = 0.7;
    const double px = at(X), py = at(Y), pz = at(Z);
    EXPECT_NEAR(px * px / (A * A) + py * py / (B * B) + (pz - C) * (pz - C) / (C * C), 1.0, 1e-11);
    EXPECT_NEAR(at(gx), px, 1e-11);
    EXPECT_NEAR(at(gz), pz, 1e-11);
    farthest = std::max(farthest, std::abs(px));
  }
  ASSERT_TRUE(summary.initial_fix.has_value());
  EXPECT_GT(farthest, 0.02);  // it rocked
  EXPECT_LT(summary.energy.drift, 1e-10);
}

// The same bowl written at other scales, 1e4 g and 1e-6 g, and as a function with a root where
// the ball never goes (not a polynomial): the same motion. The rows that hold the contact point
// are in length units whatever g's scale (rolling-bodies.md section 11).
TEST(RollingSurface, TheScaleAndTheFormOfGDoNotChangeTheMotion) {
  const std::string base = text_of("ball_in_paraboloid.toml");
  const std::string written = R"x(surface = "X^2/(2*rho1) + Y^2/(2*rho2) - Z")x";
  SimulationOptions options;
  options.t_end = 2.0;
  options.output_step = 0.05;
  options.integrator.rtol = 1e-11;
  options.integrator.atol = 1e-13;
  const Model reference = load_model(example("ball_in_paraboloid.toml"));
  const auto a = surface_rows(reference, options);
  for (const std::string& g : std::vector<std::string>{R"x(surface = "1e4*(X^2/(2*rho1) + Y^2/(2*rho2) - Z)")x",
                                                       R"x(surface = "1e-6*(X^2/(2*rho1) + Y^2/(2*rho2) - Z)")x",
                                                       R"x(surface = "(X^2/(2*rho1) + Y^2/(2*rho2) - Z)*sqrt(4 + X^2)")x"}) {
    std::string text = base;
    replace_once(text, written, g);
    const Model model = load_model_text(text);
    const auto b = surface_rows(model, options);
    EXPECT_LT(largest_difference(reference, a, model, b, {"x", "y", "z", "a", "b", "c", "ball_N"}), 1e-9) << g;
  }
}

// A ball rolling at the start, told to start sliding, on the plane written as a surface: no
// direction of sliding is defined (rolling needs no friction), as on the plane itself.
TEST(RollingSurface, StartingToSlideWhereRollingNeedsNoFrictionIsRefused) {
  std::string text = text_of("ball_in_paraboloid.toml");
  replace_once(text, R"(ground = { surface = "X^2/(2*rho1) + Y^2/(2*rho2) - Z", side = "inside" })",
               "ground = { surface = \"Z\", side = \"outside\" }\nfriction = 0.3\nmode = \"sliding\"");
  const Model model = load_model_text(text);
  SimulationOptions options;
  options.t_end = 0.5;
  const std::string m = surface_error([&] { simulate(model, options, [](const Data&) {}); });
  EXPECT_NE(m.find("no direction of sliding is defined"), std::string::npos) << m;
}

// A ball climbing an ellipsoidal bowl's wall to where its normal is horizontal along x, the axis
// the rolling rows' directions are built from: the run ends there with the reason, not with a
// ball falling through the bowl.
TEST(RollingSurface, ANormalAlongTheTangentsAxisEndsTheRun) {
  std::string text = text_of("ball_in_paraboloid.toml");
  replace_once(text, R"(ground = { surface = "X^2/(2*rho1) + Y^2/(2*rho2) - Z", side = "inside" })",
               R"(ground = { surface = "X^2/0.09 + Y^2/0.04 + (Z - 0.15)^2/0.0225 - 1", side = "inside" })");
  // Rolling along x turns the ball about y without end: y first, so that its angles stay regular.
  replace_once(text, R"(rotations = [["x", "a"], ["y", "b"], ["z", "c"]])", R"(rotations = [["y", "b"], ["x", "a"], ["z", "c"]])");
  replace_once(text, R"(vx = { value = 0.08)", R"(vx = { value = 3.0)");
  replace_once(text, R"(vy = { value = 0.05)", R"(vy = { value = 0.0)");
  const Model model = load_model_text(text);
  SimulationOptions options;
  options.t_end = 1.0;
  options.output_step = 0.01;
  double last = 0.0;
  const SimulationSummary summary = simulate(model, options, [&](const Data& data) { last = data.t; });
  EXPECT_NE(summary.status, Status::ok);
  EXPECT_NE(summary.message.find("the ground's normal turns along the world's x axis"), std::string::npos)
      << summary.message;
  EXPECT_NE(summary.message.find("1 - (e . n)^2 = "), std::string::npos) << summary.message;
  EXPECT_GT(last, 0.05);
  EXPECT_LT(last, 0.2);
}

// A ball rolling up the quartic hollow Z = X^4 / L^3, flat at the bottom (the start's check
// passes) and more curved than the ball higher up: the run ends where the hollow's curvature
// k(X) = Z'' / (1 + Z'^2)^(3/2) reaches 1/r, naming the contact, not with a step-size underflow or
// a ball cutting into the wall; slower, the ball turns back below that point and runs to the end.
TEST(RollingSurface, AHollowMoreCurvedThanTheBallMetAlongTheRunEndsItThere) {
  std::string text = text_of("ball_in_paraboloid.toml");
  replace_once(text, R"(ground = { surface = "X^2/(2*rho1) + Y^2/(2*rho2) - Z", side = "inside" })",
               R"(ground = { surface = "X^4/L^3 - Z", side = "inside" })");
  replace_once(text, "[parameters]\n", "[parameters]\nL = 0.1\n");
  replace_once(text, R"(vy = { value = 0.05)", R"(vy = { value = 0.0)");
  const double L = 0.1, r = 0.05;
  // The hollow's curvature at X, and X* where it equals 1/r (it grows with X up to past X*).
  const auto curvature = [&](double X) {
    const double slope = 4 * X * X * X / (L * L * L), second = 12 * X * X / (L * L * L);
    return second / std::pow(1 + slope * slope, 1.5);
  };
  double lo = 0.0, hi = 0.06;
  for (int i = 0; i < 100; ++i) (curvature(0.5 * (lo + hi)) < 1 / r ? lo : hi) = 0.5 * (lo + hi);
  const double X_star = 0.5 * (lo + hi);
  ASSERT_GT(curvature(0.9 * X_star), 0.0);
  ASSERT_LT(curvature(0.9 * X_star), 1 / r);

  SimulationOptions options;
  options.t_end = 1.0;
  options.output_step = 0.001;
  {
    std::string fast = text;
    replace_once(fast, R"(vx = { value = 0.08)", R"(vx = { value = 1.0)");
    const Model model = load_model_text(fast);
    const int gx = surface_column(make_result_columns(model), "ball_gx");
    SimulationSummary summary;
    const auto rows = surface_rows(model, options, &summary);
    EXPECT_EQ(summary.status, Status::singular_system) << summary.message;
    EXPECT_NE(summary.message.find("contact 'ball': the ground's hollow is as curved as the shape here"),
              std::string::npos)
        << summary.message;
    EXPECT_NE(summary.message.find("det(K_shape - K_ground) / (tr K_shape / 2)^2 on the tangent plane = "),
              std::string::npos)
        << summary.message;
    // Stopped where 1 - r k < 1e-4 (the ground is flat along Y): the contact point X, which the
    // message's state gives, within about 1e-4 of X* (k'(X) X / k is about 2 there).
    const std::size_t at = summary.message.find("ball_gx = ");
    ASSERT_NE(at, std::string::npos) << summary.message;
    const double stopped = std::stod(summary.message.substr(at + 10));
    EXPECT_GT(stopped, (1 - 2e-4) * X_star) << summary.message;
    EXPECT_LT(stopped, X_star) << summary.message;
    ASSERT_FALSE(rows.empty());
    for (const auto& row : rows) EXPECT_LT(row[static_cast<std::size_t>(gx)], stopped);
  }
  {
    std::string slow = text;
    replace_once(slow, R"(vx = { value = 0.08)", R"(vx = { value = 0.1)");
    const Model model = load_model_text(slow);
    const int gx = surface_column(make_result_columns(model), "ball_gx");
    SimulationSummary summary;
    double farthest = 0.0;
    for (const auto& row : surface_rows(model, options, &summary))
      farthest = std::max(farthest, row[static_cast<std::size_t>(gx)]);
    EXPECT_EQ(summary.status, Status::ok) << summary.message;
    EXPECT_GT(farthest, 0.3 * X_star);
    EXPECT_LT(farthest, 0.9 * X_star);
  }
  {
    // Unilateral, thrown up from 1 cm above the bottom: in the air the gap is measured from the
    // ground's point below the centre, the nearest only while the centre's distance d = r + gap is
    // below the hollow's radius of curvature there. The run ends where d k(X_U) reaches 1 (the
    // ground is flat along Y), naming the flight, and before any convexity check of a touching ball.
    std::string flying = text;
    replace_once(flying, R"(side = "inside" })", "side = \"inside\" }\nunilateral = true");
    replace_once(flying, R"(vx = { value = 0.08)", R"(vx = { value = 0.3)");
    replace_once(flying, R"(z = "r",)", R"(z = "r + 0.01",)");
    replace_once(flying, R"(velocity = { x = "vx", y = "vy", z = 0,)", R"(velocity = { x = "vx", y = "vy", z = 2,)");
    const Model model = load_model_text(flying);
    SimulationSummary summary;
    surface_rows(model, options, &summary);
    EXPECT_NE(summary.status, Status::ok);
    const std::string& m = summary.message;
    EXPECT_NE(m.find("contact 'ball': the ball flies farther from the ground than the ground's radius of curvature"),
              std::string::npos)
        << m;
    const auto value = [&](const std::string& key) {
      const std::size_t at = m.find(key);
      EXPECT_NE(at, std::string::npos) << m << "\n  lacks: " << key;
      return at == std::string::npos ? 0.0 : std::stod(m.substr(at + key.size()));
    };
    const double x = value("where x = "), z = value(", z = "), gx = value("ball_gx = "), gz = value("ball_gz = ");
    EXPECT_NEAR(std::hypot(x - gx, z - gz) * curvature(gx), 1.0, 1e-3) << m;
  }
}

// The closed-form ellipsoid is held against the bowl's curvature as a ball is: at its lowest
// point (0, 0, -c) its principal curvatures are c/a^2 = 2.5 and c/b^2 = 4.44444 (a = 0.2,
// b = 0.15, c = 0.1); the ellipsoidal bowl X^2/A^2 + Y^2/B^2 + (Z - C)^2/C^2 = 1 has C/A^2 and
// C/B^2 at its bottom. With A = B = C = 0.3 (3.33333 both) the ellipsoid is flatter along x and
// the start is refused naming both.
TEST(RollingSurface, AnEllipsoidFlatterThanItsBowlIsRefusedWithBothCurvatures) {
  const auto in_bowl = [&](double A, double B, double C) {
    std::string text = text_of("ellipsoid_rocking.toml");
    replace_once(text, R"(shape = { ellipsoid = ["a", "b", "c"] })",
                 "shape = { ellipsoid = [\"a\", \"b\", \"c\"] }\n"
                 "ground = { surface = \"X^2/A^2 + Y^2/B^2 + (Z - C)^2/C^2 - 1\", side = \"inside\" }");
    replace_once(text, "[parameters]\n",
                 fmt::format("[parameters]\nA = {}\nB = {}\nC = {}\n", A, B, C));
    return text;
  };
  const std::string m = surface_error([&] { load_model_text(in_bowl(0.3, 0.3, 0.3), "bowl.toml", {{"tilt", 0.0}}); });
  for (const std::string part : {"bowl.toml:", "contact 'foot'", "flatter than the hollow", "2.5 and 4.44444",
                                 "-0.833333 and 1.11111"})
    EXPECT_NE(m.find(part), std::string::npos) << m << "\n  lacks: " << part;
  // A bowl curved 3.33333 along X and 0.833333 along Y (A = C = 0.3, B = 0.6): the ellipsoid along
  // X is refused (-0.833333 and 3.61111); turned a quarter about z it lies with its b axis along X
  // (4.44444 against 3.33333, 2.5 against 0.833333), is accepted, and rocks.
  const std::string narrow = in_bowl(0.3, 0.6, 0.3);
  const std::string m2 = surface_error([&] { load_model_text(narrow, "bowl.toml", {{"tilt", 0.0}}); });
  EXPECT_NE(m2.find("-0.833333 and 3.61111"), std::string::npos) << m2;
  std::string turned = narrow;
  replace_once(turned, "psi = 0, theta = 0", "psi = 1.5707963267948966, theta = 0");
  const Model model = load_model_text(turned, "bowl.toml", {{"tilt", 0.0}});
  SimulationOptions options;
  options.t_end = 0.2;
  options.output_step = 0.01;
  SimulationSummary summary;
  surface_rows(model, options, &summary);
  EXPECT_EQ(summary.status, Status::ok) << summary.message;
}

// A torus (R = 0.3, tube r = 0.05, axle y) in a spherical bowl of radius Rb: upright, its
// curvatures at the bottom are 1/(R + r) = 2.85714 along the rim and 1/r = 20 across (section 11),
// so a bowl of 0.34 (2.94118) is refused with -0.0840336 and 17.0588 left, one of 1 is accepted.
// Leaned by 0.5 in a bowl of 0.4 it starts (k_t = c / (R + r c) = 2.552, c = cos 0.5) and leans
// further as it falls, until k_t reaches 1/Rb: the run ends there, and the measure it names is
// (k_t - 1/Rb)(1/r - 1/Rb) / ((k_t + 1/r) / 2)^2 computed from the state it names.
TEST(RollingSurface, ATorusFlatterThanItsBowlIsRefusedAtTheStartAndStoppedAlongTheRun) {
  const auto torus = [](double Rb, double lean) {
    return fmt::format(R"toml(name = "torus-in-bowl"
coordinates = ["x", "y", "z", "psi", "theta", "phi"]
gravity = [0, 0, "-g"]

[parameters]
m = 2.0
J = 0.07
K = 0.05
R = 0.3
r = 0.05
g = 9.81
Rb = {}
lean = {}

[[frames]]
name = "wheel"
translation = ["x", "y", "z"]
rotations = [["z", "psi"], ["x", "theta"], ["y", "phi"]]

[[bodies]]
name = "wheel"
frame = "wheel"
mass = "m"
inertia = ["K", "J", "K"]

[[contacts]]
name = "tyre"
body = "wheel"
shape = {{ torus = ["R", "r"], axis = "y" }}
ground = {{ surface = "X^2 + Y^2 + (Z - Rb)^2 - Rb^2", side = "inside" }}

[initial]
position = {{ x = 0, y = "-R*sin(lean)", z = "R*cos(lean) + r", psi = 0, theta = "lean", phi = 0 }}
)toml",
                       Rb, lean);
  };
  const std::string m = surface_error([&] { load_model_text(torus(0.34, 0.0), "torus.toml"); });
  for (const std::string part : {"torus.toml:", "contact 'tyre'", "flatter than the hollow", "2.85714 and 20",
                                 "-0.0840336 and 17.0588"})
    EXPECT_NE(m.find(part), std::string::npos) << m << "\n  lacks: " << part;
  SimulationOptions options;
  options.t_end = 0.5;
  options.output_step = 0.01;
  SimulationSummary summary;
  surface_rows(load_model_text(torus(1.0, 0.0), "torus.toml"), options, &summary);
  EXPECT_EQ(summary.status, Status::ok) << summary.message;

  surface_rows(load_model_text(torus(0.4, 0.5), "torus.toml"), options, &summary);
  ASSERT_NE(summary.status, Status::ok);
  const std::string& stop = summary.message;
  EXPECT_NE(stop.find("the ground's hollow is as curved as the shape here"), std::string::npos) << stop;
  const auto named = [&](const std::string& key) {
    const std::size_t at = stop.find(key + " = ");
    EXPECT_NE(at, std::string::npos) << key << " in " << stop;
    return at == std::string::npos ? 0.0 : std::stod(stop.substr(at + key.size() + 3));
  };
  const double theta = named("theta"), gy = named("tyre_gy"), gz = named("tyre_gz");
  const double Rb = 0.4, R = 0.3, r = 0.05;
  // The bowl's inward unit normal at the contact point, and the axle (0, cos theta, sin theta).
  const double nx = 0.0, ny = -gy / Rb, nz = (Rb - gz) / Rb;
  const double en = std::cos(theta) * ny + std::sin(theta) * nz;
  const double c = std::sqrt(1.0 - en * en / (nx * nx + ny * ny + nz * nz));
  const double k_t = c / (R + r * c);
  const double measure = (k_t - 1 / Rb) * (1 / r - 1 / Rb) / std::pow((k_t + 1 / r) / 2, 2);
  const std::size_t at = stop.find("on the tangent plane = ");
  ASSERT_NE(at, std::string::npos) << stop;
  EXPECT_NEAR(std::stod(stop.substr(at + 23)), measure, 2e-5) << stop;
  // Located as an event: the run stops where the measure reaches its limit 1e-4, not a step past
  // it (the state is printed to 6 digits).
  EXPECT_NEAR(measure, 1e-4, 5e-6) << stop;
  EXPECT_GT(theta, 0.53);  // leaned further than at the start
}

// A thin disk (R = 0.3, axle y) in a spherical bowl of radius Rb: infinitely curved across its
// rim, so only the rim's curvature along it counts, |e x n| / R (section 11; the torus's with no
// tube). Upright it is 1/R = 3.33333 against the bowl's 1/Rb: a bowl of 0.29 (3.44828) is refused
// naming both, one of 1 is accepted. Leaned by 0.5 in a bowl of 0.36 it starts (c / R = 2.92528,
// c = cos 0.5, against 2.77778), leans further as it falls, and the run ends where c / R reaches
// 1/Rb, with the measure it names equal to the closed form from the state it names.
TEST(RollingSurface, ADiskWhoseRimIsFlatterThanItsBowlIsRefusedAtTheStartAndStoppedAlongTheRun) {
  const auto disk = [](double Rb, double lean) {
    return fmt::format(R"toml(name = "disk-in-bowl"
coordinates = ["x", "y", "z", "psi", "theta", "phi"]
gravity = [0, 0, "-g"]

[parameters]
m = 2.0
J = 0.09
K = 0.045
R = 0.3
g = 9.81
Rb = {}
lean = {}

[[frames]]
name = "wheel"
translation = ["x", "y", "z"]
rotations = [["z", "psi"], ["x", "theta"], ["y", "phi"]]

[[bodies]]
name = "wheel"
frame = "wheel"
mass = "m"
inertia = ["K", "J", "K"]

[[contacts]]
name = "rim"
body = "wheel"
shape = {{ disk = "R", axis = "y" }}
ground = {{ surface = "X^2 + Y^2 + (Z - Rb)^2 - Rb^2", side = "inside" }}

[initial]
position = {{ x = 0, y = "-R*sin(lean)", z = "R*cos(lean)", psi = 0, theta = "lean", phi = 0 }}
)toml",
                       Rb, lean);
  };
  const std::string m = surface_error([&] { load_model_text(disk(0.29, 0.0), "disk.toml"); });
  for (const std::string part : {"disk.toml:", "contact 'rim'", "the disk's rim is flatter than the hollow",
                                 "curvature is 3.33333", "the ground's 3.44828"})
    EXPECT_NE(m.find(part), std::string::npos) << m << "\n  lacks: " << part;
  SimulationOptions options;
  options.t_end = 0.5;
  options.output_step = 0.01;
  SimulationSummary summary;
  surface_rows(load_model_text(disk(1.0, 0.0), "disk.toml"), options, &summary);
  EXPECT_EQ(summary.status, Status::ok) << summary.message;

  surface_rows(load_model_text(disk(0.36, 0.5), "disk.toml"), options, &summary);
  ASSERT_NE(summary.status, Status::ok);
  const std::string& stop = summary.message;
  EXPECT_NE(stop.find("the ground's hollow is as curved as the disk's rim here"), std::string::npos) << stop;
  const auto named = [&](const std::string& key) {
    const std::size_t at = stop.find(key + " = ");
    EXPECT_NE(at, std::string::npos) << key << " in " << stop;
    return at == std::string::npos ? 0.0 : std::stod(stop.substr(at + key.size() + 3));
  };
  const double x = named("x"), y = named("y"), z = named("z"), theta = named("theta");
  const double px = named("rim_gx"), py = named("rim_gy"), pz = named("rim_gz");
  const double Rb = 0.36, R = 0.3;
  // In a sphere the contact point P is the rim point farthest from the sphere's centre O, at the
  // distance s + R, s = d_perp . (P - C) / R the part of d = C - O in the disk's plane along the
  // way to P; the ground's normal there makes c = (s + R) / Rb with that plane, so
  // 1 - R / (Rb c) = s / (s + R): 0 where O is on the axle line and the whole rim lies on the
  // sphere, negative past it. The axle is (0, cos theta, sin theta): psi stays 0 by symmetry.
  const double ey = std::cos(theta), ez = std::sin(theta);
  const double dx = x, dy = y, dz = z - Rb;
  const double along = dy * ey + dz * ez;
  const double qx = dx, qy = dy - along * ey, qz = dz - along * ez;  // d_perp
  const double sp = (qx * (px - x) + qy * (py - y) + qz * (pz - z)) / R;
  const double measure = sp / (sp + R);
  const std::size_t at = stop.find("along the rim = ");
  ASSERT_NE(at, std::string::npos) << stop;
  EXPECT_NEAR(std::stod(stop.substr(at + 16)), measure, 2e-5) << stop;
  // Located at the limit (section 11), not a step past it; the closed form from the state printed
  // to 6 digits is good to a few 1e-6.
  EXPECT_NEAR(measure, 1e-4, 5e-6) << stop;
  EXPECT_NEAR(std::hypot(px - x, py - y, pz - z), R, 1e-5);  // P on the rim (the state printed to 6 digits)
  EXPECT_GT(theta, 0.55);  // leaned further than at the start

  // A paraboloid curved 1/a along x (the rim's direction at the bottom) and 1/b across: the disk
  // leaned by 0.5 (rim curvature cos(0.5) / R = 2.92528) is refused where 1/a = 4, and accepted
  // with a and b swapped (0.5 along the rim; the 4 across it does not count).
  const auto paraboloid = [&](double a, double b) {
    std::string text = disk(1.0, 0.5);
    replace_once(text, R"(ground = { surface = "X^2 + Y^2 + (Z - Rb)^2 - Rb^2", side = "inside" })",
                 fmt::format(R"(ground = {{ surface = "X^2/(2*{}) + Y^2/(2*{}) - Z", side = "inside" }})", a, b));
    return text;
  };
  const std::string refused = surface_error([&] { load_model_text(paraboloid(0.25, 2.0), "disk.toml"); });
  for (const std::string part : {"the disk's rim is flatter than the hollow", "curvature is 2.92528", "the ground's 4 "})
    EXPECT_NE(refused.find(part), std::string::npos) << refused << "\n  lacks: " << part;
  options.t_end = 0.05;
  surface_rows(load_model_text(paraboloid(2.0, 0.25), "disk.toml"), options, &summary);
  EXPECT_EQ(summary.status, Status::ok) << summary.message;
}

// Refusals, each naming the file's line and what to do.
TEST(RollingSurface, BadSurfacesAreRefusedByName) {
  const std::string base = text_of("ball_in_paraboloid.toml");
  const std::string ground = R"(ground = { surface = "X^2/(2*rho1) + Y^2/(2*rho2) - Z", side = "inside" })";
  const auto with = [&](const std::string& replacement) {
    std::string text = base;
    replace_once(text, ground, replacement);
    return text;
  };
  std::string m = surface_error([&] { load_model_text(with(R"(ground = { surface = "abs(X)/rho1 - Z", side = "inside" })")); });
  EXPECT_NE(m.find("is not differentiable"), std::string::npos) << m;
  EXPECT_NE(m.find("contact 'ball'"), std::string::npos) << m;
  m = surface_error([&] { load_model_text(with(R"(ground = { surface = "X^2 - Z + x", side = "inside" })")); });
  EXPECT_NE(m.find("depends on t or on a coordinate"), std::string::npos) << m;
  m = surface_error([&] { load_model_text(with(R"(ground = { surface = "rho1", side = "inside" })")); });
  EXPECT_NE(m.find("does not depend on X, Y or Z"), std::string::npos) << m;
  m = surface_error([&] {
    load_model_text(with(R"(ground = { surface = "X^2 - Z", side = "inside", coordinates = ["x", "y"] })"));
  });
  EXPECT_NE(m.find("needs the 3 coordinates"), std::string::npos) << m;
  m = surface_error([&] { load_model_text(with(R"(ground = { surface = "X^2 - Z" })")); });
  EXPECT_NE(m.find("needs side"), std::string::npos) << m;
  // An empty list of coordinates is not the key left out (which would add them).
  m = surface_error([&] {
    load_model_text(with(R"(ground = { surface = "X^2 - Z", side = "inside", coordinates = [] })"));
  });
  EXPECT_NE(m.find("ground.coordinates = [] is empty"), std::string::npos) << m;
  EXPECT_NE(m.find("contact 'ball'"), std::string::npos) << m;
  // The wrong side: the start's gap of about -2 r is explained by the side.
  m = surface_error([&] {
    const Model model = load_model_text(with(R"(ground = { surface = "X^2/(2*rho1) + Y^2/(2*rho2) - Z", side = "outside" })"));
    SimulationOptions options;
    options.t_end = 0.1;
    simulate(model, options, [](const Data&) {});
  });
  EXPECT_NE(m.find("ball_contact (position level): residual -0.1"), std::string::npos) << m;
  EXPECT_NE(m.find("the body is where g > 0 (side = \"outside\")"), std::string::npos) << m;
  // A ball flatter than the hollow it starts in: the contact would not be unique.
  m = surface_error([&] { load_model(example("ball_in_paraboloid.toml"), {{"r", 0.6}}); });
  EXPECT_NE(m.find("flatter than the hollow"), std::string::npos) << m;
  EXPECT_NE(m.find("ball_in_paraboloid.toml:"), std::string::npos) << m;
  EXPECT_NE(m.find("-0.333333"), std::string::npos) << m;  // 1/r - 1/rho1
}

}  // namespace
}  // namespace nhdyn
