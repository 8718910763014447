// The fixed-size finiteness tests of core/detail/finite.hpp against their definition: for every
// (n, s) of the table, all-finite terms (huge, tiny, -0) give 0, and a NaN, +inf or -inf at any
// place of any of q, q', A, Q, G, b, b0 gives a non-zero result; the same for the pair q'', R.
#include "nhdyn/core/detail/finite.hpp"

#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <cstring>
#include <limits>
#include <vector>

namespace nhdyn {
namespace {

constexpr double kBad[] = {std::numeric_limits<double>::quiet_NaN(), std::numeric_limits<double>::infinity(),
                           -std::numeric_limits<double>::infinity()};

// Finite values of every kind a term takes, cycled through an array.
double finite_value(std::size_t i) {
  constexpr double values[] = {1.0, -0.0, 1e308, -1e-308, 4.9e-324, 0.5, -3.25};
  return values[i % std::size(values)];
}

TEST(FixedFinite, TermsTestFindsEveryNonFiniteValue) {
  for (int n = 1; n <= kFixedFiniteMaxN; ++n)
    for (int s = 0; s <= n; ++s) {
      const TermsNonFinite test = find_terms_non_finite(n, s);
      ASSERT_NE(test, nullptr) << "n = " << n << ", s = " << s;
      const std::size_t un = static_cast<std::size_t>(n), us = static_cast<std::size_t>(s);
      std::array<std::vector<double>, 7> arrays{std::vector<double>(un), std::vector<double>(un),
                                                std::vector<double>(un * un), std::vector<double>(un),
                                                std::vector<double>(un), std::vector<double>(us * un),
                                                std::vector<double>(us)};
      std::size_t k = 0;
      for (std::vector<double>& a : arrays)
        for (double& x : a) x = finite_value(k++);
      std::vector<double> q_out(un, -1.0), v_out(un, -1.0);
      const auto run = [&] {
        return test(arrays[0].data(), arrays[1].data(), arrays[2].data(), arrays[3].data(), arrays[4].data(),
                    arrays[5].data(), arrays[6].data(), q_out.data(), v_out.data());
      };
      EXPECT_EQ(run(), 0.0) << "n = " << n << ", s = " << s;
      // The state is stored bit for bit (a -0.0 and a subnormal among its values).
      for (std::size_t i = 0; i < un; ++i) {
        EXPECT_EQ(std::memcmp(&q_out[i], &arrays[0][i], sizeof(double)), 0) << "q, n = " << n << ", i = " << i;
        EXPECT_EQ(std::memcmp(&v_out[i], &arrays[1][i], sizeof(double)), 0) << "v, n = " << n << ", i = " << i;
      }
      for (std::vector<double>& a : arrays)
        for (double& x : a) {
          const double kept = x;
          for (const double bad : kBad) {
            x = bad;
            EXPECT_TRUE(std::isnan(run())) << "n = " << n << ", s = " << s << ", value " << bad;
          }
          x = kept;
        }
    }
  EXPECT_EQ(find_terms_non_finite(kFixedFiniteMaxN + 1, 1), nullptr);
  EXPECT_EQ(find_terms_non_finite(3, 4), nullptr);  // more rows than coordinates: tested array by array
  EXPECT_EQ(find_terms_non_finite(0, 0), nullptr);
}

TEST(FixedFinite, PairTestFindsEveryNonFiniteValue) {
  for (int n = 1; n <= kFixedFiniteMaxN; ++n) {
    const PairNonFinite test = find_pair_non_finite(n);
    ASSERT_NE(test, nullptr) << "n = " << n;
    std::vector<double> x(static_cast<std::size_t>(n)), y(static_cast<std::size_t>(n));
    for (std::size_t i = 0; i < x.size(); ++i) {
      x[i] = finite_value(i);
      y[i] = finite_value(i + 3);
    }
    EXPECT_EQ(test(x.data(), y.data()), 0.0);
    for (std::vector<double>* a : {&x, &y})
      for (double& v : *a) {
        const double kept = v;
        for (const double bad : kBad) {
          v = bad;
          EXPECT_TRUE(std::isnan(test(x.data(), y.data()))) << "n = " << n << ", value " << bad;
          // The test array by array agrees.
          EXPECT_TRUE(std::isnan(accumulate_non_finite(accumulate_non_finite(0.0, x.data(), n), y.data(), n)));
        }
        v = kept;
      }
  }
  EXPECT_EQ(find_pair_non_finite(kFixedFiniteMaxN + 1), nullptr);
}

}  // namespace
}  // namespace nhdyn
