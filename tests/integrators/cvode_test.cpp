// Exams for CVODE behind the integrator interface: BDF and Adams on the oscillator, BDF on stiff
// problems (a fast relaxation onto cos t and Robertson's kinetics, against published values)
// with far fewer rhs evaluations than dopri5, and the C boundary: exceptions from the rhs come
// through, and CVODE never prints.
#include "nhdyn/integrators/sundials/cvode.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <stdexcept>
#include <string>
#include <vector>
#include "support/text.hpp"

namespace nhdyn {
namespace {

using nhdyn::test::linspace;

IntegratorOptions tolerances(IntegratorKind kind, double rtol, double atol) {
  IntegratorOptions options;
  options.kind = kind;
  options.rtol = rtol;
  options.atol = atol;
  return options;
}

// x'' = -x as y = (x, x'); y(0) = (1, 0) gives (cos t, -sin t).
class Oscillator : public OdeSystem {
 public:
  int size() const override { return 2; }
  Status rhs(double /*t*/, const double* y, double* ydot) override {
    ydot[0] = y[1];
    ydot[1] = -y[0];
    return Status::ok;
  }
};

class CvodeMethod : public ::testing::TestWithParam<IntegratorKind> {};

INSTANTIATE_TEST_SUITE_P(Methods, CvodeMethod,
                         ::testing::Values(IntegratorKind::cvode_bdf, IntegratorKind::cvode_adams),
                         [](const ::testing::TestParamInfo<IntegratorKind>& info) {
                           return info.param == IntegratorKind::cvode_bdf ? "bdf" : "adams";
                         });

TEST_P(CvodeMethod, MatchesTheOscillatorAtStepEndsAndInBetween) {
  Oscillator system;
  const double y0[2] = {1.0, 0.0};
  std::vector<double> times;
  for (int k = 0; k < 500; ++k) times.push_back(0.0137 + 0.01997 * k);
  times.push_back(10.0);
  double worst = 0.0;
  std::vector<double> last(2);
  const OutputFn record = [&](double t, const double* y) {
    worst = std::max(worst, std::hypot(y[0] - std::cos(t), y[1] + std::sin(t)));
    last.assign(y, y + 2);
    return Status::ok;
  };
  const IntegrationResult result =
      integrate(system, tolerances(GetParam(), 1e-10, 1e-10), 0.0, y0, times, record);
  ASSERT_EQ(result.status, Status::ok) << result.message;
  EXPECT_LT(std::hypot(last[0] - std::cos(10.0), last[1] + std::sin(10.0)), 1e-6);
  EXPECT_LT(worst, 1e-6);
  // Outputs come from the interpolating polynomial, not from steps cut short.
  EXPECT_LT(result.stats.steps, 500);
}

// y' = -1000 (y - cos t) - sin t: y = cos t from y(0) = 1, any other start relaxes onto it at
// rate 1000, which bounds explicit steps to about 3.3e-3.
class FastRelaxation : public OdeSystem {
 public:
  int size() const override { return 1; }
  Status rhs(double t, const double* y, double* ydot) override {
    ydot[0] = -1000.0 * (y[0] - std::cos(t)) - std::sin(t);
    return Status::ok;
  }
};

TEST(CvodeBdf, StiffRelaxationTakesFarFewerRhsEvaluationsThanDopri5) {
  const double y0[1] = {1.0};
  const std::vector<double> times = linspace(0.0, 10.0, 101);
  auto run = [&](IntegratorKind kind, double& worst) {
    FastRelaxation system;
    worst = 0.0;
    return integrate(system, tolerances(kind, 1e-6, 1e-8), 0.0, y0, times,
                     [&](double t, const double* y) {
                       worst = std::max(worst, std::abs(y[0] - std::cos(t)));
                       return Status::ok;
                     });
  };
  double bdf_error = 0.0;
  double dopri_error = 0.0;
  const IntegrationResult bdf = run(IntegratorKind::cvode_bdf, bdf_error);
  const IntegrationResult dopri = run(IntegratorKind::dopri5, dopri_error);
  ASSERT_EQ(bdf.status, Status::ok) << bdf.message;
  ASSERT_EQ(dopri.status, Status::ok) << dopri.message;
  EXPECT_LT(bdf_error, 1e-5);
  EXPECT_LT(dopri_error, 1e-5);
  // dopri5 needs about 10 / 3.3e-3 = 3000 steps, 18000 evaluations, whatever the tolerance.
  EXPECT_GT(dopri.stats.rhs_evaluations, 15000);
  EXPECT_LT(50 * bdf.stats.rhs_evaluations, dopri.stats.rhs_evaluations)
      << bdf.stats.rhs_evaluations << " vs " << dopri.stats.rhs_evaluations;
}

// Hairer's stiffness test in the explicit pairs (IntegratorStats::stiff_steps, stiff_from): on the
// relaxation above |lambda| = 1000 holds dopri5's steps just under 3.25e-3 and dop853's just under
// 6.1e-3 (within 20 % of the stability bound), so most steps are counted stiff, from early on; the oscillator (|lambda| = 1, steps of about 0.1 at
// this tolerance, h |lambda| far inside both bounds) has none.
TEST(StiffnessTest, TheExplicitPairsCountTheStepsThatStabilityHeld) {
  const double y0[1] = {1.0};
  const std::vector<double> times = linspace(0.0, 10.0, 101);
  for (IntegratorKind kind : {IntegratorKind::dopri5, IntegratorKind::dop853}) {
    FastRelaxation system;
    const IntegrationResult stiff = integrate(system, tolerances(kind, 1e-6, 1e-8), 0.0, y0, times,
                                              [](double, const double*) { return Status::ok; });
    ASSERT_EQ(stiff.status, Status::ok) << stiff.message;
    const double bound = kind == IntegratorKind::dopri5 ? 3.25 : 6.1;
    // About 10 / (bound / 1000) accepted steps, at least half of them near the bound.
    EXPECT_GT(stiff.stats.steps, 0.8 * 10.0 / (bound / 1000.0));
    EXPECT_GT(2 * stiff.stats.stiff_steps, stiff.stats.steps) << stiff.stats.stiff_steps << " of " << stiff.stats.steps;
    EXPECT_LT(stiff.stats.stiff_from, 0.5);

    Oscillator calm;
    const double start[2] = {1.0, 0.0};
    const IntegrationResult smooth = integrate(calm, tolerances(kind, 1e-6, 1e-8), 0.0, start, times,
                                               [](double, const double*) { return Status::ok; });
    ASSERT_EQ(smooth.status, Status::ok) << smooth.message;
    EXPECT_EQ(smooth.stats.stiff_steps, 0);
    EXPECT_TRUE(std::isnan(smooth.stats.stiff_from));
  }
}

// Robertson's chemical kinetics, the classic stiff test (Hairer-Wanner II, IV.1).
class Robertson : public OdeSystem {
 public:
  int size() const override { return 3; }
  Status rhs(double /*t*/, const double* y, double* ydot) override {
    ydot[0] = -0.04 * y[0] + 1e4 * y[1] * y[2];
    ydot[2] = 3e7 * y[1] * y[1];
    ydot[1] = -ydot[0] - ydot[2];
    return Status::ok;
  }
};

TEST(CvodeBdf, RobertsonMatchesReferenceValues) {
  Robertson system;
  const double y0[3] = {1.0, 0.0, 0.0};
  const std::vector<double> times = {0.4, 40.0, 4e5};
  std::vector<std::vector<double>> states;
  IntegratorOptions options = tolerances(IntegratorKind::cvode_bdf, 1e-8, 1e-14);
  const IntegrationResult result = integrate(system, options, 0.0, y0, times,
                                             [&](double, const double* y) {
                                               states.emplace_back(y, y + 3);
                                               return Status::ok;
                                             });
  ASSERT_EQ(result.status, Status::ok) << result.message;
  ASSERT_EQ(states.size(), 3u);
  // Reference values at t = 0.4 and 40 (Hairer-Wanner's stiff test set).
  const double reference[2][3] = {{9.851721138e-01, 3.386395348e-05, 1.479402225e-02},
                                  {7.158270687e-01, 9.185534765e-06, 2.841637470e-01}};
  for (int i = 0; i < 2; ++i)
    for (int j = 0; j < 3; ++j)
      EXPECT_NEAR(states[static_cast<std::size_t>(i)][static_cast<std::size_t>(j)],
                  reference[i][j], 1e-5 * std::abs(reference[i][j]))
          << "t = " << times[static_cast<std::size_t>(i)] << ", y" << j + 1;
  // The rates sum to zero, so the total is conserved; at t = 4e5 most of it has become y3.
  for (const std::vector<double>& y : states) EXPECT_NEAR(y[0] + y[1] + y[2], 1.0, 1e-10);
  EXPECT_NEAR(states[2][0], 4.94e-3, 1e-5);
  EXPECT_LT(result.stats.rhs_evaluations, 5000);
}

class Throws : public Oscillator {
 public:
  Status rhs(double t, const double* y, double* ydot) override {
    if (t > 1.0) throw std::runtime_error("model evaluation failed");
    return Oscillator::rhs(t, y, ydot);
  }
};

TEST_P(CvodeMethod, ExceptionFromTheRhsComesThrough) {
  Throws system;
  const double y0[2] = {1.0, 0.0};
  const std::vector<double> times = {5.0};
  EXPECT_THROW(integrate(system, tolerances(GetParam(), 1e-8, 1e-8), 0.0, y0, times,
                         [](double, const double*) { return Status::ok; }),
               std::runtime_error);
}

// y' = y^2 from y(0) = 1 blows up at t = 1.
class BlowUp : public OdeSystem {
 public:
  int size() const override { return 1; }
  Status rhs(double /*t*/, const double* y, double* ydot) override {
    ydot[0] = y[0] * y[0];
    return Status::ok;
  }
};

TEST_P(CvodeMethod, FailureIsReportedWithoutPrinting) {
  BlowUp system;
  const double y0[1] = {1.0};
  const std::vector<double> times = {2.0};
  ::testing::internal::CaptureStderr();
  ::testing::internal::CaptureStdout();
  const IntegrationResult result =
      integrate(system, tolerances(GetParam(), 1e-8, 1e-8), 0.0, y0, times,
                [](double, const double*) { return Status::ok; });
  const std::string out = ::testing::internal::GetCapturedStdout();
  const std::string err = ::testing::internal::GetCapturedStderr();
  EXPECT_EQ(result.status, Status::step_size_underflow) << result.message;
  EXPECT_GT(result.t_reached, 0.9999);
  EXPECT_LE(result.t_reached, 1.0);
  EXPECT_NE(result.message.find("t = 0.99"), std::string::npos) << result.message;
  EXPECT_EQ(out, "");
  EXPECT_EQ(err, "");
}

}  // namespace
}  // namespace nhdyn
