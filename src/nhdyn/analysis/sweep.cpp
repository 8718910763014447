#include "nhdyn/analysis/sweep.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <limits>

#include <Eigen/Eigenvalues>
#include <Eigen/SVD>

#include "nhdyn/core/error.hpp"
#include "nhdyn/model/parameters.hpp"

namespace nhdyn {
namespace {

using Eigenvalues = std::vector<std::complex<double>>;

// Eigenvalues whose real part is positive beyond their uncertainty: the motion is then certainly
// unstable in that many directions. Those within it (a zero, a pair on the imaginary axis, a
// multiple eigenvalue split by round-off) are undecided and never counted.
void classify(SweepPoint& p) {
  p.unstable = 0;
  p.undecided = 0;
  for (std::size_t i = 0; i < p.eigenvalues.size(); ++i) {
    const double re = p.eigenvalues[i].real();
    if (re > p.uncertainty[i]) ++p.unstable;
    else if (re >= -p.uncertainty[i]) ++p.undecided;
  }
}

// The eigenvalue of `e` nearest to `target` (continuation along the parameter).
std::size_t nearest(const Eigenvalues& e, std::complex<double> target) {
  std::size_t best = 0;
  for (std::size_t i = 1; i < e.size(); ++i)
    if (std::abs(e[i] - target) < std::abs(e[best] - target)) best = i;
  return best;
}

// One eigenvalue of a state matrix followed along the parameter by its eigenvector: the nearest
// value is not enough where another eigenvalue lies on the path (the bicycle's forward speed adds
// an eigenvalue 0 at every speed, which the capsize eigenvalue passes as it crosses zero).
struct Mode {
  std::complex<double> value;
  Eigen::VectorXcd vector;  // unit length
};

// The eigenpairs of s (eigenvalues as Linearization computes them: the same solver on the same matrix).
std::vector<Mode> modes_of(const Matrix& s) {
  const Eigen::EigenSolver<Matrix> eigen(s, true);
  std::vector<Mode> out;
  for (Eigen::Index j = 0; j < s.rows(); ++j) out.push_back({eigen.eigenvalues()(j), eigen.eigenvectors().col(j).normalized()});
  return out;
}

// The mode of s whose eigenvector is most nearly parallel to `previous`'s. Near a multiple
// eigenvalue (a Jordan block, where a real pair turns into a complex one) the eigenvectors of the
// modes involved become parallel and say nothing: when a second mode is nearly as parallel, the
// nearest value decides. A pair's two members have conjugate eigenvectors, which need not be far
// apart: a mode off the real axis (beyond `uncertainty`) is followed on its own side of it.
Mode follow_mode(const Matrix& s, const Mode& previous, double uncertainty) {
  const std::vector<Mode> modes = modes_of(s);
  const int side = std::abs(previous.value.imag()) > uncertainty ? (previous.value.imag() > 0.0 ? 1 : -1) : 0;
  std::size_t best = modes.size(), nearest_value = modes.size();
  double best_overlap = -1.0, second_overlap = -1.0;
  for (std::size_t j = 0; j < modes.size(); ++j) {
    if (side != 0 && modes[j].value.imag() * side < 0.0) continue;
    if (nearest_value == modes.size() ||
        std::abs(modes[j].value - previous.value) < std::abs(modes[nearest_value].value - previous.value))
      nearest_value = j;
    const double overlap = std::abs(modes[j].vector.dot(previous.vector));
    if (overlap > best_overlap) {
      second_overlap = best_overlap;
      best_overlap = overlap;
      best = j;
    } else {
      second_overlap = std::max(second_overlap, overlap);
    }
  }
  if (best == modes.size()) return previous;
  return modes[second_overlap > 0.9 * best_overlap ? nearest_value : best];
}

}  // namespace

std::vector<double> calc_eigenvalue_uncertainty(const Matrix& state_matrix, const Eigenvalues& eigenvalues) {
  const std::size_t n = eigenvalues.size();
  const double s = state_matrix.norm();
  const double e = 64.0 * std::numeric_limits<double>::epsilon();
  const auto radius = [&](std::size_t l) { return 8.0 * std::pow(e, 1.0 / static_cast<double>(l)) * s; };
  std::vector<double> out(n, radius(1));
  // Largest clusters first: an eigenvalue takes the radius of the largest cluster it belongs to.
  std::vector<bool> settled(n, false);
  for (std::size_t m = n; m >= 2; --m) {
    const double r = radius(m);
    for (std::size_t i = 0; i < n; ++i) {
      if (settled[i]) continue;
      std::vector<std::size_t> cluster;
      std::complex<double> centre = 0.0;
      for (std::size_t j = 0; j < n; ++j)
        if (std::abs(eigenvalues[j] - eigenvalues[i]) <= 2.0 * r) {
          cluster.push_back(j);
          centre += eigenvalues[j];
        }
      if (cluster.size() < m) continue;
      centre /= static_cast<double>(cluster.size());
      // g: the geometric multiplicity the cluster can have; the longest Jordan block is m - g + 1.
      const Eigen::MatrixXcd shifted =
          state_matrix.cast<std::complex<double>>() - centre * Eigen::MatrixXcd::Identity(state_matrix.rows(), state_matrix.cols());
      const Eigen::VectorXd sigma = Eigen::JacobiSVD<Eigen::MatrixXcd>(shifted).singularValues();
      std::size_t g = 0;
      for (Eigen::Index k = 0; k < sigma.size(); ++k) g += sigma(k) <= 2.0 * r ? 1 : 0;
      const std::size_t size = cluster.size();
      const std::size_t longest = g >= size ? 1 : std::max<std::size_t>(1, size - std::max<std::size_t>(g, 1) + 1);
      for (std::size_t j : cluster)
        if (!settled[j]) {
          out[j] = std::max(out[j], radius(longest));
          settled[j] = true;
        }
    }
  }
  // Near a multiple eigenvalue but split from it by d, an eigenvalue moves by about e s^2 / d
  // (a pair +-sqrt(x) near a Jordan block: x is known to e s^2): the sharper bound once d is
  // larger than the Jordan radius, so that a pair leaving zero is decided as soon as it can be.
  for (std::size_t i = 0; i < n; ++i) {
    if (out[i] <= radius(1)) continue;
    double d = std::numeric_limits<double>::infinity();
    for (std::size_t j = 0; j < n; ++j)
      if (j != i) d = std::min(d, std::abs(eigenvalues[j] - eigenvalues[i]));
    if (d > 0.0) out[i] = std::min(out[i], std::max(radius(1), 8.0 * e * s * s / d));
  }
  return out;
}

void check_sweep_options(const SweepOptions& options) {
  if (options.steps < 2 || options.steps > 1000000)
    throw InputError(fmt::format("--steps {}: give the number of grid points, from 2 to 1000000 (both ends included)",
                                 options.steps));
  if (!std::isfinite(options.from)) throw InputError(fmt::format("--from {}: not a finite number", options.from));
  if (!std::isfinite(options.to)) throw InputError(fmt::format("--to {}: not a finite number", options.to));
  if (!(options.from < options.to))
    throw InputError(fmt::format("--from {} --to {}: the range of {} is empty or reversed; give --from below --to",
                                 options.from, options.to, options.parameter));
}

namespace {

// A sweep under way: the linearization options (the first point fixes the state's choice of
// independent coordinates and speeds for all) and the result so far.
class Sweeper {
 public:
  Sweeper(const ModelAtValue& model_at, const SweepOptions& options)
      : model_at_(model_at), options_(options), lin_(options.linearization) {}

  Sweep run() {
    for (int i = 0; i < options_.steps; ++i) {
      const double value = i + 1 == options_.steps
                               ? options_.to
                               : options_.from + (options_.to - options_.from) * i / (options_.steps - 1);
      out_.points.push_back(at(value));
    }
    if (!options_.find_crossings) return out_;
    first_ = out_.points.front().value;
    last_ = out_.points.back().value;
    for (std::size_t i = 0; i + 1 < out_.points.size(); ++i) find_crossings_in(i);
    return out_;
  }

 private:
  static constexpr double ulp_scale = 4.0 * std::numeric_limits<double>::epsilon();

  // The point at `value`; its state matrix too when `state_matrix` is given.
  SweepPoint at(double value, Matrix* state_matrix = nullptr) {
    try {
      const Linearization l = calc_linearization(model_at_(value), lin_);
      if (state_matrix != nullptr) *state_matrix = l.state_matrix;
      SweepPoint p;
      p.value = value;
      p.eigenvalues = l.eigenvalues;
      p.uncertainty = calc_eigenvalue_uncertainty(l.state_matrix, l.eigenvalues);
      classify(p);
      if (out_.state.empty()) {
        out_.state = l.state;
        // The same state at every point: the choice made here, named.
        lin_.independent = l.independent;
        lin_.speeds = l.speeds;
      }
      return p;
    } catch (const InputError& e) {
      throw InputError(fmt::format("at {} = {:.17g}: {}", options_.parameter, value, e.what()));
    } catch (const ModelError& e) {
      throw ModelError(fmt::format("at {} = {:.17g}: {}", options_.parameter, value, e.what()));
    }
  }

  // 2. For a simple eigenvalue, the count's threshold is not the crossing: follow that eigenvalue
  // (by its eigenvector) to where its real part is certainly negative, then bisect on the sign of
  // its real part (the capsize speed to round-off, not to r_1 / slope). Narrows [a, b] to it and
  // sets `crossing`; a real part that never becomes certainly negative (a pair going onto the
  // imaginary axis) leaves step 1's bracket.
  void follow_to_the_sign_change(double& a, double& b, bool rising, const SweepPoint& unstable_side, std::size_t k,
                                 std::complex<double>& crossing) {
    const double first = first_, last = last_;
    Matrix s;
    at(rising ? b : a, &s);
    Mode start{crossing, {}};
    for (const Mode& m : modes_of(s))
      if (start.vector.size() == 0 || std::abs(m.value - crossing) < std::abs(start.value - crossing)) start = m;
    const double width = std::max(b - a, ulp_scale * std::max(1.0, std::abs(a)));
    double stable_end = rising ? a : b;
    Mode follow = start;
    bool found = false;
    // The search may leave the grid cell: the eigenvalue can still be undecided at the cell's
    // end (a grid point exactly at the crossing, or an uncertainty made large by a stiff mode
    // elsewhere), and step 1's bracket then holds the count's threshold, not the crossing.
    for (double step = width; step <= 2.0 * (last - first); step *= 2.0) {
      const double probe = rising ? std::max(first, a - step) : std::min(last, b + step);
      const SweepPoint p = at(probe, &s);
      follow = follow_mode(s, follow, unstable_side.uncertainty[k]);
      const std::size_t j = nearest(p.eigenvalues, follow.value);
      if (p.eigenvalues[j].real() < -p.uncertainty[j]) {
        stable_end = probe;
        found = true;
        break;
      }
      if (probe == first || probe == last) break;
    }
    if (!found) return;
    double neg = stable_end, pos = rising ? b : a;
    Mode track = start;
    for (int iter = 0; iter < 200 && std::abs(pos - neg) > ulp_scale * std::max(1.0, std::abs(neg)); ++iter) {
      const double mid = 0.5 * (neg + pos);
      if (mid == neg || mid == pos) break;
      const SweepPoint p = at(mid, &s);
      const Mode next = follow_mode(s, track, unstable_side.uncertainty[k]);
      const std::size_t j = nearest(p.eigenvalues, next.value);
      // Joined to a cluster (a multiple eigenvalue there), its sign is round-off: the
      // bracket so far is all the conditioning supports.
      const double simple = *std::min_element(p.uncertainty.begin(), p.uncertainty.end());
      if (p.uncertainty[j] > simple) break;
      track = next;
      (track.value.real() > 0.0 ? pos : neg) = mid;
    }
    crossing = track.value;
    a = std::min(neg, pos);
    b = std::max(neg, pos);
  }

  // Each change of the count of certainly unstable eigenvalues between grid points i and i + 1,
  // located and appended to the crossings.
  void find_crossings_in(std::size_t i) {
    const SweepPoint& hi = out_.points[i + 1];
    // Each change of the count in the cell in turn (0 -> 1 -> 2 when two eigenvalues cross in
    // it), from the point just after the last one found.
    SweepPoint lo = out_.points[i];
    for (std::size_t guard = 0; lo.unstable != hi.unstable && guard <= hi.eigenvalues.size(); ++guard) {
      // 1. Bisection on the count of certainly unstable eigenvalues: it stops where the crossing
      // eigenvalue's real part leaves its uncertainty.
      double a = lo.value, b = hi.value;
      SweepPoint at_a = lo, at_b = hi;
      for (int iter = 0; iter < 200 && b - a > ulp_scale * std::max(1.0, std::abs(a)); ++iter) {
        const double mid = 0.5 * (a + b);
        if (mid <= a || mid >= b) break;
        SweepPoint p = at(mid);
        if (p.unstable == lo.unstable) {
          a = mid;
          at_a = std::move(p);
        } else {
          b = mid;
          at_b = std::move(p);
        }
      }
      // The crossing eigenvalue: on the unstable side, the certainly unstable one nearest the axis.
      const SweepPoint after = at_b;  // the count just after this crossing
      const bool rising = after.unstable > lo.unstable;
      const SweepPoint& unstable_side = rising ? at_b : at_a;
      std::size_t k = unstable_side.eigenvalues.size();
      for (std::size_t j = 0; j < unstable_side.eigenvalues.size(); ++j) {
        const double re = unstable_side.eigenvalues[j].real();
        if (re > unstable_side.uncertainty[j] && (k == unstable_side.eigenvalues.size() || re < unstable_side.eigenvalues[k].real()))
          k = j;
      }
      std::complex<double> crossing = k < unstable_side.eigenvalues.size() ? unstable_side.eigenvalues[k] : 0.0;
      // 2. Step 1 stopped at the count's threshold; the crossing itself, for a simple eigenvalue.
      if (k < unstable_side.eigenvalues.size()) follow_to_the_sign_change(a, b, rising, unstable_side, k, crossing);
      StabilityCrossing c;
      c.value = 0.5 * (a + b);
      c.bracket = b - a;
      c.unstable_before = lo.unstable;
      c.unstable_after = after.unstable;
      double scale = 1.0;
      for (const std::complex<double>& x : unstable_side.eigenvalues) scale = std::max(scale, std::abs(x));
      c.frequency = std::abs(crossing.imag());
      c.oscillatory = c.frequency > 1e-6 * scale;
      if (!c.oscillatory) c.frequency = 0.0;
      out_.crossings.push_back(c);
      lo = after;
    }
  }

  const ModelAtValue& model_at_;
  const SweepOptions& options_;
  LinearizationOptions lin_;
  Sweep out_;
  double first_ = 0.0, last_ = 0.0;  // the ends of the grid
};

}  // namespace

Sweep calc_eigenvalue_sweep(const ModelAtValue& model_at, const SweepOptions& options) {
  check_sweep_options(options);
  return Sweeper(model_at, options).run();
}

ModelAtValue make_model_at_value(const Model& base, const std::string& parameter) {
  return [base, parameter](double value) {
    Model model = base;
    set_parameter(model, parameter, value);
    return model;
  };
}

Sweep calc_parameter_sweep(const Model& base, const SweepOptions& options) {
  check_sweep_options(options);
  Model at_from = base;
  set_parameter(at_from, options.parameter, options.from);  // an unknown name throws, naming the nearest
  return calc_eigenvalue_sweep(make_model_at_value(at_from, options.parameter), options);
}

}  // namespace nhdyn
