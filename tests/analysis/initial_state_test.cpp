// Initial states off the constraints: refused with every residual listed, or moved onto the
// constraints with the smallest inertia-weighted change (--fix-initial).
#include "nhdyn/analysis/initial_state.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <string>

#include "nhdyn/analysis/simulation.hpp"
#include "nhdyn/core/error.hpp"
#include "nhdyn/model/sled.hpp"
#include "nhdyn/model/terms.hpp"
#include "support/test_models.hpp"

namespace nhdyn {
namespace {

TEST(InitialState, AViolatedConstraintIsRefusedWithItsResidual) {
  Model model = make_sled_model();
  model.v0(1) = 0.25;  // sideways velocity: the blade forbids it
  SimulationOptions options;
  options.t_end = 1.0;
  try {
    simulate(model, options, [](const Data&) {});
    FAIL() << "expected ModelError";
  } catch (const ModelError& e) {
    const std::string message = e.what();
    EXPECT_NE(message.find("blade (velocity level): residual 0.25"), std::string::npos) << message;
    EXPECT_NE(message.find("--fix-initial"), std::string::npos) << message;
  }
}

// The tolerance of a residual grows with the round-off of its terms (check_initial_state): a
// pendulum 1500 km long (x^2 + y^2 - l^2, the bob at 1.2 rad from the downward vertical) has its
// residual at -4.9e-4 from rounding alone, and was refused at such a state; it starts now,
// while the same pendulum with its bob 1.5 m off the circle (1e-6 of its length: a residual of
// 4.5e6) is still refused, as is the 1.5 m pendulum with its bob 1.5 um off.
TEST(InitialState, TheToleranceOfAResidualIsThatOfItsTermsRoundOff) {
  // With `fix`, --fix-initial on a model whose [initial] wrote both coordinates and both rates:
  // nothing may move, and the state is refused or kept as the check without it decides.
  const auto refused = [](double l, double off, bool fix = false) -> std::string {
    Model model = testing::make_pendulum_model(0.5, 9.81 * l / 1.5, l);
    model.q0 << l * std::sin(1.2) + off, -l * std::cos(1.2);
    if (fix) model.q0_written = model.v0_written = {true, true};
    SimulationOptions options;
    options.t_end = 0.01;
    options.fix_initial = fix;
    try {
      const SimulationSummary summary = simulate(model, options, [](const Data&) {});
      EXPECT_EQ(summary.status, Status::ok) << summary.message;
      return "";
    } catch (const ModelError& e) {
      return e.what();
    }
  };
  const double x = 1.5e6 * std::sin(1.2), y = -1.5e6 * std::cos(1.2);
  ASSERT_GT(std::abs(x * x + y * y - 1.5e6 * 1.5e6), 1e-4);  // the round-off the old tolerance refused
  EXPECT_EQ(refused(1.5e6, 0.0), "");
  EXPECT_EQ(refused(1.5, 0.0), "");
  // The allowance is 32 units of round-off of the terms (2 l^2 = 4.5e12, a unit 1e-3), not more:
  // the bob 3e-15 l off (a residual of 13 units) starts, 1e-13 l off (450 units) is refused.
  EXPECT_EQ(refused(1.5e6, 3e-15 * 1.5e6), "");
  EXPECT_NE(refused(1.5e6, 1e-13 * 1.5e6).find("rod (position level): residual"), std::string::npos);
  EXPECT_EQ(refused(1.5e6, 0.0, true), "");
  EXPECT_NE(refused(1.5e6, 1.5, true).find("the values written cannot satisfy it"), std::string::npos);
  for (const double l : {1.5e6, 1.5}) {
    const std::string message = refused(l, 1e-6 * l);
    EXPECT_NE(message.find("rod (position level): residual"), std::string::npos) << "l = " << l << ": " << message;
    EXPECT_NE(message.find("32 units of round-off"), std::string::npos) << message;
  }
}

TEST(InitialState, VelocityFixIsTheSmallestInertiaWeightedChange) {
  Model model = make_sled_model();
  model.q0(2) = 0.4;
  model.v0 << 1.0, 0.7, -0.5;
  Data data = make_data(model);
  const InitialFix fix = fix_initial_state(model, data, 0.0, model.q0, model.v0);
  EXPECT_LT(fix.velocity_residual, 1e-13);
  EXPECT_EQ(fix.dq.norm(), 0.0);
  // Optimality of min 1/2 dv^T A dv s.t. b (v + dv) = 0: A dv is parallel to b^T, i.e. D A dv = 0
  // for the complement D = [[cos phi, sin phi, 0], [0, 0, 1]].
  compute_terms(model, data, 0.0, fix.q.data(), fix.v.data());
  const double c = std::cos(0.4), s = std::sin(0.4);
  Matrix D(2, 3);
  D << c, s, 0, 0, 0, 1;
  const Vector Adv = data.A * fix.dv;
  EXPECT_LT((D * Adv).norm(), 1e-13 * (1.0 + Adv.norm()));
  EXPECT_GT(fix.dv.norm(), 0.1);  // it did move
  // The run then starts from the fixed state and keeps to the constraint.
  SimulationOptions options;
  options.t_end = 1.0;
  options.fix_initial = true;
  options.integrator.rtol = 1e-10;
  options.integrator.atol = 1e-12;
  const SimulationSummary summary = simulate(model, options, [](const Data&) {});
  ASSERT_TRUE(summary.initial_fix.has_value());
  EXPECT_LT(summary.residuals.velocity, 1e-8);
}

TEST(InitialState, PositionFixOfAPendulumIsTheNearestPointOfTheCircle) {
  Model model = testing::make_pendulum_model(2.0, 9.81, 1.0);
  model.q0 << 1.3, 0.4;
  model.v0 << 0.2, 0.5;
  Data data = make_data(model);
  const InitialFix fix = fix_initial_state(model, data, 0.0, model.q0, model.v0);
  const Vector nearest = model.q0.normalized();
  EXPECT_LT((fix.q - nearest).norm(), 1e-13);
  EXPECT_LT(fix.position_residual, 1e-13);
  // The velocity is then made tangent at the corrected position: its radial part removed.
  const double tx = -nearest(1), ty = nearest(0);
  const double along = tx * model.v0(0) + ty * model.v0(1);
  EXPECT_NEAR(fix.v(0), tx * along, 1e-13);
  EXPECT_NEAR(fix.v(1), ty * along, 1e-13);
  EXPECT_GT(fix.position_iterations, 1);
}

TEST(InitialState, AConstraintWithoutSolutionIsReportedAsNotConverging) {
  // x^2 + y^2 = -1 has no real point: Newton cannot converge, and says so.
  Model model = testing::make_pendulum_model();
  model.evaluator = std::make_shared<testing::PendulumEvaluator>(1.0, 9.81, -1.0);
  model.q0 << 0.5, 0.5;
  Data data = make_data(model);
  try {
    fix_initial_state(model, data, 0.0, model.q0, model.v0);
    FAIL() << "expected ModelError";
  } catch (const ModelError& e) {
    EXPECT_NE(std::string(e.what()).find("did not converge"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("'rod'"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace nhdyn
