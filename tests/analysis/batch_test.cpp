// Batch runs (analysis/batch.hpp): the thread pool gives, run for run, the rows of simulate()
// called one run after another, whatever the number of threads; a failing member keeps its
// message and the others their results; inputs of the wrong size are refused before any run.
#include "nhdyn/analysis/batch.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <memory>

#include "nhdyn/core/error.hpp"
#include "nhdyn/model/sled.hpp"

namespace nhdyn {
namespace {

SimulationOptions short_run() {
  SimulationOptions options;
  options.t_end = 1.0;
  options.output_step = 0.05;
  return options;
}

Trajectory sequential(const Model& base, const Vector& v0) {
  Model model = base;
  model.v0 = v0;
  Trajectory tr;
  tr.reset(model);
  const SimulationSummary summary = simulate(model, short_run(), [&](const Data& data) { tr.append(data); });
  EXPECT_EQ(summary.status, Status::ok);
  return tr;
}

std::vector<BatchRun> sled_runs(const std::shared_ptr<const Model>& model, int count) {
  std::vector<BatchRun> runs;
  for (int i = 0; i < count; ++i) {
    Vector v0 = model->v0;
    v0(0) = 0.5 + 0.25 * i;  // along the blade at phi = 0: consistent with the constraint
    v0(2) = 1.0 - 0.1 * i;
    runs.push_back({model, std::nullopt, v0});
  }
  return runs;
}

TEST(Batch, EqualsSequentialRunsOnOneAndTwoThreads) {
  const auto model = std::make_shared<const Model>(make_sled_model());
  const std::vector<BatchRun> runs = sled_runs(model, 6);
  for (int threads : {1, 2}) {
    BatchOptions options;
    options.simulation = short_run();
    options.threads = threads;
    const std::vector<BatchResult> results = simulate_batch(runs, options);
    ASSERT_EQ(results.size(), runs.size());
    for (std::size_t i = 0; i < runs.size(); ++i) {
      ASSERT_TRUE(results[i].ok) << results[i].message;
      const Trajectory expected = sequential(*model, *runs[i].v0);
      const Trajectory& got = results[i].trajectory;
      EXPECT_EQ(got.rows(), 21);
      EXPECT_EQ(got.t, expected.t);
      EXPECT_EQ(got.q, expected.q) << "run " << i << ", " << threads << " threads";
      EXPECT_EQ(got.v, expected.v);
      EXPECT_EQ(got.qdd, expected.qdd);
      EXPECT_EQ(got.R, expected.R);
      EXPECT_EQ(got.residuals, expected.residuals);
      EXPECT_EQ(got.energy, expected.energy);
      for (int k = 0; k < model->n(); ++k) EXPECT_EQ(results[i].q_end(k), expected.q[expected.q.size() - 3 + static_cast<std::size_t>(k)]);
    }
    // Different initial states give different runs: the equalities above are not vacuous.
    EXPECT_GT(std::abs(results[0].q_end(0) - results[5].q_end(0)), 0.1);
  }
}

TEST(Batch, AFailingMemberKeepsItsMessageAndTheOthersTheirResults) {
  const auto model = std::make_shared<const Model>(make_sled_model());
  std::vector<BatchRun> runs = sled_runs(model, 4);
  (*runs[1].v0)(1) = 1.0;  // y' = 1 at phi = 0 breaks the blade constraint: refused before any step
  BatchOptions options;
  options.simulation = short_run();
  options.threads = 2;
  const std::vector<BatchResult> results = simulate_batch(runs, options);
  EXPECT_FALSE(results[1].ok);
  EXPECT_NE(results[1].message.find("blade"), std::string::npos) << results[1].message;
  EXPECT_EQ(results[1].q_end.size(), 0);
  for (std::size_t i : {0u, 2u, 3u}) {
    ASSERT_TRUE(results[i].ok) << results[i].message;
    EXPECT_EQ(results[i].trajectory.q, sequential(*model, *runs[i].v0).q);
  }
}

TEST(Batch, RefusesInitialStatesOfTheWrongSize) {
  const auto model = std::make_shared<const Model>(make_sled_model());
  std::vector<BatchRun> runs = sled_runs(model, 2);
  runs[1].q0 = Vector::Zero(2);
  EXPECT_THROW(simulate_batch(runs, BatchOptions{}), InputError);
  runs[1] = BatchRun{};
  EXPECT_THROW(simulate_batch(runs, BatchOptions{}), InputError);
  EXPECT_EQ(batch_threads(0, 3) >= 1, true);
  EXPECT_EQ(batch_threads(8, 3), 3);
  EXPECT_EQ(batch_threads(2, 0), 1);
}

}  // namespace
}  // namespace nhdyn
