// The constraint watch (analysis/constraint_watch.hpp) as users meet it: model files loaded and
// run through the library, and `nhdyn simulate` printing the warning on stderr and the watch's
// line in the summary. Well-posed models (the rolling disk, the Whipple bicycle at 5 m/s, a chain
// of sleighs on the sparse path) run long and stay silent; the blade written y' - tan(phi) x' = 0
// turning at phi' = 1 with no force (phi = t exactly, the row of b of norm 1/|cos t|) is named
// at a time within 1e-3 of pi/2, where 1/|cos t| >= 1e3, even when the outputs are 1 s apart.
#include <gtest/gtest.h>

#include <unistd.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <numbers>
#include <string>

#include <Eigen/SVD>

#include "nhdyn/analysis/constraint_watch.hpp"
#include "nhdyn/analysis/run_options.hpp"
#include "nhdyn/formulation/formulation.hpp"
#include "nhdyn/analysis/simulation.hpp"
#include "nhdyn/frontend/load_model.hpp"
#include "support/cli_run.hpp"
#include "support/models.hpp"
#include "support/text.hpp"

namespace nhdyn {
namespace {

namespace fs = std::filesystem;
using nhdyn::test::contains;
using nhdyn::test::example;
using nhdyn::test::run_nhdyn;

SimulationSummary run_watched_example(const std::string& file, double t_end) {
  const Model model = load_model(example(file));
  SimulationOptions options = make_simulation_options(model);
  options.t_end = t_end;
  return simulate(model, options, [](const Data&) {});
}

// The same models in millimetres and in kilometres stay as silent as in metres: the conditioning
// is estimated in the kinetic energy's metric (constraint_watch.hpp), and a free body's
// untouched position is kept out of its quaternion's complement rows (small_dense.hpp,
// null_space_basis). In kilometres (lengths times 1e-3) the slider crank's conditioning grew by
// 1.5e3 over 0.05 s, the tumbling body's by 1.25e3 over 0.02 s (and by 1.7e4 in millimetres), each
// a warning that its constraints were becoming dependent.
TEST(ConstraintWatchModels, TheSameModelInMillimetresOrKilometresStaysSilent) {
  for (const double scale : {1e-3, 1.0, 1e3}) {
    const std::string where = "lengths times " + std::to_string(scale);
    const Model crank = load_model(example("slider_crank.toml"),
                                   {{"a", 0.1 * scale}, {"l", 0.3 * scale}, {"g", 9.81 * scale}});
    const Model body = load_model(example("tumbling_body.toml"),
                                  {{"I1", 1.0 * scale * scale}, {"I2", 2.0 * scale * scale}, {"I3", 3.0 * scale * scale}});
    for (const Model* model : {&crank, &body}) {
      SimulationOptions options = make_simulation_options(*model);
      options.t_end = 2.0;
      const SimulationSummary summary = simulate(*model, options, [](const Data&) {});
      ASSERT_EQ(summary.status, Status::ok) << model->name << ", " << where << ": " << summary.message;
      EXPECT_TRUE(summary.warnings.empty()) << model->name << ", " << where << ": " << summary.warnings.front();
      EXPECT_LT(summary.watch.largest_condition_factor, 10.0) << model->name << ", " << where;
    }
  }
}

// The estimate itself, in the metric: at any state of the slider crank (k = 1: D is the one
// direction of null(b), whatever the units) a fresh watch estimates the same matrix, and reads
// the same conditioning, in metres and in kilometres, where with the rows alone scaled the two
// conditionings differ by up to 1000 times over a turn of the crank. Along a
// turn of the crank in kilometres, between two estimates, the true condition number of the matrix
// the watch estimates (its columns by the scales of the last estimate, ConstraintWatch::
// column_scale, then its rows to unit norm) stays within 5/3 of the estimate (Weyl's inequality),
// as the amortization claims.
TEST(ConstraintWatchModels, TheConditioningInTheMetricIsTheSameInMetresAndKilometres) {
  const auto crank = [](double scale) {
    return load_model(example("slider_crank.toml"), {{"a", 0.1 * scale}, {"l", 0.3 * scale}, {"g", 9.81 * scale}});
  };
  const Model metres = crank(1.0), kilometres = crank(1e-3);
  const FormulationOptions formulation{Formulation::sanh, Complement::qr};
  // A consistent state at crank angle alpha (a sin(alpha) = l sin(beta), x = a cos(alpha) + l cos(beta)).
  const auto state = [](double scale, double alpha, Vector& q, Vector& v) {
    const double a = 0.1 * scale, l = 0.3 * scale;
    const double beta = std::asin(a * std::sin(alpha) / l);
    q = Vector(3);
    q << alpha, beta, a * std::cos(alpha) + l * std::cos(beta);
    v = Vector::Zero(3);
  };
  Data dm = make_data(metres), dk = make_data(kilometres);
  ConstraintWatch along = make_constraint_watch(kilometres, dk, formulation.method);
  double at_estimate = 0.0;
  long estimates = 0;
  for (int i = 0; i <= 400; ++i) {
    const double alpha = 2.0 * std::numbers::pi * i / 400;
    Vector q, v;
    state(1.0, alpha, q, v);
    ASSERT_EQ(compute_dynamics(metres, dm, formulation, 0.0, q.data(), v.data()), Status::ok) << alpha;
    ConstraintWatch in_metres = make_constraint_watch(metres, dm, formulation.method);
    compute_constraint_watch(metres, dm, in_metres);
    state(1e-3, alpha, q, v);
    ASSERT_EQ(compute_dynamics(kilometres, dk, formulation, 0.0, q.data(), v.data()), Status::ok) << alpha;
    ConstraintWatch in_kilometres = make_constraint_watch(kilometres, dk, formulation.method);
    compute_constraint_watch(kilometres, dk, in_kilometres);
    // The matrices estimated are the same to round-off; the estimates, ratios of the diagonal of a
    // pivoted QR whose unit rows tie for the first pivot (round-off breaks the tie), to the
    // estimator's own spread, 15 % here.
    EXPECT_LT((in_kilometres.rows - in_metres.rows).norm(), 1e-9) << alpha;
    EXPECT_LT(std::max(in_kilometres.condition / in_metres.condition, in_metres.condition / in_kilometres.condition),
              1.25)
        << alpha;

    compute_constraint_watch(kilometres, dk, along);
    Matrix m(3, 3);
    m.topRows(1) = dk.D * dk.A;
    m.bottomRows(2) = dk.b;
    for (int c = 0; c < 3; ++c) m.col(c) *= along.column_scale(c);
    for (int r = 0; r < 3; ++r) m.row(r).normalize();
    const Eigen::JacobiSVD<Matrix> svd(m);
    const double condition = svd.singularValues()(0) / svd.singularValues()(2);
    if (along.estimates != estimates) {
      estimates = along.estimates;
      at_estimate = condition;
    }
    EXPECT_LE(condition, at_estimate * 5.0 / 3.0) << alpha;
    EXPECT_GE(condition, at_estimate * 3.0 / 5.0) << alpha;
  }
  EXPECT_GT(estimates, 1);
  EXPECT_TRUE(along.warnings.empty());
}

TEST(ConstraintWatchModels, RollingDiskOverTenTurnsStaysSilent) {
  const SimulationSummary summary = run_watched_example("rolling_disk.toml", 31.4159);
  ASSERT_EQ(summary.status, Status::ok) << summary.message;
  EXPECT_TRUE(summary.warnings.empty()) << summary.warnings.front();
  EXPECT_GT(summary.watch.watched_states, 3000);
  EXPECT_LT(summary.watch.largest_row_factor, 10.0);
  EXPECT_LT(summary.watch.largest_condition_factor, 10.0);
}

TEST(ConstraintWatchModels, WhippleBicycleAtFiveMetresPerSecondStaysSilent) {
  const SimulationSummary summary = run_watched_example("whipple_bicycle.toml", 20.0);
  ASSERT_EQ(summary.status, Status::ok) << summary.message;
  EXPECT_TRUE(summary.warnings.empty()) << summary.warnings.front();
  EXPECT_LT(summary.watch.largest_row_factor, 10.0);
  EXPECT_LT(summary.watch.largest_condition_factor, 10.0);
}

TEST(ConstraintWatchModels, TanFormNamedWithinAMillisecondOfTheSingularity) {
  const Model model = load_model_text(test::kTanBlade, "tan.toml");
  SimulationOptions options = make_simulation_options(model);
  options.t_end = 3.0;
  options.output_step = 1.0;  // the singularity falls between two outputs: the steps see it
  const SimulationSummary summary = simulate(model, options, [](const Data&) {});
  ASSERT_EQ(summary.watch.warnings.size(), 1u);
  const ConstraintWarning& w = summary.watch.warnings[0];
  EXPECT_EQ(model.constraints[static_cast<std::size_t>(w.constraint)].name, "blade");
  EXPECT_LE(std::abs(w.t - std::numbers::pi / 2), 1e-3) << w.t;
  EXPECT_NEAR(w.factor, 1.0 / std::abs(std::cos(w.t)), 1e-6 * w.factor);
}

// Two blades on one body, x' = 0 and cos(phi) x' + sin(phi) y' = 0, whose rows of b (1, 0, 0)
// and (cos phi, sin phi, 0) keep the norm 1 and become parallel as phi goes to 0: the body stays
// at rest while phi = 1 - t/2 turns freely. The row-scaled [D A; b] is (0, 0, 1), (cos phi,
// sin phi, 0), (1, 0, 0), with singular values 1, sqrt(2) cos(phi/2), sqrt(2) sin(phi/2): its
// condition number cot(phi/2) grows past 1000 times its value at phi = 1 (1.83) at phi = 1.09e-3,
// t = 1.9978. Only the conditioning can see it.
constexpr const char* kMergingBlades = R"(name = "merging-blades"
coordinates = ["x", "y", "phi"]
kinetic_energy = "m/2 * (x'^2 + y'^2) + m*rho^2/2 * phi'^2"
[parameters]
m = 1.0
rho = 0.5
[[constraints]]
name = "straight"
velocity = "x'"
[[constraints]]
name = "turning"
velocity = "cos(phi)*x' + sin(phi)*y'"
[initial]
position = { x = 0, y = 0, phi = 1 }
velocity = { x = 0, y = 0, phi = -0.5 }
)";

TEST(ConstraintWatchModels, MergingBladesNamedByTheConditioning) {
  const Model model = load_model_text(kMergingBlades, "blades.toml");
  SimulationOptions options = make_simulation_options(model);
  options.t_end = 1.9995;
  options.output_step = 5e-4;
  const SimulationSummary summary = simulate(model, options, [](const Data&) {});
  ASSERT_EQ(summary.status, Status::ok) << summary.message;
  ASSERT_EQ(summary.watch.warnings.size(), 1u);
  const ConstraintWarning& w = summary.watch.warnings[0];
  EXPECT_EQ(w.measure, WatchMeasure::conditioning);
  EXPECT_GE(w.constraint, 0);
  // Past the crossing at t = 1.9978 (the estimate is within a modest factor of the true number),
  // and before the run's end.
  EXPECT_GE(w.t, 1.996) << w.t;
  EXPECT_LE(w.t, 1.9995) << w.t;
  EXPECT_GE(w.factor, kConstraintWatchFactor);
  EXPECT_LT(summary.watch.largest_row_factor, 1.0 + 1e-12);
}

// The amortized estimate (constraint_watch.hpp): between two factorizations the true condition
// number of the row-scaled stacked matrix, from an SVD at every state, stays within a factor 5/3
// of its value at the last factorization; and far fewer states are factorized than watched.
TEST(ConstraintWatchModels, AmortizedEstimateBoundsTheTrueConditionNumber) {
  const Model model = load_model_text(kMergingBlades, "blades.toml");
  Data data = make_data(model);
  const FormulationOptions formulation{Formulation::sanh, Complement::qr};
  ConstraintWatch watch = make_constraint_watch(model, data, formulation.method);
  const int states = 4000;
  double at_estimate = 0.0;
  long estimates = 0;
  for (int i = 0; i < states; ++i) {
    const double phi = std::pow(1e-4, static_cast<double>(i) / (states - 1));  // 1 down to 1e-4
    Vector q(3), v(3);
    q << 0.0, 0.0, phi;
    v << 0.0, 0.0, -0.5;
    ASSERT_EQ(compute_dynamics(model, data, formulation, 0.0, q.data(), v.data()), Status::ok) << phi;
    compute_constraint_watch(model, data, watch);
    Matrix m(3, 3);
    m.topRows(1) = data.D * data.A;
    m.bottomRows(2) = data.b;
    // In the kinetic energy's metric, as the watch estimates it: A = diag(m, m, m rho^2) is
    // constant, and the column of phi holds a single nonzero, so that the closed form is kept.
    for (int c = 0; c < 3; ++c) m.col(c) /= std::sqrt(data.A(c, c));
    for (int r = 0; r < 3; ++r) m.row(r).normalize();
    const Eigen::JacobiSVD<Matrix> svd(m);
    const double condition = svd.singularValues()(0) / svd.singularValues()(2);
    EXPECT_NEAR(condition, 1.0 / std::tan(phi / 2), 1e-6 / std::tan(phi / 2)) << phi;
    if (watch.estimates != estimates) {
      estimates = watch.estimates;
      at_estimate = condition;
    }
    EXPECT_LE(condition, at_estimate * 5.0 / 3.0) << phi;
    EXPECT_GE(condition, at_estimate * 3.0 / 5.0) << phi;
  }
  EXPECT_EQ(watch.states, states);
  EXPECT_LT(watch.estimates, states / 10) << watch.estimates;
  EXPECT_GT(watch.estimates, 10) << watch.estimates;  // the approach to phi = 0 is followed
  ASSERT_EQ(watch.warnings.size(), 1u);
  EXPECT_EQ(watch.warnings[0].measure, WatchMeasure::conditioning);
}

class ConstraintWatchCli : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() / ("nhdyn-watch-" + std::to_string(::getpid()) + "-" +
                                        ::testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::create_directories(dir_);
  }
  void TearDown() override { fs::remove_all(dir_); }
  fs::path dir_;
};

TEST_F(ConstraintWatchCli, SimulateWarnsOnStderrAndCountsInTheSummary) {
  std::ofstream(dir_ / "tan.toml") << test::kTanBlade;
  const test::CliOutcome r = run_nhdyn("simulate tan.toml --t-end 3 --output-step 1 -o out.csv", dir_);
  EXPECT_EQ(r.exit_code, 0) << r.out;
  const std::string& err = r.out;  // stdout and stderr together
  EXPECT_TRUE(contains(err, "nhdyn: warning: constraint 'blade': the norm of its row of b went from 1 to ")) << err;
  const std::size_t at = err.find("by t = ");
  ASSERT_NE(at, std::string::npos) << err;
  EXPECT_LE(std::abs(std::stod(err.substr(at + 7)) - std::numbers::pi / 2), 1e-3) << err;
  EXPECT_TRUE(contains(r.out, "  constraint watch: 1 warning on stderr; largest change of a row of b x")) << r.out;
  // -q: the warning still comes, the summary does not.
  const test::CliOutcome quiet = run_nhdyn("simulate tan.toml --t-end 3 -q -o out.csv", dir_);
  EXPECT_TRUE(contains(quiet.out, "warning: constraint 'blade'")) << quiet.out;
  EXPECT_FALSE(contains(quiet.out, "constraint watch:")) << quiet.out;
}

TEST_F(ConstraintWatchCli, CompareAndBatchPassTheWarningsOn) {
  std::ofstream(dir_ / "tan.toml") << test::kTanBlade;
  const test::CliOutcome compare = run_nhdyn("compare tan.toml --t-end 2 -q -o cmp", dir_);
  for (const char* method : {"sanh", "lagrange", "udwadia-kalaba", "nullspace"})
    EXPECT_TRUE(contains(compare.out, fmt::format("nhdyn: warning ({}, dopri5): constraint 'blade'", method)))
        << compare.out;
  const test::CliOutcome batch = run_nhdyn("batch tan.toml --grid rho=0.5:0.7:3 --t-end 2 -o runs --threads 1", dir_);
  EXPECT_EQ(batch.exit_code, 0) << batch.out;
  EXPECT_TRUE(contains(batch.out, "nhdyn: warning: run 0: constraint 'blade'")) << batch.out;
  EXPECT_TRUE(contains(batch.out, "nhdyn: warning: 3 of 3 runs had warnings")) << batch.out;
}

TEST_F(ConstraintWatchCli, SparseChainRunsWatchedAndSilent) {
  // 30 sleighs: n = 90 coordinates, past the size where a model is compiled sparse.
  const test::CliOutcome gen = run_nhdyn("example chain --bodies 30 -o chain.toml", dir_);
  ASSERT_EQ(gen.exit_code, 0) << gen.out;
  const test::CliOutcome sim = run_nhdyn("simulate chain.toml --t-end 5 --output-step 0.1 -o out.csv", dir_);
  EXPECT_EQ(sim.exit_code, 0) << sim.out;
  EXPECT_TRUE(contains(sim.out, "sparse path")) << sim.out;
  EXPECT_TRUE(contains(sim.out, "  constraint watch: no warning; largest change of a row of b x")) << sim.out;
  EXPECT_FALSE(contains(sim.out, "warning:")) << sim.out;
  // The same chain through the library: the watch saw every output at least, on the sparse path.
  const Model model = load_model((dir_ / "chain.toml").string());
  SimulationOptions options = make_simulation_options(model);
  options.t_end = 5.0;
  options.output_step = 0.1;
  const SimulationSummary summary = simulate(model, options, [](const Data&) {});
  ASSERT_EQ(summary.status, Status::ok) << summary.message;
  EXPECT_TRUE(summary.sparse);
  EXPECT_TRUE(summary.warnings.empty());
  EXPECT_GE(summary.watch.watched_states, 51);
  EXPECT_LT(summary.watch.largest_row_factor, 10.0);
}

TEST_F(ConstraintWatchCli, WellPosedExamplesPrintNoWarning) {
  // The bicycle over its file's 5 s here; 20 s through the library above.
  for (const char* file : {"sled.toml", "rolling_disk.toml", "whipple_bicycle.toml"}) {
    const test::CliOutcome r = run_nhdyn(fmt::format("simulate '{}' -o out.csv", example(file)), dir_);
    EXPECT_EQ(r.exit_code, 0) << file << ": " << r.out;
    EXPECT_TRUE(contains(r.out, "  constraint watch: no warning;")) << file << ": " << r.out;
    EXPECT_FALSE(contains(r.out, "warning:")) << file << ": " << r.out;
  }
}

}  // namespace
}  // namespace nhdyn
