#include "nhdyn/formulation/nullspace.hpp"

#include "nhdyn/formulation/complement.hpp"
#include "nhdyn/formulation/detail/small_dense.hpp"
#include "nhdyn/model/terms.hpp"

namespace nhdyn {

Status compute_nullspace_acceleration(const Model& model, Data& data, Complement complement) {
  const int s = model.s();
  Status status = compute_complement(model, data, complement);
  if (status != Status::ok) return status;
  // The particular solution comes from b^T P = Q1 R1: with p = Q1 y, b p = P R1^T y = -b0.
  data.p.setZero();
  if (s > 0) {
    // The dynamic QR complement leaves the factorization behind; the others, and the fixed-size
    // QR kernel, do not.
    const bool basis_is_current = complement == Complement::qr &&
                                  !(data.small_kernels && small::find_kernels(model.n(), s) != nullptr);
    if (!basis_is_current) {
      status = compute_constraint_basis(model, data);
      if (status != Status::ok) return status;
    }
    const auto& perm = data.qr_bt.colsPermutation().indices();
    for (int j = 0; j < s; ++j) data.tmp_s(j) = -data.b0(perm(j));
    data.qr_bt.matrixQR().topLeftCorner(s, s).triangularView<Eigen::Upper>().transpose().solveInPlace(data.tmp_s);
    // Q_full's rows are the coordinates in bt_order (compute_constraint_basis).
    if (data.bt_in_order) {
      data.p.noalias() = data.Q_full.leftCols(s) * data.tmp_s;
    } else {
      data.tmp_n.noalias() = data.Q_full.leftCols(s) * data.tmp_s;
      for (int j = 0; j < model.n(); ++j) data.p(data.bt_order[static_cast<std::size_t>(j)]) = data.tmp_n(j);
    }
  }
  data.h = data.Q + data.G;
  data.DA.noalias() = data.D * data.A;
  data.DAD.noalias() = data.DA * data.D.transpose();
  data.tmp_n.noalias() = data.A * data.p;
  data.tmp_n = data.h - data.tmp_n;
  data.w.noalias() = data.D * data.tmp_n;
  data.llt_k.compute(data.DAD);
  if (data.llt_k.info() != Eigen::Success)
    return record_failure(data, Status::inertia_not_positive_definite, "reduced inertia D A D^T");
  data.llt_k.solveInPlace(data.w);
  data.qdd = data.p;
  data.qdd.noalias() += data.D.transpose() * data.w;
  data.R.noalias() = data.A * data.qdd;
  data.R -= data.h;
  return Status::ok;
}

}  // namespace nhdyn
