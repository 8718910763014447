// The singularity test of the stacked matrix [D A; b] does not depend on the units of its rows
// (formulation/sanh.hpp, factor_equilibrated): the rows D A scale with the masses, the rows b do not,
// so `--set m=1e100` made the pivots differ by 1e100 and a well-posed system was called singular.
// Here a random well-posed system with its rows D A scaled by 1e100 or 1e-300 is solved, by the
// Eigen path and the fixed-size kernels, to the same q'' as unscaled (q'' does not depend on the
// scale: D (s A) q'' = D (s h)); and a singular one (two dependent rows) is still refused at
// every scale.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <random>
#include <vector>

#include "nhdyn/formulation/detail/row_scaling.hpp"
#include "nhdyn/formulation/sanh.hpp"
#include "nhdyn/formulation/detail/small_dense.hpp"

namespace nhdyn {
namespace {

constexpr int kN = 4, kS = 1, kK = kN - kS;

struct Stacked {
  Matrix A, b, D;
  Vector h, b0;
};

Stacked random_stacked(std::mt19937& rng) {
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  Stacked s;
  const Matrix L = Matrix::NullaryExpr(kN, kN, [&] { return u(rng); });
  s.A = L * L.transpose() + 0.5 * Matrix::Identity(kN, kN);
  s.b = Matrix::NullaryExpr(kS, kN, [&] { return u(rng); });
  // D: an orthonormal basis of null(b), rows.
  Eigen::FullPivLU<Matrix> lu(s.b);
  const Eigen::HouseholderQR<Matrix> qr(lu.kernel());
  s.D = (qr.householderQ() * Matrix::Identity(kN, kK)).transpose();
  s.h = Vector::NullaryExpr(kN, [&] { return u(rng); });
  s.b0 = Vector::NullaryExpr(kS, [&] { return u(rng); });
  return s;
}

// q'' by the Eigen path and its verdict; `scale` multiplies A and h (the masses' units).
bool solve_dense(const Stacked& s, double scale, Vector& qdd) {
  Matrix M(kN, kN);
  M.topRows(kK) = s.D * (scale * s.A);
  M.bottomRows(kS) = s.b;
  Vector rhs(kN);
  rhs.head(kK) = s.D * (scale * s.h);
  rhs.tail(kS) = -s.b0;
  Eigen::PartialPivLU<Matrix> lu(kN);
  if (!factor_equilibrated(M, rhs, lu)) return false;
  qdd = lu.solve(rhs);
  return true;
}

bool solve_small(const Stacked& s, double scale, Vector& qdd) {
  const Matrix A = scale * s.A;
  const Vector Q = scale * s.h, G = Vector::Zero(kN);
  Vector h(kN), R(kN);
  qdd.resize(kN);
  return small::solve_stacked<kN, kS>(A.data(), Q.data(), G.data(), s.b.data(), s.b0.data(), s.D.data(), h.data(),
                                      qdd.data(), R.data());
}

TEST(UnitScale, WellPosedSystemsAreSolvedAtAnyScale) {
  std::mt19937 rng(7);
  for (int trial = 0; trial < 20; ++trial) {
    const Stacked s = random_stacked(rng);
    Vector reference, qdd;
    ASSERT_TRUE(solve_dense(s, 1.0, reference));
    for (const double scale : {1e100, 1e-300, 1e150, 1e-150}) {
      ASSERT_TRUE(solve_dense(s, scale, qdd)) << "scale " << scale;
      EXPECT_LT((qdd - reference).norm(), 1e-12 * (1.0 + reference.norm())) << "scale " << scale;
      ASSERT_TRUE(solve_small(s, scale, qdd)) << "scale " << scale;
      EXPECT_LT((qdd - reference).norm(), 1e-12 * (1.0 + reference.norm())) << "scale " << scale;
    }
  }
}

TEST(UnitScale, SingularSystemsAreRefusedAtAnyScale) {
  std::mt19937 rng(11);
  for (int trial = 0; trial < 20; ++trial) {
    Stacked s = random_stacked(rng);
    s.D.row(1) = 2.0 * s.D.row(0);  // D A has two dependent rows: [D A; b] is singular
    Vector qdd;
    for (const double scale : {1.0, 1e100, 1e150, 1e-150, 1e-300}) {
      EXPECT_FALSE(solve_dense(s, scale, qdd)) << "scale " << scale;
      EXPECT_FALSE(solve_small(s, scale, qdd)) << "scale " << scale << " trial " << trial;
    }
  }
}

// The one scaling rule (row_scaling.hpp) that every solve of [D A; b] applies: rows within
// kRowScaleRatio of each other are left alone; beyond it every row gets the power of two that
// brings its largest entry into [0.5, 1), and a zero or non-finite row scales nothing.
TEST(UnitScale, RowsAreScaledByPowersOfTwoOnlyBeyondTheRatio) {
  const auto exponents = [](std::vector<double> row_max) {
    std::vector<int> out(row_max.size(), 0);
    const bool scaled = scale_rows_by_powers_of_two(
        static_cast<int>(row_max.size()), [&](int i) { return row_max[static_cast<std::size_t>(i)]; },
        [&](int i, int e) { out[static_cast<std::size_t>(i)] = e; });
    return scaled ? out : std::vector<int>{};
  };
  EXPECT_TRUE(exponents({1.0, 0.99 * kRowScaleRatio}).empty());
  EXPECT_EQ(exponents({1.0, 2.0 * kRowScaleRatio}), (std::vector<int>{1, 28}));
  EXPECT_EQ(exponents({3e-100, 0.75, 1e100}), (std::vector<int>{-330, 0, 333}));
  EXPECT_TRUE(exponents({0.0, 1e100}).empty());
  EXPECT_TRUE(exponents({1.0, std::numeric_limits<double>::infinity()}).empty());
  // Exact: a row times its factor and back is the row, bit for bit.
  std::vector<int> e = exponents({3e-100, 1e100});
  ASSERT_EQ(e.size(), 2u);
  EXPECT_EQ(std::ldexp(std::ldexp(3e-100, -e[0]), e[0]), 3e-100);
  EXPECT_GE(std::ldexp(3e-100, -e[0]), 0.5);
  EXPECT_LT(std::ldexp(3e-100, -e[0]), 1.0);
}

}  // namespace
}  // namespace nhdyn
