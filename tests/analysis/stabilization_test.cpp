// Stabilization (docs/stabilization.md): Baumgarte and projection keep the constraint residuals
// bounded where the pure form lets them drift; projection leaves a state on the constraints as
// it is; bad gains and a projection that cannot converge are clear errors.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <string>
#include <vector>

#include "nhdyn/analysis/projection.hpp"
#include "nhdyn/analysis/simulation.hpp"
#include "nhdyn/core/error.hpp"
#include "nhdyn/formulation/diagnosis.hpp"
#include "nhdyn/model/appell.hpp"
#include "nhdyn/model/sled.hpp"
#include "support/test_models.hpp"

namespace nhdyn {
namespace {

struct PendulumRun {
  SimulationSummary summary;
  double early_position = 0.0, late_position = 0.0;  // max |phi| over the first and last fifth
  double early_velocity = 0.0, late_velocity = 0.0;
  double last_energy = 0.0;
};

// The Cartesian pendulum at a loose tolerance, so that the pure form drifts visibly.
PendulumRun run_pendulum(Stabilization stabilization, double t_end = 50.0) {
  const Model model = testing::make_pendulum_model();
  SimulationOptions options;
  options.t_end = t_end;
  options.output_step = 0.1;
  options.integrator.rtol = 1e-5;
  options.integrator.atol = 1e-7;
  options.stabilization = stabilization;
  PendulumRun run;
  run.summary = simulate(model, options, [&](const Data& data) {
    const double p = std::abs(data.phi(0)), v = std::abs(data.f(0));
    if (data.t <= 0.2 * t_end) {
      run.early_position = std::max(run.early_position, p);
      run.early_velocity = std::max(run.early_velocity, v);
    }
    if (data.t >= 0.8 * t_end) {
      run.late_position = std::max(run.late_position, p);
      run.late_velocity = std::max(run.late_velocity, v);
    }
    run.last_energy = data.energy;
  });
  return run;
}

TEST(Stabilization, NoneDriftsWhereBaumgarteAndProjectionStayBounded) {
  const PendulumRun none = run_pendulum(Stabilization::none);
  const PendulumRun baumgarte = run_pendulum(Stabilization::baumgarte);
  const PendulumRun projection = run_pendulum(Stabilization::projection);
  ASSERT_EQ(none.summary.status, Status::ok) << none.summary.message;
  ASSERT_EQ(baumgarte.summary.status, Status::ok) << baumgarte.summary.message;
  ASSERT_EQ(projection.summary.status, Status::ok) << projection.summary.message;
  // The pure form: the position residual grows along the run, well above the tolerance.
  EXPECT_GT(none.late_position, 3.0 * none.early_position);
  EXPECT_GT(none.late_position, 1e-4);
  // Baumgarte: bounded, the late residual no larger than the early one, and far below none's.
  EXPECT_LT(baumgarte.late_position, 2.0 * baumgarte.early_position + 1e-12);
  EXPECT_LT(baumgarte.late_position, 0.01 * none.late_position);
  EXPECT_LT(baumgarte.late_velocity, 2.0 * baumgarte.early_velocity + 1e-12);
  // Projection: at round-off at both levels, all along.
  EXPECT_LT(projection.summary.residuals.position, 1e-12);
  EXPECT_LT(projection.summary.residuals.velocity, 1e-12);
  EXPECT_GT(projection.summary.projection.count, 100);
  EXPECT_GT(projection.summary.projection.max_position_correction, 0.0);
  // Energy of the projected run stays at the level of the tolerance; none's drifts away.
  EXPECT_LT(std::abs(projection.last_energy - projection.summary.energy.initial),
            std::abs(none.last_energy - none.summary.energy.initial));
}

TEST(Stabilization, ProjectionKeepsEveryBuiltInExampleOnItsConstraints) {
  for (const Model& model : {make_sled_model(SledVariant::centre_of_mass), make_sled_model(SledVariant::paper),
                             make_appell_model()}) {
    SimulationOptions options;
    options.t_end = 100.0;
    options.output_step = 0.5;
    options.stabilization = Stabilization::projection;
    // Appell's residual z'^2 - a^2 (x'^2 + y'^2) grows with the speed squared, and so does its
    // round-off: measure it against the size of its terms.
    double worst_relative = 0.0;
    const SimulationSummary s = simulate(model, options, [&](const Data& data) {
      const double size = model.name == "appell" ? data.v.squaredNorm() : 1.0;
      worst_relative = std::max(worst_relative, std::abs(data.f(0)) / size);
    });
    ASSERT_EQ(s.status, Status::ok) << model.name << ": " << s.message;
    EXPECT_LT(worst_relative, model.name == "appell" ? 1e-15 : 1e-12) << model.name;
  }
}

TEST(Stabilization, ProjectionLeavesAStateOnTheConstraintsUnchanged) {
  const Model model = testing::make_pendulum_model();
  Data data = make_data(model);
  // On the circle with a tangent velocity: phi and f vanish to round-off.
  const double angle = 0.7;
  double q[2] = {std::sin(angle), -std::cos(angle)};
  double v[2] = {1.3 * std::cos(angle), 1.3 * std::sin(angle)};
  const double q0[2] = {q[0], q[1]}, v0[2] = {v[0], v[1]};
  ProjectionResult result;
  ASSERT_EQ(compute_projection(model, data, 0.0, q, v, ProjectionOptions{}, result), Status::ok);
  EXPECT_FALSE(result.changed());
  EXPECT_EQ(q[0], q0[0]);
  EXPECT_EQ(q[1], q0[1]);
  EXPECT_EQ(v[0], v0[0]);
  EXPECT_EQ(v[1], v0[1]);
}

TEST(Stabilization, ProjectionMovesAStateOntoTheConstraintsWithTheSmallestInertiaWeightedChange) {
  // From (2, 0) the nearest point of the unit circle is (1, 0); the velocity (0.5, 1) loses its
  // radial part.
  const Model model = testing::make_pendulum_model();
  Data data = make_data(model);
  double q[2] = {2.0, 0.0};
  double v[2] = {0.5, 1.0};
  ProjectionResult result;
  ASSERT_EQ(compute_projection(model, data, 0.0, q, v, ProjectionOptions{}, result), Status::ok);
  EXPECT_NEAR(q[0], 1.0, 1e-14);
  EXPECT_NEAR(q[1], 0.0, 1e-14);
  EXPECT_NEAR(v[0], 0.0, 1e-14);
  EXPECT_NEAR(v[1], 1.0, 1e-14);
  EXPECT_NEAR(result.position_change, 1.0, 1e-12);
  EXPECT_NEAR(result.velocity_change, 0.5, 1e-12);
}

TEST(Stabilization, ScaledRowsOfBStillProjectQuadratically) {
  // Appell's b is grad f / (2 z'): the secant factor must find 2 z' and converge.
  const AppellParameters p;
  const Model model = make_appell_model(p);
  Data data = make_data(model);
  double q[3] = {0.0, 0.0, 0.0};
  double v[3] = {30.0, 40.0, 1.2 * p.a * 50.0};  // on the cone z' would be 50 a
  ProjectionResult result;
  ASSERT_EQ(compute_projection(model, data, 0.0, q, v, ProjectionOptions{}, result), Status::ok);
  const double f = v[2] * v[2] - p.a * p.a * (v[0] * v[0] + v[1] * v[1]);
  EXPECT_LT(std::abs(f), 1e-15 * (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]));
  EXPECT_LE(result.velocity_iterations, 7);
}

TEST(StabilizationBadInput, NegativeOrNonFiniteBaumgarteGainsAreRefused) {
  const Model model = testing::make_pendulum_model();
  for (double bad : {-1.0, std::nan(""), std::numeric_limits<double>::infinity()}) {
    for (int which = 0; which < 2; ++which) {
      SimulationOptions options;
      options.stabilization = Stabilization::baumgarte;
      (which == 0 ? options.formulation.baumgarte.alpha : options.formulation.baumgarte.beta) = bad;
      try {
        check_simulation_options(model, options);
        ADD_FAILURE() << "gain " << bad << " accepted";
      } catch (const InputError& e) {
        const std::string msg = e.what();
        EXPECT_NE(msg.find(which == 0 ? "alpha" : "beta"), std::string::npos) << msg;
        EXPECT_NE(msg.find("non-negative"), std::string::npos) << msg;
      }
    }
  }
}

TEST(StabilizationBadInput, AProjectionThatCannotConvergeSaysWhereAndWhatToTry) {
  // A rod of imaginary length: x^2 + y^2 = -1 has no solution, so Newton cannot get there.
  Model model = testing::make_pendulum_model();
  model.evaluator = std::make_shared<testing::PendulumEvaluator>(1.0, 9.81, -1.0);
  Data data = make_data(model);
  double q[2] = {1.3, 0.4};
  double v[2] = {0.0, 0.0};
  ProjectionResult result;
  ASSERT_EQ(compute_projection(model, data, 2.5, q, v, ProjectionOptions{}, result), Status::projection_failed);
  const std::string msg = explain_failure(model, data);
  EXPECT_NE(msg.find("position constraints"), std::string::npos) << msg;
  EXPECT_NE(msg.find("t = 2.5"), std::string::npos) << msg;
  EXPECT_NE(msg.find("residual is still"), std::string::npos) << msg;
  EXPECT_NE(msg.find("--rtol"), std::string::npos) << msg;
}

TEST(StabilizationBadInput, AFailedProjectionEndsTheRunWithTheReason) {
  // One Newton step cannot reach a residual of 1e-300: the run must stop and say so, not go on.
  const Model model = make_sled_model();
  SimulationOptions options;
  options.t_end = 5.0;
  options.stabilization = Stabilization::projection;
  options.projection.max_iterations = 1;
  options.projection.tolerance = 1e-300;
  options.integrator.rtol = 1e-4;
  long rows = 0;
  const SimulationSummary s = simulate(model, options, [&](const Data&) { ++rows; });
  ASSERT_EQ(s.status, Status::projection_failed);
  EXPECT_NE(s.message.find("did not converge"), std::string::npos) << s.message;
  EXPECT_LT(s.t_reached, options.t_end);
}

}  // namespace
}  // namespace nhdyn
