// Exams for the explicit Runge-Kutta integrators: the tableaus satisfy the order conditions,
// rk4 converges with order 4 and hits output times with the promised steps, dopri5 meets its
// tolerance at step ends and in its continuous extension, scales its error with the tolerance,
// honours max_step and reports a singularity as step size underflow.
#include "nhdyn/integrators/explicit_rk.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <numeric>
#include <vector>

namespace nhdyn {
namespace {

// --- Order conditions (Hairer-Norsett-Wanner I, II.2, Table 2.2), one per rooted tree ---------

template <std::size_t S>
using Vec = std::array<double, S>;
template <std::size_t S>
using Mat = std::array<std::array<double, S>, S>;

template <std::size_t S>
double dot(const Vec<S>& u, const Vec<S>& v) {
  double s = 0.0;
  for (std::size_t i = 0; i < S; ++i) s += u[i] * v[i];
  return s;
}
template <std::size_t S>
Vec<S> times(const Vec<S>& u, const Vec<S>& v) {
  Vec<S> w{};
  for (std::size_t i = 0; i < S; ++i) w[i] = u[i] * v[i];
  return w;
}
template <std::size_t S>
Vec<S> mul(const Mat<S>& a, const Vec<S>& v) {
  Vec<S> w{};
  for (std::size_t i = 0; i < S; ++i)
    for (std::size_t j = 0; j < S; ++j) w[i] += a[i][j] * v[j];
  return w;
}

// Residuals of the conditions for orders 1..p of weights w.
template <std::size_t S>
std::vector<double> order_residuals(const Mat<S>& a, const Vec<S>& c, const Vec<S>& w, int p) {
  Vec<S> one{};
  one.fill(1.0);
  const Vec<S> c2 = times(c, c);
  const Vec<S> c3 = times(c2, c);
  const Vec<S> ac = mul(a, c);
  const Vec<S> ac2 = mul(a, c2);
  const Vec<S> aac = mul(a, ac);
  std::vector<double> r;
  r.push_back(dot(w, one) - 1.0);
  if (p >= 2) r.push_back(dot(w, c) - 1.0 / 2);
  if (p >= 3) {
    r.push_back(dot(w, c2) - 1.0 / 3);
    r.push_back(dot(w, ac) - 1.0 / 6);
  }
  if (p >= 4) {
    r.push_back(dot(w, c3) - 1.0 / 4);
    r.push_back(dot(w, times(c, ac)) - 1.0 / 8);
    r.push_back(dot(w, ac2) - 1.0 / 12);
    r.push_back(dot(w, aac) - 1.0 / 24);
  }
  if (p >= 5) {
    r.push_back(dot(w, times(c3, c)) - 1.0 / 5);
    r.push_back(dot(w, times(c2, ac)) - 1.0 / 10);
    r.push_back(dot(w, times(ac, ac)) - 1.0 / 20);
    r.push_back(dot(w, times(c, ac2)) - 1.0 / 15);
    r.push_back(dot(w, mul(a, c3)) - 1.0 / 20);
    r.push_back(dot(w, times(c, aac)) - 1.0 / 30);
    r.push_back(dot(w, mul(a, times(c, ac))) - 1.0 / 40);
    r.push_back(dot(w, mul(a, ac2)) - 1.0 / 60);
    r.push_back(dot(w, mul(a, aac)) - 1.0 / 120);
  }
  return r;
}

template <class T>
void expect_consistent_nodes() {
  for (std::size_t i = 0; i < T::c.size(); ++i) {
    const double row = std::accumulate(T::a[i].begin(), T::a[i].end(), 0.0);
    EXPECT_NEAR(row, T::c[i], 1e-15) << "row " << i;
    for (std::size_t j = i; j < T::c.size(); ++j) EXPECT_EQ(T::a[i][j], 0.0) << i << "," << j;
  }
}

TEST(Tableaus, ClassicRk4HasOrder4) {
  using T = rk::ClassicRk4;
  expect_consistent_nodes<T>();
  for (double r : order_residuals(T::a, T::c, T::b, 4)) EXPECT_NEAR(r, 0.0, 1e-15);
  EXPECT_GT(std::abs(order_residuals(T::a, T::c, T::b, 5)[8]), 1e-3);
}

TEST(Tableaus, DormandPrinceHasOrder5WithAnEmbeddedOrder4) {
  using T = rk::DormandPrince54;
  expect_consistent_nodes<T>();
  for (double r : order_residuals(T::a, T::c, T::b, 5)) EXPECT_NEAR(r, 0.0, 1e-14);
  Vec<7> b_hat{};
  for (std::size_t i = 0; i < 7; ++i) b_hat[i] = T::b[i] - T::e[i];
  for (double r : order_residuals(T::a, T::c, b_hat, 4)) EXPECT_NEAR(r, 0.0, 1e-14);
  // The estimate must see fifth-order terms, or it would estimate nothing.
  const std::vector<double> r5 = order_residuals(T::a, T::c, b_hat, 5);
  EXPECT_GT(*std::max_element(r5.begin(), r5.end(), [](double x, double y) {
    return std::abs(x) < std::abs(y);
  }), 1e-5);
  // FSAL: the last stage is evaluated at the new solution.
  for (std::size_t j = 0; j < 7; ++j) EXPECT_EQ(T::a[6][j], T::b[j]);
  EXPECT_EQ(T::c[6], 1.0);
  // The continuous extension's correction term is h sum d_i k_i applied to the zero-order
  // condition: sum d_i = 0, so it vanishes on constant derivatives.
  EXPECT_NEAR(std::accumulate(T::d.begin(), T::d.end(), 0.0), 0.0, 1e-14);
}

// --- Integration exams ------------------------------------------------------------------------

std::vector<double> linspace(double a, double b, int count) {
  std::vector<double> t(static_cast<std::size_t>(count));
  for (int i = 0; i < count; ++i) t[static_cast<std::size_t>(i)] = a + (b - a) * i / (count - 1);
  return t;
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
  StepEnd after_step(double t, double* /*y*/) override {
    step_ends.push_back(t);
    return {};
  }
  std::vector<double> step_ends;
};

struct Outcome {
  IntegrationResult result;
  double max_error = 0.0;  // largest distance from (cos t, -sin t) over the outputs
};

Outcome run_oscillator(const IntegratorOptions& options, const std::vector<double>& times,
                   Oscillator* observed = nullptr) {
  Oscillator local;
  Oscillator& system = observed ? *observed : local;
  const double y0[2] = {1.0, 0.0};
  Outcome run;
  run.result = integrate(system, options, 0.0, y0, times, [&](double t, const double* y) {
    run.max_error = std::max(run.max_error, std::hypot(y[0] - std::cos(t), y[1] + std::sin(t)));
    return Status::ok;
  });
  return run;
}

IntegratorOptions rk4_options(double step) {
  IntegratorOptions options;
  options.kind = IntegratorKind::rk4;
  options.step = step;
  return options;
}

IntegratorOptions dopri5_options(double tol) {
  IntegratorOptions options;
  options.kind = IntegratorKind::dopri5;
  options.rtol = tol;
  options.atol = tol;
  return options;
}

TEST(Rk4, GlobalErrorHasOrder4) {
  const std::vector<double> times = linspace(0.0, 10.0, 11);
  const Outcome coarse = run_oscillator(rk4_options(0.1), times);
  const Outcome fine = run_oscillator(rk4_options(0.05), times);
  ASSERT_EQ(coarse.result.status, Status::ok);
  ASSERT_EQ(fine.result.status, Status::ok);
  EXPECT_EQ(coarse.result.stats.steps, 100);
  EXPECT_EQ(fine.result.stats.steps, 200);
  const double ratio = coarse.max_error / fine.max_error;
  EXPECT_GE(ratio, 12.0) << coarse.max_error << " " << fine.max_error;
  EXPECT_LE(ratio, 20.0) << coarse.max_error << " " << fine.max_error;
  // h^4 t / 120 for the oscillator's phase error: 1e-4 * 10 / 120.
  EXPECT_LT(coarse.max_error, 2e-5);
}

TEST(Rk4, SplitsEachOutputIntervalIntoEqualSteps) {
  Oscillator system;
  const std::vector<double> times = {0.3, 1.0};
  const Outcome run = run_oscillator(rk4_options(0.1), times, &system);
  ASSERT_EQ(run.result.status, Status::ok);
  EXPECT_EQ(run.result.stats.steps, 3 + 7);
  EXPECT_EQ(run.result.stats.rhs_evaluations, 4 * 10);
  ASSERT_EQ(system.step_ends.size(), 10u);
  EXPECT_EQ(system.step_ends[2], 0.3);
  EXPECT_EQ(system.step_ends[9], 1.0);
  EXPECT_NEAR(system.step_ends[5], 0.6, 1e-15);
}

TEST(Rk4, RoundOffDoesNotAddAStep) {
  // 2.1 / 0.3 is 7.000000000000001 in floating point.
  const Outcome run = run_oscillator(rk4_options(0.3), {2.1});
  ASSERT_EQ(run.result.status, Status::ok);
  EXPECT_EQ(run.result.stats.steps, 7);
}

TEST(Rk4, DefaultStepIsATenthOfTheOutputSpacing) {
  const Outcome run = run_oscillator(rk4_options(0.0), linspace(0.0, 1.0, 11));
  ASSERT_EQ(run.result.status, Status::ok);
  EXPECT_EQ(run.result.stats.steps, 100);
}

TEST(Rk4, AStepLongerThanTheIntervalBecomesOneStep) {
  const Outcome run = run_oscillator(rk4_options(5.0), linspace(0.0, 1.0, 11));
  ASSERT_EQ(run.result.status, Status::ok);
  EXPECT_EQ(run.result.stats.steps, 10);
}

TEST(Dopri5, MeetsTightToleranceOnTheOscillator) {
  const std::vector<double> times = {10.0};
  const Outcome run = run_oscillator(dopri5_options(1e-10), times);
  ASSERT_EQ(run.result.status, Status::ok) << run.result.message;
  EXPECT_LT(run.max_error, 1e-8);
  EXPECT_EQ(run.result.stats.rhs_evaluations,
            6 * (run.result.stats.steps + run.result.stats.rejected_steps) + 2);
}

TEST(Dopri5, DenseOutputIsAccurateAndNeverShortensSteps) {
  std::vector<double> times;
  for (int k = 0; k < 1000; ++k) times.push_back(0.00731 + 0.00997 * k);
  times.push_back(10.0);
  Oscillator dense_system;
  const Outcome dense = run_oscillator(dopri5_options(1e-10), times, &dense_system);
  ASSERT_EQ(dense.result.status, Status::ok) << dense.result.message;
  EXPECT_LT(dense.max_error, 1e-8);
  // Most outputs lie strictly inside steps.
  EXPECT_LT(dense.result.stats.steps, 500);

  Oscillator end_system;
  const Outcome end_only = run_oscillator(dopri5_options(1e-10), {10.0}, &end_system);
  EXPECT_EQ(dense.result.stats.steps, end_only.result.stats.steps);
  EXPECT_EQ(dense_system.step_ends, end_system.step_ends);
}

TEST(Dopri5, ErrorIsProportionalToTheTolerance) {
  const std::vector<double> times = linspace(0.0, 10.0, 101);
  const double e5 = run_oscillator(dopri5_options(1e-5), times).max_error;
  const double e7 = run_oscillator(dopri5_options(1e-7), times).max_error;
  const double e9 = run_oscillator(dopri5_options(1e-9), times).max_error;
  // Error per step control of a fifth-order method with local extrapolation: the global error
  // goes as the tolerance, up to the controller's discreteness.
  EXPECT_GT(e5 / e7, 50.0) << e5 << " " << e7;
  EXPECT_LT(e5 / e7, 200.0) << e5 << " " << e7;
  EXPECT_GT(e7 / e9, 50.0) << e7 << " " << e9;
  EXPECT_LT(e7 / e9, 200.0) << e7 << " " << e9;
  EXPECT_LT(e9, 1e-7);
}

TEST(Dopri5, HonoursMaxStep) {
  Oscillator system;
  IntegratorOptions options = dopri5_options(1e-6);
  options.max_step = 0.05;
  const Outcome run = run_oscillator(options, {10.0}, &system);
  ASSERT_EQ(run.result.status, Status::ok);
  double t = 0.0;
  double longest = 0.0;
  for (double end : system.step_ends) {
    longest = std::max(longest, end - t);
    t = end;
  }
  EXPECT_LE(longest, 0.05 * (1.0 + 1e-12));
  EXPECT_GE(run.result.stats.steps, 200);
}

TEST(Dopri5, TooLongAFirstStepIsRejectedAndCounted) {
  IntegratorOptions options = dopri5_options(1e-10);
  options.step = 2.0;
  const Outcome run = run_oscillator(options, {10.0});
  ASSERT_EQ(run.result.status, Status::ok);
  EXPECT_GE(run.result.stats.rejected_steps, 1);
  EXPECT_LT(run.max_error, 1e-8);
}

// y' = y^2, y(0) = 1: y = 1 / (1 - t) blows up at t = 1.
class BlowUp : public OdeSystem {
 public:
  int size() const override { return 1; }
  Status rhs(double /*t*/, const double* y, double* ydot) override {
    ydot[0] = y[0] * y[0];
    return Status::ok;
  }
};

TEST(Dopri5, SingularityGivesStepSizeUnderflow) {
  BlowUp system;
  const double y0[1] = {1.0};
  const std::vector<double> times = {2.0};
  const IntegrationResult result = integrate(system, dopri5_options(1e-8), 0.0, y0, times,
                                             [](double, const double*) { return Status::ok; });
  EXPECT_EQ(result.status, Status::step_size_underflow) << result.message;
  // Within the integration error of the blow-up time.
  EXPECT_NEAR(result.t_reached, 1.0, 1e-6);
  EXPECT_NE(result.message.find("at t = "), std::string::npos) << result.message;
}

}  // namespace
}  // namespace nhdyn
