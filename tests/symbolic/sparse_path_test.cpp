// The sparse path against the dense one: a model compiled sparse writes the same terms, and the
// sparse sanh and KKT solves (one Data made on the sparse path, model/data.hpp) give the dense
// formulations' accelerations and reactions, at states away from the initial one; the invariants
// b q'' + b0 = 0 and D R = 0 hold. Bad uses are refused.
#include <gtest/gtest.h>

#include <random>

#include "nhdyn/core/error.hpp"
#include "nhdyn/formulation/formulation.hpp"
#include "nhdyn/model/data.hpp"
#include "nhdyn/model/terms.hpp"
#include "nhdyn/symbolic/chain.hpp"
#include "nhdyn/symbolic/compile.hpp"
#include "nhdyn/symbolic/spec_builder.hpp"

namespace nhdyn {
namespace {

using symbolic::CompileOptions;
using symbolic::TermsLayout;

Model chain(int bodies, TermsLayout layout) {
  symbolic::ChainParameters p;
  p.bodies = bodies;
  return symbolic::compile_model(symbolic::make_chain_spec(p), CompileOptions{layout});
}

double relative(const Vector& x, const Vector& reference) {
  return (x - reference).norm() / std::max(reference.norm(), 1e-300);
}

TEST(SparsePath, ChainPatternHoldsOnlyTheNonzeros) {
  const Model sparse = chain(10, TermsLayout::sparse);
  const TermsSparsity* pattern = sparse.evaluator->sparsity();
  ASSERT_NE(pattern, nullptr);
  // Per body: A couples x, y with theta (5 nonzeros in 3 columns... 3 diagonal + 4 off-diagonal);
  // b: blade row 2 entries, each pin row 4 entries.
  EXPECT_EQ(pattern->A.nonzeros(), 10 * 7);
  EXPECT_EQ(pattern->b.nonzeros(), 10 * 2 + 9 * 2 * 4);
  EXPECT_EQ(chain(10, TermsLayout::dense).evaluator->sparsity(), nullptr);
  // automatic: dense below kSparseFrom coordinates, sparse from there on.
  EXPECT_EQ(chain(10, TermsLayout::automatic).evaluator->sparsity(), nullptr);
  EXPECT_NE(chain(22, TermsLayout::automatic).evaluator->sparsity(), nullptr);
}

TEST(SparsePath, DenseTermsOfASparseModelAreTheDenseModelsTerms) {
  const Model sparse = chain(4, TermsLayout::sparse), dense = chain(4, TermsLayout::dense);
  DataOptions dense_path;
  dense_path.path = Path::dense;
  Data ds = make_data(sparse, dense_path), dd = make_data(dense);
  EXPECT_FALSE(ds.sparse);
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  for (int trial = 0; trial < 5; ++trial) {
    Vector q = sparse.q0, v = sparse.v0;
    for (int i = 0; i < sparse.n(); ++i) {
      q[i] += 0.3 * u(rng);
      v[i] += u(rng);
    }
    ASSERT_EQ(compute_terms(sparse, ds, 0.0, q.data(), v.data()), Status::ok);
    ASSERT_EQ(compute_terms(dense, dd, 0.0, q.data(), v.data()), Status::ok);
    EXPECT_LE((ds.A - dd.A).norm(), 1e-14 * dd.A.norm());
    EXPECT_LE((ds.b - dd.b).norm(), 1e-14 * dd.b.norm());
    EXPECT_LE((ds.Q + ds.G - dd.Q - dd.G).norm(), 1e-14 * (1.0 + (dd.Q + dd.G).norm()));
    EXPECT_LE((ds.b0 - dd.b0).norm(), 1e-14 * (1.0 + dd.b0.norm()));
  }
}

TEST(SparsePath, SanhAndKktGiveTheDenseAccelerationsAndReactions) {
  for (const int bodies : {1, 3, 12}) {
    SCOPED_TRACE(bodies);
    const Model sparse = chain(bodies, TermsLayout::sparse), dense = chain(bodies, TermsLayout::dense);
    Data sd = make_data(sparse);
    ASSERT_TRUE(sd.sparse);
    Data dd = make_data(dense);
    std::mt19937 rng(11);
    std::uniform_real_distribution<double> u(-1.0, 1.0);
    for (int trial = 0; trial < 4; ++trial) {
      Vector q = sparse.q0, v = sparse.v0;
      for (int i = 0; i < sparse.n(); ++i) {
        q[i] += 0.2 * u(rng);
        v[i] += u(rng);
      }
      ASSERT_EQ(compute_dynamics(dense, dd, FormulationOptions(Formulation::lagrange), 0.0, q.data(), v.data()),
                Status::ok);
      ASSERT_EQ(compute_dynamics(sparse, sd, FormulationOptions(Formulation::sanh), 0.0, q.data(), v.data()), Status::ok)
          << sd.failed_quantity;
      EXPECT_LT(relative(sd.qdd, dd.qdd), 1e-11);
      EXPECT_LT(relative(sd.R, dd.R), 1e-10);
      // Invariants of the solution itself: the constraints at acceleration level, and reactions
      // that do no work along the motions D allows.
      const Matrix b = Matrix(sd.b_sparse);
      EXPECT_LT((b * sd.qdd + sd.b0).norm(), 1e-11 * (1.0 + sd.b0.norm() + b.norm() * sd.qdd.norm()));
      EXPECT_LT((sd.D * b.transpose()).norm(), 1e-12 * b.norm());
      EXPECT_LT((sd.D * sd.R).norm(), 1e-12 * sd.D.norm() * (1.0 + sd.R.norm())) << sd.D.norm();

      const Vector sanh_qdd = sd.qdd;
      ASSERT_EQ(compute_dynamics(sparse, sd, FormulationOptions(Formulation::lagrange), 0.0, q.data(), v.data()),
                Status::ok)
          << sd.failed_quantity;
      EXPECT_LT(relative(sd.qdd, dd.qdd), 1e-11);
      EXPECT_LT(relative(sd.R, dd.R), 1e-10);
      EXPECT_LT(relative(sd.lambda, dd.lambda), 1e-10);
      EXPECT_LT(relative(sanh_qdd, sd.qdd), 1e-11);
    }
  }
}

TEST(SparsePath, UnconstrainedModelNeedsNoPartition) {
  symbolic::SpecBuilder b("free");
  b.coordinate("x").coordinate("y").parameter("m", 2.0).parameter("g", 9.81);
  b.kinetic_energy("m/2*(x'^2 + y'^2)").potential_energy("m*g*y");
  const Model model = symbolic::compile_model(b.build(), CompileOptions{TermsLayout::sparse});
  Data d = make_data(model);
  ASSERT_TRUE(d.sparse);
  EXPECT_TRUE(d.dependent.empty());
  EXPECT_EQ(d.D.size(), 0);  // no k x n complement without constraints: a sparse Cholesky factorization of A
  ASSERT_EQ(compute_dynamics(model, d, FormulationOptions(Formulation::sanh), 0.0, model.q0.data(), model.v0.data()),
            Status::ok);
  EXPECT_NEAR(d.qdd[0], 0.0, 1e-15);
  EXPECT_NEAR(d.qdd[1], -9.81, 1e-14);
  ASSERT_EQ(compute_dynamics(model, d, FormulationOptions(Formulation::lagrange), 0.0, model.q0.data(), model.v0.data()),
            Status::ok);
  EXPECT_NEAR(d.qdd[1], -9.81, 1e-14);
}

TEST(SparsePathBadInput, ADenseModelIsRefusedWithTheWayOut) {
  const Model dense = chain(2, TermsLayout::dense);
  DataOptions sparse_path;
  sparse_path.path = Path::sparse;
  try {
    make_data(dense, sparse_path);
    FAIL() << "expected InputError";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("was not compiled sparse"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("TermsLayout::sparse"), std::string::npos) << e.what();
  }
}

TEST(SparsePathBadInput, NonFiniteTermsAreNamed) {
  const Model sparse = chain(2, TermsLayout::sparse);
  Data d = make_data(sparse);
  Vector q = sparse.q0;
  q[2] = std::numeric_limits<double>::quiet_NaN();
  EXPECT_EQ(compute_terms(sparse, d, 0.0, q.data(), sparse.v0.data()), Status::non_finite);
  EXPECT_FALSE(d.failed_quantity.empty());
}

TEST(SparsePathBadInput, DependentConstraintsAtTheInitialStateAreRefused) {
  // The same constraint twice: b has rank 1 < s = 2.
  symbolic::SpecBuilder b("twice");
  b.coordinate("x").coordinate("y").coordinate("z");
  b.kinetic_energy("(x'^2 + y'^2 + z'^2)/2");
  b.constraint("one", "x' - y'").constraint("two", "2*x' - 2*y'");
  const Model model = symbolic::compile_model(b.build(), CompileOptions{TermsLayout::sparse});
  try {
    make_data(model);
    FAIL() << "expected ModelError";
  } catch (const ModelError& e) {
    EXPECT_NE(std::string(e.what()).find("rank below s = 2"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace nhdyn
