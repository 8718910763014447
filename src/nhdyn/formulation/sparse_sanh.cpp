#include "nhdyn/formulation/sparse_sanh.hpp"

namespace nhdyn {

Status compute_sparse_sanh_acceleration(const Model& model, SparseData& data) {
  const int s = model.s(), k = model.k();
  data.h = data.Q + data.G;
  data.c.setZero();
  data.D.setZero();
  if (s > 0) {
    // b_dep and b_ind from the current values of b.
    const double* b_values = data.b.valuePtr();
    double* dep_values = data.b_dep.valuePtr();
    for (std::size_t m = 0; m < data.b_dep_source.size(); ++m) dep_values[m] = b_values[data.b_dep_source[m]];
    data.b_ind.leftCols(k).setZero();
    for (int jj = 0; jj < k; ++jj) {
      const int j = data.independent[static_cast<std::size_t>(jj)];
      for (int m = data.b.outerIndexPtr()[j]; m < data.b.outerIndexPtr()[j + 1]; ++m)
        data.b_ind(data.b.innerIndexPtr()[m], jj) = b_values[m];
    }
    data.lu_dep->factorize(data.b_dep);
    if (data.lu_dep->info() != Eigen::Success) {
      data.failed.assign("columns of b of the dependent coordinates (b_dep)");
      return Status::singular_system;
    }
    data.b_ind.col(k) = data.b0;
    data.X = data.lu_dep->solve(data.b_ind);
    for (int jj = 0; jj < s; ++jj) {
      const int j = data.dependent[static_cast<std::size_t>(jj)];
      data.c[j] = -data.X(jj, k);
      for (int r = 0; r < k; ++r) data.D(r, j) = -data.X(jj, r);
    }
  }
  for (int r = 0; r < k; ++r) data.D(r, data.independent[static_cast<std::size_t>(r)]) = 1.0;

  // (D A D^T) w = D (h - A c); A is symmetric, so A D^T = (D A)^T.
  data.AD.noalias() = data.A * data.D.transpose();
  data.DAD.noalias() = data.D * data.AD;
  data.tmp_n = data.h;
  data.tmp_n.noalias() -= data.A * data.c;
  data.w.noalias() = data.D * data.tmp_n;
  data.llt_k.compute(data.DAD);
  if (data.llt_k.info() != Eigen::Success) {
    data.failed.assign("reduced inertia D A D^T");
    return Status::singular_system;
  }
  data.llt_k.solveInPlace(data.w);
  // q'' = c + D^T w: the independent accelerations are w, the dependent ones follow from b.
  data.qdd = data.c;
  data.qdd.noalias() += data.D.transpose() * data.w;
  data.R.noalias() = data.A * data.qdd;
  data.R -= data.h;
  return Status::ok;
}

}  // namespace nhdyn
