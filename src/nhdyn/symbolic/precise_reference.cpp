#include "nhdyn/symbolic/precise_reference.hpp"

#include <fmt/format.h>

#include <cmath>
#include <cstdint>
#include <sstream>
#include <string>
#include <utility>

#include "nhdyn/core/error.hpp"
#include "nhdyn/symbolic/detail/digits_scope.hpp"

namespace nhdyn::symbolic {
namespace {

std::string to_text(const GiNaC::ex& e) {
  std::ostringstream out;
  out << e;
  return out.str();
}

// x as a float of the current Digits (CLN's default float format for an exact non-square's root
// would be single precision otherwise).
GiNaC::numeric to_float(const GiNaC::numeric& x) { return GiNaC::ex_to<GiNaC::numeric>(GiNaC::ex(x).evalf()); }

// One term evaluated to a real float of the current Digits.
GiNaC::numeric evaluate(const GiNaC::ex& e, const GiNaC::lst& values, const std::string& what) {
  // GiNaC orders a sum's terms by hashes that depend on where its library was loaded, so a sum
  // evaluated at the working precision rounds differently from run to run. Evaluated with 20
  // guard digits and then rounded to the working precision (below), it gives the same number
  // every run.
  GiNaC::ex value;
  {
    DigitsScope guard(GiNaC::Digits + 20);
    value = e.subs(values, GiNaC::subs_options::no_pattern).evalf();
  }
  if (!GiNaC::is_exactly_a<GiNaC::numeric>(value) || !GiNaC::ex_to<GiNaC::numeric>(value).is_real())
    throw ModelError(fmt::format("the term {} is not a real number at this state: {}", what, to_text(value)));
  // evalf leaves exact integers such as 0 exact; make every entry a float of this precision so
  // that the elimination below never mixes in a lower one.
  return to_float(GiNaC::ex_to<GiNaC::numeric>(value));
}

struct Solution {
  std::vector<GiNaC::numeric> qdd, R, lambda;
};

// The terms of one state as numbers: A (n x n, row-major), h = Q + G, b (s x n, row-major), b0.
struct NumericTerms {
  int n = 0, s = 0;
  std::vector<GiNaC::numeric> A, h, b, b0;
};

NumericTerms evaluate_terms(const Derivation& d, const GiNaC::lst& values) {
  NumericTerms out;
  out.n = static_cast<int>(d.A.rows());
  out.s = static_cast<int>(d.b.rows());
  for (int i = 0; i < out.n; ++i) {
    for (int j = 0; j < out.n; ++j) out.A.push_back(evaluate(d.A(i, j), values, fmt::format("A({},{})", i, j)));
    out.h.push_back(evaluate(d.Q(i, 0), values, fmt::format("Q({})", i)) +
                    evaluate(d.G(i, 0), values, fmt::format("G({})", i)));
  }
  for (int r = 0; r < out.s; ++r) {
    for (int j = 0; j < out.n; ++j) out.b.push_back(evaluate(d.b(r, j), values, fmt::format("b({},{})", r, j)));
    out.b0.push_back(evaluate(d.b0(r, 0), values, fmt::format("b0({})", r)));
  }
  return out;
}

// The KKT system at the current Digits, by Gaussian elimination with partial pivoting.
Solution solve_at_current_digits(const NumericTerms& terms) {
  const int n = terms.n;
  const int s = terms.s;
  const int m = n + s;
  const std::vector<GiNaC::numeric>& A = terms.A;
  const std::vector<GiNaC::numeric>& h = terms.h;
  std::vector<std::vector<GiNaC::numeric>> K(static_cast<std::size_t>(m),
                                             std::vector<GiNaC::numeric>(static_cast<std::size_t>(m + 1), 0));
  const auto at = [&K](int i, int j) -> GiNaC::numeric& { return K[static_cast<std::size_t>(i)][static_cast<std::size_t>(j)]; };
  for (int i = 0; i < n; ++i) {
    for (int j = 0; j < n; ++j) at(i, j) = A[static_cast<std::size_t>(i * n + j)];
    at(i, m) = h[static_cast<std::size_t>(i)];
  }
  for (int r = 0; r < s; ++r) {
    for (int j = 0; j < n; ++j) {
      at(n + r, j) = terms.b[static_cast<std::size_t>(r * n + j)];
      at(j, n + r) = terms.b[static_cast<std::size_t>(r * n + j)];
    }
    at(n + r, m) = -terms.b0[static_cast<std::size_t>(r)];
  }
  for (int c = 0; c < m; ++c) {
    int pivot = c;
    for (int i = c + 1; i < m; ++i)
      if (GiNaC::abs(at(i, c)) > GiNaC::abs(at(pivot, c))) pivot = i;
    if (at(pivot, c).is_zero())
      throw ModelError(fmt::format("the Lagrange-multiplier system is singular at this state (column {}): "
                                   "dependent constraints or a singular inertia matrix",
                                   c));
    std::swap(K[static_cast<std::size_t>(c)], K[static_cast<std::size_t>(pivot)]);
    for (int i = c + 1; i < m; ++i) {
      if (at(i, c).is_zero()) continue;
      const GiNaC::numeric factor = at(i, c) / at(c, c);
      for (int j = c; j <= m; ++j) at(i, j) = at(i, j) - factor * at(c, j);
    }
  }
  std::vector<GiNaC::numeric> x(static_cast<std::size_t>(m), 0);
  for (int i = m - 1; i >= 0; --i) {
    GiNaC::numeric sum = at(i, m);
    for (int j = i + 1; j < m; ++j) sum = sum - at(i, j) * x[static_cast<std::size_t>(j)];
    x[static_cast<std::size_t>(i)] = sum / at(i, i);
  }
  Solution out;
  out.qdd.assign(x.begin(), x.begin() + n);
  for (int r = 0; r < s; ++r) out.lambda.push_back(-x[static_cast<std::size_t>(n + r)]);
  // R from (2.15), as the paper defines it; at this precision the cancellation between A q'' and
  // Q + G (both of the size of the largest mass) costs nothing visible in double.
  for (int i = 0; i < n; ++i) {
    GiNaC::numeric Ri = -h[static_cast<std::size_t>(i)];
    for (int j = 0; j < n; ++j) Ri = Ri + A[static_cast<std::size_t>(i * n + j)] * out.qdd[static_cast<std::size_t>(j)];
    out.R.push_back(Ri);
  }
  return out;
}

GiNaC::numeric norm2(const std::vector<GiNaC::numeric>& x) {
  GiNaC::numeric sum = 0;
  for (const GiNaC::numeric& xi : x) sum = sum + xi * xi;
  return GiNaC::sqrt(to_float(sum));
}

double relative_difference(const std::vector<GiNaC::numeric>& x, const std::vector<GiNaC::numeric>& reference) {
  std::vector<GiNaC::numeric> diff;
  for (std::size_t i = 0; i < x.size(); ++i) diff.push_back(x[i] - reference[i]);
  const GiNaC::numeric scale = norm2(reference);
  return (scale.is_zero() ? norm2(diff) : norm2(diff) / scale).to_double();
}

}  // namespace

GiNaC::numeric exact_rational(double x) {
  if (!std::isfinite(x))
    throw InputError(fmt::format("{} has no exact rational value; the high-precision reference needs finite numbers", x));
  if (x == 0.0) return 0;
  int exponent = 0;
  const double mantissa = std::frexp(x, &exponent);  // x = mantissa 2^exponent, 0.5 <= |mantissa| < 1
  // 53 bits hold every double's significand, so this integer is exact.
  const auto integer = static_cast<long>(std::ldexp(mantissa, 53));
  return GiNaC::numeric(integer) * GiNaC::numeric(2).power(exponent - 53);
}

PreciseAcceleration calc_precise_acceleration(const Spec& spec, const Derivation& derivation, double t,
                                              std::span<const double> q, std::span<const double> v, int digits) {
  const int n = spec.n();
  if (static_cast<int>(q.size()) != n || static_cast<int>(v.size()) != n)
    throw InputError(fmt::format("the state has {} coordinates and {} velocities; model '{}' has {} coordinates",
                                 q.size(), v.size(), spec.name, n));
  if (digits < 17)
    throw InputError(fmt::format("{} digits is no more than double precision; ask for 17 or more", digits));
  GiNaC::lst values;
  for (const SpecParameter& p : spec.parameters) values.append(spec.symbols.parameter(p.name) == exact_rational(p.value));
  values.append(spec.symbols.time() == exact_rational(t));
  for (int i = 0; i < n; ++i) {
    values.append(spec.symbols.coordinate(i) == exact_rational(q[static_cast<std::size_t>(i)]));
    values.append(spec.symbols.velocity(i) == exact_rational(v[static_cast<std::size_t>(i)]));
  }
  Solution result, check;
  {
    DigitsScope scope(digits);
    result = solve_at_current_digits(evaluate_terms(derivation, values));
  }
  {
    DigitsScope scope(digits + 20);
    check = solve_at_current_digits(evaluate_terms(derivation, values));
  }
  PreciseAcceleration out;
  out.digits = digits;
  out.estimated_error = std::max(relative_difference(result.qdd, check.qdd), relative_difference(result.R, check.R));
  out.qdd = std::move(result.qdd);
  out.R = std::move(result.R);
  out.lambda = std::move(result.lambda);
  return out;
}

PreciseAcceleration calc_precise_solution(const Matrix& A, const Vector& h, const Matrix& b, const Vector& b0,
                                          int digits) {
  const int n = static_cast<int>(A.rows());
  const int s = static_cast<int>(b.rows());
  if (A.cols() != n || h.size() != n || b.cols() != n || b0.size() != s)
    throw InputError(fmt::format("terms of inconsistent sizes: A {}x{}, Q + G {}, b {}x{}, b0 {}", A.rows(), A.cols(),
                                 h.size(), b.rows(), b.cols(), b0.size()));
  if (digits < 17)
    throw InputError(fmt::format("{} digits is no more than double precision; ask for 17 or more", digits));
  // The terms are exact rationals: elimination at either precision rounds only its own steps.
  NumericTerms terms;
  terms.n = n;
  terms.s = s;
  for (int i = 0; i < n; ++i) {
    for (int j = 0; j < n; ++j) terms.A.push_back(exact_rational(A(i, j)));
    terms.h.push_back(exact_rational(h(i)));
  }
  for (int r = 0; r < s; ++r) {
    for (int j = 0; j < n; ++j) terms.b.push_back(exact_rational(b(r, j)));
    terms.b0.push_back(exact_rational(b0(r)));
  }
  Solution result, check;
  {
    DigitsScope scope(digits);
    result = solve_at_current_digits(terms);
  }
  {
    DigitsScope scope(digits + 20);
    check = solve_at_current_digits(terms);
  }
  PreciseAcceleration out;
  out.digits = digits;
  out.estimated_error = std::max(relative_difference(result.qdd, check.qdd), relative_difference(result.R, check.R));
  out.qdd = std::move(result.qdd);
  out.R = std::move(result.R);
  out.lambda = std::move(result.lambda);
  return out;
}

double calc_relative_error(std::span<const double> x, const std::vector<GiNaC::numeric>& reference, int digits) {
  if (x.size() != reference.size())
    throw InputError(fmt::format("cannot compare {} values with a reference of {}", x.size(), reference.size()));
  DigitsScope scope(digits);
  std::vector<GiNaC::numeric> exact;
  for (double xi : x) exact.push_back(exact_rational(xi));
  return relative_difference(exact, reference);
}

}  // namespace nhdyn::symbolic
