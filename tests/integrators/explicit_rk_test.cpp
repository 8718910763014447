// Exams for the explicit Runge-Kutta integrators: the tableaus satisfy the order conditions,
// rk4 converges with order 4 and hits output times with the promised steps, dopri5 meets its
// tolerance at step ends and in its continuous extension, scales its error with the tolerance,
// honours max_step and reports a singularity as step size underflow; a quadrature past
// error_size() leaves the other states as they were, to the bit.
#include "nhdyn/integrators/detail/explicit_rk.hpp"

#include "nhdyn/core/error.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <numeric>
#include <utility>
#include <vector>
#include "support/text.hpp"

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

TEST(Tableaus, DormandPrince853HasOrder8WithEmbeddedOrders5And3) {
  using T = rk::DormandPrince853;
  constexpr std::size_t S = T::stages;
  // Rows summing to the nodes, up to the round-off of coefficients as large as 43.
  for (std::size_t i = 0; i < S; ++i) {
    double row = 0.0, size = 0.0;
    for (std::size_t j = 0; j < S; ++j) {
      row += T::a[i][j];
      size += std::abs(T::a[i][j]);
      if (j >= i) {
        EXPECT_EQ(T::a[i][j], 0.0) << i << "," << j;
      }
    }
    EXPECT_NEAR(row, T::c[i], 1e-15 * std::max(1.0, size)) << "row " << i;
  }
  // The conditions up to order 5 here (order 8 shows in the convergence exams below): 17 trees
  // whose residuals a mistyped digit of a, b or c would spoil.
  for (double r : order_residuals(T::a, T::c, T::b, 5)) EXPECT_NEAR(r, 0.0, 1e-13);
  // The 5th-order error estimate is the difference from a 5th-order solution b - e5, and the
  // 3rd-order one from the 3rd-order solution bhh.
  Vec<S> b5{};
  for (std::size_t i = 0; i < S; ++i) b5[i] = T::b[i] - T::e5[i];
  for (double r : order_residuals(T::a, T::c, b5, 5)) EXPECT_NEAR(r, 0.0, 1e-13);
  for (double r : order_residuals(T::a, T::c, T::bhh, 3)) EXPECT_NEAR(r, 0.0, 1e-13);
  const std::vector<double> r4 = order_residuals(T::a, T::c, T::bhh, 4);
  EXPECT_GT(std::abs(r4[4]) + std::abs(r4[5]) + std::abs(r4[6]) + std::abs(r4[7]), 1e-4);
  // FSAL: the last stage is f(t + h, y1); neither estimate uses it.
  for (std::size_t j = 0; j < S; ++j) EXPECT_EQ(T::a[S - 1][j], T::b[j]);
  EXPECT_EQ(T::c[S - 1], 1.0);
  EXPECT_EQ(T::e5[S - 1], 0.0);
  EXPECT_EQ(T::bhh[S - 1], T::b[S - 1]);
  // The stages of the continuous extension: rows consistent with their nodes, explicit.
  for (std::size_t s = 0; s < T::c_extra.size(); ++s) {
    const double row = std::accumulate(T::a_extra[s].begin(), T::a_extra[s].end(), 0.0);
    EXPECT_NEAR(row, T::c_extra[s], 1e-14) << "extra stage " << s;
    for (std::size_t j = S + s; j < T::a_extra[s].size(); ++j) EXPECT_EQ(T::a_extra[s][j], 0.0);
  }
  // With every k_j equal (a constant derivative) the interpolant must be the straight line, so
  // each row of d sums to zero.
  for (const auto& row : T::d)
    EXPECT_NEAR(std::accumulate(row.begin(), row.end(), 0.0), 0.0, 1e-12);
}

// --- Integration exams ------------------------------------------------------------------------

using nhdyn::test::linspace;

// x'' = -x as y = (x, x'); y(0) = (1, 0) gives (cos t, -sin t).
class RkOscillator : public OdeSystem {
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
                   RkOscillator* observed = nullptr) {
  RkOscillator local;
  RkOscillator& system = observed ? *observed : local;
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
  RkOscillator system;
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
  RkOscillator dense_system;
  const Outcome dense = run_oscillator(dopri5_options(1e-10), times, &dense_system);
  ASSERT_EQ(dense.result.status, Status::ok) << dense.result.message;
  EXPECT_LT(dense.max_error, 1e-8);
  // Most outputs lie strictly inside steps.
  EXPECT_LT(dense.result.stats.steps, 500);

  RkOscillator end_system;
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
  RkOscillator system;
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

// --- DOP853 ------------------------------------------------------------------------------------

IntegratorOptions dop853_options(double tol) {
  IntegratorOptions options;
  options.kind = IntegratorKind::dop853;
  options.rtol = tol;
  options.atol = tol;
  return options;
}

// Options that make an adaptive method take steps of exactly h: every error passes the test and
// the step never grows beyond max_step.
IntegratorOptions fixed_step(IntegratorKind kind, double h) {
  IntegratorOptions options;
  options.kind = kind;
  options.rtol = 0.0;
  options.atol = 1e6;
  options.step = h;
  options.max_step = h;
  return options;
}

// The Kepler problem, y = (q1, q2, p1, p2), q'' = -q / |q|^3, with eccentricity e: a nonlinear
// system in several components, so all elementary differentials (not only those of a scalar
// equation) enter its error. Closed form from Kepler's equation E - e sin E = t.
class Kepler : public OdeSystem {
 public:
  explicit Kepler(double eccentricity) : e_(eccentricity) {}
  int size() const override { return 4; }
  Status rhs(double /*t*/, const double* y, double* ydot) override {
    const double r2 = y[0] * y[0] + y[1] * y[1];
    const double r3 = r2 * std::sqrt(r2);
    ydot[0] = y[2];
    ydot[1] = y[3];
    ydot[2] = -y[0] / r3;
    ydot[3] = -y[1] / r3;
    return Status::ok;
  }
  StepEnd after_step(double t, double* /*y*/) override {
    step_ends.push_back(t);
    return {};
  }
  std::array<double, 4> exact(double t) const {
    double E = t;
    for (int i = 0; i < 50; ++i) E -= (E - e_ * std::sin(E) - t) / (1.0 - e_ * std::cos(E));
    const double w = std::sqrt(1.0 - e_ * e_);
    const double rate = 1.0 / (1.0 - e_ * std::cos(E));
    return {std::cos(E) - e_, w * std::sin(E), -std::sin(E) * rate, w * std::cos(E) * rate};
  }
  std::vector<double> step_ends;

 private:
  double e_;
};

struct KeplerRun {
  IntegrationResult result;
  double max_error = 0.0;  // largest distance from the closed form over the outputs
};

KeplerRun run_kepler(const IntegratorOptions& options, double t0, const std::vector<double>& times,
                     Kepler& system) {
  const std::array<double, 4> y0 = system.exact(t0);
  KeplerRun run;
  run.result = integrate(system, options, t0, y0.data(), times, [&](double t, const double* y) {
    const std::array<double, 4> x = system.exact(t);
    double d = 0.0;
    for (int i = 0; i < 4; ++i) d = std::max(d, std::abs(y[i] - x[static_cast<std::size_t>(i)]));
    run.max_error = std::max(run.max_error, d);
    return Status::ok;
  });
  return run;
}

double kepler_fixed_step_error(IntegratorKind kind, int steps) {
  const double t_end = 2.0 * std::acos(-1.0);
  Kepler system(0.3);
  const KeplerRun run = run_kepler(fixed_step(kind, t_end / steps), 0.0, {t_end}, system);
  EXPECT_EQ(run.result.status, Status::ok) << run.result.message;
  EXPECT_EQ(run.result.stats.steps, steps);
  EXPECT_EQ(run.result.stats.rejected_steps, 0);
  return run.max_error;
}

TEST(Dop853, GlobalErrorHasOrder8) {
  // One orbit of eccentricity 0.3 in N and 2N equal steps: the error falls by 2^8 = 256 (200 at
  // these steps, where the next term still shows; an order of 7 or 9 would give 128 or 512),
  // while dopri5's falls by 2^5 = 32.
  const double coarse = kepler_fixed_step_error(IntegratorKind::dop853, 50);
  const double fine = kepler_fixed_step_error(IntegratorKind::dop853, 100);
  const double ratio = coarse / fine;
  EXPECT_GT(ratio, 160.0) << coarse << " " << fine;
  EXPECT_LT(ratio, 350.0) << coarse << " " << fine;
  const double dopri5_ratio = kepler_fixed_step_error(IntegratorKind::dopri5, 100) /
                              kepler_fixed_step_error(IntegratorKind::dopri5, 200);
  EXPECT_GT(dopri5_ratio, 25.0);
  EXPECT_LT(dopri5_ratio, 40.0);
}

// The largest error of the continuous extension inside one step of size h from the exact state
// at t0 = 0.2 (near the pericentre, where the solution bends most).
double one_step_interpolation_error(IntegratorKind kind, double h) {
  Kepler system(0.3);
  const double t0 = 0.2;
  std::vector<double> times;
  for (int i = 1; i < 10; ++i) times.push_back(t0 + 0.1 * i * h);
  times.push_back(t0 + h);
  const KeplerRun run = run_kepler(fixed_step(kind, h), t0, times, system);
  EXPECT_EQ(run.result.status, Status::ok) << run.result.message;
  EXPECT_EQ(run.result.stats.steps, 1);
  return run.max_error;
}

TEST(Dop853, ContinuousExtensionHasOrder7) {
  // A 7th-order interpolant is off by O(h^8) inside the step (the step end by O(h^9)): halving
  // h divides the error by 2^8. dopri5's 4th-order one divides it by 2^5.
  const double coarse = one_step_interpolation_error(IntegratorKind::dop853, 0.2);
  const double fine = one_step_interpolation_error(IntegratorKind::dop853, 0.1);
  EXPECT_GT(coarse / fine, 200.0) << coarse << " " << fine;
  EXPECT_LT(coarse / fine, 320.0) << coarse << " " << fine;
  const double dopri5_ratio = one_step_interpolation_error(IntegratorKind::dopri5, 0.2) /
                              one_step_interpolation_error(IntegratorKind::dopri5, 0.1);
  EXPECT_GT(dopri5_ratio, 25.0);
  EXPECT_LT(dopri5_ratio, 40.0);
}

TEST(Dop853, GlobalErrorFollowsTheTolerance) {
  // Three orbits: the error at the outputs goes down with the tolerance, about in proportion.
  std::vector<double> times = linspace(0.0, 6.0 * std::acos(-1.0), 301);
  std::vector<double> errors;
  for (double tol : {1e-6, 1e-8, 1e-10, 1e-12}) {
    Kepler system(0.5);
    const KeplerRun run = run_kepler(dop853_options(tol), 0.0, times, system);
    ASSERT_EQ(run.result.status, Status::ok) << run.result.message;
    EXPECT_LT(run.max_error, 1000.0 * tol) << "rtol " << tol;
    errors.push_back(run.max_error);
  }
  for (std::size_t i = 0; i + 1 < errors.size(); ++i) {
    EXPECT_GT(errors[i] / errors[i + 1], 20.0) << errors[i] << " " << errors[i + 1];
    EXPECT_LT(errors[i] / errors[i + 1], 500.0) << errors[i] << " " << errors[i + 1];
  }
}

TEST(Dop853, CountsTwelveRhsPerStepElevenPerRejection) {
  Kepler system(0.5);
  IntegratorOptions options = dop853_options(1e-10);
  options.step = 1.0;  // too long a first step: the error test rejects it
  const KeplerRun run = run_kepler(options, 0.0, {10.0}, system);
  ASSERT_EQ(run.result.status, Status::ok) << run.result.message;
  const IntegratorStats& stats = run.result.stats;
  EXPECT_GE(stats.rejected_steps, 1);
  // The first f(t0, y0), then 11 stages per attempt and the FSAL stage of each accepted step.
  EXPECT_EQ(stats.rhs_evaluations, 1 + 11 * (stats.steps + stats.rejected_steps) + stats.steps);
  EXPECT_LT(run.max_error, 1e-7);
}

TEST(Dop853, OutputsComeFromTheContinuousExtensionAndNeverShortenSteps) {
  std::vector<double> times;
  for (int k = 0; k < 1000; ++k) times.push_back(0.00731 + 0.00997 * k);
  times.push_back(10.0);
  Kepler dense_system(0.5);
  const KeplerRun dense = run_kepler(dop853_options(1e-10), 0.0, times, dense_system);
  ASSERT_EQ(dense.result.status, Status::ok) << dense.result.message;
  EXPECT_LT(dense.max_error, 1e-7);

  Kepler end_system(0.5);
  const KeplerRun end_only = run_kepler(dop853_options(1e-10), 0.0, {10.0}, end_system);
  ASSERT_EQ(end_only.result.status, Status::ok);
  EXPECT_EQ(dense_system.step_ends, end_system.step_ends);
  // Most outputs lie strictly inside steps, and each step holding one costs its 3 extra stages.
  EXPECT_LT(dense.result.stats.steps, 500);
  long steps_with_outputs = 0;
  double start = 0.0;
  std::size_t next = 0;
  for (double end : dense_system.step_ends) {
    bool inside = false;
    for (; next < times.size() && times[next] <= end; ++next) inside = inside || times[next] < end;
    if (inside) ++steps_with_outputs;
    start = end;
  }
  EXPECT_GT(steps_with_outputs, 0);
  EXPECT_EQ(start, 10.0);
  EXPECT_EQ(dense.result.stats.rhs_evaluations,
            end_only.result.stats.rhs_evaluations + 3 * steps_with_outputs);
}

TEST(Dop853, TakesFarFewerRhsThanDopri5AtTightTolerances) {
  // Fewer steps by tol^(1/5 - 1/8) at twice dopri5's cost per step: on this orbit 1.9 times fewer
  // rhs evaluations at 1e-10, 3.3 times at 1e-12 (and about the same at 1e-6).
  for (const auto& [tol, factor] : {std::pair{1e-10, 1.5}, std::pair{1e-12, 2.5}}) {
    Kepler a(0.5), b(0.5);
    const KeplerRun dop853 = run_kepler(dop853_options(tol), 0.0, {20.0}, a);
    const KeplerRun dopri5 = run_kepler(dopri5_options(tol), 0.0, {20.0}, b);
    ASSERT_EQ(dop853.result.status, Status::ok);
    ASSERT_EQ(dopri5.result.status, Status::ok);
    EXPECT_LT(factor * static_cast<double>(dop853.result.stats.rhs_evaluations),
              static_cast<double>(dopri5.result.stats.rhs_evaluations))
        << "rtol " << tol;
    // At no loss of accuracy.
    EXPECT_LT(dop853.max_error, 2.0 * dopri5.max_error) << "rtol " << tol;
  }
}

// y' = y^2, y(0) = 1: y = 1 / (1 - t) blows up at t = 1.
class RkBlowUp : public OdeSystem {
 public:
  int size() const override { return 1; }
  Status rhs(double /*t*/, const double* y, double* ydot) override {
    ydot[0] = y[0] * y[0];
    return Status::ok;
  }
};

TEST(Dopri5, SingularityGivesStepSizeUnderflow) {
  RkBlowUp system;
  const double y0[1] = {1.0};
  const std::vector<double> times = {2.0};
  const IntegrationResult result = integrate(system, dopri5_options(1e-8), 0.0, y0, times,
                                             [](double, const double*) { return Status::ok; });
  EXPECT_EQ(result.status, Status::step_size_underflow) << result.message;
  // Within the integration error of the blow-up time.
  EXPECT_NEAR(result.t_reached, 1.0, 1e-6);
  EXPECT_NE(result.message.find("at t = "), std::string::npos) << result.message;
}

TEST(Dop853, SingularityGivesStepSizeUnderflow) {
  RkBlowUp system;
  const double y0[1] = {1.0};
  const std::vector<double> times = {2.0};
  const IntegrationResult result = integrate(system, dop853_options(1e-8), 0.0, y0, times,
                                             [](double, const double*) { return Status::ok; });
  EXPECT_EQ(result.status, Status::step_size_underflow) << result.message;
  EXPECT_NEAR(result.t_reached, 1.0, 1e-6);
}

// The oscillator with a quadrature past error_size(): W' = x'^2, W(0) = 0, so that
// W(t) = t / 2 - sin(2 t) / 4. Its right-hand side never reads W (OdeSystem::error_size).
class RkOscillatorWithWork : public OdeSystem {
 public:
  int size() const override { return 3; }
  int error_size() const override { return 2; }
  Status rhs(double /*t*/, const double* y, double* ydot) override {
    ydot[0] = y[1];
    ydot[1] = -y[0];
    ydot[2] = y[1] * y[1];
    return Status::ok;
  }
  StepEnd after_step(double t, double* /*y*/) override {
    step_ends.push_back(t);
    return {};
  }
  std::vector<double> step_ends;
};

// A quadrature formed only in the states a step returns changes nothing else: the same steps and
// the same oscillator to the bit at every output (inside steps and at their ends), and W within
// the tolerance of its closed form, for each explicit method.
TEST(ExplicitRk, AQuadraturePastTheErrorSizeLeavesTheOtherStatesAsTheyWere) {
  std::vector<double> times;
  for (int k = 1; k <= 200; ++k) times.push_back(0.05 * k);
  for (const IntegratorOptions& options : {rk4_options(0.01), dopri5_options(1e-10), dop853_options(1e-10)}) {
    SCOPED_TRACE(integrator_name(options.kind));
    RkOscillator plain;
    RkOscillatorWithWork with_work;
    std::vector<std::array<double, 2>> plain_states;
    std::vector<std::array<double, 3>> work_states;
    const double y0[3] = {1.0, 0.0, 0.0};
    const IntegrationResult a = integrate(plain, options, 0.0, y0, times, [&](double, const double* y) {
      plain_states.push_back({y[0], y[1]});
      return Status::ok;
    });
    const IntegrationResult b = integrate(with_work, options, 0.0, y0, times, [&](double, const double* y) {
      work_states.push_back({y[0], y[1], y[2]});
      return Status::ok;
    });
    ASSERT_EQ(a.status, Status::ok) << a.message;
    ASSERT_EQ(b.status, Status::ok) << b.message;
    EXPECT_EQ(plain.step_ends, with_work.step_ends);
    EXPECT_EQ(a.stats.rhs_evaluations, b.stats.rhs_evaluations);
    ASSERT_EQ(plain_states.size(), times.size());
    ASSERT_EQ(work_states.size(), times.size());
    double worst = 0.0;
    for (std::size_t i = 0; i < times.size(); ++i) {
      EXPECT_EQ(plain_states[i][0], work_states[i][0]) << "t = " << times[i];
      EXPECT_EQ(plain_states[i][1], work_states[i][1]) << "t = " << times[i];
      const double t = times[i];
      worst = std::max(worst, std::abs(work_states[i][2] - (t / 2 - std::sin(2 * t) / 4)));
    }
    // rk4 with h = 0.01 errs by about h^4 over t = 10; the adaptive pairs by their tolerance.
    EXPECT_LT(worst, 1e-7);
    EXPECT_GT(work_states.back()[2], 4.0);  // W(10) = 5 - sin(20) / 4 = 4.77...
  }
}

// error_size() must lie in [1, size()]: the error norm divides by it, and the stages form that
// many states.
class RkBadErrorSize : public OdeSystem {
 public:
  explicit RkBadErrorSize(int weighed) : weighed_(weighed) {}
  int size() const override { return 2; }
  int error_size() const override { return weighed_; }
  Status rhs(double /*t*/, const double* y, double* ydot) override {
    ydot[0] = y[1];
    ydot[1] = -y[0];
    return Status::ok;
  }

 private:
  int weighed_;
};

TEST(ExplicitRk, AnErrorSizeOutsideOneToTheStateCountIsRefused) {
  for (int weighed : {0, -1, 3}) {
    RkBadErrorSize system(weighed);
    const double y0[2] = {1.0, 0.0};
    const std::vector<double> times = {1.0};
    try {
      integrate(system, dopri5_options(1e-8), 0.0, y0, times, [](double, const double*) { return Status::ok; });
      ADD_FAILURE() << "error_size " << weighed << " was accepted";
    } catch (const InputError& e) {
      EXPECT_NE(std::string(e.what()).find("error_size"), std::string::npos) << e.what();
    }
  }
}

}  // namespace
}  // namespace nhdyn
