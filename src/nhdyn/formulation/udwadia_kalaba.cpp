#include "nhdyn/formulation/udwadia_kalaba.hpp"

#include <cmath>

#include "nhdyn/model/terms.hpp"

namespace nhdyn {

Status compute_udwadia_kalaba_acceleration(const Model& model, Data& data) {
  const int s = model.s();
  // The square root of A^-1 is taken as W = L^-T from A = L L^T: any W with W W^T = A^-1 turns
  // Gauss's function (q'' - a)^T A (q'' - a) into |W^-1 (q'' - a)|^2, which is all the
  // derivation of Udwadia and Kalaba uses (docs/design.md).
  data.llt_n.compute(data.A);
  if (data.llt_n.info() != Eigen::Success)
    return record_failure(data, Status::inertia_not_positive_definite, "inertia matrix A");
  data.h = data.Q + data.G;
  data.p = data.h;
  data.llt_n.solveInPlace(data.p);  // a = A^-1 (Q + G), the unconstrained acceleration
  data.qdd = data.p;
  if (s > 0) {
    // (b W)^T = L^-1 b^T. Its column-pivoted QR, (bW)^T P = Q1 R1, gives the Moore-Penrose
    // inverse of the full-row-rank bW without an SVD: bW = P R1^T Q1^T, so the minimum-norm z
    // with bW z = r is z = Q1 R1^-T P^T r.
    data.bWt = data.b.transpose();
    // Column by column: Eigen's triangular solve with a matrix right-hand side allocates its
    // blocking workspace, the one with a vector right-hand side does not.
    for (int j = 0; j < s; ++j) {
      Eigen::Block<Matrix, Eigen::Dynamic, 1, true> column = data.bWt.col(j);
      data.llt_n.matrixL().solveInPlace(column);
    }
    data.qr_bWt.compute(data.bWt);
    const Matrix& R1 = data.qr_bWt.matrixQR();
    // Udwadia-Kalaba's pseudo-inverse would accept consistent redundant constraints; like the
    // other formulations we report rank deficiency instead of silently dropping a constraint.
    if (!(std::abs(R1(s - 1, s - 1)) > std::abs(R1(0, 0)) * 1e-13))
      return record_failure(data, Status::dependent_constraints, "constraint matrix b");
    data.qr_bWt.householderQ().evalTo(data.Q_full, data.hh_work);
    const auto& perm = data.qr_bWt.colsPermutation().indices();
    // r = -b0 - b a, the constraints' residual under the unconstrained motion, permuted.
    data.tmp_s.noalias() = data.b * data.p;  // negating the product itself would need a temporary
    data.tmp_s = -data.b0 - data.tmp_s;
    for (int j = 0; j < s; ++j) data.lambda(j) = data.tmp_s(perm(j));
    R1.topLeftCorner(s, s).triangularView<Eigen::Upper>().transpose().solveInPlace(data.lambda);
    data.tmp_n.noalias() = data.Q_full.leftCols(s) * data.lambda;
    data.llt_n.matrixU().solveInPlace(data.tmp_n);  // W x = L^-T x
    data.qdd += data.tmp_n;
    // lambda = (b A^-1 b^T)^-1 r = P R1^-1 R1^-T P^T r, so that R = b^T lambda.
    R1.topLeftCorner(s, s).triangularView<Eigen::Upper>().solveInPlace(data.lambda);
    data.tmp_s = data.lambda;
    for (int j = 0; j < s; ++j) data.lambda(perm(j)) = data.tmp_s(j);
    data.has_multipliers = true;
  }
  // R = A (q'' - a).
  data.tmp_n = data.qdd - data.p;
  data.R.noalias() = data.A * data.tmp_n;
  return Status::ok;
}

}  // namespace nhdyn
