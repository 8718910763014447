#include "nhdyn/formulation/sparse_sanh.hpp"

#include "nhdyn/model/terms.hpp"

namespace nhdyn {
namespace {

// Beyond this, a change of the dependent coordinates is due: the dependent accelerations would
// amplify the independent ones (and their errors) a millionfold.
constexpr double kLargestX = 1e6;

// Fills b_dep and [b_ind, b0] from b and solves for X = b_dep^-1 [b_ind, b0]. False when b_dep is
// singular or X too large.
bool solve_partition(const Model& model, Data& data) {
  const int k = model.k();
  const double* b_values = data.b_sparse.valuePtr();
  double* dep_values = data.b_dep_sparse.valuePtr();
  for (std::size_t m = 0; m < data.b_dep_source.size(); ++m) dep_values[m] = b_values[data.b_dep_source[m]];
  data.b_ind.leftCols(k).setZero();
  for (int jj = 0; jj < k; ++jj) {
    const int j = data.independent[static_cast<std::size_t>(jj)];
    for (int m = data.b_sparse.outerIndexPtr()[j]; m < data.b_sparse.outerIndexPtr()[j + 1]; ++m)
      data.b_ind(data.b_sparse.innerIndexPtr()[m], jj) = b_values[m];
  }
  data.b_ind.col(k) = data.b0;
  if (!data.lu_dep.factorize(data.b_dep_sparse)) return false;
  data.X = data.b_ind;
  data.lu_dep.solve_in_place(data.X);
  const double largest = data.X.leftCols(k).size() > 0 ? data.X.leftCols(k).cwiseAbs().maxCoeff() : 0.0;
  return largest <= kLargestX;  // false for NaN as well
}

Status solve_unconstrained(Data& data) {
  data.h = data.Q + data.G;
  data.llt_a->factorize(data.A_sparse);
  if (data.llt_a->info() != Eigen::Success)
    return record_failure(data, Status::inertia_not_positive_definite, "inertia matrix A");
  data.qdd = data.llt_a->solve(data.h);
  data.R.noalias() = data.A_sparse * data.qdd;
  data.R -= data.h;
  return Status::ok;
}

}  // namespace

Status compute_sparse_sanh_acceleration(const Model& model, Data& data) {
  const int s = model.s(), k = model.k();
  if (s == 0) return solve_unconstrained(data);
  if (!solve_partition(model, data)) {
    const Status status = compute_sparse_partition(model, data);
    if (status != Status::ok) return status;
    if (!solve_partition(model, data))
      return record_failure(data, Status::singular_system, "columns of b of the dependent coordinates (b_dep)");
  }
  data.h = data.Q + data.G;
  data.p.setZero();  // c: zero on the independent coordinates
  data.D.setZero();
  for (int jj = 0; jj < s; ++jj) {
    const int j = data.dependent[static_cast<std::size_t>(jj)];
    data.p[j] = -data.X(jj, k);
    for (int r = 0; r < k; ++r) data.D(r, j) = -data.X(jj, r);
  }
  for (int r = 0; r < k; ++r) data.D(r, data.independent[static_cast<std::size_t>(r)]) = 1.0;

  // (D A D^T) w = D (h - A c); A is symmetric, so A D^T = (D A)^T.
  data.AD.noalias() = data.A_sparse * data.D.transpose();
  data.DAD.noalias() = data.D * data.AD;
  data.tmp_n = data.h;
  data.tmp_n.noalias() -= data.A_sparse * data.p;
  data.w.noalias() = data.D * data.tmp_n;
  data.llt_k.compute(data.DAD);
  if (data.llt_k.info() != Eigen::Success)
    return record_failure(data, Status::inertia_not_positive_definite, "reduced inertia D A D^T");
  data.llt_k.solveInPlace(data.w);
  // q'' = c + D^T w: the independent accelerations are w, the dependent ones follow from b.
  data.qdd = data.p;
  data.qdd.noalias() += data.D.transpose() * data.w;
  data.R.noalias() = data.A_sparse * data.qdd;
  data.R -= data.h;
  return Status::ok;
}

}  // namespace nhdyn
