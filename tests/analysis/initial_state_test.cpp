// Initial states off the constraints: refused with every residual listed, or moved onto the
// constraints with the smallest inertia-weighted change (--fix-initial).
#include "nhdyn/analysis/initial_state.hpp"

#include <gtest/gtest.h>

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
