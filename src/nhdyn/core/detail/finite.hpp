// A finiteness test for the hot path. Eigen's allFinite() on a dynamic-size array is an
// out-of-line loop per array; the kernels test several small arrays at every evaluation, so
// they fold them into one sum: x * 0 is 0 for a finite x and NaN for NaN or +-inf, and a NaN
// survives every addition. The caller names the culprit only when this test fails.
// Internal: used by the kernels of model/ and formulation/, not part of the public API (nhdyn/nhdyn.hpp).
#pragma once

#include <Eigen/Core>

namespace nhdyn {

// Adds x * 0 over n values to `acc`; acc stays 0 while every value is finite.
inline double accumulate_non_finite(double acc, const double* x, Eigen::Index n) {
  for (Eigen::Index i = 0; i < n; ++i) acc += x[i] * 0.0;
  return acc;
}

template <typename Derived>
double accumulate_non_finite(double acc, const Eigen::DenseBase<Derived>& x) {
  return accumulate_non_finite(acc, x.derived().data(), x.size());
}

}  // namespace nhdyn
