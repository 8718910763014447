// The exact row scaling of a stacked system whose rows carry different units, applied before its
// singularity test (docs/cli.md, "What bad input gets"). The rows D A of [D A; b] scale with the
// masses and the rows b do not, so `--set m=1e100` makes pivots 1e100 apart: an unscaled test
// called a well-posed system singular, or let a singular one of such rows pass. Written once here
// for every solve of [D A; b]: the sanh formulation (sanh.cpp, and the fixed-size kernels of
// small_dense.hpp), the program-motion solve (program_motion.cpp), the contact modes
// (contact_modes.cpp) and the impulse at a touchdown (analysis/detail/contact_switches.cpp). Plain double
// and templates only, so that the fixed-size kernels use it too; allocates nothing.
// Internal: used by formulation/ and analysis/, not part of the public API (nhdyn/nhdyn.hpp).
#pragma once

#include <algorithm>
#include <cmath>
#include <limits>

namespace nhdyn {

// Rows whose largest entries differ by more than this (2^26, half the digits of a double) are
// scaled; systems in comparable units are factored as they are, bit for bit as before.
inline constexpr double kRowScaleRatio = 67108864.0;  // 2^26

// For a system of `rows` rows whose largest |entry| in row i is row_max(i): when these differ by
// more than kRowScaleRatio (and all are finite and nonzero), calls scale_row(i, e) for every row,
// with e the exponent that brings row i's largest entry into [0.5, 1) by a factor 2^-e (exact:
// scale with std::ldexp(x, -e), the right-hand side's row with it). Returns whether it scaled.
// A zero row is left to the singularity test (it is singular in any units).
template <class RowMax, class ScaleRow>
bool scale_rows_by_powers_of_two(int rows, const RowMax& row_max, const ScaleRow& scale_row) {
  double smallest = std::numeric_limits<double>::infinity(), largest = 0.0;
  for (int i = 0; i < rows; ++i) {
    const double r = row_max(i);
    smallest = std::min(smallest, r);
    largest = std::max(largest, r);
  }
  if (!(smallest > 0.0 && std::isfinite(largest) && largest > kRowScaleRatio * smallest)) return false;
  for (int i = 0; i < rows; ++i) {
    int exponent = 0;
    std::frexp(row_max(i), &exponent);
    scale_row(i, exponent);
  }
  return true;
}

}  // namespace nhdyn
