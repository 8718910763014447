// SparseLuFactor (model/sparse_lu.hpp), the sparse path's LU of b_dep: its solutions against a
// dense LU of the same matrices, the reuse of the pivot order while it is good and a new search once
// it is not, and singular matrices refused.
#include <gtest/gtest.h>

#include <Eigen/LU>
#include <algorithm>
#include <cmath>
#include <random>
#include <stdexcept>
#include <vector>

#include "nhdyn/model/sparse_lu.hpp"

namespace {

using nhdyn::Matrix;
using nhdyn::SparseLuFactor;
using nhdyn::SparseMatrix;

SparseMatrix sparse(const Matrix& dense) {
  SparseMatrix m = dense.sparseView();
  m.makeCompressed();
  return m;
}

// A chain-like matrix: a diagonal, a subdiagonal and a few entries far from both, each value
// drawn again at every call with the same pattern (`values` seeds the values only).
SparseMatrix banded(int n, unsigned values) {
  std::mt19937 random(values);
  std::uniform_real_distribution<double> u(0.5, 2.0);
  std::vector<Eigen::Triplet<double, int>> entries;
  for (int i = 0; i < n; ++i) {
    entries.emplace_back(i, i, u(random));
    if (i > 0) entries.emplace_back(i, i - 1, u(random) - 1.25);
    if (i % 7 == 3 && i + 5 < n) entries.emplace_back(i, i + 5, u(random) - 1.25);
  }
  SparseMatrix m(n, n);
  m.setFromTriplets(entries.begin(), entries.end());
  m.makeCompressed();
  return m;
}

TEST(SparseLuFactor, SolvesAsADenseLuDoesAndReusesItsPivotOrderWhileItIsGood) {
  const int n = 60;
  SparseLuFactor lu;
  lu.analyze(banded(n, 1));
  for (unsigned k = 1; k <= 5; ++k) {
    const SparseMatrix m = banded(n, k);
    ASSERT_TRUE(lu.factorize(m)) << k;
    Matrix rhs = Matrix::NullaryExpr(n, 3, [](Eigen::Index i, Eigen::Index j) { return std::sin(1.0 + i + 7.0 * j); });
    const Matrix expected = Matrix(m).partialPivLu().solve(rhs);
    lu.solve_in_place(rhs);
    EXPECT_LT((rhs - expected).cwiseAbs().maxCoeff(), 1e-12 * (1.0 + expected.cwiseAbs().maxCoeff())) << k;
  }
  EXPECT_EQ(lu.pivoting_factorizations(), 1);
  EXPECT_EQ(lu.reusing_factorizations(), 4);
}

TEST(SparseLuFactor, SearchesForPivotsAgainWhenTheReusedOrderDegrades) {
  // The first matrix pivots on its diagonal; the second, of the same pattern, has a diagonal entry
  // 1e-14: on the old order the elimination would amplify round-off by 1e14 (an error of order
  // 1e-2 in x), so the factorization searches again and x is exact to round-off.
  Matrix first(2, 2), second(2, 2);
  first << 1.0, 1.0, 0.1, 1.0;
  second << 1e-14, 1.0, 1.0, 1.0;
  SparseLuFactor lu;
  lu.analyze(sparse(first));
  ASSERT_TRUE(lu.factorize(sparse(first)));
  ASSERT_TRUE(lu.factorize(sparse(second)));
  EXPECT_EQ(lu.pivoting_factorizations(), 2);
  EXPECT_EQ(lu.reusing_factorizations(), 0);
  Matrix x(2, 1);
  x << 1.0, 2.0;
  lu.solve_in_place(x);
  const Matrix expected = second.fullPivLu().solve((Matrix(2, 1) << 1.0, 2.0).finished());
  EXPECT_LT((x - expected).cwiseAbs().maxCoeff(), 1e-14);
  // And back to a matrix the new order suits: reused.
  ASSERT_TRUE(lu.factorize(sparse(second)));
  EXPECT_EQ(lu.reusing_factorizations(), 1);
}

TEST(SparseLuFactor, KeepsItsSolutionsAccurateAsTheMatrixDriftsFromWhereItsOrderWasSearched) {
  // Twenty 2 x 2 blocks [e 1; 1 1] chained by a subdiagonal, e shrinking from 2 to 2e-10 over 60
  // calls: the order searched at e = 2 pivots on e, whose growth 1/e would cost ten digits by the
  // end. Each solution's backward error stays at round-off: the order is searched again as the
  // growth creeps up.
  const int blocks = 20, n = 2 * blocks;
  auto matrix = [&](double e) {
    std::vector<Eigen::Triplet<double, int>> entries;
    for (int b = 0; b < blocks; ++b) {
      const int i = 2 * b;
      entries.emplace_back(i, i, e);
      entries.emplace_back(i, i + 1, 1.0);
      entries.emplace_back(i + 1, i, 1.0);
      entries.emplace_back(i + 1, i + 1, 1.0);
      if (b > 0) entries.emplace_back(i, i - 1, 0.5);
    }
    SparseMatrix m(n, n);
    m.setFromTriplets(entries.begin(), entries.end());
    m.makeCompressed();
    return m;
  };
  SparseLuFactor lu;
  lu.analyze(matrix(2.0));
  double worst = 0.0;
  for (int k = 0; k <= 60; ++k) {
    const double e = 2.0 * std::pow(10.0, -k / 6.0);
    const SparseMatrix m = matrix(e);
    ASSERT_TRUE(lu.factorize(m)) << k;
    const Matrix rhs = Matrix::NullaryExpr(n, 1, [](Eigen::Index i, Eigen::Index) { return std::cos(0.3 * i); });
    Matrix x = rhs;
    lu.solve_in_place(x);
    const Matrix dense = Matrix(m);
    const double backward = (dense * x - rhs).cwiseAbs().maxCoeff() /
                            (dense.cwiseAbs().rowwise().sum().maxCoeff() * x.cwiseAbs().maxCoeff());
    worst = std::max(worst, backward);
  }
  EXPECT_LT(worst, 1e-15);
  EXPECT_GT(lu.reusing_factorizations(), 0);  // and the order was kept where it could be
  EXPECT_GT(lu.pivoting_factorizations(), 1);
}

TEST(SparseLuFactor, RefusesASingularMatrixAndFactorsTheNextOne) {
  Matrix good(3, 3), singular(3, 3);
  good << 2, 1, 0, 1, 3, 1, 0, 1, 4;
  singular << 1, 1, 0, 1, 1, 0, 0, 1, 4;  // two equal rows, same pattern
  SparseLuFactor lu;
  lu.analyze(sparse(good));
  ASSERT_TRUE(lu.factorize(sparse(good)));
  EXPECT_FALSE(lu.factorize(sparse(singular)));
  Matrix x = Matrix::Ones(3, 1);
  EXPECT_THROW(lu.solve_in_place(x), std::logic_error);  // no factorization after the failed one
  ASSERT_TRUE(lu.factorize(sparse(good)));
  lu.solve_in_place(x);
  EXPECT_LT((good * x - Matrix::Ones(3, 1)).cwiseAbs().maxCoeff(), 1e-15);
}

TEST(SparseLuFactor, SaysWhatIsMissingWhenCalledOutOfOrder) {
  SparseLuFactor lu;
  Matrix eye = Matrix::Identity(2, 2);
  EXPECT_THROW(lu.factorize(sparse(eye)), std::logic_error);
  Matrix rectangular = Matrix::Ones(2, 3);
  EXPECT_THROW(lu.analyze(sparse(rectangular)), std::logic_error);
}

}  // namespace
