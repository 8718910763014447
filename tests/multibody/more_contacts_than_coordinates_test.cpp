// A body with more contact rows than coordinates (s >= n), whose contacts are never all held
// (docs/contact-modes.md, "More contacts than freedom"): examples/ball_off_sphere_onto_floor.toml
// against the closed form of docs/derivations/contact-modes.md section 10.6 (lift-off from the
// sphere, the parabola to the floor, the plastic landing that keeps the angular momentum about the
// contact point), the contact forces of the contacts touching, and what is refused: contacts
// held together that wedge the body, rows held in every mode that reach n, and the analyses that
// hold every row at once. Also compare on a run with switch rows (they come between output times).
#include <gtest/gtest.h>

#include <cmath>
#include <string>
#include <vector>

#include "nhdyn/analysis/comparison.hpp"
#include "nhdyn/analysis/linearization.hpp"
#include "nhdyn/analysis/simulation.hpp"
#include "nhdyn/core/error.hpp"
#include "nhdyn/frontend/load_model.hpp"
#include "nhdyn/io/results.hpp"
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

FloorRun run(const Model& model, double t_end) {
  FloorRun out;
  out.columns = make_result_columns(model);
  SimulationOptions options;
  options.t_end = t_end;
  options.output_step = 0.01;
  options.integrator.rtol = 1e-10;
  options.integrator.atol = 1e-12;
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
