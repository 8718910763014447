// A body with more contact rows than coordinates (s >= n), whose contacts are never all held
// (docs/contact-modes.md, "More contacts than freedom"): examples/ball_off_sphere_onto_floor.toml
// against the closed form of docs/derivations/contact-modes.md section 10.6 (lift-off from the
// sphere, the parabola to the floor, the plastic landing that keeps the angular momentum about the
// contact point), the contact forces of the contacts touching, and what is refused: contacts
// held together that wedge the body, rows held in every mode that reach n, and the analyses that
// hold every row at once. Also compare on a run with switch rows (they come between output times).
#include <fmt/format.h>
#include <gtest/gtest.h>

#include <cmath>
#include <string>
#include <vector>

#include "nhdyn/analysis/comparison.hpp"
#include "nhdyn/analysis/linearization.hpp"
#include "nhdyn/analysis/simulation.hpp"
#include "nhdyn/core/error.hpp"
#include "nhdyn/frontend/events.hpp"
#include "nhdyn/frontend/load_model.hpp"
#include "nhdyn/integrators/ode.hpp"
#include "nhdyn/frontend/model_file.hpp"
#include "nhdyn/io/results.hpp"
#include "nhdyn/model/parameters.hpp"
#include "nhdyn/symbolic/derivation.hpp"
#include "nhdyn/symbolic/equations.hpp"
#include "support/models.hpp"
#include "support/text.hpp"

namespace nhdyn {
namespace {

using nhdyn::test::example;

struct FloorRun {
  SimulationSummary summary;
  ResultColumns columns;
  std::vector<std::vector<double>> rows;
  double at(std::size_t row, const std::string& name) const {
    for (std::size_t i = 0; i < columns.all.size(); ++i)
      if (columns.all[i] == name) return rows.at(row).at(i);
    ADD_FAILURE() << "no column " << name;
    return 0.0;
  }
};

// The runs' options: the example's tolerances.
SimulationOptions run_options(double t_end, double output_step, IntegratorKind integrator = IntegratorKind::dopri5) {
  SimulationOptions options;
  options.t_end = t_end;
  options.output_step = output_step;
  options.integrator.kind = integrator;
  options.integrator.rtol = 1e-10;
  options.integrator.atol = 1e-12;
  return options;
}

FloorRun run(const Model& model, double t_end) {
  FloorRun out;
  out.columns = make_result_columns(model);
  const SimulationOptions options = run_options(t_end, 0.01);
  out.summary = simulate(model, options, [&](const Data& data) {
    std::vector<double> row;
    fill_result_row(model, data, row);
    out.rows.push_back(std::move(row));
  });
  return out;
}

std::string floor_example() { return test::read_text(example("ball_off_sphere_onto_floor.toml")); }

std::string replaced(std::string text, const std::string& from, const std::string& to) {
  const std::size_t at = text.find(from);
  EXPECT_NE(at, std::string::npos) << from;
  if (at != std::string::npos) text.replace(at, from.size(), to);
  return text;
}

// Section 10.6: m = 0.1, r = 0.1, R = 1, H = 1.5, theta0 = 1e-3, k = 2/5.
TEST(MoreContactsThanCoordinates, ABallRollsOffASphereLandsOnTheFloorAndRollsOnAtTheClosedFormSpeed) {
  const Model model = load_model(example("ball_off_sphere_onto_floor.toml"));
  ASSERT_EQ(model.n(), 6);
  ASSERT_EQ(model.s(), 6);  // both contacts held would leave no motion
  const FloorRun r = run(model, 4.0);
  ASSERT_EQ(r.summary.status, Status::ok) << r.summary.message;
  const double m = 0.1, g = 9.81, rr = 0.1, rho = 1.1, H = 1.5, theta0 = 1e-3, k = 0.4;

  ASSERT_EQ(r.summary.events.crossings.size(), 2u);
  const EventRecord& liftoff = r.summary.events.crossings[0];
  const EventRecord& touchdown = r.summary.events.crossings[1];
  EXPECT_EQ(liftoff.name, "ball_liftoff");
  EXPECT_EQ(touchdown.name, "floor_touchdown");
  // Lift-off from the sphere at cos(theta) = 2 cos(theta0) / (3 + k), at the speed N = 0 gives.
  const double c = 2 * std::cos(theta0) / (3 + k), s = std::sqrt(1 - c * c);
  const double vL = std::sqrt(g * rho * c);
  EXPECT_NEAR((liftoff.q[2] - H) / rho, c, 1e-9);
  EXPECT_NEAR(liftoff.v[0], vL * c, 1e-8);
  EXPECT_NEAR(liftoff.v[2], -vL * s, 1e-8);
  EXPECT_NEAR(liftoff.v[4], vL / rr, 1e-7);  // b' = omega_y: rolling on the sphere's outside
  // (F1): the parabola from the lift-off reaches z = r after tau.
  const double zL = H + rho * c;
  const double tau = (-vL * s + std::sqrt(vL * vL * s * s + 2 * g * (zL - rr))) / g;
  EXPECT_NEAR(touchdown.t - liftoff.t, tau, 1e-8);
  EXPECT_NEAR(touchdown.q[2], rr, 1e-10);

  // (F2) after the plastic landing, then constant; the floor carries m g, the sphere nothing.
  const double vx = (vL * c + k * vL) / (1 + k);
  const std::size_t last = r.rows.size() - 1;
  EXPECT_NEAR(r.at(last, "x'"), vx, 1e-8);
  EXPECT_NEAR(r.at(last, "b'"), vx / rr, 1e-7);
  EXPECT_NEAR(r.at(last, "z'"), 0.0, 1e-10);
  EXPECT_EQ(r.at(last, "ball_mode"), 2.0);
  EXPECT_EQ(r.at(last, "floor_mode"), 0.0);
  EXPECT_NEAR(r.at(last, "floor_N"), m * g, 1e-10);
  EXPECT_NEAR(r.at(last, "floor_Fx"), 0.0, 1e-10);
  EXPECT_EQ(r.at(last, "ball_N"), 0.0);  // a free contact's unknowns are not solved for
  EXPECT_EQ(r.at(last, "ball_Fx"), 0.0);
  // The landing took the energy the closed form says, and the balance holds through it.
  const double E0 = m * g * (H + rho * std::cos(theta0));
  EXPECT_NEAR(r.at(last, "impact_loss"), E0 - (1 + k) * m * vx * vx / 2 - m * g * rr, 1e-9);
  EXPECT_LT(r.summary.energy.balance_error, 1e-9);

  // While it rolls on the sphere, its normal force is (R2) of section 10.2, the floor's 0.
  bool checked = false;
  for (std::size_t i = 0; i < r.rows.size(); ++i) {
    if (r.at(i, "t") < 1.0 || r.at(i, "ball_mode") != 0.0) continue;
    const double ct = (r.at(i, "z") - H) / rho;
    EXPECT_NEAR(r.at(i, "ball_N"), m * g * ((3 + k) * ct - 2 * std::cos(theta0)) / (1 + k), 1e-9);
    EXPECT_EQ(r.at(i, "floor_N"), 0.0);
    EXPECT_EQ(r.at(i, "floor_mode"), 2.0);
    checked = true;
  }
  EXPECT_TRUE(checked);
}

// More rows than coordinates (s > n): a third contact, a plane through the origin tilted below the
// floor where the ball lands (free throughout), or rubber rolling on the floor (a fourth row of its
// own): 9 and 7 rows on 6 coordinates load and give the run of the example, to round-off.
TEST(MoreContactsThanCoordinates, MoreRowsThanCoordinatesLoadAndRunAsTheExample) {
  const FloorRun base = run(load_model(example("ball_off_sphere_onto_floor.toml")), 4.0);
  ASSERT_EQ(base.summary.status, Status::ok) << base.summary.message;
  const std::string wall = floor_example() + R"toml(
[[contacts]]
name = "below"
body = "ball"
shape = { sphere = "r" }
ground = { plane = [0.1, 0, 1] }
unilateral = true
mode = "free"
)toml";
  const std::string rubber = replaced(floor_example(), "ground = \"plane\"\n", "ground = \"plane\"\nrolling = \"rubber\"\n");
  for (const auto& [text, rows] : {std::pair{wall, 9}, std::pair{rubber, 7}}) {
    const Model model = load_model_text(text, "more.toml");
    EXPECT_EQ(model.s(), rows);
    const FloorRun r = run(model, 4.0);
    ASSERT_EQ(r.summary.status, Status::ok) << r.summary.message;
    ASSERT_EQ(r.summary.events.crossings.size(), 2u);
    EXPECT_NEAR(r.summary.events.crossings[1].t, base.summary.events.crossings[1].t, 1e-9);
    EXPECT_NEAR(r.at(r.rows.size() - 1, "x'"), base.at(base.rows.size() - 1, "x'"), 1e-9);
  }
}

// Every integrator that locates events gives the closed form's landing. Right after the lift-off
// the gap sits at the integration error: CVODE's first steps are shorter than the time it needs to
// rise above it, and its root finding saw the gap cross 0 there (a touchdown with no approach
// speed, then another: a false Zeno that ended the run). Such a crossing is no impact.
TEST(MoreContactsThanCoordinates, EveryIntegratorLandsTheBallAtTheClosedFormSpeed) {
  const Model model = load_model(example("ball_off_sphere_onto_floor.toml"));
  const double k = 0.4, c = 2 * std::cos(1e-3) / (3 + k), vL = std::sqrt(9.81 * 1.1 * c);
  for (const IntegratorKind integrator :
       {IntegratorKind::dopri5, IntegratorKind::dop853, IntegratorKind::cvode_bdf, IntegratorKind::cvode_adams}) {
    const SimulationOptions options = run_options(4.0, 0.5, integrator);
    double last_vx = 0.0;
    const SimulationSummary summary =
        simulate(model, options, [&](const Data& data) { last_vx = data.v(0); });
    ASSERT_EQ(summary.status, Status::ok) << integrator_name(integrator) << ": " << summary.message;
    ASSERT_EQ(summary.events.crossings.size(), 2u) << integrator_name(integrator);
    EXPECT_EQ(summary.events.crossings[1].name, "floor_touchdown");
    EXPECT_NEAR(last_vx, (vL * c + k * vL) / (1 + k), 1e-6) << integrator_name(integrator);
  }
  // With friction on the sphere the ball slips first (section 10.2, (R3)) and lifts off while
  // sliding, its gap then at -3e-12 (the drift): no touchdown follows before the floor's (there
  // was one at the lift-off itself, with dopri5 here and with cvode-bdf at every tolerance).
  const std::string text = replaced(floor_example(), "side = \"outside\" }\nunilateral = true\n",
                                    "side = \"outside\" }\nunilateral = true\nfriction = 0.3\n");
  const Model friction = load_model_text(text, "friction.toml");
  const auto angle = [](const EventRecord& e) { return std::atan2(e.q[0], e.q[2] - 1.5) * 180 / M_PI; };
  for (const IntegratorKind integrator :
       {IntegratorKind::dopri5, IntegratorKind::dop853, IntegratorKind::cvode_bdf, IntegratorKind::cvode_adams}) {
    const SimulationOptions options = run_options(4.0, 0.5, integrator);
    const SimulationSummary summary = simulate(friction, options, [](const Data&) {});
    ASSERT_EQ(summary.status, Status::ok) << integrator_name(integrator) << ": " << summary.message;
    std::vector<std::string> names;
    for (const EventRecord& e : summary.events.crossings) names.push_back(e.name);
    ASSERT_EQ(names, (std::vector<std::string>{"ball_slip", "ball_liftoff", "floor_touchdown"}))
        << integrator_name(integrator);
    EXPECT_NEAR(angle(summary.events.crossings[0]), 35.38, 0.01);  // the derivation's figures for mu = 0.3
    EXPECT_NEAR(angle(summary.events.crossings[1]), 52.12, 0.01);
  }
}

// Both contacts held at the start: six rows on six coordinates, no motion. The run is refused with
// the contacts named, before any row.
TEST(MoreContactsThanCoordinates, ContactsHeldTogetherThatWedgeTheBodyAreRefusedNamingThem) {
  const std::string text = replaced(floor_example(), "mode = \"free\"", "mode = \"rolling\"");
  const Model model = load_model_text(text, "wedged.toml");
  try {
    run(model, 1.0);
    FAIL() << "a wedged start ran";
  } catch (const ModelError& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find("the contacts 'ball', 'floor' held together keep 6 constraint rows on 6 coordinates"),
              std::string::npos)
        << what;
    EXPECT_NE(what.find("mode = \"free\""), std::string::npos) << what;
  }
}

// Rows that no mode drops count against n: with both contacts bilateral and without friction the
// six rows are held in every mode, which is refused at load with the count; with one of them
// unilateral, three rows are always held and the model loads.
TEST(MoreContactsThanCoordinates, RowsHeldInEveryModeThatReachNAreRefusedAtLoad) {
  std::string text = floor_example();
  text = replaced(text, "unilateral = true\n\n", "\n");  // the sphere's contact: bilateral, no friction
  text = replaced(text, "unilateral = true\nrestitution = 0\nmode = \"free\"\n", "");
  try {
    load_model_text(text, "bilateral.toml");
    FAIL() << "six bilateral rows on six coordinates loaded";
  } catch (const ModelError& e) {
    EXPECT_NE(std::string(e.what()).find("6 constraints for 6 coordinates"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("bilateral.toml"), std::string::npos) << e.what();
  }
  // One of them unilateral: 3 rows always held, the model loads.
  const std::string one = replaced(floor_example(), "unilateral = true\n\n", "\n");
  EXPECT_NO_THROW(load_model_text(one, "one.toml"));
}

// A ball and two grounds, the floor z = 0 and a wall x = 0 (the ball on its -x side), with the
// keys each test gives its two contacts.
std::string floor_and_wall(const std::string& floor_keys, const std::string& wall_keys, const std::string& start) {
  return R"toml(name = "floor-and-wall"
coordinates = ["x", "y", "z", "a", "b", "c"]
gravity = [0, 0, "-g"]

[parameters]
m = 0.1
r = 0.1
g = 9.81

[[frames]]
name = "ball"
translation = ["x", "y", "z"]
rotations = [["y", "b"], ["x", "a"], ["z", "c"]]

[[bodies]]
name = "ball"
frame = "ball"
mass = "m"
inertia = ["2/5*m*r^2", "2/5*m*r^2", "2/5*m*r^2"]

[[contacts]]
name = "floor"
body = "ball"
shape = { sphere = "r" }
ground = "plane"
unilateral = true
)toml" + floor_keys + R"toml(
[[contacts]]
name = "wall"
body = "ball"
shape = { sphere = "r" }
ground = { plane = [-1, 0, 0] }
unilateral = true
)toml" + wall_keys + "\n[initial]\n" + start + "\n";
}

// A ball slid without spin along a rough floor (mu = 0.1) into the wall, which holds it without
// slip (no friction limit) and returns it at e = 1/2. Before the wall its speed falls as
// v0 - mu g t while the friction spins it up (omega = 5 mu g t / (2 r)). The wall's impulse
// reverses v_x to -e v_b and, stopping its contact point, takes the spin's part k r omega / (1 + k)
// as an upward speed: held, the floor would have to pull the ball down (it did), so it lifts off
// there. The ball flies 2 v_z / g, lands sliding (the sticking impulse is outside the cone: the
// landing takes mu V off v_x's magnitude and mu V (1 + k) / k off the slip), and the floor's
// friction opposes the slip left (it used to keep the direction of the slip before the wall and
// push: the energy grew) until it sticks, 2 |s| / (7 mu g) later, at v_x - mu g that time.
TEST(MoreContactsThanCoordinates, ASlidingContactTakesTheSlipThatAnotherContactsImpactLeaves) {
  const std::string text = floor_and_wall("friction = 0.1\n", "restitution = 0.5\nmode = \"free\"\n",
                                          "position = { x = -0.5, y = 0, z = \"r\", a = 0, b = 0, c = 0 }\n"
                                          "velocity = { x = 2, y = 0, z = 0, a = 0, b = 0, c = 0 }");
  const FloorRun r = run(load_model_text(text, "wall.toml"), 2.0);
  ASSERT_EQ(r.summary.status, Status::ok) << r.summary.message;
  const double mu = 0.1, g = 9.81, v0 = 2.0, e = 0.5, k = 0.4, rr = 0.1;
  const double tw = (v0 - std::sqrt(v0 * v0 - 2 * mu * g * 0.4)) / (mu * g);  // the centre 0.4 on, at x = -r
  const double vb = v0 - mu * g * tw, wb = 5 * mu * g * tw / (2 * rr);
  const double vx = -e * vb, vz = k * rr * wb / (1 + k), w = vz / rr;  // after the wall
  const double tl = tw + 2 * vz / g;                                   // the landing
  const double slip = std::abs(vx - rr * w) - mu * vz * (1 + k) / k;   // after the landing
  const double vl = vx + mu * vz, ts = tl + 2 * slip / (7 * mu * g);
  std::vector<std::string> names;
  for (const EventRecord& c : r.summary.events.crossings) names.push_back(c.name);
  ASSERT_EQ(names, (std::vector<std::string>{"wall_touchdown", "floor_liftoff", "floor_touchdown", "floor_stick"}));
  EXPECT_NEAR(r.summary.events.crossings[0].t, tw, 1e-9);
  EXPECT_EQ(r.summary.events.crossings[1].t, r.summary.events.crossings[0].t);
  EXPECT_NEAR(r.summary.events.crossings[1].v[0], vx, 1e-10);
  EXPECT_NEAR(r.summary.events.crossings[1].v[2], vz, 1e-10);
  EXPECT_NEAR(r.summary.events.crossings[1].v[4], w, 1e-9);  // b' = omega_y
  EXPECT_NEAR(r.summary.events.crossings[2].t, tl, 1e-9);
  EXPECT_NEAR(r.summary.events.crossings[2].v[0], vl, 1e-9);
  EXPECT_NEAR(r.summary.events.crossings[3].t, ts, 1e-8);
  const std::size_t last = r.rows.size() - 1;
  EXPECT_NEAR(r.at(last, "x'"), vl + mu * g * (ts - tl), 1e-8);
  EXPECT_LE(r.at(last, "work_friction"), 0.0);
  EXPECT_LT(r.summary.energy.balance_error, 1e-12);
}

// Both gaps closing at one instant (the ball thrown into the corner, frictionless, e = 1/2 at
// both): both touchdowns are taken there, one after the other (the second's gap was not positive
// where the segment after the first starts, and it used to pass through the wall), and the ball
// flies back at (-e v_x, -e v_z), to land again 2 e v_z / g later.
TEST(MoreContactsThanCoordinates, TwoTouchdownsAtOneInstantAreBothTaken) {
  const std::string text = floor_and_wall("friction = 0\nrestitution = 0.5\nmode = \"free\"\n",
                                          "friction = 0\nrestitution = 0.5\nmode = \"free\"\n",
                                          "position = { x = -1.1, y = 0, z = 1.1, a = 0, b = 0, c = 0 }\n"
                                          "velocity = { x = 2, y = 0, z = 0.4525, a = 0, b = 0, c = 0 }");
  const FloorRun r = run(load_model_text(text, "corner.toml"), 1.0);
  ASSERT_EQ(r.summary.status, Status::ok) << r.summary.message;
  const double vz = 0.4525 - 9.81 * 0.5;  // at t = 0.5, where x = -r and z = r
  ASSERT_EQ(r.summary.events.crossings.size(), 3u);
  EXPECT_NEAR(r.summary.events.crossings[0].t, 0.5, 1e-12);
  EXPECT_NEAR(r.summary.events.crossings[1].t, 0.5, 1e-12);
  EXPECT_NE(r.summary.events.crossings[0].name, r.summary.events.crossings[1].name);
  EXPECT_NEAR(r.summary.events.crossings[1].v[0], -1.0, 1e-10);
  EXPECT_NEAR(r.summary.events.crossings[1].v[2], -0.5 * vz, 1e-10);
  EXPECT_EQ(r.summary.events.crossings[2].name, "floor_touchdown");
  EXPECT_NEAR(r.summary.events.crossings[2].t, 0.5 - 2 * 0.5 * vz / 9.81, 1e-9);
  for (std::size_t i = 0; i < r.rows.size(); ++i) EXPECT_GT(r.at(i, "wall_gap"), -1e-9) << "at t = " << r.at(i, "t");
  // Plastic at the floor and holding there, the wall's rows join the floor's rolling ones: six of
  // rank 5 (the ball could still spin about the line through both contact points), which the Do
  // Sanh form cannot take: the run ends naming both contacts, not through the wall.
  const std::string plastic = floor_and_wall("mode = \"free\"\n", "restitution = 0.5\nmode = \"free\"\n",
                                             "position = { x = -1.1, y = 0, z = 1.1, a = 0, b = 0, c = 0 }\n"
                                             "velocity = { x = 2, y = 0, z = 0.4525, a = 0, b = 0, c = 0 }");
  const FloorRun p = run(load_model_text(plastic, "plastic.toml"), 1.0);
  EXPECT_EQ(p.summary.status, Status::integrator_failure);
  EXPECT_NE(p.summary.message.find("'floor' (rolling), 'wall' (touching down), keep 6 constraint rows of rank 5 on 6"),
            std::string::npos)
      << p.summary.message;
}

// A ball sliding without friction along the floor at 3 m/s into a dome (a sphere of radius 1
// centred 0.9 below the floor), frictionless too, e = 1/2. The dome's impulse along its normal n
// lifts the ball: held through the impact, the floor would have to pull it down (it did: the ball
// left at (1.5, 0)). It leaves instead, with its own NAME_liftoff, and the ball flies off at
// v - (1 + e)(v . n) n.
TEST(MoreContactsThanCoordinates, AContactThatWouldPullThroughAnotherContactsImpactLeavesTheGround) {
  std::string text = floor_and_wall("friction = 0\n", "friction = 0\nrestitution = 0.5\nmode = \"free\"\n",
                                    "position = { x = 0.9, y = 0, z = \"r\", a = 0, b = 0, c = 0 }\n"
                                    "velocity = { x = -3, y = 0, z = 0, a = 0, b = 0, c = 0 }");
  text = replaced(text, "ground = { plane = [-1, 0, 0] }",
                  "ground = { surface = \"X^2 + Y^2 + (Z + 0.9)^2 - 1\", side = \"outside\" }");
  const FloorRun r = run(load_model_text(text, "dome.toml"), 0.3);
  ASSERT_EQ(r.summary.status, Status::ok) << r.summary.message;
  const double xc = std::sqrt(1.1 * 1.1 - 1.0);  // the centre where it meets the dome, at z = r
  std::string names;
  for (const EventRecord& e : r.summary.events.crossings) names += fmt::format(" {} {}", e.name, e.t);
  ASSERT_EQ(r.summary.events.crossings.size(), 2u) << names;
  EXPECT_EQ(r.summary.events.crossings[0].name, "wall_touchdown");
  EXPECT_NEAR(r.summary.events.crossings[0].t, (0.9 - xc) / 3, 1e-10);
  EXPECT_EQ(r.summary.events.crossings[1].name, "floor_liftoff");
  EXPECT_EQ(r.summary.events.crossings[1].t, r.summary.events.crossings[0].t);
  const double nx = xc / 1.1, nz = 1.0 / 1.1, vn = -3 * nx;
  EXPECT_NEAR(r.summary.events.crossings[1].v[0], -3 - 1.5 * vn * nx, 1e-10);
  EXPECT_NEAR(r.summary.events.crossings[1].v[2], -1.5 * vn * nz, 1e-10);
  EXPECT_EQ(r.at(r.rows.size() - 1, "floor_mode"), 2.0);
}

// A ball rolling at 2 m/s into a frictionless wall (friction = 0, e = 1/2) on a floor that holds it
// without slip: the wall takes no tangential impulse, so it keeps only its gap row through the
// impact (with its no-slip rows too, the six rows had rank 5 and the run ended). The ball rolls
// back at -e v0, the floor's impulse turning its spin to match, b' = -e v0 / r.
TEST(MoreContactsThanCoordinates, ARollingBallBouncesOffAFrictionlessWall) {
  const std::string text = floor_and_wall("", "friction = 0\nrestitution = 0.5\nmode = \"free\"\n",
                                          "position = { x = -0.5, y = 0, z = \"r\", a = 0, b = 0, c = 0 }\n"
                                          "velocity = { x = 2, y = 0, z = 0, a = 0, b = 20, c = 0 }");
  const FloorRun r = run(load_model_text(text, "frictionless.toml"), 1.0);
  ASSERT_EQ(r.summary.status, Status::ok) << r.summary.message;
  ASSERT_EQ(r.summary.events.crossings.size(), 1u);
  EXPECT_EQ(r.summary.events.crossings[0].name, "wall_touchdown");
  EXPECT_NEAR(r.summary.events.crossings[0].t, 0.2, 1e-10);  // the centre 0.4 on at 2 m/s
  const std::size_t last = r.rows.size() - 1;
  EXPECT_NEAR(r.at(last, "x'"), -1.0, 1e-10);
  EXPECT_NEAR(r.at(last, "b'"), -10.0, 1e-9);
  EXPECT_NEAR(r.at(last, "floor_N"), 0.981, 1e-10);
}

// A ball given mode = "free" at rest on the floor: the gap starts at 0 and closes as gravity pulls
// the ball down (it passed through the floor, no event). The touchdown is at once, with no speed
// to take, and the ball rests with N = m g.
TEST(MoreContactsThanCoordinates, AFreeContactAtRestOnItsGroundTouchesDownAtOnce) {
  const std::string text = floor_and_wall("mode = \"free\"\n", "mode = \"free\"\n",
                                          "position = { x = -1, y = 0, z = \"r\", a = 0, b = 0, c = 0 }\n"
                                          "velocity = { x = 0, y = 0, z = 0, a = 0, b = 0, c = 0 }");
  const FloorRun r = run(load_model_text(text, "rest.toml"), 0.5);
  ASSERT_EQ(r.summary.status, Status::ok) << r.summary.message;
  ASSERT_EQ(r.summary.events.crossings.size(), 1u);
  EXPECT_EQ(r.summary.events.crossings[0].name, "floor_touchdown");
  EXPECT_LT(r.summary.events.crossings[0].t, 1e-12);
  const std::size_t last = r.rows.size() - 1;
  EXPECT_NEAR(r.at(last, "z"), 0.1, 1e-12);
  EXPECT_NEAR(r.at(last, "floor_N"), 0.981, 1e-12);
  EXPECT_EQ(r.at(last, "floor_mode"), 0.0);
}

// A contact given mode = "free" that touches its ground at t0 moving into it would pass through:
// no event finds a touchdown whose gap starts at 0. Refused, with the gap and the speed.
TEST(MoreContactsThanCoordinates, AFreeStartOnTheGroundMovingIntoItIsRefused) {
  const std::string text = floor_and_wall("mode = \"free\"\n", "mode = \"free\"\n",
                                          "position = { x = -1, y = 0, z = \"r\", a = 0, b = 0, c = 0 }\n"
                                          "velocity = { x = 0, y = 0, z = -1, a = 0, b = 0, c = 0 }");
  try {
    run(load_model_text(text, "into.toml"), 1.0);
    FAIL() << "a free start moving into the floor ran";
  } catch (const ModelError& e) {
    EXPECT_NE(std::string(e.what()).find("contact 'floor' is given mode = \"free\", but at t0 it touches the ground "
                                         "(gap 0 m) and moves into it (-1 m/s)"),
              std::string::npos)
        << e.what();
  }
}

// A stop condition that an impact makes true (the floor's normal force past m g / 2, the speed
// past 1.6 m/s, both only after the landing) crosses at the impact itself, where the state jumps:
// no step sees it, and the run went on to its end warning that it never became true.
TEST(MoreContactsThanCoordinates, AStopConditionThatAnImpactMakesTrueStopsTheRunThere) {
  const Model model = load_model(example("ball_off_sphere_onto_floor.toml"));
  for (const std::string condition : {"floor_N > 0.5", "x' > 1.6"}) {
    SimulationOptions options = run_options(4.0, 0.01);
    options.events.push_back(make_stop_condition(model, condition));
    double last_t = 0.0;
    const SimulationSummary summary = simulate(model, options, [&](const Data& data) { last_t = data.t; });
    ASSERT_EQ(summary.status, Status::ok) << summary.message;
    EXPECT_EQ(summary.events.stopped_by, 0) << condition;
    ASSERT_EQ(summary.events.crossings.size(), 3u) << condition;
    EXPECT_EQ(summary.events.crossings[1].name, "floor_touchdown");
    EXPECT_EQ(summary.events.crossings[2].t, summary.events.crossings[1].t) << condition;
    EXPECT_EQ(summary.t_reached, summary.events.crossings[1].t) << condition;
    EXPECT_EQ(last_t, summary.events.crossings[1].t) << condition;
  }
  // A record event crossing at the same jump is recorded too, the stop after it.
  SimulationOptions options = run_options(4.0, 0.01);
  options.events.push_back(make_stop_condition(model, "x' > 1.6"));
  options.events.push_back(make_record_event(model, "fast=x' - 1.7"));
  const SimulationSummary summary = simulate(model, options, [](const Data&) {});
  ASSERT_EQ(summary.status, Status::ok) << summary.message;
  std::vector<std::string> names;
  for (const EventRecord& e : summary.events.crossings) names.push_back(e.name);
  EXPECT_EQ(names, (std::vector<std::string>{"ball_liftoff", "floor_touchdown", "x' > 1.6", "fast"}));
}

// --fix-initial moves only the values the model file leaves free onto the rows that hold at the
// start: not onto a free contact's gap (the floor 1.4 m below the ball, given mode = "free" or,
// with more rows than coordinates, started free by its open gap) and not onto a sliding contact's
// slip (ball_thrown_sliding's 3 m/s). Each was refused: "the values written cannot satisfy" it.
TEST(MoreContactsThanCoordinates, FixInitialLeavesTheRowsOfContactsThatStartFreeOrSliding) {
  const std::string no_mode = replaced(floor_example(), "mode = \"free\"\n", "");
  for (const auto& [text, events] : {std::pair{floor_example(), 2u}, std::pair{no_mode, 2u}}) {
    const Model model = load_model_text(text, "fix.toml");
    SimulationOptions options = run_options(4.0, 0.5);
    options.fix_initial = true;
    const SimulationSummary summary = simulate(model, options, [](const Data&) {});
    ASSERT_EQ(summary.status, Status::ok) << summary.message;
    EXPECT_EQ(summary.events.crossings.size(), events);
  }
  const Model sliding = load_model(example("ball_thrown_sliding.toml"));
  SimulationOptions options = run_options(1.0, 0.1);
  options.fix_initial = true;
  double v_end = 0.0;
  const SimulationSummary summary = simulate(sliding, options, [&](const Data& data) { v_end = data.v(0); });
  ASSERT_EQ(summary.status, Status::ok) << summary.message;
  ASSERT_EQ(summary.events.crossings.size(), 1u);
  EXPECT_EQ(summary.events.crossings[0].name, "ball_stick");
  double v0 = 0.0;
  for (const Parameter& p : sliding.parameters)
    if (p.name == "v0") v0 = p.value;
  EXPECT_NEAR(v_end, 5 * v0 / 7, 1e-9);  // section 10.1: the slip kept, the ball rolls at 5 v0 / 7
}

// A dumbbell (a rod along x with a ball of radius r at each end, I = 2/5 m r^2 about the rod)
// pushed sideways at v on a floor with mu = 0.3, both ends given mode = "sliding": rolling both
// would be six rows on its six coordinates, and the start was refused as wedged. The ends slide
// from the start (their no-slip rows dropped) and the dumbbell behaves as a ball (k = 2/5): both
// stick at 2 v / (7 mu g) at 5 v / 7. Rolling on both ends is then six rows of rank 5 (it could
// roll about its rod): the run ends there naming both.
TEST(MoreContactsThanCoordinates, ADumbbellStartedSlidingOnBothEndsSlidesUntilItSticks) {
  const std::string text = R"toml(name = "dumbbell"
coordinates = ["x", "y", "z", "a", "b", "c"]
gravity = [0, 0, "-g"]

[parameters]
m = 1.0
r = 0.1
L = 0.5
g = 9.81

[[frames]]
name = "bar"
translation = ["x", "y", "z"]
rotations = [["z", "c"], ["y", "b"], ["x", "a"]]

[[bodies]]
name = "bar"
frame = "bar"
mass = "m"
inertia = ["2/5*m*r^2", "m*L^2", "m*L^2"]

[[contacts]]
name = "left"
body = "bar"
shape = { sphere = "r" }
centre = ["-L", 0, 0]
ground = "plane"
unilateral = true
friction = 0.3
mode = "sliding"

[[contacts]]
name = "right"
body = "bar"
shape = { sphere = "r" }
centre = ["L", 0, 0]
ground = "plane"
unilateral = true
friction = 0.3
mode = "sliding"

[initial]
position = { x = 0, y = 0, z = "r", a = 0, b = 0, c = 0 }
velocity = { x = 0, y = 1, z = 0, a = 0, b = 0, c = 0 }
)toml";
  const Model model = load_model_text(text, "dumbbell.toml");
  ASSERT_EQ(model.s(), 6);
  double last_vy = 0.0;
  const SimulationSummary summary = simulate(model, run_options(1.0, 0.01), [&](const Data& data) { last_vy = data.v(1); });
  const double t_stick = 2 * 1.0 / (7 * 0.3 * 9.81);
  ASSERT_NE(summary.status, Status::ok);
  EXPECT_NEAR(summary.t_reached, t_stick, 1e-8) << summary.message;
  EXPECT_NE(summary.message.find("the contacts 'left', 'right' held together keep 6 constraint rows on 6 coordinates"),
            std::string::npos)
      << summary.message;
  EXPECT_NEAR(last_vy, 5.0 / 7.0, 1e-8);
}

// A linearization holds every constraint at once: for s >= n it says why it cannot, by name.
TEST(MoreContactsThanCoordinates, ALinearizationIsRefusedWithTheReason) {
  const Model model = load_model(example("ball_off_sphere_onto_floor.toml"));
  try {
    calc_linearization(model);
    FAIL() << "linearized";
  } catch (const InputError& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find("6 constraints on 6 coordinates"), std::string::npos) << what;
    EXPECT_NE(what.find("a linearization holds every constraint"), std::string::npos) << what;
  }
}

// `nhdyn equations` shows such a model's rows, and says that no single D serves them all (where
// k = n - s and a hint to add k independent coordinates stood).
TEST(MoreContactsThanCoordinates, TheEquationsSayTheRowsAreNeverAllHeld) {
  const symbolic::Spec spec = load_model_file(example("ball_off_sphere_onto_floor.toml"));
  const symbolic::Derivation d = symbolic::derive(spec);
  const std::string text = symbolic::format_equations(spec, d, symbolic::EquationFormat::text);
  EXPECT_NE(text.find("n = 6 coordinates, s = 6 constraints, never all held (contact modes)"), std::string::npos) << text;
  EXPECT_NE(text.find("Complement D: none for all 6 rows at once"), std::string::npos) << text;
  EXPECT_EQ(text.find("independent = ["), std::string::npos) << text;
  EXPECT_NE(text.find("floor_roll2"), std::string::npos) << text;
  const std::string latex = symbolic::format_equations(spec, d, symbolic::EquationFormat::latex);
  EXPECT_NE(latex.find("No complement $D$ for all the rows at once"), std::string::npos);
}

// compare on runs whose rows include switch rows between the output times (they used to be
// counted as output rows and overflow the per-time arrays): every output time gets its row, and
// the case against the tight reference errs at the tolerance's scale.
TEST(MoreContactsThanCoordinates, CompareTakesTheRowsOfTheOutputTimesOnly) {
  const Model model = load_model(example("ball_off_sphere_onto_floor.toml"));
  ComparisonOptions options;
  options.run.t_end = 4.0;
  options.run.output_step = 0.05;
  options.run.integrator.rtol = 1e-10;
  options.run.integrator.atol = 1e-12;
  options.cases.push_back({Formulation::sanh, IntegratorKind::dopri5});
  options.cost_samples = 10;
  const Comparison c = compare_formulations(model, options);
  ASSERT_EQ(c.results.size(), 1u);
  const ComparisonResult& r = c.results[0];
  EXPECT_EQ(r.summary.status, Status::ok) << r.summary.message;
  ASSERT_EQ(r.error.size(), c.times.size());
  for (std::size_t i = 0; i < r.error.size(); ++i) {
    EXPECT_TRUE(std::isfinite(r.error[i])) << "no row at t = " << c.times[i];
    EXPECT_LT(r.error[i], 1e-6) << "at t = " << c.times[i];
  }
  EXPECT_TRUE(std::isfinite(r.solve_ns));  // solved in the modes the run starts in
  // Another method than sanh is refused before anything runs (it cannot solve contact modes).
  options.cases[0].method = Formulation::lagrange;
  EXPECT_THROW(compare_formulations(model, options), InputError);
}

}  // namespace
}  // namespace nhdyn
