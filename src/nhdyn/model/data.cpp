#include "nhdyn/model/data.hpp"

#include <fmt/format.h>
#include <unistd.h>

#include <cmath>

#include "nhdyn/core/error.hpp"

namespace nhdyn {

double dense_data_bytes(int n, int s) {
  const double dn = n, ds = s;
  return 8.0 * (5.0 * dn * dn + 2.0 * (dn + ds) * (dn + ds) + 6.0 * dn * ds + 2.0 * ds * ds);
}

double physical_memory_bytes() {
  const long pages = sysconf(_SC_PHYS_PAGES);
  const long page_size = sysconf(_SC_PAGESIZE);
  return pages > 0 && page_size > 0 ? static_cast<double>(pages) * static_cast<double>(page_size) : 0.0;
}

void check_dense_memory(const Model& model, double available) {
  const int n = model.n(), s = model.s();
  const double needed = dense_data_bytes(n, s);
  if (available <= 0.0 || needed <= available) return;
  // The largest n that fits with the same ratio s / n.
  const double ratio = static_cast<double>(s) / n;
  const double per_n2 = dense_data_bytes(1000, static_cast<int>(std::lround(1000 * ratio))) / 1e6;
  const double largest = std::floor(std::sqrt(available / per_n2));
  constexpr double GB = 1e9;
  throw ModelError(fmt::format(
      "model '{}' is too large for the dense solvers: with n = {} coordinates and s = {} constraints a "
      "simulation's dense matrices need {:.3g} GB (about 8 (5 n^2 + 2 (n + s)^2 + 6 n s + 2 s^2) bytes), and this "
      "machine has {:.3g} GB; the limit here is about n = {:.0f} coordinates. Use the sparse path (a model "
      "compiled sparse with make_sparse_data, docs/performance.md) or a smaller model",
      model.name, n, s, needed / GB, available / GB, largest));
}

Data make_data(const Model& model) {
  check_model_shape(model);
  check_dense_memory(model, physical_memory_bytes());
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
