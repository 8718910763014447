#include "nhdyn/formulation/detail/small_dense.hpp"

#include <utility>

namespace nhdyn::small {
namespace {

// kTable[n][s] for 1 <= n <= kSmallMaxN, 0 <= s <= n; other entries stay empty.
template <int N, int... S>
constexpr void fill_row(std::array<std::array<Kernels, kSmallMaxN + 1>, kSmallMaxN + 1>& table,
                        std::integer_sequence<int, S...>) {
  ((table[N][S] = Kernels{&null_space_basis<N, S>, &solve_stacked<N, S>, &sanh_qr<N, S>}), ...);
}

template <int... N>
constexpr std::array<std::array<Kernels, kSmallMaxN + 1>, kSmallMaxN + 1> make_table(
    std::integer_sequence<int, N...>) {
  std::array<std::array<Kernels, kSmallMaxN + 1>, kSmallMaxN + 1> table{};
  (fill_row<N + 1>(table, std::make_integer_sequence<int, N + 2>{}), ...);
  return table;
}

constexpr auto kTable = make_table(std::make_integer_sequence<int, kSmallMaxN>{});

}  // namespace

const Kernels* find_kernels(int n, int s) {
  if (n < 1 || n > kSmallMaxN || s < 0 || s > n) return nullptr;
  return &kTable[static_cast<std::size_t>(n)][static_cast<std::size_t>(s)];
}

}  // namespace nhdyn::small
