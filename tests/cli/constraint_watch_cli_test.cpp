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

#include "nhdyn/analysis/run_options.hpp"
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
  EXPECT_TRUE(contains(batch.out, "nhdyn: warning: 3 of 3 runs had constraint-watch warnings")) << batch.out;
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
