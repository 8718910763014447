// Dense kernels for small systems (n <= kSmallMaxN), written as plain-double loops with n and s
// known at compile time. At n = 3 a dynamic-size Eigen call costs more in dispatch than in
// arithmetic (docs/performance.md); these loops let the compiler unroll everything. They compute
// the same quantities as the dynamic path, with the same rank and singularity tests, so that the
// choice between them changes nothing but the time.
// Internal: the formulation module's own kernels, not part of the public API (nhdyn/nhdyn.hpp).
//
// Storage is column-major as in Eigen: A(i, j) = A[i + n j], b(i, j) = b[i + s j],
// D(i, j) = D[i + k j].
#pragma once

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <utility>

#include "nhdyn/core/detail/finite.hpp"
#include "nhdyn/formulation/detail/row_scaling.hpp"

namespace nhdyn::small {

inline constexpr int kSmallMaxN = 8;
inline constexpr double kEps = std::numeric_limits<double>::epsilon();

// An orthonormal basis of null(b) as the rows of D (k x n): the last k columns of Q in a
// Householder QR factorization with column pivoting b^T P = Q [R1; 0]. The rank test is that of
// the dynamic path (complement.cpp): the last pivot of R1 against the first. Returns false when
// b has rank below s.
//
// The rows of b^T (the coordinates) are taken in `order` (n indices; null: their own order),
// Data::bt_order, which puts the coordinates b never touches last, as compute_constraint_basis
// takes them: a reflector H_j = I - tau v v^T maps its column onto the j-th coordinate, so that
// with an untouched coordinate first (the position of a free body before its quaternion, held to
// unit norm) v, and with it every row of D, would mix that coordinate into the constrained ones.
// Such a D is a complement all the same, but its rows D A then mix the body's mass with its
// inertias, in whatever units they have (a body in millimetres: 1 against 1e6), and the stacked
// matrix loses digits it need not. Taken last, the untouched coordinates are rows of D of their
// own (unit vectors).
template <int N, int S>
bool null_space_basis_reordered(const double* b, const int* order, double* D);

template <int N, int S>
bool null_space_basis(const double* b, const int* order, double* D) {
  constexpr int K = N - S;
  if constexpr (S == 0) {
    for (int i = 0; i < K * N; ++i) D[i] = 0.0;
    for (int i = 0; i < N; ++i) D[i + K * i] = 1.0;
    return true;
  } else {
    if (order != nullptr) [[unlikely]]
      return null_space_basis_reordered<N, S>(b, order, D);
    std::array<double, N * S> bt;  // b^T, overwritten by the reflectors
    std::array<double, S> tau;
    for (int i = 0; i < S; ++i)
      for (int j = 0; j < N; ++j) bt[j + N * i] = b[i + S * j];
    double first_pivot = 0.0;
    for (int j = 0; j < S; ++j) {
      int p = j;
      double best = -1.0;
      for (int c = j; c < S; ++c) {
        double norm2 = 0.0;
        for (int i = j; i < N; ++i) norm2 += bt[i + N * c] * bt[i + N * c];
        if (norm2 > best) {
          best = norm2;
          p = c;
        }
      }
      if (p != j)
        for (int i = 0; i < N; ++i) std::swap(bt[i + N * j], bt[i + N * p]);
      double* v = bt.data() + N * j;
      const double norm = std::sqrt(best);
      if (j == 0) first_pivot = norm;
      if (!(norm > first_pivot * kEps * 16.0 * (N + S)) || !(first_pivot > 0.0)) return false;
      const double alpha = v[j] >= 0.0 ? -norm : norm;  // R1(j, j)
      const double v0 = v[j] - alpha;
      for (int i = j + 1; i < N; ++i) v[i] /= v0;  // essential part; the reflector's v[j] is 1
      tau[j] = -v0 / alpha;                         // H_j = I - tau v v^T
      for (int c = j + 1; c < S; ++c) {
        double* w = bt.data() + N * c;
        double d = w[j];
        for (int i = j + 1; i < N; ++i) d += v[i] * w[i];
        d *= tau[j];
        w[j] -= d;
        for (int i = j + 1; i < N; ++i) w[i] -= d * v[i];
      }
    }
    // Column s + r of Q = H_1 ... H_s e_{s+r}: the reflectors applied from the last to the first,
    // each to the k columns in turn, so that the k independent chains of dependent operations
    // overlap (the same operations as one column after the other, in a different order).
    std::array<double, N * K> y{};
    for (int r = 0; r < K; ++r) y[S + r + N * r] = 1.0;
    for (int j = S - 1; j >= 0; --j) {
      const double* v = bt.data() + N * j;
      for (int r = 0; r < K; ++r) {
        double* yr = y.data() + N * r;
        double d = yr[j];
        for (int i = j + 1; i < N; ++i) d += v[i] * yr[i];
        d *= tau[j];
        yr[j] -= d;
        for (int i = j + 1; i < N; ++i) yr[i] -= d * v[i];
      }
    }
    for (int r = 0; r < K; ++r)
      for (int i = 0; i < N; ++i) D[r + K * i] = y[i + N * r];
    return true;
  }
}

// null_space_basis with the coordinates taken in `order`: b's columns gathered in that order, the
// basis of the gathered b, and its columns put back. Out of line, so that the kernels inlined
// into the fused one (flatten) keep the common case's code as it is.
template <int N, int S>
[[gnu::noinline]] bool null_space_basis_reordered(const double* b, const int* order, double* D) {
  constexpr int K = N - S;
  std::array<double, S * N> gathered;
  std::array<double, K * N> basis;
  for (int j = 0; j < N; ++j)
    for (int i = 0; i < S; ++i) gathered[i + S * j] = b[i + S * order[j]];
  if (!null_space_basis<N, S>(gathered.data(), nullptr, basis.data())) return false;
  for (int j = 0; j < N; ++j)
    for (int r = 0; r < K; ++r) D[r + K * order[j]] = basis[r + K * j];
  return true;
}

// Gaussian elimination with partial pivoting of the N x N matrix M (column-major) and its right-
// hand side r, in place; false when a pivot is zero or the smallest is round-off of the largest.
// Every loop has bounds known at compile time and is unrolled, and the pivot row is exchanged by
// selects rather than by an index known only at run time: every entry has a fixed place, so the
// compiler keeps the matrix in registers (an exchange through a run-time index stored entries one
// by one that the next column's update then loaded two at a time, which stalls the load).
template <int N>
[[gnu::always_inline]] inline bool eliminate(std::array<double, N * N>& M, std::array<double, N>& r,
                                             std::array<double, N>& inverse) {
  double largest = 0.0;
  double smallest = std::numeric_limits<double>::infinity();
#pragma GCC unroll 8
  for (int c = 0; c < N; ++c) {
    int p = c;
    double best = std::abs(M[c + N * c]);
#pragma GCC unroll 8
    for (int i = c + 1; i < N; ++i) {
      const double candidate = std::abs(M[i + N * c]);
      if (candidate > best) {
        best = candidate;
        p = i;
      }
    }
#pragma GCC unroll 8
    for (int i = c + 1; i < N; ++i) {
      const bool exchange = p == i;
#pragma GCC unroll 8
      for (int j = c; j < N; ++j) {
        const double top = M[c + N * j], other = M[i + N * j];
        M[c + N * j] = exchange ? other : top;
        M[i + N * j] = exchange ? top : other;
      }
      const double top = r[c], other = r[i];
      r[c] = exchange ? other : top;
      r[i] = exchange ? top : other;
    }
    const double pivot = M[c + N * c];
    largest = std::max(largest, std::abs(pivot));
    smallest = std::min(smallest, std::abs(pivot));
    if (pivot == 0.0) return false;
    // For the back-substitution, off its chain of dependent steps; the last unknown divides there.
    if (c + 1 < N) inverse[c] = 1.0 / pivot;
    // A division, not a product with 1/pivot: a row equal to the pivot row then has l = 1 exactly
    // and cancels to zero, so that dependent rows are found singular as Eigen finds them. The
    // multipliers are kept in the pivot's column.
#pragma GCC unroll 8
    for (int i = c + 1; i < N; ++i) M[i + N * c] /= pivot;
#pragma GCC unroll 8
    for (int j = c + 1; j < N; ++j) {
      const double above = M[c + N * j];
#pragma GCC unroll 8
      for (int i = c + 1; i < N; ++i) M[i + N * j] -= M[i + N * c] * above;
    }
#pragma GCC unroll 8
    for (int i = c + 1; i < N; ++i) r[i] -= M[i + N * c] * r[c];
  }
  return smallest > largest * kEps * N;
}

// The stacked system [D A; b] q'' = [D h; -b0] with h = Q + G, by Gaussian elimination with
// partial pivoting, then R = A q'' - h. The singularity test is that of factor_equilibrated
// (sanh.hpp): the smallest pivot against the largest, rows in very different units scaled first. Returns false when the system is singular.
template <int N, int S>
bool solve_stacked(const double* A, const double* Q, const double* G, const double* b, const double* b0,
                   const double* D, double* h, double* qdd, double* R) {
  constexpr int K = N - S;
  std::array<double, N * N> M;
  std::array<double, N> r;
  for (int i = 0; i < N; ++i) h[i] = Q[i] + G[i];
  for (int i = 0; i < K; ++i) {
    for (int c = 0; c < N; ++c) {
      double acc = 0.0;
      for (int l = 0; l < N; ++l) acc += D[i + K * l] * A[l + N * c];
      M[i + N * c] = acc;
    }
    double acc = 0.0;
    for (int l = 0; l < N; ++l) acc += D[i + K * l] * h[l];
    r[i] = acc;
  }
  for (int i = 0; i < S; ++i) {
    for (int c = 0; c < N; ++c) M[K + i + N * c] = b[i + S * c];
    r[K + i] = -b0[i];
  }
  // Rows in very different units scaled first, as factor_equilibrated does (row_scaling.hpp).
  std::array<double, N> row{};
  for (int c = 0; c < N; ++c)  // down each column (storage order): the same maxima, vectorized
    for (int i = 0; i < N; ++i) row[i] = std::max(row[i], std::abs(M[i + N * c]));
  scale_rows_by_powers_of_two(
      N, [&](int i) { return row[i]; },
      [&](int i, int exponent) {
        for (int c = 0; c < N; ++c) M[i + N * c] = std::ldexp(M[i + N * c], -exponent);
        r[i] = std::ldexp(r[i], -exponent);
      });
  std::array<double, N> inverse;
  const bool regular = eliminate<N>(M, r, inverse);
  if (!regular) return false;
  // In a local array, not through the output pointer, which may alias the inputs as far as the
  // compiler knows: each entry would be stored and loaded again by the next row.
  std::array<double, N> x;
#pragma GCC unroll 8
  for (int i = N - 1; i >= 0; --i) {
    double acc = r[i];
#pragma GCC unroll 8
    for (int j = i + 1; j < N; ++j) acc -= M[i + N * j] * x[j];
    x[i] = i == N - 1 ? acc / M[i + N * i] : acc * inverse[i];
  }
  for (int i = 0; i < N; ++i) {
    double acc = -h[i];
    for (int j = 0; j < N; ++j) acc += A[i + N * j] * x[j];
    R[i] = acc;
  }
  std::copy(x.begin(), x.end(), qdd);
  return true;
}

// What sanh_qr found: the first failure in the order the separate kernels and checks meet them.
enum class SanhResult { ok, dependent_constraints, singular, non_finite_qdd, non_finite_R };

// The sanh formulation with the QR complement in one call: null_space_basis, solve_stacked and
// the finiteness test of q'' and R (core/detail/finite.hpp's accumulate_non_finite, inlined at
// this size), as the separate calls do them. One call instead of four, the two kernels inlined into it (flatten), lets D stay
// in registers between them and saves the calls' fixed costs: at n = 3 a right-hand side 10 %
// faster than the four calls.
template <int N, int S>
[[gnu::flatten]] SanhResult sanh_qr(const double* A, const double* Q, const double* G, const double* b,
                                    const double* b0, const int* order, double* D, double* h, double* qdd,
                                    double* R) {
  if (!null_space_basis<N, S>(b, order, D)) return SanhResult::dependent_constraints;
  if (!solve_stacked<N, S>(A, Q, G, b, b0, D, h, qdd, R)) return SanhResult::singular;
  if (accumulate_non_finite(0.0, qdd, N) != 0.0) return SanhResult::non_finite_qdd;  // NaN != 0 too
  if (accumulate_non_finite(0.0, R, N) != 0.0) return SanhResult::non_finite_R;
  return SanhResult::ok;
}

}  // namespace nhdyn::small

namespace nhdyn::small {

// The instantiations of the kernels above for one (n, s).
struct Kernels {
  bool (*null_space_basis)(const double* b, const int* order, double* D);
  bool (*solve_stacked)(const double* A, const double* Q, const double* G, const double* b, const double* b0,
                        const double* D, double* h, double* qdd, double* R);
  SanhResult (*sanh_qr)(const double* A, const double* Q, const double* G, const double* b, const double* b0,
                        const int* order, double* D, double* h, double* qdd, double* R);
};

// The kernels for n coordinates and s constraints, or nullptr when n > kSmallMaxN (the caller
// then takes the dynamic path).
const Kernels* find_kernels(int n, int s);

}  // namespace nhdyn::small
