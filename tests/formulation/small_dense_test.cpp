// The fixed-size kernels for small n (formulation/detail/small_dense.hpp) against the dynamic Eigen
// path, on random systems of every size they cover and a few beyond: same q'' and R, a D that
// is an orthonormal basis of null(b), and the same verdict on dependent constraints and on a
// singular stacked matrix. Each q'' is also checked against the constraints and the equations
// projected on null(b), so that two paths that agreed on a wrong answer would still fail.
#include <gtest/gtest.h>

#include <limits>
#include <random>
#include <string>
#include <utility>
#include <vector>

#include "nhdyn/formulation/detail/small_dense.hpp"
#include "nhdyn/formulation/formulation.hpp"
#include "nhdyn/model/data.hpp"
#include "support/test_models.hpp"

namespace nhdyn {
namespace {

struct RandomSystem {
  Matrix A, b;
  Vector Q, b0;
};

RandomSystem random_system(int n, int s, std::mt19937& rng) {
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  RandomSystem r;
  const Matrix L = Matrix::NullaryExpr(n, n, [&] { return u(rng); });
  r.A = L * L.transpose() + 0.5 * Matrix::Identity(n, n);
  r.Q = Vector::NullaryExpr(n, [&] { return u(rng); });
  r.b = Matrix::NullaryExpr(s, n, [&] { return u(rng); });
  r.b0 = Vector::NullaryExpr(s, [&] { return u(rng); });
  return r;
}

struct SmallSolution {
  Status status;
  Matrix D;
  Vector qdd, R;
};

SmallSolution solve(const Model& model, bool small, Complement complement, Formulation method = Formulation::sanh) {
  Data data = make_data(model);
  data.small_kernels = small;
  SmallSolution s;
  s.status = compute_dynamics(model, data, {method, complement}, 0.0, model.q0.data(), model.v0.data());
  s.D = data.D;
  s.qdd = data.qdd;
  s.R = data.R;
  return s;
}

TEST(SmallKernels, SameAccelerationsAsTheDynamicPathForEverySize) {
  std::mt19937 rng(20261123);
  for (int n = 1; n <= 10; ++n) {
    for (int s = 0; s < n; ++s) {
      for (int trial = 0; trial < 3; ++trial) {
        const RandomSystem sys = random_system(n, s, rng);
        const Model model = testing::make_constant_model(sys.A, sys.Q, sys.b, sys.b0);
        const std::string where = "n = " + std::to_string(n) + ", s = " + std::to_string(s);
        for (Formulation method : {Formulation::sanh, Formulation::nullspace}) {
          for (Complement c : {Complement::qr, Complement::partition}) {
            const SmallSolution fast = solve(model, true, c, method);
            const SmallSolution slow = solve(model, false, c, method);
            ASSERT_EQ(fast.status, Status::ok) << where;
            ASSERT_EQ(slow.status, Status::ok) << where;
            const double scale = 1.0 + slow.qdd.norm();
            EXPECT_LT((fast.qdd - slow.qdd).norm(), 1e-10 * scale) << where;
            EXPECT_LT((fast.R - slow.R).norm(), 1e-10 * (1.0 + slow.R.norm())) << where;
            // The constraints hold, and the equations hold along null(b): R is normal to it.
            if (s > 0) {
              EXPECT_LT((sys.b * fast.qdd + sys.b0).norm(), 1e-10 * scale) << where;
            }
            EXPECT_LT((fast.D * (sys.A * fast.qdd - sys.Q)).norm(), 1e-10 * scale) << where;
          }
        }
        const SmallSolution qr = solve(model, true, Complement::qr);
        ASSERT_EQ(qr.D.rows(), n - s);
        if (s > 0) {
          EXPECT_LT((qr.D * sys.b.transpose()).norm(), 1e-12) << where << ": D b^T";
        }
        EXPECT_LT((qr.D * qr.D.transpose() - Matrix::Identity(n - s, n - s)).norm(), 1e-12)
            << where << ": D D^T";
      }
    }
  }
}

// The coordinates b never touches are rows of D of their own (null_space_basis, Data::bt_order):
// a free body's position x, y, z before its unit quaternion, b = 2 e^T on the last four. Taken
// first, x was the reflector's coordinate and every other row of D mixed it into the quaternion's.
// Both paths, a quaternion at a general orientation.
TEST(SmallKernels, CoordinatesTheConstraintsDoNotTouchAreRowsOfDOfTheirOwn) {
  std::mt19937 rng(3);
  RandomSystem sys = random_system(7, 1, rng);
  Eigen::Vector4d e(0.3, -0.5, 0.7, 0.4);
  e.normalize();
  sys.b.setZero();
  sys.b.rightCols(4) = 2.0 * e.transpose();
  const Model model = testing::make_constant_model(sys.A, sys.Q, sys.b, sys.b0);
  for (const bool small : {true, false}) {
    const SmallSolution r = solve(model, small, Complement::qr);
    ASSERT_EQ(r.status, Status::ok);
    ASSERT_EQ(r.D.rows(), 6);
    // Three rows are the unit vectors of x, y and z (up to sign), exactly; the three others have
    // no x, y, z part at all.
    std::vector<int> unit_of(3, 0);
    for (int i = 0; i < 6; ++i) {
      const double position_part = r.D.row(i).head(3).cwiseAbs().maxCoeff();
      if (position_part == 0.0) continue;
      int j = 0;
      r.D.row(i).head(3).cwiseAbs().maxCoeff(&j);
      EXPECT_EQ(std::abs(r.D(i, j)), 1.0) << "small " << small << ", row " << i;
      EXPECT_EQ(r.D.row(i).cwiseAbs().sum(), 1.0) << "small " << small << ", row " << i;
      ++unit_of[static_cast<std::size_t>(j)];
    }
    EXPECT_EQ(unit_of, (std::vector<int>{1, 1, 1})) << "small " << small;
    EXPECT_LT((r.D * sys.b.transpose()).norm(), 1e-15) << "small " << small;
    EXPECT_LT((r.D * r.D.transpose() - Matrix::Identity(6, 6)).norm(), 1e-14) << "small " << small;
    EXPECT_LT((sys.b * r.qdd + sys.b0).norm(), 1e-13) << "small " << small;
    EXPECT_LT((r.D * (sys.A * r.qdd - sys.Q)).norm(), 1e-12 * (1.0 + r.qdd.norm())) << "small " << small;
  }
  // The nullspace formulation reads the same factorization for its particular solution.
  const SmallSolution stacked = solve(model, false, Complement::qr);
  for (const bool small : {true, false}) {
    const SmallSolution nullspace = solve(model, small, Complement::qr, Formulation::nullspace);
    ASSERT_EQ(nullspace.status, Status::ok);
    EXPECT_LT((nullspace.qdd - stacked.qdd).norm(), 1e-12 * (1.0 + stacked.qdd.norm())) << "small " << small;
  }
}

TEST(SmallKernels, DependentConstraintsAreRefusedAsOnTheDynamicPath) {
  std::mt19937 rng(7);
  for (int n : {3, 4, 8}) {
    RandomSystem sys = random_system(n, 2, rng);
    sys.b.row(1) = 3.0 * sys.b.row(0);
    const Model model = testing::make_constant_model(sys.A, sys.Q, sys.b, sys.b0);
    EXPECT_EQ(solve(model, true, Complement::qr).status, Status::dependent_constraints) << "n = " << n;
    EXPECT_EQ(solve(model, false, Complement::qr).status, Status::dependent_constraints) << "n = " << n;
  }
}

TEST(SmallKernels, SingularStackedMatrixIsRefusedAsOnTheDynamicPath) {
  // A zero inertia matrix makes D A zero: the stacked matrix has rank s < n.
  std::mt19937 rng(11);
  for (int n : {2, 3, 6}) {
    RandomSystem sys = random_system(n, 1, rng);
    sys.A.setZero();
    const Model model = testing::make_constant_model(sys.A, sys.Q, sys.b, sys.b0);
    EXPECT_EQ(solve(model, true, Complement::qr).status, Status::singular_system) << "n = " << n;
    EXPECT_EQ(solve(model, false, Complement::qr).status, Status::singular_system) << "n = " << n;
  }
}

// The fused kernel (small_dense.hpp's sanh_qr) reports an overflow in q'' or in R as the
// separate calls do: the same status and the same quantity named, on both paths.
TEST(SmallKernels, OverflowInTheAccelerationsOrTheReactionsIsNamedAsOnTheDynamicPath) {
  const auto failure = [](const Model& model, bool small) {
    Data data = make_data(model);
    data.small_kernels = small;
    const Status status =
        compute_dynamics(model, data, {Formulation::sanh, Complement::qr}, 0.0, model.q0.data(), model.v0.data());
    return std::make_pair(status, data.failed_quantity);
  };
  // q'': the rows D A (of order 1e-300) are scaled up to meet b's, and D h = D Q (1e300) with them.
  Matrix b(1, 2);
  b << 1.0, 0.0;
  Vector Q(2);
  Q << 0.0, 1e300;
  const Model tiny_masses = testing::make_constant_model(1e-300 * Matrix::Identity(2, 2), Q, b, Vector::Zero(1));
  for (bool small : {true, false}) {
    const auto [status, quantity] = failure(tiny_masses, small);
    EXPECT_EQ(status, Status::non_finite) << small;
    EXPECT_EQ(quantity, "accelerations q''") << small;
  }
  // R alone: b q'' = -b0 gives q''_0 = 1e10, finite, and A q'' = 1e310 overflows.
  Vector b0(1);
  b0 << -1e10;
  const Model huge_masses = testing::make_constant_model(1e300 * Matrix::Identity(2, 2), Vector::Zero(2), b, b0);
  for (bool small : {true, false}) {
    const auto [status, quantity] = failure(huge_masses, small);
    EXPECT_EQ(status, Status::non_finite) << small;
    EXPECT_EQ(quantity, "reactions R") << small;
  }
}

// compute_dynamics takes the fused kernel without testing the terms apart: it relies on a NaN or
// an infinity anywhere in A, Q, G, b or b0 making the kernel fail (q'' or R not finite, or a
// rank or pivot test failing). Every entry of every term, at every size the kernel covers, with
// each of NaN, +inf and -inf, on an otherwise regular system.
TEST(SmallKernels, EveryNonFiniteTermMakesTheFusedKernelFail) {
  std::mt19937 rng(20261205);
  const double bad_values[] = {std::numeric_limits<double>::quiet_NaN(), std::numeric_limits<double>::infinity(),
                               -std::numeric_limits<double>::infinity()};
  long tried = 0;
  for (int n = 1; n <= small::kSmallMaxN; ++n) {
    for (int s = 0; s <= n; ++s) {
      const small::Kernels* kernels = small::find_kernels(n, s);
      ASSERT_NE(kernels, nullptr) << n << " " << s;
      const RandomSystem sys = random_system(n, s, rng);
      const Vector G = Vector::NullaryExpr(n, [&] { return std::uniform_real_distribution<double>(-1, 1)(rng); });
      std::vector<std::vector<double>> terms = {
          std::vector<double>(sys.A.data(), sys.A.data() + sys.A.size()),
          std::vector<double>(sys.Q.data(), sys.Q.data() + n), std::vector<double>(G.data(), G.data() + n),
          std::vector<double>(sys.b.data(), sys.b.data() + sys.b.size()),
          std::vector<double>(sys.b0.data(), sys.b0.data() + s)};
      std::vector<double> D(static_cast<std::size_t>((n - s) * n) + 1), h(static_cast<std::size_t>(n)),
          qdd(static_cast<std::size_t>(n)), R(static_cast<std::size_t>(n));
      const auto run = [&] {
        return kernels->sanh_qr(terms[0].data(), terms[1].data(), terms[2].data(), terms[3].data(), terms[4].data(),
                                nullptr, D.data(), h.data(), qdd.data(), R.data());
      };
      // The system itself is regular, s = n (a single point) included.
      ASSERT_EQ(run(), small::SanhResult::ok) << "n = " << n << ", s = " << s;
      const char* names[] = {"A", "Q", "G", "b", "b0"};
      for (std::size_t term = 0; term < terms.size(); ++term)
        for (double& entry : terms[term]) {
          const double kept = entry;
          for (double bad : bad_values) {
            entry = bad;
            EXPECT_NE(run(), small::SanhResult::ok) << "n = " << n << ", s = " << s << ", " << names[term] << "["
                                                     << (&entry - terms[term].data()) << "] = " << bad;
            ++tried;
          }
          entry = kept;
        }
    }
  }
  EXPECT_GT(tried, 3000);
}

// The fused path of compute_dynamics names a non-finite term as the separate kernels do: the
// same status and the same quantity as with the fixed-size kernels off, for each term.
TEST(SmallKernels, ANonFiniteTermIsNamedAsOnTheDynamicPath) {
  std::mt19937 rng(5);
  const double nan = std::numeric_limits<double>::quiet_NaN();
  for (const char* term : {"inertia matrix A", "generalized forces Q", "constraint matrix b", "constraint term b0"}) {
    RandomSystem sys = random_system(3, 1, rng);
    const std::string name = term;
    if (name == "inertia matrix A") sys.A(2, 1) = nan;
    if (name == "generalized forces Q") sys.Q(1) = std::numeric_limits<double>::infinity();
    if (name == "constraint matrix b") sys.b(0, 2) = nan;
    if (name == "constraint term b0") sys.b0(0) = -std::numeric_limits<double>::infinity();
    const Model model = testing::make_constant_model(sys.A, sys.Q, sys.b, sys.b0);
    for (bool small : {true, false}) {
      Data data = make_data(model);
      data.small_kernels = small;
      const Status status =
          compute_dynamics(model, data, {Formulation::sanh, Complement::qr}, 0.0, model.q0.data(), model.v0.data());
      EXPECT_EQ(status, Status::non_finite) << name << " " << small;
      EXPECT_EQ(data.failed_quantity, name) << small;
      EXPECT_EQ(data.stage, Stage::empty) << name << " " << small;
    }
  }
}

}  // namespace
}  // namespace nhdyn
