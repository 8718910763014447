// Contacts that slide and stick ([[contacts]] with friction, docs/contact-modes.md): bodies thrown
// sliding on a plane against the closed forms of docs/derivations/contact-modes.md section 10.1
// (the time they start rolling, their final speed, the friction's work), the energy balance
// through the switch, and the keys' bad values.
#include <fmt/format.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <string>
#include <vector>

#include "nhdyn/analysis/simulation.hpp"
#include "nhdyn/core/error.hpp"
#include "nhdyn/frontend/load_model.hpp"
#include "nhdyn/io/results.hpp"
#include "nhdyn/model/parameters.hpp"
#include "support/models.hpp"
#include "support/text.hpp"

namespace nhdyn {
namespace {

using nhdyn::test::example;

double mode_parameter(const Model& model, const std::string& name) {
  for (const Parameter& p : model.parameters)
    if (p.name == name) return p.value;
  ADD_FAILURE() << "no parameter " << name;
  return 0.0;
}

int mode_column(const ResultColumns& columns, const std::string& name) {
  for (std::size_t i = 0; i < columns.all.size(); ++i)
    if (columns.all[i] == name) return static_cast<int>(i);
  ADD_FAILURE() << "no column " << name;
  return 0;
}

struct ModeRun {
  SimulationSummary summary;
  ResultColumns columns;
  std::vector<std::vector<double>> rows;
  double at(std::size_t row, const std::string& name) const {
    return rows.at(row).at(static_cast<std::size_t>(mode_column(columns, name)));
  }
};

ModeRun run_modes(const Model& model, double t_end, double atol = 1e-12) {
  ModeRun out;
  out.columns = make_result_columns(model);
  SimulationOptions options;
  options.t_end = t_end;
  options.output_step = 0.01;
  options.integrator.rtol = 1e-10;
  options.integrator.atol = atol;
  out.summary = simulate(model, options, [&](const Data& data) {
    std::vector<double> row;
    fill_result_row(model, data, row);
    out.rows.push_back(std::move(row));
  });
  EXPECT_EQ(out.summary.status, Status::ok) << out.summary.message;
  return out;
}

// The tippe top of examples/tippe_top.toml with every length times `scale` (its radius and g; the
// time unchanged), for its first `t_end` seconds, sliding: the results in the example's units
// (z / scale; the quaternion has none).
ModeRun run_scaled_tippe_top(double scale, double t_end) {
  const Model model = load_model(example("tippe_top.toml"), {{"R", 0.02 * scale}, {"g", 9.81 * scale}});
  ModeRun out = run_modes(model, t_end, 1e-13 * std::min(1.0, scale));
  const std::size_t z = static_cast<std::size_t>(mode_column(out.columns, "z"));
  for (std::vector<double>& row : out.rows) row.at(z) /= scale;
  return out;
}

// The row written at the only switch (an event row).
std::size_t mode_switch_row(const ModeRun& r, double t) {
  for (std::size_t i = 0; i < r.rows.size(); ++i)
    if (r.rows[i][0] == t) return i;
  ADD_FAILURE() << "no row at the switch t = " << t;
  return 0;
}

// Section 10.1, a solid ball thrown without spin: t* = 2 v0 / (7 mu g), then it rolls at 5 v0 / 7;
// the friction's work is -m v0^2 / 7, all the kinetic energy lost.
TEST(ContactModes, BallThrownSlidingSticksAtTheClosedFormTimeAndRollsAtFiveSevenths) {
  const Model model = load_model(example("ball_thrown_sliding.toml"));
  const double m = mode_parameter(model, "m"), g = mode_parameter(model, "g"), mu = mode_parameter(model, "mu");
  const double v0 = mode_parameter(model, "v0");
  const ModeRun r = run_modes(model, 1.0);
  ASSERT_EQ(r.summary.events.crossings.size(), 1u);
  EXPECT_EQ(r.summary.events.crossings[0].name, "ball_stick");
  const double t_star = 2 * v0 / (7 * mu * g);
  EXPECT_NEAR(t_star, 0.3495, 1e-4);  // the derivation's test value
  EXPECT_NEAR(r.summary.events.crossings[0].t, t_star, 1e-12);
  // Until t* the centre decelerates at mu g: x(t*) = v0 t* - mu g t*^2 / 2.
  EXPECT_NEAR(r.summary.events.crossings[0].q[0], v0 * t_star - mu * g * t_star * t_star / 2, 1e-11);
  const std::size_t s = mode_switch_row(r, r.summary.events.crossings[0].t);
  EXPECT_EQ(r.at(s, "ball_mode"), 0.0);  // a switch row carries the mode after it
  EXPECT_EQ(r.at(s - 1, "ball_mode"), 1.0);
  EXPECT_EQ(r.at(0, "ball_mode"), 1.0);
  EXPECT_NEAR(r.at(0, "ball_slip_speed"), v0, 1e-12);
  EXPECT_NEAR(r.at(0, "ball_slip_x"), v0, 1e-12);
  EXPECT_NEAR(r.at(0, "ball_N"), m * g, 1e-12);
  EXPECT_NEAR(r.at(0, "ball_Fx"), -mu * m * g, 1e-12);
  EXPECT_NEAR(r.at(s, "ball_slip_speed"), 0.0, 1e-12);
  const std::size_t last = r.rows.size() - 1;
  EXPECT_NEAR(r.at(last, "x'"), 5 * v0 / 7, 1e-12);
  EXPECT_NEAR(r.at(last, "ball_Fx"), 0.0, 1e-12);
  EXPECT_NEAR(r.at(last, "work_friction"), -m * v0 * v0 / 7, 1e-12);
  // Rolling after the stick: its no-slip rows hold to round-off, the friction does no more work.
  EXPECT_LT(r.summary.residuals.velocity, 1e-12);
  EXPECT_LT(r.summary.energy.balance_error, 1e-12);
  EXPECT_NEAR(r.summary.energy.change, -m * v0 * v0 / 7, 1e-12);
}

// docs/derivations/contact-modes.md 3.6: a bilateral contact slides with Coulomb's friction of
// |N|. The ball thrown sliding (mu = 0.25, v0 = 3 m/s) is pulled up at its centre by k t, k = 2
// N/s: N = m g - k t changes sign at t = m g / k = 0.4905 s (an event NAME_reversal, the mode
// stays sliding), and the centre decelerates at mu |g - k t / m| throughout, the friction doing
// negative work: x'(t) = v0 - mu integral_0^t |g - k s / m| ds.
TEST(ContactModes, BilateralContactSlidesWithTheFrictionOfAbsNAcrossTheSignChangeOfN) {
  std::string text = nhdyn::test::read_text(example("ball_thrown_sliding.toml"));
  nhdyn::test::replace_once(text, "[initial]", "[forces]\nz = \"k*t\"\n[initial]");
  nhdyn::test::replace_once(text, "[parameters]", "[parameters]\nk = 2.0");
  const Model model = load_model_text(text, "pulled.toml");
  const double m = mode_parameter(model, "m"), g = mode_parameter(model, "g"), mu = mode_parameter(model, "mu");
  const double v0 = mode_parameter(model, "v0"), k = 2.0, t_end = 0.8;
  const ModeRun r = run_modes(model, t_end);
  ASSERT_EQ(r.summary.events.crossings.size(), 1u);
  EXPECT_EQ(r.summary.events.crossings[0].name, "ball_reversal");
  const double t_star = m * g / k;
  EXPECT_NEAR(r.summary.events.crossings[0].t, t_star, 1e-12);
  const auto speed = [&](double t) {
    const double a = std::min(t, t_star);
    double integral = g * a - k * a * a / (2 * m);
    if (t > t_star) integral += k * (t * t - t_star * t_star) / (2 * m) - g * (t - t_star);
    return v0 - mu * integral;
  };
  for (std::size_t i = 0; i < r.rows.size(); ++i) {
    const double t = r.rows[i][0];
    EXPECT_NEAR(r.at(i, "x'"), speed(t), 1e-11) << "t = " << t;
    EXPECT_EQ(r.at(i, "ball_mode"), 1.0) << "t = " << t;
    EXPECT_NEAR(r.at(i, "ball_N"), m * g - k * t, 1e-11) << "t = " << t;
    EXPECT_NEAR(r.at(i, "ball_Fx"), -mu * std::abs(m * g - k * t), 1e-11) << "t = " << t;
  }
  EXPECT_NEAR(speed(t_end), 2.15904875, 1e-12);  // the integral by hand
  EXPECT_LT(r.at(r.rows.size() - 1, "work_friction"), 0.0);
  EXPECT_LT(r.summary.energy.balance_error, 1e-11);
}

// A ball dropped into the bowl of examples/ball_in_bowl.toml, whose orientation is three angles:
// rolling on, its middle angle reaches -270 degrees (gimbal lock) at t = 1.0817, where the run
// ends; the message names the cause found at that state (A nearly singular), not the row written
// before it.
TEST(ContactModes, ABallWhoseAnglesReachGimbalLockEndsTheRunNamingIt) {
  std::string text = nhdyn::test::read_text(example("ball_in_bowl.toml"));
  nhdyn::test::replace_once(text, "rolling = \"rolling\"\n",
                            "rolling = \"rolling\"\nfriction = [0.105, 0.1]\nunilateral = true\nmode = \"free\"\n");
  nhdyn::test::replace_once(text, "z = \"Rb - sqrt", "z = \"0.05 + Rb - sqrt");
  nhdyn::test::replace_once(text, "x0 = { value = 0.01", "x0 = { value = 0.15");
  const Model model = load_model_text(text, "thrown.toml");
  SimulationOptions options;
  options.t_end = 2.0;
  options.output_step = 0.01;
  options.integrator.rtol = 1e-11;
  options.integrator.atol = 1e-13;
  const SimulationSummary summary = simulate(model, options, [](const Data&) {});
  ASSERT_NE(summary.status, Status::ok);
  EXPECT_NEAR(summary.t_reached, 1.0817, 1e-3) << summary.message;
  EXPECT_NE(summary.message.find("A is nearly singular there"), std::string::npos) << summary.message;
  EXPECT_NE(summary.message.find("gimbal lock"), std::string::npos) << summary.message;
  EXPECT_NE(summary.message.find("rotations = \"quaternion\""), std::string::npos) << summary.message;
}

// A switch located within round-off of an output time: one row stands for that time, and it is the
// switch's row, with the mode after it, on whichever side of the output time the switch falls.
// v0 puts t* = 2 v0 / (7 mu g) on the output time 0.35; its last bits move t* across it.
TEST(ContactModes, ASwitchAtAnOutputTimeReplacesItsRow) {
  Model model = load_model(example("ball_thrown_sliding.toml"));
  const double g = mode_parameter(model, "g"), mu = mode_parameter(model, "mu");
  const double v_grid = 0.35 * 7 * mu * g / 2;
  const double window = 64 * std::numeric_limits<double>::epsilon();
  const double t_grid = make_output_times(0.0, 0.36, 0.01).at(35);  // the output time 0.35
  int after = 0, before = 0;
  for (int k = -5; k <= 5; ++k) {
    const double v0 = v_grid * (1 + k * 3e-15);
    set_parameter(model, "v0", v0);  // the initial velocity follows
    const ModeRun r = run_modes(model, 0.36);
    ASSERT_EQ(r.summary.events.crossings.size(), 1u);
    const double t_switch = r.summary.events.crossings[0].t;
    std::vector<std::size_t> near;
    for (std::size_t i = 0; i < r.rows.size(); ++i)
      if (std::abs(r.rows[i][0] - t_switch) <= window) near.push_back(i);
    ASSERT_EQ(near.size(), 1u) << k;
    EXPECT_EQ(r.rows[near[0]][0], t_switch) << k;  // the switch's own row
    EXPECT_EQ(r.at(near[0], "ball_mode"), 0.0) << k;
    EXPECT_EQ(r.at(near[0] - 1, "ball_mode"), 1.0) << k;
    if (std::abs(t_switch - t_grid) <= window) (t_switch > t_grid ? after : before) += 1;
  }
  // Both sides were met (the rows are those of the switch on both).
  EXPECT_GT(after, 0);
  EXPECT_GT(before, 0);
}

// With backspin r W > 5 v0 / 2 the ball comes back: it sticks at t* = k (v0 + r W) / (mu g (1 + k))
// and rolls on at (v0 - k r W) / (1 + k) < 0.
TEST(ContactModes, BallWithBackspinComesBack) {
  const Model model = load_model(example("ball_thrown_sliding.toml"), {{"w0", -500.0}});
  const double g = mode_parameter(model, "g"), mu = mode_parameter(model, "mu"), v0 = mode_parameter(model, "v0");
  const double r_ball = mode_parameter(model, "r"), W = 500.0, k = 0.4;
  const ModeRun r = run_modes(model, 2.0);
  ASSERT_EQ(r.summary.events.crossings.size(), 1u);
  EXPECT_EQ(r.summary.events.crossings[0].name, "ball_stick");
  EXPECT_NEAR(r.summary.events.crossings[0].t, k * (v0 + r_ball * W) / (mu * g * (1 + k)), 1e-11);
  const double back = (v0 - k * r_ball * W) / (1 + k);
  EXPECT_LT(back, 0.0);
  EXPECT_NEAR(r.at(r.rows.size() - 1, "x'"), back, 1e-11);
  EXPECT_LT(r.summary.energy.balance_error, 1e-11);
}

// A thin disk (k = 1/2) or a hoop (k = 1) thrown along its plane: t* = v0 / (3 mu g) and
// v0 / (2 mu g), final speeds 2 v0 / 3 and v0 / 2.
std::string thrown_wheel_model(const std::string& inertia) {
  return R"(
name = "wheel-thrown"
coordinates = ["x", "y", "z", "b"]
gravity = [0, 0, "-g"]
[parameters]
m = 0.5
r = 0.3
g = 9.81
mu = 0.2
v0 = 2.0
[[frames]]
name = "wheel"
translation = ["x", "y", "z"]
rotations = [["y", "b"]]
[[bodies]]
name = "wheel"
frame = "wheel"
mass = "m"
inertia = )" + inertia + R"(
[[contacts]]
name = "rim"
body = "wheel"
shape = { disk = "r", axis = "y" }
friction = "mu"
[initial]
position = { x = 0, y = 0, z = "r", b = 0 }
velocity = { x = "v0", y = 0, z = 0, b = 0 }
)";
}

TEST(ContactModes, DiskAndHoopThrownSlidingStickAtTheirClosedFormTimes) {
  struct Case {
    const char* inertia;
    double k;
  };
  for (const Case& c : {Case{"[\"m*r^2/4\", \"m*r^2/2\", \"m*r^2/4\"]", 0.5}, Case{"[\"m*r^2/2\", \"m*r^2\", \"m*r^2/2\"]", 1.0}}) {
    SCOPED_TRACE(c.inertia);
    // No mode given: it slips at t0, so it starts sliding.
    const Model model = load_model_text(thrown_wheel_model(c.inertia), "wheel.toml");
    const double g = 9.81, mu = 0.2, v0 = 2.0;
    const ModeRun r = run_modes(model, 2.0);
    ASSERT_EQ(r.summary.events.crossings.size(), 1u);
    EXPECT_EQ(r.summary.events.crossings[0].name, "rim_stick");
    EXPECT_NEAR(r.summary.events.crossings[0].t, c.k * v0 / (mu * g * (1 + c.k)), 1e-11);
    EXPECT_NEAR(r.at(r.rows.size() - 1, "x'"), v0 / (1 + c.k), 1e-11);
    EXPECT_NEAR(r.at(r.rows.size() - 1, "work_friction"), -0.5 * 0.5 * v0 * v0 * c.k / (1 + c.k), 1e-11);
    EXPECT_LT(r.summary.energy.balance_error, 1e-11);
  }
}

// docs/derivations/contact-modes.md section 5, (O1): an upright thin disk at rest on the floor,
// pushed at its centre by P = (Px, Py) (along its rolling direction x and across it, y), with too
// little friction to roll. Its contact point responds to a tangential push F with S F, S =
// diag(3/m, 5/m) (the axle's and a diameter's inertia, m r^2/2 and m r^2/4), and the normal does not
// couple to it, so the friction at the onset is -mu N e with e = (kappa I + mu N S)^-1 sigma_f,
// sigma_f = P / m, kappa > 0 making e a unit vector: neither the direction of P (45 degrees
// here) nor the direction opposite to the friction rolling needs, (1, 0.6) for P = (3, 3) N
// (31 degrees, the isotropic rule (O2)).
TEST(ContactModes, UprightDiskPushedObliquelyStartsSlidingInTheAnisotropicOnsetDirection) {
  const std::string text = nhdyn::test::free_disk_text("disk-pushed", "mu = 0.1\nPx = 3\nPy = 3\n", R"toml(
[[contacts]]
name = "rim"
body = "disk"
shape = { disk = "r", axis = "y" }
friction = "mu"
[forces]
x = "Px"
y = "Py"
)toml");
  const Model model = load_model_text(text, "disk.toml");
  const double m = 0.5, g = 9.81, mu = 0.1, P = 3.0;
  const double sigma_f[2] = {P / m, P / m}, S[2] = {3 / m, 5 / m}, muN = mu * m * g;
  // kappa by bisection on |e(kappa)| = 1 (|e| falls as kappa grows).
  const auto e_of = [&](double kappa, int i) { return sigma_f[i] / (kappa + muN * S[i]); };
  double lo = 0.0, hi = 100.0;
  for (int n = 0; n < 200; ++n) {
    const double mid = 0.5 * (lo + hi);
    (std::hypot(e_of(mid, 0), e_of(mid, 1)) > 1.0 ? lo : hi) = mid;
  }
  const double e[2] = {e_of(lo, 0), e_of(lo, 1)};
  const ModeRun r = run_modes(model, 0.05);
  ASSERT_FALSE(r.rows.empty());
  EXPECT_EQ(r.at(0, "rim_mode"), 1.0);  // sliding from t0
  // The friction at t0 is -mu N e: along -x (Flong) and -y (Flat) for the upright disk heading x.
  const double F[2] = {r.at(0, "rim_Fx"), r.at(0, "rim_Fy")};
  EXPECT_NEAR(std::hypot(F[0], F[1]), muN, 1e-9);
  EXPECT_NEAR(-F[0] / muN, e[0], 1e-8);
  EXPECT_NEAR(-F[1] / muN, e[1], 1e-8);
  // And the slip grows along e (s = kappa e t + O(t^2)).
  const double s[2] = {r.at(1, "rim_slip_x"), r.at(1, "rim_slip_y")};
  EXPECT_NEAR(std::atan2(s[1], s[0]), std::atan2(e[1], e[0]), 1e-2);
  EXPECT_GT(std::abs(std::atan2(e[1], e[0]) - std::atan2(0.6, 1.0)), 0.1);  // not (O2)
}

// A solid cylinder released at rest on an incline of angle alpha (gravity tilted, the plane
// z = 0): it slides from the start iff tan(alpha) > 3 mu (section 10.3), with x'' = g (sin(alpha) -
// mu cos(alpha)) and never sticks; below that it rolls at x'' = 2 g sin(alpha) / 3.
std::string incline_model(double alpha, const std::string& friction = "\"mu\"") {
  return R"toml(
name = "cylinder-on-incline"
coordinates = ["x", "y", "z", "b"]
gravity = ["g*sin(alpha)", 0, "-g*cos(alpha)"]
[parameters]
m = 2.0
r = 0.1
g = 9.81
mu = 0.2
alpha = )toml" + std::to_string(alpha) + R"toml(
[[frames]]
name = "cylinder"
translation = ["x", "y", "z"]
rotations = [["y", "b"]]
[[bodies]]
name = "cylinder"
frame = "cylinder"
mass = "m"
inertia = ["m*r^2/4", "m*r^2/2", "m*r^2/4"]
[[contacts]]
name = "rim"
body = "cylinder"
shape = { disk = "r", axis = "y" }
ground = { plane = [0, 0, 1] }
friction = )toml" + friction + R"toml(
[initial]
position = { x = 0, y = 0, z = "r", b = 0 }
)toml";
}

TEST(ContactModes, CylinderOnASteepInclineSlidesFromTheStartAndRollsBelowTheBound) {
  const double g = 9.81, mu = 0.2;
  for (const double alpha : {0.7, 0.4}) {
    SCOPED_TRACE(alpha);
    const bool steep = std::tan(alpha) > 3 * mu;
    const Model model = load_model_text(incline_model(alpha), "incline.toml");
    const ModeRun r = run_modes(model, 1.0);
    EXPECT_TRUE(r.summary.events.crossings.empty());
    const std::size_t last = r.rows.size() - 1;
    EXPECT_EQ(r.at(0, "rim_mode"), steep ? 1.0 : 0.0);
    EXPECT_EQ(r.at(last, "rim_mode"), steep ? 1.0 : 0.0);
    const double a = steep ? g * (std::sin(alpha) - mu * std::cos(alpha)) : 2 * g * std::sin(alpha) / 3;
    EXPECT_NEAR(r.at(last, "x'"), a * 1.0, 1e-10);
    if (steep) {
      // The slip grows at g (sin(alpha) - 3 mu cos(alpha)); the friction is mu N up the slope.
      EXPECT_NEAR(r.at(last, "rim_slip_speed"), g * (std::sin(alpha) - 3 * mu * std::cos(alpha)), 1e-10);
      EXPECT_NEAR(r.at(last, "rim_Fx"), -mu * 2.0 * g * std::cos(alpha), 1e-10);
    } else {
      EXPECT_LT(r.summary.residuals.velocity, 1e-10);
    }
    EXPECT_LT(r.summary.energy.balance_error, 1e-10);
  }
  // friction = [mu_s, mu_k]: between 3 mu_k and 3 mu_s the static friction holds it from rest.
  const Model held = load_model_text(incline_model(0.7, "[0.3, 0.2]"), "incline.toml");
  const ModeRun r = run_modes(held, 1.0);
  EXPECT_TRUE(r.summary.events.crossings.empty());
  EXPECT_EQ(r.at(r.rows.size() - 1, "rim_mode"), 0.0);
  EXPECT_NEAR(r.at(r.rows.size() - 1, "x'"), 2 * g * std::sin(0.7) / 3, 1e-10);
}

// A unilateral contact that would pull at t0 (gravity away from the ground) is refused before
// the run, with N and the mode to start in.
TEST(ContactModes, UnilateralContactPullingAtTheStartIsRefused) {
  std::string text = test::read_text(example("ball_on_sphere.toml"));
  text.replace(text.find("gravity = [0, 0, \"-g\"]"), 22, "gravity = [0, 0, \"g\"]");
  const Model model = load_model_text(text, "sphere.toml");
  SimulationOptions options;
  options.t_end = 0.1;
  try {
    simulate(model, options, [](const Data&) {});
    ADD_FAILURE() << "accepted";
  } catch (const ModelError& e) {
    const std::string message = e.what();
    EXPECT_NE(message.find("contact 'ball' is unilateral"), std::string::npos) << message;
    EXPECT_NE(message.find("N = -"), std::string::npos) << message;
    EXPECT_NE(message.find("mode = \"free\""), std::string::npos) << message;
  }
}

// Section 10.2, a ball released at theta0 = 1e-3 from the top of a fixed sphere. Without a
// friction limit it rolls until N = 0 at cos(theta) = 2 cos(theta0) / (3 + k) and lifts off; with
// mu = 0.3 it slips at (R3) and lifts off while sliding, at the root of (R4).
double sphere_angle(const EventRecord& e) { return std::atan2(e.q[0], e.q[2]); }

TEST(ContactModes, BallOnASphereLiftsOffAtTenSeventeenthsOrSlipsFirst) {
  const double k = 0.4, theta0 = 1e-3;
  {
    const Model model = load_model(example("ball_on_sphere.toml"));
    const ModeRun r = run_modes(model, 3.2);
    ASSERT_EQ(r.summary.events.crossings.size(), 1u);
    EXPECT_EQ(r.summary.events.crossings[0].name, "ball_liftoff");
    EXPECT_NEAR(std::cos(sphere_angle(r.summary.events.crossings[0])), 2 * std::cos(theta0) / (3 + k), 1e-9);
    const std::size_t last = r.rows.size() - 1;
    EXPECT_EQ(r.at(last, "ball_mode"), 2.0);
    EXPECT_GT(r.at(last, "ball_gap"), 0.05);  // flying away from the sphere
    EXPECT_NEAR(r.at(last, "ball_N"), 0.0, 1e-12);
    EXPECT_LT(r.summary.energy.balance_error, 1e-9);
  }
  std::string text = test::read_text(example("ball_on_sphere.toml"));
  text.replace(text.find("unilateral = true\n"), 18, "unilateral = true\nfriction = 0.3\n");
  const Model model = load_model_text(text, "sphere.toml");
  const ModeRun r = run_modes(model, 3.1);
  ASSERT_EQ(r.summary.events.crossings.size(), 2u);
  EXPECT_EQ(r.summary.events.crossings[0].name, "ball_slip");
  EXPECT_EQ(r.summary.events.crossings[1].name, "ball_liftoff");
  const double mu = 0.3;
  const double theta_s = std::atan2((3 + k) * mu, k) -
                         std::asin(2 * mu * std::cos(theta0) / std::sqrt(k * k + (3 + k) * (3 + k) * mu * mu));
  EXPECT_NEAR(sphere_angle(r.summary.events.crossings[0]), theta_s, 1e-8);
  // (R4): rho u = rho theta'^2 while sliding, from theta_s; lift-off where rho u = g cos(theta).
  const double rho_u_s = 2 * 9.81 * (std::cos(theta0) - std::cos(theta_s)) / (1 + k);
  const auto p = [&](double x) { return (2 * mu * mu - 1) * std::cos(x) - 3 * mu * std::sin(x); };
  const auto excess = [&](double x) {
    const double E = std::exp(2 * mu * (x - theta_s));
    return rho_u_s * E + 2 * 9.81 / (1 + 4 * mu * mu) * (p(x) - E * p(theta_s)) - 9.81 * std::cos(x);
  };
  double lo = theta_s + 1e-6, hi = 1.5;
  for (int i = 0; i < 200; ++i) ((excess(0.5 * (lo + hi)) < 0) ? lo : hi) = 0.5 * (lo + hi);
  EXPECT_NEAR(hi * 180 / M_PI, 52.12, 0.01);  // the derivation's figure
  EXPECT_NEAR(sphere_angle(r.summary.events.crossings[1]), hi, 1e-7);
  EXPECT_LT(r.at(r.rows.size() - 1, "work_friction"), 0.0);
  EXPECT_LT(r.summary.energy.balance_error, 1e-9);
  // With one coefficient the slip grows from 0 as t^2 and its direction is stiff while it is small:
  // dopri5 spends most of its steps there, and the run says so, from the slip's onset.
  const std::string& stiff = r.summary.stiffness;
  EXPECT_NE(stiff.find("the run is stiff from t = "), std::string::npos) << stiff;
  EXPECT_NE(stiff.find("--integrator cvode-bdf"), std::string::npos) << stiff;
  EXPECT_NE(stiff.find("a single friction coefficient"), std::string::npos) << stiff;
  EXPECT_GT(2 * r.summary.stats.stiff_steps, r.summary.stats.steps);
  EXPECT_GE(r.summary.stats.stiff_from, r.summary.events.crossings[0].t);
  EXPECT_LT(r.summary.stats.stiff_from, r.summary.events.crossings[0].t + 1e-3);
  // Two coefficients: the slip grows as t from the onset, no stiff stretch and no warning.
  std::string two = text;
  two.replace(two.find("friction = 0.3\n"), 15, "friction = [0.3, 0.25]\n");
  const ModeRun r2 = run_modes(load_model_text(two, "sphere2.toml"), 3.1);
  ASSERT_EQ(r2.summary.events.crossings.size(), 2u);
  EXPECT_EQ(r2.summary.stiffness, "");
  EXPECT_LT(10 * r2.summary.stats.steps, r.summary.stats.steps);
}

// A ball dropped from 40 m onto ball_on_sphere's sphere (R = 1, r = 0.1) at x = 0.3: it falls
// freely and its centre reaches R + r where z = sqrt((R + r)^2 - x^2), at t* = sqrt(2 (40 - z) / g).
// Free flight is a polynomial, so the integrator's steps are long (about 1 s): the ball crosses the
// sphere within one of them, the gap positive at both ends, and the touchdown is found only by
// looking inside the step (EventFunctions::may_dip), with every integrator that locates events
// (CVODE's root finding sees sign changes only). A ball dropped at x = 1.15 passes the sphere
// 0.05 from it: no touchdown, its gap never below 0.05.
TEST(ContactModes, ABallFallingPastASphereWithinOneStepTouchesDownOnIt) {
  const auto dropped = [](double x) {
    std::string text = test::read_text(example("ball_on_sphere.toml"));
    const std::string start = "position = { x = \"(R + r)*sin(theta0)\", y = 0, z = \"(R + r)*cos(theta0)\"";
    text.replace(text.find(start), start.size(), fmt::format("position = {{ x = {}, y = 0, z = 40", x));
    return load_model_text(text, "drop.toml");
  };
  const double g = 9.81, x = 0.3;
  const double t_star = std::sqrt(2 * (40 - std::sqrt(1.1 * 1.1 - x * x)) / g);
  for (const IntegratorKind integrator :
       {IntegratorKind::dopri5, IntegratorKind::dop853, IntegratorKind::cvode_bdf, IntegratorKind::cvode_adams}) {
    const bool explicit_rk = integrator == IntegratorKind::dopri5 || integrator == IntegratorKind::dop853;
    SimulationOptions options;
    options.t_end = 4.0;
    options.output_step = 0.5;
    options.integrator.kind = integrator;
    options.integrator.rtol = 1e-10;
    options.integrator.atol = 1e-12;
    const SimulationSummary summary = simulate(dropped(x), options, [](const Data&) {});
    ASSERT_EQ(summary.status, Status::ok) << summary.message;
    ASSERT_GE(summary.events.crossings.size(), 1u);
    const EventRecord& touchdown = summary.events.crossings[0];
    EXPECT_EQ(touchdown.name, "ball_touchdown");
    // BDF's interpolating polynomial is of lower order than the explicit methods' extensions.
    EXPECT_NEAR(touchdown.t, t_star, explicit_rk ? 1e-9 : 1e-8);
    EXPECT_NEAR(std::hypot(touchdown.q[0], touchdown.q[1], touchdown.q[2]), 1.1, explicit_rk ? 1e-9 : 1e-7);
    // Long steps: the touchdown was inside one of them, not at a step's end.
    if (explicit_rk) {
      EXPECT_LT(summary.stats.steps, 40);
    }
  }
  const Model past = dropped(1.15);
  const ModeRun r = run_modes(past, 4.0);
  EXPECT_TRUE(r.summary.events.crossings.empty()) << r.summary.events.crossings[0].name;
  double lowest = 1e300;
  for (std::size_t i = 0; i < r.rows.size(); ++i) lowest = std::min(lowest, r.at(i, "ball_gap"));
  EXPECT_GT(lowest, 0.05 - 1e-9);
  EXPECT_LT(lowest, 0.06);  // the rows every 0.01 s pass near the closest point
}

// Free flight is an exact polynomial, so one step may hold a climb, its top and the fall onto the
// ground: the search inside a step assumes no shape of the gap. A ball thrown up at 2 m/s from
// z = 2 at x = 0.3 lands on the sphere where 2 + 2 t - g t^2 / 2 = sqrt((R + r)^2 - x^2); one
// dropped 0.5 m onto its top with e = 1/2 bounces at t1 = sqrt(2 h / g), 2 t1, 2.5 t1, ... and
// the touchdowns accumulate at 3 t1 (Zeno), which ends the run there.
TEST(ContactModes, ABallThrownUpOrBouncingOnASphereTouchesDownWhereTheParabolaMeetsIt) {
  const auto thrown = [](double x, double z, double vz, double e) {
    std::string text = test::read_text(example("ball_on_sphere.toml"));
    const std::string start = "position = { x = \"(R + r)*sin(theta0)\", y = 0, z = \"(R + r)*cos(theta0)\"";
    text.replace(text.find(start), start.size(), fmt::format("position = {{ x = {}, y = 0, z = {}", x, z));
    const std::string still = "velocity = { x = 0, y = 0, z = 0,";
    text.replace(text.find(still), still.size(), fmt::format("velocity = {{ x = 0, y = 0, z = {},", vz));
    text.replace(text.find("unilateral = true\n"), 18, fmt::format("unilateral = true\nrestitution = {}\n", e));
    return load_model_text(text, "thrown.toml");
  };
  const double g = 9.81;
  const double landing = (2 + std::sqrt(4 + 2 * g * (2 - std::sqrt(1.21 - 0.09)))) / g;
  const double t1 = std::sqrt(2 * 0.5 / g);
  for (const IntegratorKind integrator :
       {IntegratorKind::dopri5, IntegratorKind::dop853, IntegratorKind::cvode_bdf, IntegratorKind::cvode_adams}) {
    const bool explicit_rk = integrator == IntegratorKind::dopri5 || integrator == IntegratorKind::dop853;
    SimulationOptions options;
    options.t_end = 1.5;
    options.output_step = 0.5;
    options.integrator.kind = integrator;
    options.integrator.rtol = 1e-10;
    options.integrator.atol = 1e-12;
    const SimulationSummary up = simulate(thrown(0.3, 2.0, 2.0, 0.0), options, [](const Data&) {});
    ASSERT_GE(up.events.crossings.size(), 1u) << integrator_name(integrator) << ": " << up.message;
    EXPECT_EQ(up.events.crossings[0].name, "ball_touchdown");
    EXPECT_NEAR(up.events.crossings[0].t, landing, explicit_rk ? 1e-9 : 1e-8) << integrator_name(integrator);
    if (!explicit_rk) continue;  // CVODE's restart right after an impact on a curved ground: see docs
    const SimulationSummary bounce = simulate(thrown(0.0, 1.6, 0.0, 0.5), options, [](const Data&) {});
    EXPECT_NE(bounce.status, Status::ok);
    EXPECT_NE(bounce.message.find("(Zeno)"), std::string::npos) << bounce.message;
    ASSERT_GE(bounce.events.crossings.size(), 3u) << bounce.message;
    EXPECT_NEAR(bounce.events.crossings[0].t, t1, 1e-9);
    EXPECT_NEAR(bounce.events.crossings[1].t, 2 * t1, 1e-9);
    EXPECT_NEAR(bounce.events.crossings[2].t, 2.5 * t1, 1e-9);
    EXPECT_NEAR(bounce.events.crossings.back().t, 3 * t1, 1e-6);
  }
}

// A disk dropped from 0.3 m turning about a diameter at 60 rad/s: in free flight its lean turns
// at a constant rate and its centre falls on a parabola, an exact polynomial for the angles'
// coordinates, so one step holds several turns, and the gap z - r |cos(theta)| dips through zero
// and back before it changes sign. The first touchdown is the first root of
// r cos(theta0) + h - g t^2 / 2 - r |cos(theta0 + 60 t)|.
TEST(ContactModes, ASpinningDiskTouchesDownAtItsFirstContactNotALaterOne) {
  const double r = 0.2, theta0 = 0.3, h = 0.3, w = 60.0, g = 9.81;
  const auto gap = [&](double t) { return r * std::cos(theta0) + h - g * t * t / 2 - r * std::abs(std::cos(theta0 + w * t)); };
  double lo = 0.0, hi = 0.0;
  for (double t = 0.0; t < 1.0; t += 1e-4)
    if (gap(t + 1e-4) < 0.0) {
      lo = t;
      hi = t + 1e-4;
      break;
    }
  for (int i = 0; i < 100; ++i) ((gap(0.5 * (lo + hi)) > 0.0) ? lo : hi) = 0.5 * (lo + hi);
  std::string text = test::read_text(example("rolling_disk_hop.toml"));
  const std::string still = "velocity = { x = 0, y = 0, z = 0, psi = 0, theta = 0, phi = 0 }";
  text.replace(text.find(still), still.size(), "velocity = { x = 0, y = 0, z = 0, psi = 0, theta = 60, phi = 0 }");
  const Model model = load_model_text(text, "spinning.toml", {{"h", h}});
  for (const IntegratorKind integrator :
       {IntegratorKind::dopri5, IntegratorKind::dop853, IntegratorKind::cvode_bdf, IntegratorKind::cvode_adams}) {
    SimulationOptions options;
    options.t_end = 0.3;
    options.output_step = 0.1;
    options.integrator.kind = integrator;
    options.integrator.rtol = 1e-11;
    options.integrator.atol = 1e-12;
    const SimulationSummary summary = simulate(model, options, [](const Data&) {});
    ASSERT_GE(summary.events.crossings.size(), 1u) << integrator_name(integrator) << ": " << summary.message;
    EXPECT_EQ(summary.events.crossings[0].name, "disk_touchdown");
    EXPECT_NEAR(summary.events.crossings[0].t, hi, 1e-8) << integrator_name(integrator);
  }
}

// After lift-off the ball flies away from the sphere: its rolling rows, dropped, have tangents
// (C - K) x ... that grow with the distance, by 5e4 over 10 s. The constraint watch compares only
// the rows the modes keep, so the free flight makes no warning (it made one on ball_roll2).
TEST(ContactModes, TheConstraintWatchLeavesTheRowsOfAFreeContactAlone) {
  const Model model = load_model(example("ball_on_sphere.toml"));
  const ModeRun r = run_modes(model, 10.0);
  ASSERT_EQ(r.summary.status, Status::ok) << r.summary.message;
  ASSERT_EQ(r.summary.events.crossings.size(), 1u);
  EXPECT_EQ(r.at(r.rows.size() - 1, "ball_mode"), 2.0);  // free
  EXPECT_GT(r.at(r.rows.size() - 1, "ball_gap"), 100.0);
  EXPECT_TRUE(r.summary.warnings.empty()) << r.summary.warnings.front();
  EXPECT_LT(r.summary.watch.largest_row_factor, 10.0);
}

// A ball dropped from h0 onto the plane (unilateral, Newton's restitution e, no friction limit:
// a sticking impulse): it touches down at sqrt(2 h0 / g), bounces at e times its speed, and the
// touchdowns accumulate at t1 (1 + 2 e / (1 - e)) (Zeno), which ends the run with a message and
// its rows; plastic (e = 0) it stays on the ground, rolling, N = m g. The impacts' energy is
// booked with the reactions' work, so h - h0 - W does not jump.
std::string dropped_ball(double e) {
  std::string text = test::read_text(example("ball_thrown_sliding.toml"));
  const std::string keys = "friction = \"mu\"\nmode = \"sliding\"\n";
  text.replace(text.find(keys), keys.size(),
               "unilateral = true\nrestitution = " + std::to_string(e) + "\n");
  text.replace(text.find("z = \"r\""), 7, "z = \"r + 0.2\"");
  return text;
}

// A unilateral contact whose body starts inside the ground (the dropped ball 1 cm into the floor,
// given mode = "free" or left to choose) is refused before the run with its gap: free, it fell
// through the floor with exit 0 (a touchdown is a gap closing from above); on the wrong side of a
// sphere it was refused for its normal force, whose advice (start it free) then ran the same fall.
TEST(ContactModes, AUnilateralContactStartingInsideTheGroundIsRefusedWithItsGap) {
  for (const char* mode : {"", "mode = \"free\"\n"}) {
    std::string text = dropped_ball(0.5);
    text.replace(text.find("z = \"r + 0.2\""), 13, "z = \"r - 0.01\"");
    text.replace(text.find("unilateral = true\n"), 18, std::string("unilateral = true\n") + mode);
    const Model model = load_model_text(text, "drop.toml");
    SimulationOptions options;
    options.t_end = 0.1;
    try {
      simulate(model, options, [](const Data&) {});
      ADD_FAILURE() << "accepted, " << mode;
    } catch (const ModelError& e) {
      const std::string message = e.what();
      EXPECT_NE(message.find("drop.toml:"), std::string::npos) << message;
      EXPECT_NE(message.find("contact 'ball' is unilateral, but at t0 its gap is -0.01 m < 0"), std::string::npos)
          << message;
    }
  }
  // Started on the far side of the sphere (its gap about minus twice the ball's radius): the gap,
  // not the normal force.
  std::string text = test::read_text(example("ball_on_sphere.toml"));
  ASSERT_NE(text.find("side = \"outside\""), std::string::npos);
  text.replace(text.find("side = \"outside\""), 16, "side = \"inside\"");
  try {
    simulate(load_model_text(text, "sphere.toml"), SimulationOptions{}, [](const Data&) {});
    ADD_FAILURE() << "accepted";
  } catch (const ModelError& e) {
    EXPECT_NE(std::string(e.what()).find("its gap is -"), std::string::npos) << e.what();
  }
}

// An elastic ball bouncing every 4 ms from 20 um: more than 10 000 touchdowns, evenly spread, are
// regular switching, not an accumulation (a run was ended at its 10 001st switch, "Zeno or
// chattering"); each bounce reaches the height it fell from.
TEST(ContactModes, TenThousandRegularBouncesAreNotAnAccumulation) {
  std::string text = dropped_ball(1.0);
  text.replace(text.find("z = \"r + 0.2\""), 13, "z = \"r + 2e-5\"");
  const Model model = load_model_text(text, "bounce.toml");
  SimulationOptions options;
  options.t_end = 42.5;
  options.output_step = 42.5;
  const SimulationSummary summary = simulate(model, options, [](const Data&) {});
  ASSERT_EQ(summary.status, Status::ok) << summary.message;
  const double period = 2.0 * std::sqrt(2.0 * 2e-5 / 9.81);  // 4.04 ms
  ASSERT_GT(summary.events.crossings.size(), 10000u);
  EXPECT_NEAR(static_cast<double>(summary.events.crossings.size()), std::floor((42.5 - period / 2) / period) + 1, 1.0);
  EXPECT_NEAR(summary.events.crossings.back().t - summary.events.crossings[summary.events.crossings.size() - 2].t,
              period, 1e-9);
}

TEST(ContactModes, DroppedBallBouncesWithNewtonsLawUntilTheTouchdownsAccumulate) {
  const double g = 9.81, h0 = 0.2, e = 0.5;
  const double t1 = std::sqrt(2 * h0 / g), v1 = std::sqrt(2 * g * h0);
  {
    const Model model = load_model_text(dropped_ball(e), "drop.toml");
    ModeRun r;
    r.columns = make_result_columns(model);
    SimulationOptions options;
    options.t_end = 2.0;
    options.output_step = 0.01;
    options.integrator.rtol = 1e-10;
    options.integrator.atol = 1e-12;
    r.summary = simulate(model, options, [&](const Data& data) {
      std::vector<double> row;
      fill_result_row(model, data, row);
      r.rows.push_back(std::move(row));
    });
    EXPECT_NE(r.summary.status, Status::ok);
    EXPECT_NE(r.summary.message.find("Zeno"), std::string::npos) << r.summary.message;
    ASSERT_GE(r.summary.events.crossings.size(), 4u);
    double t = t1, v = v1;
    for (std::size_t k = 0; k < 4; ++k) {
      EXPECT_EQ(r.summary.events.crossings[k].name, "ball_touchdown");
      EXPECT_NEAR(r.summary.events.crossings[k].t, t, 1e-9) << k;
      EXPECT_NEAR(r.summary.events.crossings[k].v[2], e * v, 1e-8) << k;  // the row carries the velocity after
      v *= e;
      t += 2 * v / g;
    }
    // impact_loss (I5), cumulative: the first touchdown (moving at v0 = 3 m/s along x, no spin)
    // takes a sticking impulse, (1 - e^2) m V^2 / 2 + k m v0^2 / (2 (1 + k)); the ball then rolls
    // and the next ones are normal, (1 - e^2) m V^2 / 2. The reactions' work stays that of the
    // finite reactions (none in flight).
    const double m = 0.1, k = 0.4, v0 = 3.0;
    const std::size_t first = mode_switch_row(r, r.summary.events.crossings[0].t);
    const double loss1 = (1 - e * e) * m * v1 * v1 / 2 + k * m * v0 * v0 / (2 * (1 + k));
    EXPECT_NEAR(r.at(first, "impact_loss"), loss1, 1e-12);
    EXPECT_NEAR(r.at(first - 1, "impact_loss"), 0.0, 1e-15);
    const std::size_t second = mode_switch_row(r, r.summary.events.crossings[1].t);
    EXPECT_NEAR(r.at(second, "impact_loss"), loss1 + (1 - e * e) * m * e * e * v1 * v1 / 2, 1e-12);
    EXPECT_NEAR(r.at(second, "work_reactions"), 0.0, 1e-12);
    EXPECT_NEAR(r.at(second, "work"), -r.at(second, "impact_loss") + r.at(second, "work_forces"), 1e-15);
    const double t_inf = t1 * (1 + 2 * e / (1 - e));
    EXPECT_LT(r.summary.t_reached, t_inf + 1e-6);
    EXPECT_GT(r.summary.t_reached, t_inf - 1e-3);
    EXPECT_LT(r.summary.energy.balance_error, 1e-9);
  }
  // A normal drop (v0 = 0), plastic: impact_loss = m V^2 / 2, the closed form (1 - e^2) m V^2 / 2.
  std::string normal = dropped_ball(0.0);
  normal.replace(normal.find("v0 = { value = 3.0"), 18, "v0 = { value = 0.0");
  const Model plastic = load_model_text(normal, "drop.toml");
  const ModeRun r = run_modes(plastic, 0.5);
  ASSERT_EQ(r.summary.events.crossings.size(), 1u);
  EXPECT_NEAR(r.summary.events.crossings[0].t, t1, 1e-9);
  const std::size_t last = r.rows.size() - 1;
  EXPECT_EQ(r.at(last, "ball_mode"), 0.0);
  EXPECT_NEAR(r.at(last, "z'"), 0.0, 1e-12);
  EXPECT_NEAR(r.at(last, "ball_N"), 0.1 * g, 1e-10);
  EXPECT_NEAR(r.at(last, "impact_loss"), 0.1 * v1 * v1 / 2, 1e-12);  // plastic: all the kinetic energy
  EXPECT_LT(r.summary.energy.balance_error, 1e-9);
}

// A ball landing obliquely with spin (section 7.1): released at the height h with the centre
// velocity (vx, vy, 0) and the spin w0 about y, a unilateral contact with friction mu and
// restitution e. It touches down at t1 = sqrt(2 h / g) with V = g t1 and the slip
// s- = (vx - r w0, vy); (I3) decides sticking or sliding, (I4) gives the velocities after, (I5)
// the energy taken.
std::string landing_ball(double e, double mu, double vx, double vy, double w0, double h) {
  std::string text = test::read_text(example("ball_thrown_sliding.toml"));
  const std::string keys = "friction = \"mu\"\nmode = \"sliding\"\n";
  text.replace(text.find(keys), keys.size(),
               "friction = \"mu\"\nunilateral = true\nrestitution = " + std::to_string(e) + "\n");
  text.replace(text.find("mu = { value = 0.25 }"), 21, "mu = { value = " + std::to_string(mu) + " }");
  text.replace(text.find("z = \"r\""), 7, "z = \"r + " + std::to_string(h) + "\"");
  const std::string velocity = "velocity = { x = \"v0\", y = 0, z = 0, a = 0, b = \"w0\", c = 0 }";
  text.replace(text.find(velocity), velocity.size(),
               "velocity = { x = " + std::to_string(vx) + ", y = " + std::to_string(vy) + ", z = 0, a = 0, b = " +
                   std::to_string(w0) + ", c = 0 }");
  return text;
}

ModeRun run_landing(const std::string& text, double t_end) {
  const Model model = load_model_text(text, "landing.toml");
  return run_modes(model, t_end);
}

TEST(ContactModes, BallLandingObliquelyWithSpinTakesTheSlidingImpulseOfTheClosedForm) {
  const double m = 0.1, r = 0.02, g = 9.81, k = 0.4, mu = 0.1, e = 0.5, h = 0.05;
  const double vx = 2.0, w0 = -50.0;  // backspin: s- = vx - r w0 = 3 m/s
  const ModeRun run = run_landing(landing_ball(e, mu, vx, 0.0, w0, h), 0.25);
  ASSERT_EQ(run.summary.events.crossings.size(), 2u);
  // Two touchdowns, each a sliding impact (I3 violated); in flight x', b' are constant.
  double t = std::sqrt(2 * h / g), V = g * t, x_dot = vx, spin = w0, loss = 0.0;
  for (std::size_t j = 0; j < 2; ++j) {
    SCOPED_TRACE(j);
    const EventRecord& ev = run.summary.events.crossings[j];
    EXPECT_EQ(ev.name, "ball_touchdown");
    EXPECT_NEAR(ev.t, t, 1e-9);
    const double s_before = x_dot - r * spin;
    EXPECT_GT(k * s_before / (1 + k), mu * (1 + e) * V);  // the sticking impulse is outside the cone
    const double s_after = s_before - mu * (1 + e) * V * (1 + k) / k;
    EXPECT_GT(s_after, 0.0);
    x_dot -= mu * (1 + e) * V;
    spin += mu * (1 + e) * V / (k * r);
    loss += m * (1 - e * e) * V * V / 2 + mu * m * (1 + e) * V * (s_before + s_after) / 2;
    EXPECT_NEAR(ev.v[0], x_dot, 1e-9);
    EXPECT_NEAR(ev.v[2], e * V, 1e-9);
    EXPECT_NEAR(ev.v[4], spin, 1e-7);
    const std::size_t row = mode_switch_row(run, ev.t);
    EXPECT_EQ(run.at(row, "ball_mode"), 2.0);  // it bounces
    EXPECT_NEAR(run.at(row, "impact_loss"), loss, 1e-10);
    t += 2 * e * V / g;
    V *= e;
  }
  EXPECT_LT(run.summary.energy.balance_error, 1e-9);  // h - h0 - W through the bounces
  EXPECT_NEAR(run.at(run.rows.size() - 1, "work_reactions"), 0.0, 1e-12);
  EXPECT_TRUE(run.summary.warnings.empty());
}

TEST(ContactModes, PlasticLandingSlidesOnAlongThePreImpactSlipOrSticksInsideTheCone) {
  const double r = 0.02, g = 9.81, k = 0.4, h = 0.05;
  const double t1 = std::sqrt(2 * h / g), V = g * t1;
  {
    // Spatial slip s- = (vx - r w0, vy): the impulse slides along it, the ball leaves the impact
    // sliding with s+ = (|s-| - mu V (1 + k) / k) e_s and sticks k |s+| / (mu g (1 + k)) later.
    const double mu = 0.2, vx = 1.0, vy = 1.5, w0 = 20.0;
    const ModeRun run = run_landing(landing_ball(0.0, mu, vx, vy, w0, h), 1.0);
    ASSERT_EQ(run.summary.events.crossings.size(), 2u);
    EXPECT_EQ(run.summary.events.crossings[0].name, "ball_touchdown");
    EXPECT_EQ(run.summary.events.crossings[1].name, "ball_stick");
    const double sx = vx - r * w0, sy = vy, s = std::hypot(sx, sy);
    const double s_after = s - mu * V * (1 + k) / k;
    ASSERT_GT(s_after, 0.0);
    const EventRecord& ev = run.summary.events.crossings[0];
    EXPECT_NEAR(ev.v[0], vx - mu * V * sx / s, 1e-9);
    EXPECT_NEAR(ev.v[1], vy - mu * V * sy / s, 1e-9);
    EXPECT_NEAR(ev.v[2], 0.0, 1e-12);
    const std::size_t row = mode_switch_row(run, ev.t);
    EXPECT_EQ(run.at(row, "ball_mode"), 1.0);
    EXPECT_NEAR(run.at(row, "ball_slip_x"), s_after * sx / s, 1e-9);
    EXPECT_NEAR(run.at(row, "ball_slip_y"), s_after * sy / s, 1e-9);
    EXPECT_NEAR(run.summary.events.crossings[1].t, t1 + k * s_after / (mu * g * (1 + k)), 1e-9);
    EXPECT_NEAR(run.at(row, "impact_loss"), 0.1 * V * V / 2 + mu * 0.1 * V * (s + s_after) / 2, 1e-10);
    EXPECT_LT(run.summary.energy.balance_error, 1e-9);
  }
  {
    // A small slip: the sticking impulse is inside the cone, the ball rolls at once at 5 vx / 7.
    const double mu = 0.5, vx = 0.3;
    const ModeRun run = run_landing(landing_ball(0.0, mu, vx, 0.0, 0.0, h), 0.3);
    ASSERT_EQ(run.summary.events.crossings.size(), 1u);
    const EventRecord& ev = run.summary.events.crossings[0];
    EXPECT_NEAR(ev.v[0], 5 * vx / 7, 1e-10);
    EXPECT_NEAR(ev.v[4], 5 * vx / 7 / r, 1e-8);
    const std::size_t row = mode_switch_row(run, ev.t);
    EXPECT_EQ(run.at(row, "ball_mode"), 0.0);
    EXPECT_NEAR(run.at(row, "impact_loss"), 0.1 * V * V / 2 + k * 0.1 * vx * vx / (2 * (1 + k)), 1e-10);
    EXPECT_LT(run.summary.energy.balance_error, 1e-9);
  }
}

// Painleve's rod (section 3.8): a rod of mass m, length 2 l, turned by b about y, with a ball of
// radius rho at its end (l, 0, 0) touching the plane z = 0. Its contact's inverse inertia (S11):
// Lambda_nn = (1 + 3 c^2) / m, Lambda_nt = 3 c (s + rho / l) / m, Lambda_tt = 1/m + 3 (s + rho/l)^2 / m.
std::string painleve_rod(const std::string& keys, double b0, double h, double vx) {
  return R"toml(
name = "painleve-rod"
coordinates = ["x", "y", "z", "b"]
gravity = [0, 0, "-g"]
[parameters]
m = 1.0
l = 0.5
rho = 0.01
g = 9.81
b0 = )toml" + fmt::format("{:.17g}", b0) + R"toml(
h = )toml" + fmt::format("{:.17g}", h) + R"toml(
vx = )toml" + fmt::format("{:.17g}", vx) + R"toml(
[[frames]]
name = "rod"
translation = ["x", "y", "z"]
rotations = [["y", "b"]]
[[bodies]]
name = "rod"
frame = "rod"
mass = "m"
inertia = ["m*l^2/3", "m*l^2/3", "m*l^2/3"]
[[contacts]]
name = "end"
body = "rod"
shape = { sphere = "rho" }
centre = ["l", 0, 0]
unilateral = true
)toml" + keys + R"toml(
[initial]
position = { x = 0, y = 0, z = "l*sin(b0) + rho + h", b = "b0" }
velocity = { x = "vx", y = 0, z = 0, b = 0 }
)toml";
}

struct RodInertia {
  double nn, nt, tt;
};
RodInertia rod_inertia(double b) {
  const double c = std::cos(b), s = std::sin(b), a = s + 0.01 / 0.5;
  return {1 + 3 * c * c, 3 * c * a, 1 + 3 * a * a};  // m = 1
}

// The end slides away from under the centre (sigma = +1) at b0 = atan(2): w_eff = Lambda_nn -
// mu Lambda_nt vanishes at mu_c = (1 + 3 c^2) / (3 c (s + rho / l)) (S12). Above it the start is
// refused naming the contact, t and w_eff; below it the rod slides with N = m g / (m w_eff) (S8).
TEST(ContactModes, PainlevesRodStopsAboveTheCriticalFrictionAndSlidesBelowIt) {
  const double b0 = std::atan(2.0), g = 9.81;
  const RodInertia L = rod_inertia(b0);
  const double mu_c = L.nn / L.nt;
  EXPECT_NEAR(mu_c, 1.30417, 1e-5);
  {
    const double mu = 1.01 * mu_c;
    const Model model = load_model_text(painleve_rod(fmt::format("friction = {:.17g}\n", mu), b0, 0.0, 2.0), "rod.toml");
    SimulationOptions options;
    options.t_end = 0.05;
    try {
      simulate(model, options, [](const Data&) {});
      ADD_FAILURE() << "accepted";
    } catch (const ModelError& e) {
      const std::string message = e.what();
      EXPECT_NE(message.find("rod.toml:"), std::string::npos) << message;
      EXPECT_NE(message.find("contact 'end' slides in Painleve's paradox at t = 0"), std::string::npos) << message;
      EXPECT_NE(message.find(fmt::format("w_eff = {:.6g} 1/kg", L.nn - mu * L.nt)), std::string::npos) << message;
      EXPECT_NE(message.find(fmt::format("frictionless {:.6g} 1/kg", L.nn)), std::string::npos) << message;
      EXPECT_NE(message.find("no mode is consistent"), std::string::npos) << message;
    }
  }
  const double mu = 0.99 * mu_c;
  const Model model = load_model_text(painleve_rod(fmt::format("friction = {:.17g}\n", mu), b0, 0.0, 2.0), "rod.toml");
  ModeRun r;
  r.columns = make_result_columns(model);
  SimulationOptions options;
  options.t_end = 0.002;
  options.output_step = 0.001;
  options.integrator.rtol = 1e-10;
  options.integrator.atol = 1e-12;
  r.summary = simulate(model, options, [&](const Data& data) {
    std::vector<double> row;
    fill_result_row(model, data, row);
    r.rows.push_back(std::move(row));
  });
  EXPECT_EQ(r.summary.status, Status::ok) << r.summary.message;
  // It slides, until the large friction stops the slip (a stick, not a stop: the "dynamic jam").
  EXPECT_EQ(r.at(0, "end_mode"), 1.0);
  for (const EventRecord& e : r.summary.events.crossings) EXPECT_EQ(e.name, "end_stick");
  // Near the singularity N is large: 100 m g at 1 % below mu_c.
  EXPECT_NEAR(r.at(0, "end_N"), g / (L.nn - mu * L.nt), 1e-9 * g / (L.nn - mu * L.nt));
  EXPECT_NEAR(r.at(0, "end_Fx"), -mu * r.at(0, "end_N"), 1e-9 * r.at(0, "end_N"));
}

// Painleve's paradox met during a run: the rod stands on its end (rolling, at b0 = atan(2)) and a
// torque -T t about y, growing, tips it over faster than gravity: the friction rolling needs
// points to -x and grows while N falls, so the end slips, away from under the rod (sigma = +1).
// With mu_k above mu_c(b) (S12) that sliding start is in Painleve's paradox: the run ends
// there (not a bad start) with the contact, t and w_eff = Lambda_nn - mu Lambda_nt at the
// configuration reached, and the rows so far; below min mu_c (1.30416 at b = 1.105) it slides on.
TEST(ContactModes, PainlevesRodTippedByATorqueStopsWhereItWouldStartSliding) {
  const double b0 = std::atan(2.0);
  const auto rod = [&](double mu) {
    std::string text = painleve_rod(fmt::format("friction = {}\nmode = \"rolling\"\n", mu), b0, 0.0, 0.0);
    text.replace(text.find("[initial]"), 9, "[forces]\nb = \"-100*t\"\n[initial]");
    return load_model_text(text, "rod.toml");
  };
  const auto run = [](const Model& model, double t_end) {
    ModeRun r;
    r.columns = make_result_columns(model);
    SimulationOptions options;
    options.t_end = t_end;
    options.output_step = 1e-5;
    options.integrator.rtol = 1e-10;
    options.integrator.atol = 1e-12;
    r.summary = simulate(model, options, [&](const Data& data) {
      std::vector<double> row;
      fill_result_row(model, data, row);
      r.rows.push_back(std::move(row));
    });
    return r;
  };
  const ModeRun stop = run(rod(1.5), 0.1);
  EXPECT_NE(stop.summary.status, Status::ok);
  const std::string& message = stop.summary.message;
  EXPECT_NE(message.find("contact 'end' slides in Painleve's paradox at t = "), std::string::npos) << message;
  // The torque lifts the free rod's end (nu_0 > 0): sliding with N > 0 and free are both
  // consistent, Painleve's indeterminacy (the table of 3.4).
  EXPECT_NE(message.find("two modes are consistent"), std::string::npos) << message;
  EXPECT_NE(message.find("the run ends here with its results so far"), std::string::npos) << message;
  ASSERT_GT(stop.rows.size(), 100u);  // the rows before are kept
  const std::size_t last = stop.rows.size() - 1;
  EXPECT_EQ(stop.at(last, "end_mode"), 0.0);
  // The stop is where the rolling friction reaches the cone, |F| = mu N, ...
  EXPECT_NEAR(std::abs(stop.at(last, "end_Fx")) / stop.at(last, "end_N"), 1.5, 1e-2);
  EXPECT_LT(stop.at(last, "end_Fx"), 0.0);
  // ... and the w_eff it reports is (S11) at the configuration reached (the last row, 1e-5 s before).
  const std::size_t at = message.find("w_eff = ");
  ASSERT_NE(at, std::string::npos);
  const double w_eff = std::stod(message.substr(at + 8));
  const RodInertia L = rod_inertia(stop.at(last, "b"));
  EXPECT_NEAR(w_eff, L.nn - 1.5 * L.nt, 1e-3);
  EXPECT_LT(w_eff, 0.0);

  const ModeRun slides = run(rod(1.2), 0.1);
  ASSERT_GE(slides.summary.events.crossings.size(), 1u) << slides.summary.message;
  EXPECT_EQ(slides.summary.events.crossings[0].name, "end_slip");
  EXPECT_EQ(slides.at(mode_switch_row(slides, slides.summary.events.crossings[0].t), "end_mode"), 1.0);
  EXPECT_EQ(slides.summary.message.find("Painleve"), std::string::npos) << slides.summary.message;
}

// Newton's law with a sticking impulse gains energy at a coupled contact when e^2 > 1 - M_nt^2 /
// (M_nn M_tt) = 1 - Lambda_nt^2 / (Lambda_nn Lambda_tt), for the approach v_t = (Lambda_nt /
// Lambda_nn) v_n (section 7): the rod landing at b = 0.6 with e = 0.95. The impact is warned about
// once, impact_loss is the closed form (v^T M v - e^2 M_nn v_n^2) / 2 < 0, and h - h0 - W holds.
TEST(ContactModes, AnImpactThatGainsEnergyIsWarnedAboutOnceAndBookedInImpactLoss) {
  const double b = 0.6, g = 9.81, h = 0.02, e = 0.95;
  const RodInertia L = rod_inertia(b);
  EXPECT_GT(e * e, 1 - L.nt * L.nt / (L.nn * L.tt));
  const double t1 = std::sqrt(2 * h / g), vn = -g * t1, vt = L.nt / L.nn * vn;
  const Model model = load_model_text(painleve_rod(fmt::format("restitution = {}\n", e), b, h, vt), "rod.toml");
  const ModeRun r = run_modes(model, t1 + 0.01);
  ASSERT_GE(r.summary.events.crossings.size(), 1u);
  EXPECT_EQ(r.summary.events.crossings[0].name, "end_touchdown");
  EXPECT_NEAR(r.summary.events.crossings[0].t, t1, 1e-9);
  // M = Lambda^-1 (2 x 2, t and n): v^T M v = (Lnn vt^2 - 2 Lnt vt vn + Ltt vn^2) / det.
  const double det = L.tt * L.nn - L.nt * L.nt;
  const double loss = ((L.nn * vt * vt - 2 * L.nt * vt * vn + L.tt * vn * vn) / det - e * e * L.tt / det * vn * vn) / 2;
  EXPECT_LT(loss, 0.0);
  EXPECT_NEAR(r.at(mode_switch_row(r, t1 + (r.summary.events.crossings[0].t - t1)), "impact_loss"), loss, 1e-10);
  ASSERT_EQ(r.summary.warnings.size(), 1u);
  const std::string& warning = r.summary.warnings[0];
  EXPECT_NE(warning.find("contact 'end': the impact at t = "), std::string::npos) << warning;
  EXPECT_NE(warning.find("gains energy"), std::string::npos) << warning;
  EXPECT_NE(warning.find(fmt::format("{:.6g} J", -loss)), std::string::npos) << warning;
  EXPECT_LT(r.summary.energy.balance_error, 1e-9);
}

std::string thrown_ball_with(const std::string& keys) {
  std::string text = test::read_text(example("ball_thrown_sliding.toml"));
  const std::string old = "friction = \"mu\"\nmode = \"sliding\"\n";
  const std::size_t at = text.find(old);
  EXPECT_NE(at, std::string::npos);
  return text.replace(at, old.size(), keys);
}

void expect_mode_keys_refused(const std::string& keys, const std::string& words) {
  SCOPED_TRACE(keys);
  try {
    load_model_text(thrown_ball_with(keys), "ball.toml");
    ADD_FAILURE() << "accepted";
  } catch (const ModelError& e) {
    const std::string message = e.what();
    EXPECT_NE(message.find("ball.toml:"), std::string::npos) << message;
    EXPECT_NE(message.find("contact 'ball'"), std::string::npos) << message;
    EXPECT_NE(message.find(words), std::string::npos) << message;
  }
}

TEST(ContactModes, BadKeysAreRefusedNamingTheContactAndTheLine) {
  expect_mode_keys_refused("friction = -0.1\n", "a Coulomb friction coefficient is a number >= 0");
  expect_mode_keys_refused("friction = \"-mu\"\n", "a Coulomb friction coefficient is a number >= 0");
  expect_mode_keys_refused("friction = [0.2, 0.3]\n", "mu_s = 0.2 below mu_k = 0.3");
  expect_mode_keys_refused("friction = 0.2\nrestitution = 1.5\n", "between 0");
  expect_mode_keys_refused("friction = 0.2\nmode = \"slipping\"\n", "unknown mode 'slipping'");
  expect_mode_keys_refused("mode = \"sliding\"\n", "needs a friction coefficient");
  expect_mode_keys_refused("friction = 0.2\nmode = \"free\"\n", "needs unilateral = true");
}

// The solve of the contact modes works in the coordinates' own scales (formulation/contact_modes.cpp,
// coordinate_scales): a tippe top 40 nm across has the inertias of its quaternion 1e-12 below its
// mass, and the stacked matrix of its sliding was judged singular at the start (Painleve's
// paradox, the run refused) where the 4 cm top slides. Scaled by 1e-6 or 1e6 it slides as the
// example does, to the integration's tolerance, through its first 0.1 s.
TEST(ContactModes, ATippeTopFortyNanometresOrFortyKilometresAcrossSlidesAsTheExampleDoes) {
  const ModeRun reference = run_scaled_tippe_top(1.0, 0.1);
  ASSERT_EQ(reference.summary.status, Status::ok) << reference.summary.message;
  for (const double scale : {1e-6, 1e6}) {
    const ModeRun scaled = run_scaled_tippe_top(scale, 0.1);
    ASSERT_EQ(scaled.summary.status, Status::ok) << "scale " << scale << ": " << scaled.summary.message;
    ASSERT_EQ(scaled.rows.size(), reference.rows.size()) << "scale " << scale;
    for (std::size_t i = 0; i < reference.rows.size(); ++i) {
      EXPECT_EQ(scaled.at(i, "ball_mode"), reference.at(i, "ball_mode")) << "scale " << scale << ", t = " << reference.rows[i][0];
      for (const char* name : {"z", "e0", "e1", "e2", "e3"})
        EXPECT_NEAR(scaled.at(i, name), reference.at(i, name), 1e-8)
            << "scale " << scale << ", " << name << " at t = " << reference.rows[i][0];
    }
  }
}

// The impulse at a touchdown is solved in the same coordinates' scales (analysis/detail/
// contact_switches.cpp, solve_impulse): the disk of examples/rolling_disk_hop.toml a micrometre
// across (its angles' inertias 1e-14 of its mass) ended at its first touchdown, "the impulse
// equations are singular", as it did at 1e8 times the example's lengths. At both it lands, bounces
// and lands again at the example's times, every state in the example's units to the tolerance.
TEST(ContactModes, ADiskAMicrometreOrAHundredThousandKilometresAcrossHopsAsTheExampleDoes) {
  const auto run = [](double scale) {
    const Model model = load_model(example("rolling_disk_hop.toml"),
                                   {{"r", 0.2 * scale}, {"g", 9.81 * scale}, {"h", 0.05 * scale}});
    ModeRun out = run_modes(model, 0.3, 1e-12 * std::min(1.0, scale));
    for (const char* name : {"x", "y", "z"})
      for (std::vector<double>& row : out.rows) row.at(static_cast<std::size_t>(mode_column(out.columns, name))) /= scale;
    return out;
  };
  const ModeRun reference = run(1.0);
  ASSERT_EQ(reference.summary.status, Status::ok) << reference.summary.message;
  // Three touchdowns in 0.3 s (rows off the 0.01 s grid), the first at t1 = 0.1009637...
  std::vector<double> touchdowns;
  for (const std::vector<double>& row : reference.rows)
    if (std::abs(row[0] * 100.0 - std::round(row[0] * 100.0)) > 1e-6) touchdowns.push_back(row[0]);
  ASSERT_EQ(touchdowns.size(), 3u);
  for (const double scale : {1e-6, 1e8}) {
    const ModeRun scaled = run(scale);
    ASSERT_EQ(scaled.summary.status, Status::ok) << "scale " << scale << ": " << scaled.summary.message;
    ASSERT_EQ(scaled.rows.size(), reference.rows.size()) << "scale " << scale;
    for (std::size_t i = 0; i < reference.rows.size(); ++i) {
      EXPECT_NEAR(scaled.rows[i][0], reference.rows[i][0], 1e-10) << "scale " << scale;
      EXPECT_EQ(scaled.at(i, "disk_mode"), reference.at(i, "disk_mode")) << "scale " << scale << ", t = " << reference.rows[i][0];
      for (const char* name : {"x", "y", "z", "psi", "theta", "phi", "theta'"})
        EXPECT_NEAR(scaled.at(i, name), reference.at(i, name), 1e-8)
            << "scale " << scale << ", " << name << " at t = " << reference.rows[i][0];
    }
  }
}

// The coefficients are checked as the run evaluates them, after --set: the model file's checks
// (expect_mode_keys_refused above) saw the file's values only, and a friction of -0.1 made the
// thrown ball speed up, a restitution of -0.5 sank the disk into the floor, both with exit 0.
TEST(ContactModes, CoefficientsGivenThroughParametersAreCheckedAsEvaluated) {
  const auto refused = [](const char* file, const char* name, double value) -> std::string {
    const Model model = load_model(example(file), {{name, value}});
    SimulationOptions options;
    options.t_end = 0.01;
    try {
      simulate(model, options, [](const Data&) {});
    } catch (const ModelError& e) {
      return e.what();
    }
    return "";
  };
  EXPECT_NE(refused("ball_thrown_sliding.toml", "mu", -0.1).find("contact 'ball': its friction coefficients are "
                                                                 "mu_s = -0.1, mu_k = -0.1"),
            std::string::npos);
  EXPECT_NE(refused("rolling_disk_hop.toml", "e", -0.5).find("contact 'disk': its restitution is -0.5"),
            std::string::npos);
  EXPECT_NE(refused("rolling_disk_hop.toml", "e", 2.0).find("its restitution is 2"), std::string::npos);
  EXPECT_EQ(refused("rolling_disk_hop.toml", "e", 1.0), "");
  EXPECT_EQ(refused("ball_thrown_sliding.toml", "mu", 0.0), "");
}

}  // namespace
}  // namespace nhdyn
