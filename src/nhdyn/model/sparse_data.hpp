// SparseData: the Data of the sparse path, for models compiled sparse (symbolic/compile.hpp,
// Evaluator::sparsity()). A and b are Eigen sparse matrices on the evaluator's pattern, filled in
// place by compute_sparse_terms; the sparse formulations (formulation/sparse_sanh.hpp,
// formulation/sparse_lagrange.hpp) keep their factorizations here, with the symbolic analysis of
// each pattern done once by make_sparse_data. Dense n x n storage appears nowhere, so a chain of a
// thousand bodies (n = 3000) needs megabytes, not the gigabyte of the dense Data.
//
// Unlike the dense kernels, the numeric factorizations of Eigen's SparseLU allocate their factors
// on every call (the library offers no way to reuse them); everything else is sized here.
#pragma once

#include <Eigen/Cholesky>
#include <Eigen/LU>
#include <Eigen/SparseCore>
#include <Eigen/SparseLU>
#include <memory>
#include <string>
#include <vector>

#include "nhdyn/core/status.hpp"
#include "nhdyn/core/types.hpp"
#include "nhdyn/model/model.hpp"

namespace nhdyn {

using SparseMatrix = Eigen::SparseMatrix<double, Eigen::ColMajor, int>;
using SparseLU = Eigen::SparseLU<SparseMatrix, Eigen::COLAMDOrdering<int>>;

struct SparseData {
  // --- state and terms (compute_sparse_terms) ----------------------------------------------------
  double t = 0.0;
  Vector q, v;          // n
  SparseMatrix A;       // n x n, the evaluator's pattern
  Vector Q, G;          // n
  SparseMatrix b;       // s x n, the evaluator's pattern
  Vector b0;            // s
  bool has_terms = false;  // the terms belong to (t, q, v)

  // --- results (compute_sparse_sanh_acceleration, compute_sparse_lagrange_acceleration) -----------
  Vector qdd;           // n accelerations
  Vector R;             // n reactions A q'' - Q - G
  Vector lambda;        // s multipliers (lagrange only), R = b^T lambda
  std::string failed;   // what failed, when a kernel returns a non-ok status

  // --- partition of the coordinates (chosen by make_sparse_data at the initial state) ---------------
  std::vector<int> independent;  // k coordinate indices, ascending
  std::vector<int> dependent;    // s coordinate indices, ascending; b_dep = b(:, dependent)
  std::vector<int> column_slot;  // n: position of each coordinate within `independent` or `dependent`

  // --- sanh scratch ---------------------------------------------------------------------------------
  SparseMatrix b_dep;            // s x s, values gathered from b
  std::vector<int> b_dep_source; // for each value of b_dep, its index among b's values
  Matrix b_ind;                  // s x (k + 1): the columns of b of the independent coordinates, then b0
  std::unique_ptr<SparseLU> lu_dep;  // b_dep, pattern analysed once (SparseLU cannot be moved)
  Matrix X;                      // s x (k + 1), b_dep^-1 [b_ind, b0] (one solve for both)
  Matrix D;                      // k x n, partitioned complement [I, -X^T] (original column order)
  Matrix AD;                     // n x k, A D^T
  Matrix DAD;                    // k x k, D A D^T
  Eigen::LLT<Matrix> llt_k;      // k x k
  Vector h;                      // n, Q + G
  Vector c;                      // n, particular solution of b c = -b0 with c_independent = 0
  Vector tmp_n;                  // n
  Vector w;                      // k, accelerations of the independent coordinates

  // --- lagrange (KKT) scratch -----------------------------------------------------------------------
  SparseMatrix K;                // (n + s) x (n + s), [A b^T; b 0]
  std::vector<int> K_source;     // for each value of K: index into A's values (>= 0) or ~index into b's
  std::unique_ptr<SparseLU> lu_kkt;  // K, pattern analysed once
  Vector kkt_rhs, kkt_sol;       // n + s

  std::vector<double> scratch;   // evaluator workspace
};

// Allocates SparseData for a model whose evaluator has a sparsity pattern, evaluates the terms at
// the initial state and chooses the dependent coordinates there (a sparse QR of b with column
// pivoting: s columns that are independent). Throws ModelError when the model was not compiled
// sparse or b has no s independent columns at the initial state.
SparseData make_sparse_data(const Model& model);

// Fills A, Q, G, b, b0 at (t, q, v) through Evaluator::sparse_terms. Status::non_finite when a
// term is not finite (data.failed names it).
Status compute_sparse_terms(const Model& model, SparseData& data, double t, const double* q, const double* v);

}  // namespace nhdyn
