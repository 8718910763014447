#include "nhdyn/core/detail/finite.hpp"

#include <array>
#include <utility>

namespace nhdyn {
namespace {

// Adds x * 0 over M values to four sums side by side, unrolled.
template <int M>
inline void add_non_finite(double (&sum)[4], const double* x) {
#pragma GCC unroll 64
  for (int i = 0; i < M; ++i) sum[i & 3] += x[i] * 0.0;
}

// Copies M values from x to `out` as it adds x * 0 (x and out may be the same array).
template <int M>
inline void copy_non_finite(double (&sum)[4], const double* x, double* out) {
#pragma GCC unroll 64
  for (int i = 0; i < M; ++i) {
    const double value = x[i];
    sum[i & 3] += value * 0.0;
    out[i] = value;
  }
}

template <int N, int S>
double terms_non_finite(const double* q, const double* v, const double* A, const double* Q, const double* G,
                        const double* b, const double* b0, double* q_out, double* v_out) {
  double sum[4] = {0.0, 0.0, 0.0, 0.0};
  copy_non_finite<N>(sum, q, q_out);
  copy_non_finite<N>(sum, v, v_out);
  add_non_finite<N * N>(sum, A);
  add_non_finite<N>(sum, Q);
  add_non_finite<N>(sum, G);
  add_non_finite<S * N>(sum, b);
  add_non_finite<S>(sum, b0);
  return (sum[0] + sum[1]) + (sum[2] + sum[3]);
}

template <int N>
double pair_non_finite(const double* x, const double* y) {
  double sum[4] = {0.0, 0.0, 0.0, 0.0};
  add_non_finite<N>(sum, x);
  add_non_finite<N>(sum, y);
  return (sum[0] + sum[1]) + (sum[2] + sum[3]);
}

// The instantiations for 1 <= n <= kFixedFiniteMaxN and 0 <= s <= n, row by row: (n, s) at
// (n - 1) (n + 2) / 2 + s.
constexpr int kTermsEntries = kFixedFiniteMaxN * (kFixedFiniteMaxN + 3) / 2;
constexpr int terms_index(int n, int s) { return (n - 1) * (n + 2) / 2 + s; }

template <int N, int... S>
constexpr void fill_row(std::array<TermsNonFinite, kTermsEntries>& table, std::integer_sequence<int, S...>) {
  ((table[static_cast<std::size_t>(terms_index(N, S))] = &terms_non_finite<N, S>), ...);
}

template <int... N>
constexpr std::array<TermsNonFinite, kTermsEntries> make_terms_table(std::integer_sequence<int, N...>) {
  std::array<TermsNonFinite, kTermsEntries> table{};
  (fill_row<N + 1>(table, std::make_integer_sequence<int, N + 2>{}), ...);
  return table;
}

constexpr std::array<TermsNonFinite, kTermsEntries> kTermsTable =
    make_terms_table(std::make_integer_sequence<int, kFixedFiniteMaxN>{});

template <int... N>
constexpr std::array<PairNonFinite, kFixedFiniteMaxN> make_pair_table(std::integer_sequence<int, N...>) {
  return {&pair_non_finite<N + 1>...};
}

constexpr std::array<PairNonFinite, kFixedFiniteMaxN> kPairTable =
    make_pair_table(std::make_integer_sequence<int, kFixedFiniteMaxN>{});

}  // namespace

TermsNonFinite find_terms_non_finite(int n, int s) {
  if (n < 1 || n > kFixedFiniteMaxN || s < 0 || s > n) return nullptr;
  return kTermsTable[static_cast<std::size_t>(terms_index(n, s))];
}

PairNonFinite find_pair_non_finite(int n) {
  if (n < 1 || n > kFixedFiniteMaxN) return nullptr;
  return kPairTable[static_cast<std::size_t>(n - 1)];
}

}  // namespace nhdyn
