#include "nhdyn/optimize/replay.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <vector>

#include <Eigen/Dense>

#include "nhdyn/integrators/ode.hpp"

namespace nhdyn {
namespace {

// y = [q; q'] under the controls of one interval [t_a, t_b], interpolated through the values of
// its points (two: linear; three: quadratic through the ends and the middle).
class ControlledSystem final : public OdeSystem {
 public:
  explicit ControlledSystem(const OptimalControlProblem& problem)
      : problem_(problem), n_(problem.n()), m_(problem.m()), s_(problem.model.s()) {
    scratch_.assign(problem.model.evaluator->scratch_size(), 0.0);
    A_.resize(n_, n_);
    Q_.resize(n_);
    G_.resize(n_);
    b_.resize(s_, n_);
    b0_.resize(s_);
    force_registers_.assign(static_cast<std::size_t>(problem.force.registers()), 0.0);
    layout_q_.assign(static_cast<std::size_t>(n_ + m_), 0.0);
    layout_v_.assign(static_cast<std::size_t>(n_ + m_), 0.0);
    force_.assign(static_cast<std::size_t>(n_), 0.0);
  }
  void set_interval(double ta, double tb, std::vector<std::vector<double>> values) {
    ta_ = ta;
    tb_ = tb;
    values_ = std::move(values);
  }
  int size() const override { return 2 * n_; }
  Status rhs(double t, const double* y, double* ydot) override {
    const double s = (t - ta_) / (tb_ - ta_);
    for (int j = 0; j < m_; ++j) {
      const std::size_t jj = static_cast<std::size_t>(j);
      const double u = values_.size() == 2
                           ? (1 - s) * values_[0][jj] + s * values_[1][jj]
                           : values_[0][jj] * (1 - s) * (1 - 2 * s) + 4 * values_[1][jj] * s * (1 - s) +
                                 values_[2][jj] * s * (2 * s - 1);
      layout_q_[static_cast<std::size_t>(n_ + j)] = u;
    }
    std::copy(y, y + n_, layout_q_.begin());
    std::copy(y + n_, y + 2 * n_, layout_v_.begin());
    problem_.force.run(t, layout_q_.data(), layout_v_.data(), force_registers_.data(), force_.data());
    problem_.model.evaluator->terms(t, y, y + n_, scratch_.data(), TermsOut{A_.data(), Q_.data(), G_.data(), b_.data(), b0_.data()});
    const Eigen::Map<const Eigen::VectorXd> F(force_.data(), n_);
    Eigen::MatrixXd M(n_, n_);
    Eigen::VectorXd rhs(n_);
    const int k = n_ - s_;
    if (s_ > 0) {
      const Eigen::HouseholderQR<Eigen::MatrixXd> qr(b_.transpose());
      const Eigen::MatrixXd basis = qr.householderQ();
      const Eigen::MatrixXd D = basis.rightCols(k).transpose();
      M.topRows(k) = D * A_;
      M.bottomRows(s_) = b_;
      rhs.head(k) = D * (Q_ + G_ + F);
      rhs.tail(s_) = -b0_;
    } else {
      M = A_;
      rhs = Q_ + G_ + F;
    }
    const Eigen::VectorXd a = M.partialPivLu().solve(rhs);
    std::copy(y + n_, y + 2 * n_, ydot);
    for (int i = 0; i < n_; ++i) {
      ydot[n_ + i] = a(i);
      if (!std::isfinite(a(i))) return Status::non_finite;
    }
    return Status::ok;
  }

 private:
  const OptimalControlProblem& problem_;
  int n_, m_, s_;
  double ta_ = 0.0, tb_ = 1.0;
  std::vector<std::vector<double>> values_;
  std::vector<double> scratch_, force_registers_, layout_q_, layout_v_, force_;
  Eigen::MatrixXd A_, b_;
  Eigen::VectorXd Q_, G_, b0_;
};

}  // namespace

ReplayResult calc_replay(const OptimalControlProblem& problem, const std::vector<double>& times,
                         const std::vector<double>& q, const std::vector<double>& v, const std::vector<double>& u) {
  const int n = problem.n(), m = problem.m();
  const int points = static_cast<int>(times.size());
  const int stride = problem.method == CollocationMethod::hermite_simpson ? 2 : 1;
  ControlledSystem system(problem);
  IntegratorOptions options;
  options.kind = IntegratorKind::dop853;
  options.rtol = 1e-11;
  options.atol = 1e-12;
  std::vector<double> y(static_cast<std::size_t>(2 * n));
  std::copy(q.begin(), q.begin() + n, y.begin());
  std::copy(v.begin(), v.begin() + n, y.begin() + n);
  ReplayResult result;
  result.local.assign(static_cast<std::size_t>(n), 0.0);
  result.local_ok = true;
  bool open_loop_stopped = false;
  std::vector<double> start(y.size()), local_end(y.size());
  for (int p = 0; p + stride < points; p += stride) {
    std::vector<std::vector<double>> values;
    for (int k = 0; k <= stride; ++k)
      values.emplace_back(u.begin() + static_cast<std::ptrdiff_t>((p + k) * m),
                          u.begin() + static_cast<std::ptrdiff_t>((p + k + 1) * m));
    const double ta = times[static_cast<std::size_t>(p)], tb = times[static_cast<std::size_t>(p + stride)];
    system.set_interval(ta, tb, std::move(values));
    const double output[] = {tb};
    // From the optimum's own state at ta: the interval's error alone.
    std::copy(q.begin() + static_cast<std::ptrdiff_t>(p * n), q.begin() + static_cast<std::ptrdiff_t>((p + 1) * n),
              start.begin());
    std::copy(v.begin() + static_cast<std::ptrdiff_t>(p * n), v.begin() + static_cast<std::ptrdiff_t>((p + 1) * n),
              start.begin() + n);
    if (result.local_ok) {
      const IntegrationResult local = integrate(system, options, ta, start.data(), output, [&](double, const double* state) {
        std::copy(state, state + 2 * n, local_end.begin());
        return Status::ok;
      });
      if (local.status != Status::ok) {
        result.local_ok = false;
        result.local_message = fmt::format("the replay of [{:g}, {:g}] from the optimum's state at {:g} stopped at t = "
                                           "{:g}: {}",
                                           ta, tb, ta, local.t_reached, local.message);
      } else {
        for (int i = 0; i < n; ++i)
          result.local[static_cast<std::size_t>(i)] =
              std::max(result.local[static_cast<std::size_t>(i)],
                       std::abs(local_end[static_cast<std::size_t>(i)] - q[static_cast<std::size_t>((p + stride) * n + i)]));
      }
    }
    if (open_loop_stopped) continue;
    std::vector<double> end(y.size());
    const IntegrationResult run = integrate(system, options, ta, y.data(), output, [&](double, const double* state) {
      std::copy(state, state + 2 * n, end.begin());
      return Status::ok;
    });
    if (run.status != Status::ok) {
      result.message = fmt::format("the replay stopped at t = {:g}: {}", run.t_reached, run.message);
      open_loop_stopped = true;  // the intervals' own replays go on
      continue;
    }
    y = end;
    for (int i = 0; i < n; ++i)
      result.difference =
          std::max(result.difference, std::abs(y[static_cast<std::size_t>(i)] - q[static_cast<std::size_t>((p + stride) * n + i)]));
  }
  result.ok = !open_loop_stopped;
  if (result.ok) result.q_end.assign(y.begin(), y.begin() + n);
  return result;
}

}  // namespace nhdyn
