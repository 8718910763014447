#include "nhdyn/model/data.hpp"

namespace nhdyn {

Data make_data(const Model& model) {
  check_model_shape(model);
  const int n = model.n();
  const int s = model.s();
  const int k = model.k();
  Data d;
  d.t = model.t0;
  d.q = model.q0;
  d.v = model.v0;
  d.A = Matrix::Zero(n, n);
  d.Q = Vector::Zero(n);
  d.G = Vector::Zero(n);
  d.b = Matrix::Zero(s, n);
  d.b0 = Vector::Zero(s);
  d.stabilization = Vector::Zero(s);
  d.b0_model = Vector::Zero(s);
  d.D = Matrix::Zero(k, n);
  d.independent.assign(static_cast<std::size_t>(k), 0);
  d.qdd = Vector::Zero(n);
  d.R = Vector::Zero(n);
  d.lambda = Vector::Zero(s);
  d.phi = Vector::Zero(model.position_constraints());
  d.f = Vector::Zero(model.velocity_constraints());
  d.e = Vector::Zero(s);
  // Long enough for every quantity name the kernels report, so that setting it never allocates.
  d.failed_quantity.reserve(64);
  d.scratch.assign(model.evaluator->scratch_size(), 0.0);
  d.h = Vector::Zero(n);
  d.M = Matrix::Zero(n, n);
  d.rhs = Vector::Zero(n);
  d.K = Matrix::Zero(n + s, n + s);
  d.kkt_rhs = Vector::Zero(n + s);
  d.kkt_sol = Vector::Zero(n + s);
  d.bt = Matrix::Zero(n, s);
  d.Q_full = Matrix::Zero(n, n);
  d.hh_work = Vector::Zero(n);
  d.DA = Matrix::Zero(k, n);
  d.DAD = Matrix::Zero(k, k);
  d.p = Vector::Zero(n);
  d.w = Vector::Zero(k);
  d.tmp_n = Vector::Zero(n);
  d.tmp_n2 = Vector::Zero(n);
  d.tmp_s = Vector::Zero(s);
  d.tmp_k = Vector::Zero(k);
  d.tmp_s2 = Vector::Zero(s);
  d.projection_scale = Vector::Ones(s);
  d.bWt = Matrix::Zero(n, s);
  d.b_dep = Matrix::Zero(s, s);
  d.b_ind = Matrix::Zero(s, k);
  d.X = Matrix::Zero(s, k);
  d.dependent.assign(static_cast<std::size_t>(s), 0);
  d.is_dependent.assign(static_cast<std::size_t>(n), 0);
  d.lu_n = Eigen::PartialPivLU<Matrix>(n);
  d.lu_kkt = Eigen::PartialPivLU<Matrix>(n + s);
  d.lu_s = Eigen::PartialPivLU<Matrix>(s);
  d.qr_bt = Eigen::ColPivHouseholderQR<Matrix>(n, s);
  d.qr_b = Eigen::ColPivHouseholderQR<Matrix>(s, n);
  // Factor an identity once rather than assign a default-constructed LLT, whose status is
  // uninitialized (copying it is undefined behaviour); the storage is sized either way.
  d.llt_k.compute(Matrix::Identity(k, k));
  d.llt_n.compute(Matrix::Identity(n, n));
  d.qr_bWt = Eigen::ColPivHouseholderQR<Matrix>(n, s);
  return d;
}

}  // namespace nhdyn
