// A finiteness test for the hot path. Eigen's allFinite() on a dynamic-size array is an
// out-of-line loop per array; the kernels test several small arrays at every evaluation, so
// they fold them into one sum: x * 0 is 0 for a finite x and NaN for NaN or +-inf, and a NaN
// survives every addition. The caller names the culprit only when this test fails.
// Internal: used by the kernels of model/ and formulation/, not part of the public API (nhdyn/nhdyn.hpp).
#pragma once

#include <Eigen/Core>

namespace nhdyn {

// Adds x * 0 over n values to `acc`; acc stays 0 while every value is finite. Four sums side by
// side: one sum is a chain of dependent additions (about 4 cycles each, 44 ns over the 81 values
// of a rattleback's terms), four take a third of that; the result is 0 or NaN either way.
inline double accumulate_non_finite(double acc, const double* x, Eigen::Index n) {
  double s0 = 0.0, s1 = 0.0, s2 = 0.0, s3 = 0.0;
  Eigen::Index i = 0;
  for (; i + 4 <= n; i += 4) {
    s0 += x[i] * 0.0;
    s1 += x[i + 1] * 0.0;
    s2 += x[i + 2] * 0.0;
    s3 += x[i + 3] * 0.0;
  }
  for (; i < n; ++i) s0 += x[i] * 0.0;
  return acc + ((s0 + s1) + (s2 + s3));
}

template <typename Derived>
double accumulate_non_finite(double acc, const Eigen::DenseBase<Derived>& x) {
  return accumulate_non_finite(acc, x.derived().data(), x.size());
}

// The same test of a small dense model's terms, q, q', A, Q, G, b and b0 together, with n and s
// known at compile time: one call of unrolled code instead of seven loops, whose fixed costs were
// most of the test at n = 3 (a third of a sled's right-hand side outside the solve). 0 when every
// value is finite, NaN otherwise. It also copies q and q' to q_out and v_out (the same arrays or
// apart): the state is stored where it is read for the test, without a call of memcpy for each.
using TermsNonFinite = double (*)(const double* q, const double* v, const double* A, const double* Q,
                                  const double* G, const double* b, const double* b0, double* q_out,
                                  double* v_out);
// The test for n coordinates and s constraints, or nullptr beyond kFixedFiniteMaxN coordinates or
// for s > n (the caller then tests array by array).
inline constexpr int kFixedFiniteMaxN = 8;
TermsNonFinite find_terms_non_finite(int n, int s);
// q'' and R (n each) together, for n <= kFixedFiniteMaxN; nullptr beyond.
using PairNonFinite = double (*)(const double* x, const double* y);
PairNonFinite find_pair_non_finite(int n);

}  // namespace nhdyn
