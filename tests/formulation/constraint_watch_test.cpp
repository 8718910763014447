// The constraint watch (analysis/constraint_watch.hpp) on the blade written in the paper's form
// y' - tan(phi) x' = 0 (the built-in sled-paper with its centre of mass on the blade, a = 0, on a
// level plane): no force turns the body, so phi'' = 0 and phi = t at phi'(0) = 1, and the row of b,
// (-tan(phi), 1, 0), has the norm 1/|cos(t)|. It passes the watch's factor F at t = acos(1/F),
// 1 ms before the singularity at t = pi/2: the warning must name the blade at a time in between, on
// the dense path with every formulation and on the sparse path. The regular form of the same
// constraint, -sin(phi) x' + cos(phi) y' = 0 (the built-in sled), has a row of norm 1 for ever and
// must stay silent over the same motion, as must the sled with its default parameters over a long run.
#include <gtest/gtest.h>

#include <cmath>
#include <numbers>

#include "formulation/sparse_twin.hpp"
#include "nhdyn/analysis/constraint_watch.hpp"
#include "nhdyn/analysis/simulation.hpp"
#include "nhdyn/core/error.hpp"
#include "nhdyn/model/sled.hpp"

namespace nhdyn {
namespace {

// The blade turning at phi' = 1 with no force: x' = cos(t), y' = sin(t) on the exact motion.
Model make_turning_blade_for_watch(SledVariant variant) {
  SledParameters p;
  p.a = 0.0;
  p.alpha = 0.0;
  p.rho = 0.5;
  Model model = make_sled_model(variant, p);
  model.q0 = Vector::Zero(3);
  model.v0 = Vector(3);
  model.v0 << 1.0, 0.0, 1.0;
  return model;
}

SimulationSummary run_watch(const Model& model, Formulation method, Complement complement, double t_end,
                            Path path = Path::automatic) {
  SimulationOptions options;
  options.t_end = t_end;
  options.output_step = 0.01;
  options.formulation.method = method;
  options.formulation.complement = complement;
  options.path = path;
  return simulate(model, options, [](const Data&) {});
}

void expect_blade_warning_before_singularity(const Model& model, const SimulationSummary& summary,
                                             const std::string& what) {
  ASSERT_EQ(summary.watch.warnings.size(), 1u) << what;
  ASSERT_EQ(summary.warnings.size(), 1u) << what;
  const ConstraintWarning& w = summary.watch.warnings[0];
  EXPECT_EQ(model.constraints[static_cast<std::size_t>(w.constraint)].name, "blade") << what;
  EXPECT_EQ(w.measure, WatchMeasure::row_norm) << what;
  // phi = t exactly (phi'' = 0): the first watched state past the factor lies in
  // [acos(1/F), pi/2]; the output at t = 1.57 is inside, so the watch cannot be later.
  EXPECT_GE(w.t, std::acos(1.0 / kConstraintWatchFactor)) << what;
  EXPECT_LE(w.t, std::numbers::pi / 2) << what;
  EXPECT_NEAR(w.initial, 1.0, 1e-12) << what;
  EXPECT_NEAR(w.factor, 1.0 / std::abs(std::cos(w.t)), 1e-6 * w.factor) << what;
  EXPECT_NE(summary.warnings[0].find("constraint 'blade'"), std::string::npos) << summary.warnings[0];
  EXPECT_NE(summary.warnings[0].find(fmt::format("t = {:.6g}", w.t)), std::string::npos) << summary.warnings[0];
}

TEST(ConstraintWatch, TanFormOfTheBladeIsWarnedAboutJustBeforePhiCrossesHalfPi) {
  const Model model = make_turning_blade_for_watch(SledVariant::paper);
  const struct {
    Formulation method;
    Complement complement;
  } runs[] = {{Formulation::sanh, Complement::qr},
              {Formulation::sanh, Complement::analytic},
              {Formulation::sanh, Complement::partition},
              {Formulation::lagrange, Complement::qr},
              {Formulation::udwadia_kalaba, Complement::qr},
              {Formulation::nullspace, Complement::qr}};
  for (const auto& run : runs) {
    const SimulationSummary summary = run_watch(model, run.method, run.complement, 1.6);
    const std::string what = fmt::format("{} / {}", formulation_name(run.method), complement_name(run.complement));
    EXPECT_FALSE(summary.sparse) << what;
    expect_blade_warning_before_singularity(model, summary, what);
    EXPECT_GT(summary.watch.watched_states, 157) << what;  // every output at least
  }
}

TEST(ConstraintWatch, SparsePathFollowsTheRowsOfB) {
  const Model model = testing::make_sparse_twin(make_turning_blade_for_watch(SledVariant::paper));
  const SimulationSummary summary = run_watch(model, Formulation::sanh, Complement::qr, 1.6, Path::sparse);
  EXPECT_TRUE(summary.sparse);
  expect_blade_warning_before_singularity(model, summary, "sparse sanh");
  const SimulationSummary lagrange = run_watch(model, Formulation::lagrange, Complement::qr, 1.6, Path::sparse);
  EXPECT_TRUE(lagrange.sparse);
  expect_blade_warning_before_singularity(model, lagrange, "sparse lagrange");
}

TEST(ConstraintWatch, RegularFormOfTheSameMotionStaysSilent) {
  // The row (-sin phi, cos phi, 0) has norm 1 at every heading, through phi = pi/2 and beyond.
  const Model model = make_turning_blade_for_watch(SledVariant::centre_of_mass);
  for (Path path : {Path::dense, Path::sparse}) {
    const Model run_model = path == Path::sparse ? testing::make_sparse_twin(model) : model;
    const SimulationSummary summary = run_watch(run_model, Formulation::sanh, Complement::qr, 10.0, path);
    ASSERT_EQ(summary.status, Status::ok) << summary.message;
    EXPECT_TRUE(summary.warnings.empty()) << summary.warnings.front();
    EXPECT_LT(summary.watch.largest_row_factor, 1.0 + 1e-12);
    if (path == Path::dense) {
      EXPECT_LT(summary.watch.largest_condition_factor, 10.0);
    }
  }
}

TEST(ConstraintWatch, SledOverALongRunStaysSilent) {
  const Model model = make_sled_model();
  for (Formulation method : {Formulation::sanh, Formulation::lagrange}) {
    const SimulationSummary summary = run_watch(model, method, Complement::qr, 200.0);
    ASSERT_EQ(summary.status, Status::ok) << summary.message;
    EXPECT_TRUE(summary.warnings.empty()) << summary.warnings.front();
    EXPECT_LT(summary.watch.largest_row_factor, 1.0 + 1e-12);
    EXPECT_LT(summary.watch.largest_condition_factor, 10.0) << formulation_name(method);
  }
}

TEST(ConstraintWatch, ThresholdIsAnOptionAndOffMeansSilent) {
  const Model model = make_turning_blade_for_watch(SledVariant::paper);
  SimulationOptions options;
  options.t_end = 1.6;
  options.watch_constraints = false;
  const SimulationSummary off = simulate(model, options, [](const Data&) {});
  EXPECT_TRUE(off.warnings.empty());
  EXPECT_EQ(off.watch.watched_states, 0);
  // A factor of 10 is passed at t = acos(1/10) = 1.4706.
  options.watch_constraints = true;
  options.watch_factor = 10.0;
  const SimulationSummary ten = simulate(model, options, [](const Data&) {});
  ASSERT_EQ(ten.watch.warnings.size(), 1u);
  EXPECT_GE(ten.watch.warnings[0].t, std::acos(0.1));
  EXPECT_LE(ten.watch.warnings[0].t, std::acos(0.1) + options.output_step);
  options.watch_factor = 1.0;
  EXPECT_THROW(simulate(model, options, [](const Data&) {}), InputError);
}

}  // namespace
}  // namespace nhdyn
