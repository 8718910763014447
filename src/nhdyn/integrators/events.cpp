#include "nhdyn/integrators/events.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>

namespace nhdyn {
namespace {

int sign_of(double x) { return x > 0.0 ? 1 : (x < 0.0 ? -1 : 0); }

// |g| at a located root above this fraction of its size at the step's ends: a jump, not a zero.
constexpr double kJumpFraction = 1e-3;

}  // namespace

bool is_jump(double g_root, double g_start, double g_end) {
  const double scale = std::max(std::abs(g_start), std::abs(g_end));
  return !(std::isfinite(g_root) && !(std::abs(g_root) > kJumpFraction * scale));
}

Status find_root(const std::function<Status(double x, double& fx)>& f, double a, double fa, double b,
                 double fb, double& root) {
  constexpr double eps = std::numeric_limits<double>::epsilon();
  if (fb == 0.0) {
    root = b;
    return Status::ok;
  }
  if (fa == 0.0) {
    root = a;
    return Status::ok;
  }
  const int after = sign_of(fb);
  double c = a, fc = fa;
  double d = b - a, e = d;
  // Each iteration at least halves the bracket every few steps; 400 is far beyond what the
  // resolution of a double in [0, 1] needs and only guards against a non-finite f.
  for (int iteration = 0; iteration < 400; ++iteration) {
    if ((fb > 0.0) == (fc > 0.0)) {
      c = a;
      fc = fa;
      d = e = b - a;
    }
    if (std::abs(fc) < std::abs(fb)) {
      a = b;
      b = c;
      c = a;
      fa = fb;
      fb = fc;
      fc = fa;
    }
    const double tol = 2.0 * eps * std::abs(b) + std::numeric_limits<double>::min();
    const double m = 0.5 * (c - b);
    if (std::abs(m) <= tol || fb == 0.0) break;
    if (std::abs(e) < tol || std::abs(fa) <= std::abs(fb)) {
      d = e = m;
    } else {
      // Inverse quadratic interpolation, or the secant when only two points are distinct.
      const double s = fb / fa;
      double p, q;
      if (a == c) {
        p = 2.0 * m * s;
        q = 1.0 - s;
      } else {
        const double qa = fa / fc, r = fb / fc;
        p = s * (2.0 * m * qa * (qa - r) - (b - a) * (r - 1.0));
        q = (qa - 1.0) * (r - 1.0) * (s - 1.0);
      }
      if (p > 0.0) q = -q;
      else p = -p;
      if (2.0 * p < std::min(3.0 * m * q - std::abs(tol * q), std::abs(e * q))) {
        e = d;
        d = p / q;
      } else {
        d = e = m;
      }
    }
    a = b;
    fa = fb;
    b += std::abs(d) > tol ? d : (m > 0.0 ? tol : -tol);
    const Status status = f(b, fb);
    if (status != Status::ok) return status;
    if (!std::isfinite(fb)) return Status::non_finite;
  }
  // b is the best estimate; report the end of the bracket on the far side of the crossing.
  root = (fb == 0.0 || sign_of(fb) == after) ? b : c;
  return Status::ok;
}

EventTracker::EventTracker(EventFunctions& events, int n, double rtol, double atol)
    : events_(events),
      rtol_(rtol),
      atol_(atol),
      m_(events.count()),
      sign_(static_cast<std::size_t>(m_), 0),
      g_end_(static_cast<std::size_t>(m_), 0.0),
      g_(static_cast<std::size_t>(m_), 0.0),
      y_(static_cast<std::size_t>(n), 0.0),
      g_start_(static_cast<std::size_t>(m_), 0.0) {
  crossed_.reserve(static_cast<std::size_t>(m_));
  dips_.reserve(static_cast<std::size_t>(m_));
}

Status EventTracker::restart(double t, const double* y) {
  const Status status = events_.evaluate(t, y, g_.data());
  if (status != Status::ok) return status;
  for (std::size_t i = 0; i < g_.size(); ++i) {
    const int s = sign_of(g_[i]);
    if (s != 0) sign_[i] = s;  // a zero keeps the side it was reached from
  }
  g_start_ = g_;
  return Status::ok;
}

Status EventTracker::check(double t1, const double* y1, bool& crossed) {
  crossed = false;
  crossed_.clear();
  const Status status = events_.evaluate(t1, y1, g_end_.data());
  if (status != Status::ok) return status;
  for (int i = 0; i < m_; ++i) {
    const std::size_t k = static_cast<std::size_t>(i);
    const int before = sign_[k];
    const int after = sign_of(g_end_[k]);
    if (before == 0 || after == before) continue;
    const CrossingDirection direction = events_.direction(i);
    const bool rising = before < 0;
    if (direction == CrossingDirection::rising && !rising) continue;
    if (direction == CrossingDirection::falling && rising) continue;
    crossed_.push_back(i);
  }
  collect_dips(false);
  crossed = !crossed_.empty() || !dips_.empty();
  return Status::ok;
}

Status EventTracker::check_dips(double t1, const double* y1, bool& dipped) {
  dipped = false;
  crossed_.clear();
  const Status status = events_.evaluate(t1, y1, g_end_.data());
  if (status != Status::ok) return status;
  collect_dips(true);
  dipped = !dips_.empty();
  return Status::ok;
}

bool EventTracker::any_may_dip() const {
  for (int i = 0; i < m_; ++i)
    if (events_.may_dip(i)) return true;
  return false;
}

void EventTracker::collect_dips(bool with_changes) {
  dips_.clear();
  for (int i = 0; i < m_; ++i) {
    const std::size_t k = static_cast<std::size_t>(i);
    const int before = sign_[k];
    if (before == 0 || !events_.may_dip(i)) continue;
    if (!with_changes && sign_of(g_end_[k]) != before) continue;
    const CrossingDirection direction = events_.direction(i);
    // A dip from the positive side crosses falling, from the negative side rising.
    if (direction == CrossingDirection::rising && before > 0) continue;
    if (direction == CrossingDirection::falling && before < 0) continue;
    dips_.push_back(i);
  }
}

Status EventTracker::value(int i, double t, double h, double theta, const Interpolant& interpolate, double& g) {
  interpolate(theta, y_.data());
  const Status status = events_.evaluate(t + theta * h, y_.data(), g_.data());
  g = g_[static_cast<std::size_t>(i)];
  // Locating one event near another's pole (z = x near p = 1/x): only g_i matters here.
  if (status == Status::non_finite && std::isfinite(g)) return Status::ok;
  return status;
}

Status EventTracker::find_dip(int i, double t, double h, const Interpolant& interpolate, double& theta,
                              double& theta_back) {
  theta = theta_back = -1.0;
  const std::size_t k = static_cast<std::size_t>(i);
  const double side = sign_[k];
  // f = g_i seen from the side it starts on: positive at the start, a dip is where it turns negative.
  const auto f = [&](double x, double& fx) {
    const Status status = value(i, t, h, x, interpolate, fx);
    fx *= side;
    return status;
  };
  // Samples of the whole step: a free flight is a polynomial, so one step may hold a climb, the
  // top and the fall onto the ground (or a body's turns): no shape of f is assumed. Where the
  // samples rise and fall more than a few times (a body turning several times in one step) they
  // are refined until they resolve it.
  std::vector<double>& fs = samples_;
  int count = 16;
  for (;;) {
    fs.assign(static_cast<std::size_t>(count) + 1, 0.0);
    fs.front() = side * g_start_[k];
    fs.back() = side * g_end_[k];
    for (int j = 1; j < count; ++j) {
      const Status status = f(static_cast<double>(j) / count, fs[static_cast<std::size_t>(j)]);
      if (status != Status::ok) return status;
    }
    // Turns counted on changes above the tolerances on f's size, so that round-off on a gap that
    // does not change (a body held still by its other contacts) does not count.
    const double noise = atol_ + (rtol_ + 1e-12) * std::max(std::abs(fs.front()), std::abs(fs.back()));
    int turns = 0, last = 0;
    for (int j = 1; j <= count; ++j) {
      const double change = fs[static_cast<std::size_t>(j)] - fs[static_cast<std::size_t>(j - 1)];
      if (!(std::abs(change) > noise)) continue;
      const int sign = change > 0.0 ? 1 : -1;
      if (last != 0 && sign != last) ++turns;
      last = sign;
    }
    if (turns <= 4 || count >= 512) break;
    count = std::min(count * 4, 512);
  }
  const auto at = [&](int j) { return static_cast<double>(j) / count; };
  const auto sample = [&](int j) { return fs[static_cast<std::size_t>(j)]; };
  const double f0 = sample(0), f1 = sample(count);
  const auto [low, high] = std::minmax_element(fs.begin(), fs.end());
  // A dip counts when f goes below zero by more than the interpolant may be off by on f's own
  // size, the tolerances (right after a lift-off, where f opens from zero, the interpolant has
  // values of either sign far below that), and more than 1e-7 of how much f changes over the step.
  const double scale = std::max(std::abs(f0), std::abs(f1));
  const double depth = std::max({atol_ + rtol_ * scale, 1e-7 * (*high - *low), 1e-12 * scale});
  // The slopes at the ends, where a minimum may hide between the end and the next sample.
  constexpr double kDelta = 1e-4;
  const auto falls_from_start = [&]() {
    double fa = 0.0;
    return f(kDelta / count, fa) == Status::ok && fa < f0;
  };
  const auto rises_to_end = [&]() {
    double fb = 0.0;
    return f(1.0 - kDelta / count, fb) == Status::ok && fb < f1;
  };
  constexpr double kGolden = 0.3819660112501051;  // (3 - sqrt 5) / 2
  // Each local minimum of the samples, in time order: the first that holds a dip gives the crossing.
  for (int j = 0; j <= count; ++j) {
    // A valley: below the sample before it by more than depth (a flat stretch, or round-off on
    // one, is no valley and costs no search), and not above the one after it.
    const bool minimum = (j == 0 || sample(j) < sample(j - 1) - depth) && (j == count || sample(j) <= sample(j + 1));
    if (!minimum) continue;
    if (j == 0 && !falls_from_start()) continue;
    // The end of a step where g changed sign is the sign change itself, which locate() finds as
    // before; only a dip before it is this search's.
    if (j == count && (f1 < 0.0 || !rises_to_end())) continue;
    // Golden sections around the sample towards the minimum, until a value below -depth or a
    // bracket 1e-9 of the step wide: a graze shallower than that is not worth a switch.
    double a = at(std::max(j - 1, 0)), b = at(std::min(j + 1, count));
    double x = at(j), fx = sample(j);
    for (int iteration = 0; iteration < 100 && !(fx < -depth) && b - a > 1e-9; ++iteration) {
      const double u = (x - a > b - x) ? x - kGolden * (x - a) : x + kGolden * (b - x);
      double fu = 0.0;
      const Status status = f(u, fu);
      if (status != Status::ok) return status;
      if (fu < fx) {
        if (u < x) b = x;
        else a = x;
        x = u;
        fx = fu;
      } else {
        if (u < x) a = u;
        else b = u;
      }
    }
    if (!(fx < -depth)) continue;  // f narrows there but stays positive
    // Where f first reaches zero: between the last sample before x where it is positive (the
    // step's start at worst, where it is) and x; and, for an event of both directions, where it
    // comes back: between x and the first sample after it where it is positive (the end at worst).
    int left = std::min(static_cast<int>(std::floor(x * count)), count);
    if (at(left) >= x) --left;
    while (left > 0 && !(sample(left) > 0.0)) --left;
    Status status = find_root(f, at(left), sample(left), x, fx, theta);
    if (status != Status::ok || events_.direction(i) != CrossingDirection::both) return status;
    int right = std::max(static_cast<int>(std::ceil(x * count)), 0);
    if (at(right) <= x) ++right;
    while (right < count && !(sample(right) > 0.0)) ++right;
    if (!(sample(right) > 0.0)) return Status::ok;  // it does not come back within the step
    return find_root(f, x, fx, at(right), sample(right), theta_back);
  }
  return Status::ok;
}

Status EventTracker::locate(double t, double h, const Interpolant& interpolate, std::vector<Crossing>& out) {
  out.clear();
  for (int i : dips_) {
    double theta = -1.0, theta_back = -1.0;
    const Status status = find_dip(i, t, h, interpolate, theta, theta_back);
    if (status != Status::ok) return status;
    if (theta >= 0.0) out.push_back({i, t + theta * h, theta});
    if (theta_back >= 0.0) out.push_back({i, theta_back >= 1.0 ? t + h : t + theta_back * h, theta_back});
  }
  for (int i : crossed_) {
    const std::size_t k = static_cast<std::size_t>(i);
    // A g that may dip can have gone through zero and back before the sign change at the end:
    // the first crossing is the one found by the same search (the end being one of its minima).
    if (events_.may_dip(i)) {
      double theta = -1.0, theta_back = -1.0;
      const Status status = find_dip(i, t, h, interpolate, theta, theta_back);
      if (status != Status::ok) return status;
      if (theta >= 0.0) {
        out.push_back({i, t + theta * h, theta});
        if (theta_back >= 0.0) out.push_back({i, theta_back >= 1.0 ? t + h : t + theta_back * h, theta_back});
        continue;
      }
    }
    double g0 = 0.0;
    Status status = value(i, t, h, 0.0, interpolate, g0);
    if (status != Status::ok) return status;
    // The interpolant starts at the step's start state, where g had the sign sign_[k] (or was zero,
    // reached from that side).
    if (sign_of(g0) == -sign_[k]) g0 = 0.0;
    double theta = 1.0;
    double last = 0.0;
    status = find_root(
        [&](double x, double& fx) {
          const Status s = value(i, t, h, x, interpolate, fx);
          last = fx;
          return s;
        },
        0.0, g0, 1.0, g_end_[k], theta);
    if (status == Status::non_finite && std::isinf(last)) {  // the search met the pole itself
      ++jumps_;
      if (jumps_ == 1) first_jump_t_ = t + theta * h;
      continue;
    }
    if (status != Status::ok) return status;
    // A sign change is a crossing only where g is continuous: at a pole (1/x) or a wrap-around
    // (atan2) g changes sign by a jump, and the bracket closes on the jump with |g| as large as at
    // the step's ends. At a true root |g| there is round-off, orders of magnitude below.
    double g_root = 0.0;
    status = value(i, t, h, theta, interpolate, g_root);
    if (status != Status::ok) return status;
    if (!is_jump(g_root, g0, g_end_[k])) {
      out.push_back({i, theta >= 1.0 ? t + h : t + theta * h, theta});
    } else {
      ++jumps_;
      if (jumps_ == 1) first_jump_t_ = t + theta * h;
    }
  }
  std::sort(out.begin(), out.end(), [](const Crossing& a, const Crossing& b) {
    return a.t != b.t ? a.t < b.t : a.index < b.index;
  });
  return Status::ok;
}

void EventTracker::advance() {
  g_start_ = g_end_;
  for (std::size_t i = 0; i < g_end_.size(); ++i) {
    const int s = sign_of(g_end_[i]);
    // Landing exactly on zero passes to the other side: the next step starts from there.
    if (s != 0) sign_[i] = s;
    else if (sign_[i] != 0) sign_[i] = -sign_[i];
  }
}

}  // namespace nhdyn
