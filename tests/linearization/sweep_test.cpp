// The sweep over a parameter (analysis/sweep.hpp): the benchmark bicycle's weave and capsize
// speeds found by root finding to 1e-9 against the published values, the eigenvalues on the grid
// against the independent 4 x 4 matrix, the upright rolling disk's threshold sqrt(g/(3 r)), and
// the bad ranges and step counts refused with the value named.
#include <gtest/gtest.h>

#include <cmath>
#include <complex>
#include <string>
#include <vector>

#include "linearization/support.hpp"
#include "nhdyn/analysis/sweep.hpp"
#include "nhdyn/core/error.hpp"
#include "nhdyn/symbolic/derivation.hpp"

namespace nhdyn {
namespace {

struct FileSweep {
  symbolic::Spec spec;
  symbolic::Derivation derivation;
  std::string parameter;
  explicit FileSweep(const std::string& file, std::string p)
      : spec(load_model_file(testing::example_path(file))), derivation(symbolic::derive(spec)), parameter(std::move(p)) {}
  ModelAtValue model_at() {
    return [this](double value) {
      spec.set_parameter(parameter, value);
      return symbolic::compile_model(spec, derivation);
    };
  }
};

TEST(Sweep, BenchmarkBicycleWeaveAndCapsizeSpeeds) {
  FileSweep file("bicycle_linear.toml", "v");
  SweepOptions o;
  o.parameter = "v";
  o.from = 0.0;
  o.to = 10.0;
  o.steps = 101;
  const Sweep sweep = calc_eigenvalue_sweep(file.model_at(), o);
  ASSERT_EQ(sweep.points.size(), 101u);
  EXPECT_DOUBLE_EQ(sweep.points[50].value, 5.0);
  EXPECT_EQ(sweep.points.back().value, 10.0);
  const testing::BicycleMatrices bike;
  for (const SweepPoint& p : sweep.points) {
    const std::vector<std::complex<double>> want = bike.eigenvalues(p.value);
    ASSERT_EQ(p.eigenvalues.size(), 4u);
    for (std::size_t i = 0; i < 4; ++i)
      EXPECT_LT(std::abs(p.eigenvalues[i] - want[i]), 1e-10 * std::max(1.0, std::abs(want[i]))) << p.value;
  }
  // Below the weave speed the weave pair is unstable (and at v = 0 the capsize and a real
  // eigenvalue too); between 4.29 and 6.02 everything is stable; above, capsize.
  ASSERT_EQ(sweep.crossings.size(), 2u);
  const StabilityCrossing& weave = sweep.crossings[0];
  const StabilityCrossing& capsize = sweep.crossings[1];
  // The bisection stops at a sign change of the real part, not at the counting threshold (which
  // left the capsize speed 1.4e-12 late): both speeds to 5e-13 (they come out within 1e-13).
  EXPECT_NEAR(weave.value, testing::kWeaveSpeed, 5e-13);
  EXPECT_TRUE(weave.oscillatory);
  EXPECT_EQ(weave.unstable_before, 2);
  EXPECT_EQ(weave.unstable_after, 0);
  EXPECT_GT(weave.frequency, 1.0);
  EXPECT_NEAR(capsize.value, testing::kCapsizeSpeed, 5e-13);
  EXPECT_FALSE(capsize.oscillatory);
  EXPECT_EQ(capsize.unstable_before, 0);
  EXPECT_EQ(capsize.unstable_after, 1);
}

// Negative control: the tolerance 1e-9 tells a bicycle whose K2 differs in the seventh digit.
TEST(Sweep, APerturbedBicycleMissesThePublishedSpeeds) {
  FileSweep file("bicycle_linear.toml", "v");
  file.spec.set_parameter("K2_pd", 76.59734589573222 * (1 + 1e-7));
  SweepOptions o;
  o.parameter = "v";
  o.from = 0.0;
  o.to = 10.0;
  o.steps = 11;
  const Sweep sweep = calc_eigenvalue_sweep(file.model_at(), o);
  ASSERT_EQ(sweep.crossings.size(), 2u);
  EXPECT_GT(std::abs(sweep.crossings[0].value - testing::kWeaveSpeed), 1e-8);
  EXPECT_GT(std::abs(sweep.crossings[1].value - testing::kCapsizeSpeed), 1e-8);
}

TEST(Sweep, UprightRollingDiskThreshold) {
  FileSweep file("rolling_disk_upright.toml", "w");
  SweepOptions o;
  o.parameter = "w";
  o.from = 1.0;
  o.to = 10.0;
  o.steps = 10;
  o.linearization.cyclic = {"psi"};
  const Sweep sweep = calc_eigenvalue_sweep(file.model_at(), o);
  ASSERT_EQ(sweep.crossings.size(), 1u);
  EXPECT_NEAR(sweep.crossings[0].value, std::sqrt(9.81 / (3 * 0.2)), 1e-9);
  EXPECT_FALSE(sweep.crossings[0].oscillatory);
  EXPECT_EQ(sweep.crossings[0].unstable_before, 1);
  EXPECT_EQ(sweep.crossings[0].unstable_after, 0);
}

TEST(Sweep, BadRangesAndStepsAreRefusedWithTheValue) {
  SweepOptions o;
  o.parameter = "v";
  o.steps = 1;
  try {
    check_sweep_options(o);
    ADD_FAILURE();
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("--steps 1"), std::string::npos) << e.what();
  }
  o.steps = 11;
  o.from = 3;
  o.to = 3;
  try {
    check_sweep_options(o);
    ADD_FAILURE();
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("--from 3 --to 3"), std::string::npos) << e.what();
  }
  o.from = 5;
  o.to = 1;
  EXPECT_THROW(check_sweep_options(o), InputError);
  o.from = std::nan("");
  try {
    check_sweep_options(o);
    ADD_FAILURE();
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("--from nan"), std::string::npos) << e.what();
  }
  o.from = 0;
  o.to = 1;
  o.steps = 2000000;
  EXPECT_THROW(check_sweep_options(o), InputError);
}

TEST(Sweep, AFailingPointNamesTheParameterValue) {
  // The pendulum is steady only at theta0 = 0 and pi: a sweep over theta0 fails at the first
  // point that is not, and says which.
  FileSweep file("pendulum_cartesian.toml", "theta0");
  SweepOptions o;
  o.parameter = "theta0";
  o.from = 0.0;
  o.to = 1.0;
  o.steps = 3;
  try {
    calc_eigenvalue_sweep(file.model_at(), o);
    ADD_FAILURE();
  } catch (const ModelError& e) {
    const std::string m = e.what();
    EXPECT_NE(m.find("at theta0 = 0.5"), std::string::npos) << m;
    EXPECT_NE(m.find("not a steady motion"), std::string::npos) << m;
  }
}

}  // namespace
}  // namespace nhdyn
