// The sparse path against the dense one on the built-in models, through their sparse twins
// (sparse_twin.hpp): one Data made for either path gives the same q'', R, multipliers, residuals
// and energy at random states, with and without Baumgarte's terms; the projection moves a state
// off the constraints to the same point; the start-up checks find an indefinite A and dependent
// constraints with sparse factorizations; formulations without sparse kernels are refused by name
// or fall back to the dense path; a Data holds only the workspace of its path and formulation.
#include <gtest/gtest.h>

#include <random>
#include <stdexcept>
#include <string>

#include "formulation/sparse_twin.hpp"
#include "nhdyn/analysis/projection.hpp"
#include "nhdyn/analysis/residuals.hpp"
#include "nhdyn/core/error.hpp"
#include "nhdyn/formulation/diagnosis.hpp"
#include "nhdyn/formulation/formulation.hpp"
#include "nhdyn/model/appell.hpp"
#include "nhdyn/model/sled.hpp"
#include "nhdyn/model/terms.hpp"
#include "support/test_models.hpp"
#include "support/text.hpp"

namespace nhdyn {
namespace {

using nhdyn::test::contains;

double relative(const Vector& x, const Vector& reference) {
  return (x - reference).norm() / std::max(reference.norm(), 1e-300);
}

std::vector<Model> built_in_models() {
  return {make_sled_model(), make_sled_model(SledVariant::paper), make_appell_model()};
}

TEST(SparseKernels, AgreeWithTheDenseKernelsOnTheBuiltInModels) {
  for (const Model& model : built_in_models()) {
    const Model twin = testing::make_sparse_twin(model);
    Data sparse = make_data(twin), dense = make_data(model);
    ASSERT_TRUE(sparse.sparse) << model.name;
    ASSERT_FALSE(dense.sparse) << model.name;
    std::mt19937 rng(5);
    std::uniform_real_distribution<double> u(-1.0, 1.0);
    for (int trial = 0; trial < 10; ++trial)
      for (Formulation m : {Formulation::sanh, Formulation::lagrange})
        for (bool baumgarte : {false, true}) {
          SCOPED_TRACE(model.name + " " + std::string(formulation_name(m)) + (baumgarte ? " baumgarte" : ""));
          Vector q = model.q0, v = model.v0;
          for (int i = 0; i < model.n(); ++i) {
            q(i) += u(rng);
            v(i) += u(rng);
          }
          FormulationOptions options(m, Complement::qr);
          options.baumgarte.enabled = baumgarte;
          ASSERT_EQ(compute_dynamics(model, dense, options, 0.3, q.data(), v.data()), Status::ok);
          ASSERT_EQ(compute_dynamics(twin, sparse, options, 0.3, q.data(), v.data()), Status::ok)
              << sparse.failed_quantity;
          EXPECT_LT(relative(sparse.qdd, dense.qdd), 1e-12);
          // R = A q'' - Q - G is a difference: its round-off scale is |A| |q''| + |Q + G|.
          EXPECT_LT((sparse.R - dense.R).norm(), 1e-13 * (dense.A.norm() * dense.qdd.norm() + (dense.Q + dense.G).norm()));
          EXPECT_EQ(sparse.has_multipliers, dense.has_multipliers);
          if (dense.has_multipliers) {
            EXPECT_LT(relative(sparse.lambda, dense.lambda), 1e-11);
          }
          compute_residuals(model, dense);
          compute_residuals(twin, sparse);
          compute_energy(model, dense);
          compute_energy(twin, sparse);
          // e = b q'' + b0 is round-off on both paths (without Baumgarte) and the same quantity.
          EXPECT_LT((sparse.e - dense.e).norm(), 1e-12 * (1.0 + dense.b.norm() * dense.qdd.norm()));
          EXPECT_EQ(sparse.phi, dense.phi);
          EXPECT_EQ(sparse.f, dense.f);
          EXPECT_EQ(sparse.energy, dense.energy);
          // The sparse sanh solve's own invariants: D b^T = 0 and D R = 0.
          if (m == Formulation::sanh) {
            EXPECT_LT((sparse.D * dense.b.transpose()).norm(), 1e-13 * (1.0 + sparse.D.norm() * dense.b.norm()));
            EXPECT_LT((sparse.D * sparse.R).norm(), 1e-12 * sparse.D.norm() * (1.0 + sparse.R.norm()));
          }
        }
  }
}

TEST(SparseKernels, ProjectionMovesAStateToTheSamePointOnBothPaths) {
  for (const Model& model : {make_sled_model(), make_appell_model()}) {
    const Model twin = testing::make_sparse_twin(model);
    Data sparse = make_data(twin), dense = make_data(model);
    Vector q = model.q0, v = model.v0;
    v(0) += 0.3;  // off the velocity constraint
    v(1) -= 0.2;
    q(1) += 0.1;
    Vector qs = q, vs = v;
    ProjectionResult rd, rs;
    ASSERT_EQ(compute_projection(model, dense, 0.0, q.data(), v.data(), ProjectionOptions{}, rd), Status::ok);
    ASSERT_EQ(compute_projection(twin, sparse, 0.0, qs.data(), vs.data(), ProjectionOptions{}, rs), Status::ok);
    EXPECT_TRUE(rd.changed()) << model.name;
    EXPECT_LT((qs - q).norm(), 1e-13 * (1.0 + q.norm())) << model.name;
    EXPECT_LT((vs - v).norm(), 1e-12 * (1.0 + v.norm())) << model.name;
    EXPECT_EQ(rs.velocity_iterations, rd.velocity_iterations) << model.name;
    EXPECT_LE(rs.velocity_residual, ProjectionOptions{}.tolerance) << model.name;
  }
}

TEST(SparseKernels, FormulationsWithoutSparseKernelsAreRefusedOrTakeTheDensePath) {
  const Model twin = testing::make_sparse_twin(make_sled_model());
  Data sparse = make_data(twin);
  ASSERT_EQ(compute_terms(twin, sparse, 0.0, twin.q0.data(), twin.v0.data()), Status::ok);
  for (Formulation m : {Formulation::udwadia_kalaba, Formulation::nullspace}) {
    try {
      compute_acceleration(twin, sparse, FormulationOptions(m));
      FAIL() << "expected logic_error";
    } catch (const std::logic_error& e) {
      EXPECT_TRUE(contains(e.what(), "no sparse kernels") && contains(e.what(), "sanh or lagrange")) << e.what();
    }
    DataOptions options;
    options.method = m;
    Data fallback = make_data(twin, options);  // automatic: the dense path for this formulation
    EXPECT_FALSE(fallback.sparse);
    EXPECT_EQ(compute_dynamics(twin, fallback, FormulationOptions(m), 0.0, twin.q0.data(), twin.v0.data()), Status::ok);
    options.path = Path::sparse;
    try {
      make_data(twin, options);
      FAIL() << "expected InputError";
    } catch (const InputError& e) {
      EXPECT_TRUE(contains(e.what(), formulation_name(m).data()) && contains(e.what(), "sanh, lagrange")) << e.what();
    }
  }
}

TEST(SparseKernels, DataHoldsOnlyTheWorkspaceOfItsPathAndFormulation) {
  const Model model = make_sled_model();
  const int n = model.n(), s = model.s();
  DataOptions sanh_only;
  sanh_only.method = Formulation::sanh;
  sanh_only.projection = false;
  Data d = make_data(model, sanh_only);
  EXPECT_EQ(d.M.rows(), n);
  EXPECT_EQ(d.K.size(), 0);
  EXPECT_EQ(d.llt_n.matrixLLT().size(), 0);
  EXPECT_EQ(d.bWt.size(), 0);
  EXPECT_LT(dense_data_bytes(n, s, sanh_only), dense_data_bytes(n, s));
  // Asking it for another formulation or a projection says what to do.
  ASSERT_EQ(compute_terms(model, d, 0.0, model.q0.data(), model.v0.data()), Status::ok);
  EXPECT_THROW(compute_acceleration(model, d, FormulationOptions(Formulation::lagrange)), std::logic_error);
  Vector q = model.q0, v = model.v0;
  ProjectionResult result;
  EXPECT_THROW(compute_projection(model, d, 0.0, q.data(), v.data(), ProjectionOptions{}, result), std::logic_error);

  Data sparse = make_data(testing::make_sparse_twin(model));
  EXPECT_EQ(sparse.A.size(), 0);
  EXPECT_EQ(sparse.b.size(), 0);
  EXPECT_EQ(sparse.M.size(), 0);
  EXPECT_EQ(sparse.K.size(), 0);
  EXPECT_EQ(sparse.Q_full.size(), 0);
  EXPECT_EQ(sparse.A_sparse.rows(), n);
  EXPECT_EQ(sparse.b_sparse.rows(), s);
}

TEST(SparseKernels, AnIndefiniteInertiaIsFoundBySparseFactorization) {
  Matrix A = Matrix::Identity(3, 3);
  A(2, 2) = -2.0;
  Matrix b(1, 3);
  b << 1, 0, 0;
  const Model twin = testing::make_sparse_twin(testing::make_constant_model(A, Vector::Ones(3), b, Vector::Zero(1)));
  Data data = make_data(twin);
  ASSERT_TRUE(data.sparse);
  try {
    check_state_or_throw(twin, data, 0.0, twin.q0.data(), twin.v0.data());
    FAIL() << "expected ModelError";
  } catch (const ModelError& e) {
    EXPECT_TRUE(contains(e.what(), "not positive definite")) << e.what();
    EXPECT_TRUE(contains(e.what(), "smallest pivot of its LDL^T factorization -2")) << e.what();
  }
}

TEST(SparseKernels, DependentConstraintsOfALargeModelAreNamedWithoutADenseSvd) {
  // 70 coordinates: beyond the dense checks' size. c3 = 2 c1.
  const int n = 70;
  Matrix b = Matrix::Zero(3, n);
  b(0, 0) = 1.0;
  b(1, 1) = 1.0;
  b(1, 2) = 1.0;
  b(2, 0) = 2.0;
  const Model model = testing::make_constant_model(Matrix::Identity(n, n), Vector::Ones(n), b, Vector::Zero(3));
  Data data = make_data(model);
  try {
    check_state_or_throw(model, data, 0.0, model.q0.data(), model.v0.data());
    FAIL() << "expected ModelError";
  } catch (const ModelError& e) {
    const std::string what = e.what();
    EXPECT_TRUE(contains(what, "'c1'") || contains(what, "'c3'")) << what;
    EXPECT_FALSE(contains(what, "'c2'")) << what;
    EXPECT_TRUE(contains(what, "rank 2 below s = 3")) << what;
  }
  // The sparse path refuses it when the Data is made: no dependent coordinates can be chosen.
  EXPECT_THROW(make_data(testing::make_sparse_twin(model)), ModelError);
}

}  // namespace
}  // namespace nhdyn
