#include "nhdyn/analysis/sweep.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <limits>

#include "nhdyn/core/error.hpp"

namespace nhdyn {
namespace {

// Eigenvalues that are zero at every parameter value (a conserved momentum, a cyclic speed) are
// left out of the counts: their real parts are round-off of either sign.
// A real part counts as positive above 64 ulps of the largest eigenvalue, the round-off of the
// eigenvalue solver: a pair on the imaginary axis (a conservative system) has real parts of that
// size and either sign. A real eigenvalue crossing zero with slope c is then located to
// 64 eps |lambda|_max / c.
int count_unstable(std::vector<std::complex<double>> eigenvalues, int structural_zeros) {
  std::sort(eigenvalues.begin(), eigenvalues.end(),
            [](const std::complex<double>& a, const std::complex<double>& b) { return std::abs(a) < std::abs(b); });
  double scale = 1.0;
  for (const std::complex<double>& e : eigenvalues) scale = std::max(scale, std::abs(e));
  int count = 0;
  for (std::size_t i = static_cast<std::size_t>(structural_zeros); i < eigenvalues.size(); ++i)
    count += eigenvalues[i].real() > 64.0 * std::numeric_limits<double>::epsilon() * scale ? 1 : 0;
  return count;
}

int count_zeros(const std::vector<std::complex<double>>& eigenvalues) {
  double scale = 1.0;
  for (const std::complex<double>& e : eigenvalues) scale = std::max(scale, std::abs(e));
  int zeros = 0;
  for (const std::complex<double>& e : eigenvalues) zeros += std::abs(e) <= 1e-9 * scale ? 1 : 0;
  return zeros;
}

}  // namespace

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

Sweep calc_eigenvalue_sweep(const ModelAtValue& model_at, const SweepOptions& options) {
  check_sweep_options(options);
  Sweep out;
  LinearizationOptions lin = options.linearization;
  const auto at = [&](double value) -> Linearization {
    try {
      return calc_linearization(model_at(value), lin);
    } catch (const InputError& e) {
      throw InputError(fmt::format("at {} = {:.17g}: {}", options.parameter, value, e.what()));
    } catch (const ModelError& e) {
      throw ModelError(fmt::format("at {} = {:.17g}: {}", options.parameter, value, e.what()));
    }
  };
  for (int i = 0; i < options.steps; ++i) {
    const double value = i + 1 == options.steps
                             ? options.to
                             : options.from + (options.to - options.from) * i / (options.steps - 1);
    const Linearization l = at(value);
    if (i == 0) {
      out.state = l.state;
      // The same state at every point: the choice made here, named.
      lin.independent = l.independent;
      lin.speeds = l.speeds;
    }
    out.points.push_back({value, l.eigenvalues});
  }
  if (!options.find_crossings) return out;

  for (std::size_t i = 0; i + 1 < out.points.size(); ++i) {
    const SweepPoint& lo = out.points[i];
    const SweepPoint& hi = out.points[i + 1];
    const int zeros = std::min(count_zeros(lo.eigenvalues), count_zeros(hi.eigenvalues));
    const int before = count_unstable(lo.eigenvalues, zeros);
    const int after = count_unstable(hi.eigenvalues, zeros);
    if (before == after) continue;
    // Bisection on the count: it stays right until the crossing eigenvalue's real part is
    // round-off, so the bracket shrinks to (round-off of the eigenvalue) / (its slope).
    double a = lo.value, b = hi.value;
    std::vector<std::complex<double>> near = hi.eigenvalues;
    for (int iter = 0; iter < 200 && b - a > 4.0 * std::numeric_limits<double>::epsilon() * std::max(1.0, std::abs(a));
         ++iter) {
      const double mid = 0.5 * (a + b);
      if (mid <= a || mid >= b) break;
      const Linearization l = at(mid);
      if (count_unstable(l.eigenvalues, zeros) == before) {
        a = mid;
      } else {
        b = mid;
        near = l.eigenvalues;
      }
    }
    StabilityCrossing c;
    c.value = 0.5 * (a + b);
    c.bracket = b - a;
    c.unstable_before = before;
    c.unstable_after = after;
    // The crossing eigenvalue: of those not structurally zero, the one nearest the imaginary axis.
    std::vector<std::complex<double>> e = near;
    std::sort(e.begin(), e.end(),
              [](const std::complex<double>& x, const std::complex<double>& y) { return std::abs(x) < std::abs(y); });
    e.erase(e.begin(), e.begin() + zeros);
    double scale = 1.0;
    for (const std::complex<double>& x : e) scale = std::max(scale, std::abs(x));
    const auto best = std::min_element(e.begin(), e.end(), [](const std::complex<double>& x, const std::complex<double>& y) {
      return std::abs(x.real()) < std::abs(y.real());
    });
    if (best != e.end()) {
      c.frequency = std::abs(best->imag());
      c.oscillatory = c.frequency > 1e-6 * scale;
      if (!c.oscillatory) c.frequency = 0.0;
    }
    out.crossings.push_back(c);
  }
  return out;
}

}  // namespace nhdyn
