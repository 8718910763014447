#include "nhdyn/integrators/detail/explicit_rk.hpp"

#include "nhdyn/integrators/events.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <optional>
#include <string_view>
#include <utility>
#include <vector>

#include <fmt/format.h>

namespace nhdyn {
namespace {

constexpr double eps = std::numeric_limits<double>::epsilon();

// One explicit Runge-Kutta step for any tableau. Owns the stage derivatives k_i and a scratch
// state, allocated once per integrate() call. A stage's state holds only the `read` leading
// states, those the right-hand side reads (OdeSystem::error_size: the states past them are
// quadratures); the state a step returns, y1, holds them all.
template <class Tableau>
class Stepper {
 public:
  Stepper(int n, int read) : n_(n), read_(read), y_stage_(static_cast<std::size_t>(n)) {
    for (std::vector<double>& k : k_) k.assign(static_cast<std::size_t>(n), 0.0);
  }

  double* k(int i) { return k_[static_cast<std::size_t>(i)].data(); }
  const double* k(int i) const { return k_[static_cast<std::size_t>(i)].data(); }
  double* scratch() { return y_stage_.data(); }
  // After step(): the state of the last stage before the FSAL one, its first `read` entries.
  const double* scratch_view() const { return y_stage_.data(); }

  // The FSAL stage of one step is the first of the next: swapping the buffers saves a copy.
  void reuse_last_stage() { std::swap(k_.front(), k_.back()); }

  // Evaluates stages 2..s of a step of size h from (t, y), k(0) holding f(t, y) on entry, and
  // writes y1 = y + h sum b_i k_i. With FSAL and evaluate_last false, the last stage f(t + h, y1)
  // is left for the caller (its error estimate does not need it). On a non-ok status, t_fail is
  // where the rhs failed.
  Status step(OdeSystem& system, double t, const double* y, double h, double* y1,
              IntegratorStats& stats, double& t_fail, bool evaluate_last = true) {
    Status status = Status::ok;
    // Stages 2..s, each with its row of the tableau known at compile time (see combine).
    [&]<int... S>(std::integer_sequence<int, S...>) {
      (void)(stage<S + 1>(system, t, y, h, y1, stats, t_fail, evaluate_last, status) && ...);
    }(std::make_integer_sequence<int, Tableau::stages - 1>{});
    if constexpr (!Tableau::fsal) {
      if (status == Status::ok) combine<Tableau::stages>(y, h, y1, n_);
    }
    return status;
  }

 private:
  // Stage `s`: its state, then f there into k(s); false when the step goes no further (the FSAL
  // stage left to the caller, or a failed rhs with `status` and t_fail set).
  template <int s>
  bool stage(OdeSystem& system, double t, const double* y, double h, double* y1, IntegratorStats& stats,
             double& t_fail, bool evaluate_last, Status& status) {
    constexpr bool last = Tableau::fsal && s == Tableau::stages - 1;
    // With FSAL the last row of a equals b, so the last stage state is y1 itself.
    double* target = last ? y1 : y_stage_.data();
    combine<s>(y, h, target, last ? n_ : read_);
    if (last && !evaluate_last) return false;
    const double ts = t + Tableau::c[static_cast<std::size_t>(s)] * h;
    ++stats.rhs_evaluations;
    status = system.rhs(ts, target, k(s));
    if (status != Status::ok) {
      t_fail = ts;
      return false;
    }
    return true;
  }

  // Row `row` of the tableau: a's, or b for row = stages.
  template <int row>
  static constexpr const std::array<double, Tableau::stages>& weights() {
    if constexpr (row < Tableau::stages) return Tableau::a[static_cast<std::size_t>(row)];
    else return Tableau::b;
  }

  // The stages whose weights in row `row` are not zero, at compile time: the sparse tableaus are
  // full of zeros.
  template <int row>
  static constexpr auto nonzero_weights() {
    constexpr const std::array<double, Tableau::stages>& w = weights<row>();
    std::array<int, Tableau::stages> stages{};
    int count = 0;
    for (int j = 0; j < row && j < Tableau::stages; ++j)
      if (w[static_cast<std::size_t>(j)] != 0.0) stages[static_cast<std::size_t>(count++)] = j;
    return std::pair{stages, count};
  }

  // target = y + h sum_j w_j k_j over row `row`'s nonzero weights, for the first `count` states.
  // Each entry's sum is formed in a register, in the order of j, and stored once: the same
  // additions as adding one stage after another to the whole target, without storing and loading
  // the target for every stage; with the weights known at compile time the sum over j is unrolled.
  // The states the right-hand side reads of a small system (2 n <= kFixedStates) are summed by a
  // loop whose length is known at compile time, unrolled whole (the same additions).
  template <int row>
  void combine(const double* y, double h, double* target, int count) const {
    constexpr auto nonzero = nonzero_weights<row>();
    constexpr int used = nonzero.second;
    constexpr const std::array<double, Tableau::stages>& w = weights<row>();
    std::array<double, used> coef;
    std::array<const double*, used> from;
    for (int m = 0; m < used; ++m) {
      const std::size_t j = static_cast<std::size_t>(nonzero.first[static_cast<std::size_t>(m)]);
      coef[static_cast<std::size_t>(m)] = h * w[j];
      from[static_cast<std::size_t>(m)] = k_[j].data();
    }
    int done = 0;
    if (count >= read_) {
      [&]<int... F>(std::integer_sequence<int, F...>) {
        (void)((read_ == 2 * (F + 1) ? (sum_entries<used, 2 * (F + 1)>(coef, from, y, target), done = read_, true)
                                     : false) ||
               ...);
      }(std::make_integer_sequence<int, kFixedStates / 2>{});
    }
    for (int i = done; i < count; ++i) target[i] = sum_entry<used>(coef, from, y, i);
  }

  // Entry i of the stage sum.
  template <int used>
  static double sum_entry(const std::array<double, used>& coef, const std::array<const double*, used>& from,
                          const double* y, int i) {
    double sum = y[i];
#pragma GCC unroll 16
    for (int m = 0; m < used; ++m) sum += coef[static_cast<std::size_t>(m)] * from[static_cast<std::size_t>(m)][i];
    return sum;
  }

  // Entries 0..count-1, count known at compile time.
  template <int used, int count>
  static void sum_entries(const std::array<double, used>& coef, const std::array<const double*, used>& from,
                          const double* y, double* target) {
#pragma GCC unroll 16
    for (int i = 0; i < count; ++i) target[i] = sum_entry<used>(coef, from, y, i);
  }

  static constexpr int kFixedStates = 12;

  int n_;
  int read_;
  std::vector<double> y_stage_;
  std::array<std::vector<double>, Tableau::stages> k_;
};

bool all_finite(const double* y, int n) {
  for (int i = 0; i < n; ++i)
    if (!std::isfinite(y[i])) return false;
  return true;
}

// The result of a run that ends at t_reached with `status` and `message`.
IntegrationResult ended(Status status, double t_reached, const IntegratorStats& stats, std::string message = {}) {
  IntegrationResult result;
  result.status = status;
  result.t_reached = t_reached;
  result.stats = stats;
  result.message = std::move(message);
  return result;
}

IntegrationResult rhs_failure(std::string_view method, Status status, double t_fail,
                              double t_reached, const IntegratorStats& stats) {
  return ended(status, t_reached, stats,
               fmt::format("{}: the right-hand side failed at t = {}: {}", method, t_fail, describe(status)));
}

IntegrationResult step_end_failure(std::string_view method, Status status, double t, const IntegratorStats& stats) {
  return ended(status, t, stats, fmt::format("{}: after the step to t = {}: {}", method, t, describe(status)));
}

IntegrationResult budget_exhausted(std::string_view method, long max_steps, double t,
                                   const IntegratorStats& stats) {
  return ended(Status::too_many_steps, t, stats,
               fmt::format("{}: the budget of {} steps (accepted + rejected) was used up at t = {}; raise max_steps "
                           "or loosen the tolerances",
                           method, max_steps, t));
}

// Steps that no longer advance: every kStallSteps steps (accepted + rejected) the pace of the
// last ones is projected to the end; a run that at that pace would need more than kStallFactor
// times the steps its budget has left ends there. A solution running into a singularity it cannot
// pass (a square root of a quantity that falls to 0, a surface that ends) shrinks its steps
// without limit but slowly enough to grind through the budget for many minutes before saying so.
constexpr long kStallSteps = 100000;
constexpr double kStallFactor = 10.0;

IntegrationResult stalled(std::string_view method, double t, double advanced, double needed, long max_steps,
                          const IntegratorStats& stats) {
  return ended(
      Status::too_many_steps, t, stats,
      fmt::format(
          "{}: the integration stalls at t = {}: its last {} steps advanced t by {:.3g}, a pace that needs about "
          "{:.3g} steps to the end, more than {} times what is left of the budget of {}; the solution is probably "
          "singular there (a square root or a logarithm of a quantity that reaches 0, a surface or a constraint that "
          "ends, a denominator that vanishes), or too stiff for an explicit integrator (try cvode-bdf): check the "
          "model at that state, or raise max_steps to go on",
          method, t, kStallSteps, advanced, needed, kStallFactor, max_steps));
}

IntegrationResult stopped_at(double t, const IntegratorStats& stats) { return ended(Status::stopped, t, stats); }

// RMS norm of v / (atol + rtol |w|), the weights of Hairer's initial step heuristic.
double weighted_rms(const double* v, const double* w, int n, double rtol, double atol) {
  double sum = 0.0;
  for (int i = 0; i < n; ++i) {
    const double r = v[i] / (atol + rtol * std::abs(w[i]));
    sum += r * r;
  }
  return std::sqrt(sum / n);
}

// Hairer-Norsett-Wanner I, II.4 "Starting step size": an explicit Euler step of size h0 measures
// the second derivative, and h makes the local error of a method of order p about 0.01.
// Uses one rhs evaluation; scratch and f1 are n-vectors it may overwrite.
Status initial_step(OdeSystem& system, const IntegratorOptions& options, int order, double t0,
                    const double* y0, const double* f0, double hmax, double* scratch, double* f1,
                    IntegratorStats& stats, double& h) {
  const int n = system.size(), weighed = system.error_size();
  const double d0 = weighted_rms(y0, y0, weighed, options.rtol, options.atol);
  const double d1 = weighted_rms(f0, y0, weighed, options.rtol, options.atol);
  double h0 = (d0 < 1e-5 || d1 < 1e-5) ? 1e-6 : 0.01 * d0 / d1;
  h0 = std::min(h0, hmax);
  for (int i = 0; i < n; ++i) scratch[i] = y0[i] + h0 * f0[i];
  ++stats.rhs_evaluations;
  const Status status = system.rhs(t0 + h0, scratch, f1);
  if (status != Status::ok) return status;
  for (int i = 0; i < n; ++i) scratch[i] = f1[i] - f0[i];
  const double d2 = weighted_rms(scratch, y0, weighed, options.rtol, options.atol) / h0;
  const double dmax = std::max(d1, d2);
  const double h1 =
      dmax <= 1e-15 ? std::max(1e-6, h0 * 1e-3) : std::pow(0.01 / dmax, 1.0 / (order + 1));
  h = std::min({100.0 * h0, h1, hmax});
  return Status::ok;
}

// What the adaptive pairs differ in, besides their tableau: the error estimate, whether it needs
// the FSAL stage (dopri5's does, so that stage is evaluated before the error test; DOP853's does
// not, so rejected steps skip it) and the continuous extension.
template <class Tableau>
constexpr bool error_uses_last_stage = true;
template <>
constexpr bool error_uses_last_stage<rk::DormandPrince853> = false;

// Hairer's stiffness test (DOPRI5 and DOP853, "the problem seems to become stiff"): the last two
// stages of a step are both at t + h, so h |f(t + h, y1) - f(t + h, y_s)| / |y1 - y_s| estimates
// h |lambda| for the dominant eigenvalue of the Jacobian; near the method's stability bound the
// step size is held by stability, not by accuracy. Hairer counts the steps beyond the bound; the
// step-size controller keeps h |lambda| just inside it (about 0.83 of it for dopri5 and 0.95 for
// dop853 on y' = -1000 y), so a step within 20 % of the bound counts here (accuracy alone gives
// far smaller h |lambda| at any usual tolerance). 15 such steps with fewer than 6 others between
// them make a stiff stretch; its first step's t is reported (IntegratorStats::stiff_from).
struct StiffnessTest {
  int stiff = 0;  // stiff steps in the current stretch
  int calm = 0;   // other steps since the last stiff one
  double stretch_from = 0.0;
  bool pending = false;  // the accepted step's test waits for its FSAL stage

  template <class Tableau>
  void after_accepted_step(const Stepper<Tableau>& stepper, const double* y1, int n, double t, double h,
                           IntegratorStats& stats) {
    static_assert(Tableau::c[Tableau::stages - 2] == 1.0 && Tableau::c[Tableau::stages - 1] == 1.0,
                  "the test compares the two last stages, both at t + h");
    const double* ys = stepper.scratch_view();
    const double* fs = stepper.k(Tableau::stages - 2);
    const double* f1 = stepper.k(Tableau::stages - 1);
    double num = 0.0, den = 0.0;
    for (int i = 0; i < n; ++i) {
      num += (f1[i] - fs[i]) * (f1[i] - fs[i]);
      den += (y1[i] - ys[i]) * (y1[i] - ys[i]);
    }
    if (!(den > 0.0) || !std::isfinite(num)) return;
    if (h * std::sqrt(num / den) > 0.8 * Tableau::stability_bound) {
      ++stats.stiff_steps;
      calm = 0;
      if (stiff++ == 0) stretch_from = t;
      if (stiff == 15 && std::isnan(stats.stiff_from)) stats.stiff_from = stretch_from;
    } else if (++calm == 6) {
      stiff = 0;
    }
  }
};

// The weighted RMS norm of the error estimate of the step (t, y) -> (t + h, y1), weights
// atol + rtol max(|y|, |y1|); the step is accepted when it is at most 1. Dormand-Prince 5(4):
// the difference from the embedded 4th-order solution, O(h^5).
double step_error(const Stepper<rk::DormandPrince54>& stepper, int n, const double* y,
                  const double* y1, double h, const IntegratorOptions& options) {
  using Tableau = rk::DormandPrince54;
  double sum = 0.0;
  for (int i = 0; i < n; ++i) {
    double e = 0.0;
    for (int j = 0; j < Tableau::stages; ++j)
      e += Tableau::e[static_cast<std::size_t>(j)] * stepper.k(j)[i];
    const double sk = options.atol + options.rtol * std::max(std::abs(y[i]), std::abs(y1[i]));
    const double r = h * e / sk;
    sum += r * r;
  }
  return std::sqrt(sum / n);
}

// Weights b - bhh of the 3rd-order error estimate of DOP853.
constexpr std::array<double, rk::DormandPrince853::stages> dop853_e3 = [] {
  std::array<double, rk::DormandPrince853::stages> e3{};
  for (std::size_t j = 0; j < e3.size(); ++j)
    e3[j] = rk::DormandPrince853::b[j] - rk::DormandPrince853::bhh[j];
  return e3;
}();

// Hairer's DOP853 estimate: with E5 and E3 the weighted sums of squares of the 5th- and
// 3rd-order estimates (each without its factor h), err = h E5 / sqrt(n (E5 + 0.01 E3)). E5 is
// O(h^10) and E3 O(h^6), so err is O(h^8) where the asymptotics hold, while the 3rd-order term
// keeps the estimate from vanishing by accident in large steps (Hairer-Norsett-Wanner I, II.10).
double step_error(const Stepper<rk::DormandPrince853>& stepper, int n, const double* y,
                  const double* y1, double h, const IntegratorOptions& options) {
  using Tableau = rk::DormandPrince853;
  double err5 = 0.0;
  double err3 = 0.0;
  for (int i = 0; i < n; ++i) {
    double e5 = 0.0;
    double e3 = 0.0;
    // The last stage (f(t + h, y1), not evaluated yet) has weight 0 in both.
    for (int j = 0; j + 1 < Tableau::stages; ++j) {
      const double kj = stepper.k(j)[i];
      e5 += Tableau::e5[static_cast<std::size_t>(j)] * kj;
      e3 += dop853_e3[static_cast<std::size_t>(j)] * kj;
    }
    const double sk = options.atol + options.rtol * std::max(std::abs(y[i]), std::abs(y1[i]));
    err5 += (e5 / sk) * (e5 / sk);
    err3 += (e3 / sk) * (e3 / sk);
  }
  double denominator = err5 + 0.01 * err3;
  if (denominator <= 0.0) denominator = 1.0;
  return std::abs(h) * err5 / std::sqrt(n * denominator);
}

// y(t + theta h) inside an accepted step (t, y) -> (t + h, y1), from the step's stages (the last
// one f(t + h, y1)). prepare() readies one step, evaluate() may then be called for any theta in
// [0, 1]; continuous across steps, as the ends are y and y1.
template <class Tableau>
class ContinuousExtension;

// Hairer's CONTD5, order 4: no extra stages.
template <>
class ContinuousExtension<rk::DormandPrince54> {
 public:
  using Tableau = rk::DormandPrince54;
  ContinuousExtension(int n, int /*read*/) : n_(n) {}

  Status prepare(OdeSystem& /*system*/, const Stepper<Tableau>& stepper, double /*t*/,
                 const double* y, const double* y1, double h, IntegratorStats& /*stats*/,
                 double& /*t_fail*/) {
    stepper_ = &stepper;
    y_ = y;
    y1_ = y1;
    h_ = h;
    return Status::ok;
  }

  void evaluate(double theta, double* out) const {
    const double theta1 = 1.0 - theta;
    const double* k_first = stepper_->k(0);
    const double* k_last = stepper_->k(Tableau::stages - 1);
    for (int i = 0; i < n_; ++i) {
      const double ydiff = y1_[i] - y_[i];
      const double bspl = h_ * k_first[i] - ydiff;
      const double hermite = ydiff - h_ * k_last[i] - bspl;
      double dk = 0.0;
      for (int j = 0; j < Tableau::stages; ++j)
        dk += Tableau::d[static_cast<std::size_t>(j)] * stepper_->k(j)[i];
      out[i] = y_[i] + theta * (ydiff + theta1 * (bspl + theta * (hermite + theta1 * h_ * dk)));
    }
  }

 private:
  int n_;
  const Stepper<Tableau>* stepper_ = nullptr;
  const double* y_ = nullptr;
  const double* y1_ = nullptr;
  double h_ = 0.0;
};

// Hairer's CONTD8, order 7: three more stages (3 rhs evaluations) give the coefficients of
//   y + theta (r1 + s (r2 + theta (r3 + s (r4 + theta (r5 + s (r6 + theta r7)))))),  s = 1 - theta,
// r1..r3 from y, y1, f(t, y), f(t + h, y1) (the cubic Hermite part), r4..r7 = h sum_j d_j k_j.
template <>
class ContinuousExtension<rk::DormandPrince853> {
 public:
  using Tableau = rk::DormandPrince853;
  // The extra stages' states hold the `read` leading states, as the Stepper's do.
  ContinuousExtension(int n, int read) : n_(n), read_(read), y_stage_(static_cast<std::size_t>(n)) {
    for (std::vector<double>& k : extra_) k.assign(static_cast<std::size_t>(n), 0.0);
    for (std::vector<double>& r : r_) r.assign(static_cast<std::size_t>(n), 0.0);
  }

  Status prepare(OdeSystem& system, const Stepper<Tableau>& stepper, double t, const double* y,
                 const double* y1, double h, IntegratorStats& stats, double& t_fail) {
    const auto stage = [&](int j) -> const double* {
      return j < Tableau::stages ? stepper.k(j)
                                 : extra_[static_cast<std::size_t>(j - Tableau::stages)].data();
    };
    for (int s = 0; s < Tableau::extra_stages; ++s) {
      const std::array<double, Tableau::all_stages>& w =
          Tableau::a_extra[static_cast<std::size_t>(s)];
      std::copy(y, y + read_, y_stage_.begin());
      for (int j = 0; j < Tableau::stages + s; ++j) {
        if (w[static_cast<std::size_t>(j)] == 0.0) continue;
        const double coef = h * w[static_cast<std::size_t>(j)];
        const double* kj = stage(j);
        for (int i = 0; i < read_; ++i) y_stage_[static_cast<std::size_t>(i)] += coef * kj[i];
      }
      const double ts = t + Tableau::c_extra[static_cast<std::size_t>(s)] * h;
      ++stats.rhs_evaluations;
      const Status status =
          system.rhs(ts, y_stage_.data(), extra_[static_cast<std::size_t>(s)].data());
      if (status != Status::ok) {
        t_fail = ts;
        return status;
      }
    }
    const double* k_first = stepper.k(0);
    const double* k_last = stepper.k(Tableau::stages - 1);
    for (int i = 0; i < n_; ++i) {
      const std::size_t ui = static_cast<std::size_t>(i);
      const double ydiff = y1[i] - y[i];
      const double bspl = h * k_first[i] - ydiff;
      r_[0][ui] = y[i];
      r_[1][ui] = ydiff;
      r_[2][ui] = bspl;
      r_[3][ui] = ydiff - h * k_last[i] - bspl;
    }
    for (std::size_t m = 0; m < Tableau::d.size(); ++m) {
      std::vector<double>& r = r_[4 + m];
      std::fill(r.begin(), r.end(), 0.0);
      for (int j = 0; j < Tableau::all_stages; ++j) {
        const double w = Tableau::d[m][static_cast<std::size_t>(j)];
        if (w == 0.0) continue;
        const double* kj = stage(j);
        for (int i = 0; i < n_; ++i) r[static_cast<std::size_t>(i)] += w * kj[i];
      }
      for (double& x : r) x *= h;
    }
    return Status::ok;
  }

  void evaluate(double theta, double* out) const {
    const double s = 1.0 - theta;
    for (std::size_t i = 0; i < static_cast<std::size_t>(n_); ++i)
      out[i] =
          r_[0][i] +
          theta *
              (r_[1][i] +
               s * (r_[2][i] +
                    theta * (r_[3][i] +
                             s * (r_[4][i] +
                                  theta * (r_[5][i] + s * (r_[6][i] + theta * r_[7][i]))))));
  }

 private:
  int n_;
  int read_;
  std::vector<double> y_stage_;
  std::array<std::vector<double>, Tableau::extra_stages> extra_;
  std::array<std::vector<double>, 8> r_;  // r_0 = y, then r1..r7 above
};

// The state of one run of the adaptive driver below, shared by its parts; allocated once per run.
template <class Tableau>
struct AdaptiveRun {
  AdaptiveRun(std::string_view method, OdeSystem& system, const IntegratorOptions& options, const double* y0,
              std::span<const double> output_times, const OutputFn& output, EventFunctions* events)
      : method(method), system(system), options(options), output_times(output_times), output(output), events(events),
        n(system.size()), y(y0, y0 + n), y1(static_cast<std::size_t>(n)), y_out(static_cast<std::size_t>(n)),
        stepper(n, system.error_size()), extension(n, system.error_size()) {}

  std::string_view method;
  OdeSystem& system;
  const IntegratorOptions& options;
  std::span<const double> output_times;
  const OutputFn& output;
  EventFunctions* events;
  int n;
  std::vector<double> y;      // the state at the step's start
  std::vector<double> y1;     // the state at the step's end
  std::vector<double> y_out;  // a state interpolated inside the step
  Stepper<Tableau> stepper;
  ContinuousExtension<Tableau> extension;
  IntegratorStats stats;
  std::optional<EventTracker> tracker;  // with events only
  std::vector<EventTracker::Crossing> crossings;
  std::size_t next = 0;  // the first output time not yet written
  StiffnessTest stiffness;
};

// The stiffness test of the accepted step (t, h) once its FSAL stage at y1 is ready, once a step.
template <class Tableau>
void test_stiffness(AdaptiveRun<Tableau>& run, double t, double h, bool last_stage_ready) {
  if (!run.stiffness.pending || !last_stage_ready) return;
  run.stiffness.pending = false;
  run.stiffness.after_accepted_step(run.stepper, run.y1.data(), run.system.error_size(), t, h, run.stats);
}

// Before the first step from t: the event tracker started, f(t, y) in the first stage and the
// first step size h (the given one, or Hairer's estimate). A failure is the run's result.
template <class Tableau>
std::optional<IntegrationResult> start_adaptive(AdaptiveRun<Tableau>& run, double t, double hmax, double& h) {
  if (run.events != nullptr && run.events->count() > 0) {
    run.tracker.emplace(*run.events, run.n, run.options.rtol, run.options.atol);
    run.crossings.reserve(static_cast<std::size_t>(run.events->count()));
    const Status status = run.tracker->restart(t, run.y.data());
    if (status != Status::ok) return rhs_failure(run.method, status, t, t, run.stats);
  }
  ++run.stats.rhs_evaluations;
  Status status = run.system.rhs(t, run.y.data(), run.stepper.k(0));
  if (status != Status::ok) return rhs_failure(run.method, status, t, t, run.stats);
  if (run.options.step > 0.0) {
    h = std::min(run.options.step, hmax);
  } else {
    status = initial_step(run.system, run.options, Tableau::order, t, run.y.data(), run.stepper.k(0), hmax,
                          run.stepper.scratch(), run.stepper.k(1), run.stats, h);
    if (status != Status::ok) return rhs_failure(run.method, status, t, t, run.stats);
  }
  return std::nullopt;
}

// A step size too small to advance t: underflow, or no finite state at any step size.
IntegrationResult step_size_failure(std::string_view method, bool error_finite, double t, double h,
                                    const IntegratorStats& stats) {
  IntegrationResult failure;
  failure.status = error_finite ? Status::step_size_underflow : Status::non_finite;
  failure.t_reached = t;
  failure.stats = stats;
  failure.message = error_finite ? fmt::format("{}: step size underflow at t = {} (h = {}): the solution may be "
                                               "singular there, or the tolerances too tight",
                                               method, t, h)
                                 : fmt::format("{}: non-finite states at t = {} for every step size down to h = {}",
                                               method, t, h);
  return failure;
}

// The outputs of the step from t (size h) before t_limit, from its continuous extension.
template <class Tableau>
std::optional<IntegrationResult> write_outputs_before(AdaptiveRun<Tableau>& run, double t, double h, double t_limit) {
  for (; run.next < run.output_times.size() && run.output_times[run.next] < t_limit; ++run.next) {
    const double t_out = run.output_times[run.next];
    run.extension.evaluate((t_out - t) / h, run.y_out.data());
    if (run.output(t_out, run.y_out.data()) == Status::stopped) return stopped_at(t_out, run.stats);
  }
  return std::nullopt;
}

// Inside an accepted step from t to t_new (size h) with outputs or event crossings in it: the
// continuous extension prepared, the crossings located on it and handed on in order, each after
// the outputs before it, then the outputs before t_new. Outputs inside the step follow the step's
// own solution; after_step acts at the step end, so an output there sees the state it leaves.
template <class Tableau>
std::optional<IntegrationResult> inside_step(AdaptiveRun<Tableau>& run, double t, double h, double t_new,
                                             bool crossed, bool& last_stage_ready) {
  if (!last_stage_ready) {
    ++run.stats.rhs_evaluations;
    const Status status = run.system.rhs(t_new, run.y1.data(), run.stepper.k(Tableau::stages - 1));
    if (status != Status::ok) return rhs_failure(run.method, status, t_new, t, run.stats);
    last_stage_ready = true;
  }
  double t_fail = t;
  Status status = run.extension.prepare(run.system, run.stepper, t, run.y.data(), run.y1.data(), h, run.stats, t_fail);
  if (status != Status::ok) return rhs_failure(run.method, status, t_fail, t, run.stats);
  if (crossed) {
    status = run.tracker->locate(
        t, h, [&](double theta, double* out) { run.extension.evaluate(theta, out); }, run.crossings);
    if (status != Status::ok) return rhs_failure(run.method, status, t_new, t, run.stats);
    for (const EventTracker::Crossing& crossing : run.crossings) {
      if (auto stop = write_outputs_before(run, t, h, crossing.t)) return stop;
      if (crossing.theta >= 1.0) std::copy(run.y1.begin(), run.y1.end(), run.y_out.begin());
      else run.extension.evaluate(crossing.theta, run.y_out.data());
      const Status event_status = run.events->on_event(crossing.index, crossing.t, run.y_out.data());
      if (event_status == Status::stopped) return stopped_at(crossing.t, run.stats);
      if (event_status != Status::ok) return step_end_failure(run.method, event_status, crossing.t, run.stats);
    }
  }
  return write_outputs_before(run, t, h, t_new);
}

// At the end t_new of an accepted step: after_step on the end state (the events restarted
// if it changed it), the FSAL stage of the state the next step starts from, the output at t_new.
template <class Tableau>
std::optional<IntegrationResult> end_step(AdaptiveRun<Tableau>& run, double t, double h, double t_new,
                                          bool last_stage_ready) {
  if (run.tracker) run.tracker->advance();
  const StepEnd end = run.system.after_step(t_new, run.y1.data());
  if (end.status != Status::ok) return step_end_failure(run.method, end.status, t_new, run.stats);
  if (run.tracker && end.changed) {
    const Status status = run.tracker->restart(t_new, run.y1.data());
    if (status != Status::ok) return rhs_failure(run.method, status, t_new, t_new, run.stats);
  }
  // The FSAL stage belongs to the state before a change; evaluated here, it is that of the
  // state the next step starts from.
  if (end.changed || !last_stage_ready) {
    ++run.stats.rhs_evaluations;
    const Status status = run.system.rhs(t_new, run.y1.data(), run.stepper.k(Tableau::stages - 1));
    if (status != Status::ok) return rhs_failure(run.method, status, t_new, t_new, run.stats);
  }
  // A changed state's FSAL stage is not the step's: the test is left out for that step.
  test_stiffness(run, t, h, !end.changed);
  if (run.next < run.output_times.size() && run.output_times[run.next] == t_new) {
    if (run.output(t_new, run.y1.data()) == Status::stopped) return stopped_at(t_new, run.stats);
    ++run.next;
  }
  return std::nullopt;
}

// The driver of the adaptive pairs: Hairer's step-size control with the tableau's constants,
// outputs inside a step from the continuous extension (never shortening a step), only the last
// step shortened to end on the last output time, so the rhs is never evaluated beyond it.
template <class Tableau>
IntegrationResult integrate_adaptive(std::string_view method, OdeSystem& system,
                                     const IntegratorOptions& options, double t0, const double* y0,
                                     std::span<const double> output_times,
                                     const OutputFn& output, EventFunctions* events) {
  constexpr double beta = Tableau::beta;
  constexpr double expo1 = Tableau::exponent;
  constexpr double fac_min = Tableau::fac_min;
  constexpr double fac_max = Tableau::fac_max;
  constexpr double safety = Tableau::safety;
  static_assert(Tableau::fsal, "the adaptive driver reuses the last stage as the next first one");

  IntegrationResult result;
  result.t_reached = t0;
  if (output_times.empty()) return result;

  AdaptiveRun<Tableau> run(method, system, options, y0, output_times, output, events);
  if (output_times.front() == t0) {
    if (output(t0, run.y.data()) == Status::stopped) return stopped_at(t0, run.stats);
    ++run.next;
  }
  if (run.next == output_times.size()) return result;
  const double t_end = output_times.back();
  const double hmax = options.max_step > 0.0 ? std::min(options.max_step, t_end - t0) : t_end - t0;

  double t = t0;
  double h = 0.0;
  if (auto failure = start_adaptive(run, t, hmax, h)) return *std::move(failure);

  double err_old = 1e-4;  // Hairer's FACOLD: the previous accepted error, floored
  // err_old^beta, the PI controller's memory, computed once when err_old changes (beta = 0 for
  // DOP853, where it is 1).
  double err_old_beta = beta == 0.0 ? 1.0 : std::pow(err_old, beta);
  bool last_rejected = false;
  bool last_error_finite = true;
  double stall_t = t;  // t at the last stall check
  long stall_next = run.stats.steps + run.stats.rejected_steps + kStallSteps;
  for (;;) {
    if (run.stats.steps + run.stats.rejected_steps >= options.max_steps)
      return budget_exhausted(method, options.max_steps, t, run.stats);
    if (const long used = run.stats.steps + run.stats.rejected_steps; used >= stall_next) {
      const double needed = (t_end - t) / (t - stall_t) * static_cast<double>(kStallSteps);
      if (!(needed <= kStallFactor * static_cast<double>(options.max_steps - used)))
        return stalled(method, t, t - stall_t, needed, options.max_steps, run.stats);
      stall_t = t;
      stall_next = used + kStallSteps;
    }
    if (!(h >= 16.0 * eps * std::max(std::abs(t), std::numeric_limits<double>::min())))
      return step_size_failure(method, last_error_finite, t, h, run.stats);
    // Reaching t_end within 1% of a step is done in that step; stretching the last step a little
    // is cheaper than a sliver of a step after it.
    const bool last = t + 1.01 * h >= t_end;
    if (last) h = t_end - t;

    double t_fail = t;
    Status status = run.stepper.step(system, t, run.y.data(), h, run.y1.data(), run.stats, t_fail,
                                     error_uses_last_stage<Tableau>);
    // A trial stage where the model is not finite (a step reaching past where the motion is
    // defined, sqrt(1 - t) at t > 1) is rejected as an overflowing step is: the run fails only
    // when no step size down to the floor gets past, at the place it cannot pass.
    if (status != Status::ok && status != Status::non_finite) return rhs_failure(method, status, t_fail, t, run.stats);
    const double err = status == Status::ok
                           ? step_error(run.stepper, system.error_size(), run.y.data(), run.y1.data(), h, options)
                           : std::numeric_limits<double>::quiet_NaN();
    last_error_finite = std::isfinite(err) && all_finite(run.y1.data(), run.n);

    if (!last_error_finite) {
      // An overflow in a too-long step, or a stage past the model's domain: retreat as far as
      // the controller ever does.
      ++run.stats.rejected_steps;
      last_rejected = true;
      h *= fac_min;
      continue;
    }
    const double fac11 = std::pow(err, expo1);
    if (err > 1.0) {
      ++run.stats.rejected_steps;
      last_rejected = true;
      h /= std::min(1.0 / fac_min, fac11 / safety);
      continue;
    }

    const double fac = std::clamp(fac11 / err_old_beta / safety, 1.0 / fac_max, 1.0 / fac_min);
    double h_new = h / fac;
    err_old = std::max(err, 1e-4);
    if constexpr (beta != 0.0) err_old_beta = std::pow(err_old, beta);
    // Right after a rejection, growing the step again invites another one.
    if (last_rejected) h_new = std::min(h_new, h);
    last_rejected = false;
    ++run.stats.steps;

    const double t_new = last ? t_end : t + h;
    bool last_stage_ready = error_uses_last_stage<Tableau>;
    // The stiffness test needs the FSAL stage at y1: dopri5's error estimate has it already; DOP853
    // evaluates it for an output inside the step or in end_step, and the test waits for it there.
    run.stiffness.pending = true;
    test_stiffness(run, t, h, last_stage_ready);
    // Events: a change of sign of some g between the step's ends is located on the step's
    // continuous extension (events.hpp), before after_step moves the end state.
    bool crossed = false;
    if (run.tracker) {
      status = run.tracker->check(t_new, run.y1.data(), crossed);
      if (status != Status::ok) return rhs_failure(method, status, t_new, t, run.stats);
    }
    if (crossed || (run.next < output_times.size() && output_times[run.next] < t_new)) {
      if (auto stop = inside_step(run, t, h, t_new, crossed, last_stage_ready)) return *std::move(stop);
      test_stiffness(run, t, h, last_stage_ready);
    }
    if (auto stop = end_step(run, t, h, t_new, last_stage_ready)) return *std::move(stop);

    std::swap(run.y, run.y1);
    run.stepper.reuse_last_stage();
    t = t_new;
    if (last) break;
    h = std::min(h_new, hmax);
  }
  result.t_reached = t;
  result.stats = run.stats;
  return result;
}

}  // namespace

IntegrationResult integrate_rk4(OdeSystem& system, const IntegratorOptions& options, double t0,
                                const double* y0, std::span<const double> output_times,
                                const OutputFn& output) {
  constexpr std::string_view method = "rk4";
  const int n = system.size();
  IntegrationResult result;
  result.t_reached = t0;
  if (output_times.empty()) return result;

  std::vector<double> y(y0, y0 + n);
  std::vector<double> y1(static_cast<std::size_t>(n));
  Stepper<rk::ClassicRk4> stepper(n, system.error_size());
  IntegratorStats stats;

  std::size_t next = 0;
  if (output_times.front() == t0) {
    if (output(t0, y.data()) == Status::stopped) return stopped_at(t0, stats);
    ++next;
  }
  const std::size_t intervals = output_times.size() - next;
  if (intervals == 0) return result;
  const double h_nominal =
      options.step > 0.0 ? options.step
                         : (output_times.back() - t0) / static_cast<double>(intervals) / 10.0;

  double t = t0;
  for (; next < output_times.size(); ++next) {
    const double t_start = t;
    const double t_out = output_times[next];
    // The slack keeps an interval that is a whole number of steps up to round-off from gaining
    // one more step.
    const double ratio = std::min((t_out - t_start) / h_nominal * (1.0 - 1e-12), 1e18);
    const long steps = std::max(1L, static_cast<long>(std::ceil(ratio)));
    const double h = (t_out - t_start) / static_cast<double>(steps);
    for (long j = 1; j <= steps; ++j) {
      if (stats.steps >= options.max_steps)
        return budget_exhausted(method, options.max_steps, t, stats);
      ++stats.rhs_evaluations;
      Status status = system.rhs(t, y.data(), stepper.k(0));
      double t_fail = t;
      if (status == Status::ok)
        status = stepper.step(system, t, y.data(), h, y1.data(), stats, t_fail);
      if (status != Status::ok) return rhs_failure(method, status, t_fail, t, stats);
      // Multiplying rather than accumulating keeps round-off from drifting the step ends; the
      // last one is the output time itself.
      const double t_new = j == steps ? t_out : t_start + static_cast<double>(j) * h;
      if (!all_finite(y1.data(), n)) {
        IntegrationResult failure = rhs_failure(method, Status::non_finite, t_new, t, stats);
        failure.message = fmt::format(
            "{}: the step from t = {} to t = {} gave a non-finite state; reduce the step", method,
            t, t_new);
        return failure;
      }
      std::swap(y, y1);
      ++stats.steps;
      t = t_new;
      // Nothing is carried from one rk4 step to the next, so a changed state needs no restart.
      const StepEnd end = system.after_step(t, y.data());
      if (end.status != Status::ok) return step_end_failure(method, end.status, t, stats);
    }
    if (output(t, y.data()) == Status::stopped) return stopped_at(t, stats);
  }
  result.t_reached = t;
  result.stats = stats;
  return result;
}


IntegrationResult integrate_dopri5(OdeSystem& system, const IntegratorOptions& options, double t0,
                                   const double* y0, std::span<const double> output_times,
                                   const OutputFn& output, EventFunctions* events) {
  return integrate_adaptive<rk::DormandPrince54>("dopri5", system, options, t0, y0, output_times,
                                                 output, events);
}

IntegrationResult integrate_dop853(OdeSystem& system, const IntegratorOptions& options, double t0,
                                   const double* y0, std::span<const double> output_times,
                                   const OutputFn& output, EventFunctions* events) {
  return integrate_adaptive<rk::DormandPrince853>("dop853", system, options, t0, y0, output_times,
                                                  output, events);
}

}  // namespace nhdyn
