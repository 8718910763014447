#include "nhdyn/formulation/complement.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <string>

#include "nhdyn/core/error.hpp"
#include "nhdyn/formulation/detail/small_dense.hpp"
#include "nhdyn/model/terms.hpp"

namespace nhdyn {
namespace {

// A factor's rank test: pivots of a column-pivoted QR decrease in magnitude, so the last one
// against the first measures how close the constraints are to dependent.
bool pivots_show_full_rank(const Matrix& qr_matrix, int s) {
  if (s == 0) return true;
  const double first = std::abs(qr_matrix(0, 0));
  const double last = std::abs(qr_matrix(s - 1, s - 1));
  const double eps = std::numeric_limits<double>::epsilon();
  return first > 0.0 && last > first * eps * 16.0 * static_cast<double>(qr_matrix.rows() + s);
}

Status compute_partitioned(const Model& model, Data& data) {
  const int n = model.n();
  const int s = model.s();
  const int k = model.k();
  // Column pivoting on b picks, one after another, the coordinates whose columns of b are the
  // most independent: they become the dependent ones, so that b_dep is as well conditioned as
  // this greedy choice allows.
  data.qr_b.compute(data.b);
  if (!pivots_show_full_rank(data.qr_b.matrixQR(), s))
    return record_failure(data, Status::dependent_constraints, "constraint matrix b");
  std::fill(data.is_dependent.begin(), data.is_dependent.end(), 0);
  for (int j = 0; j < s; ++j) data.is_dependent[static_cast<std::size_t>(data.qr_b.colsPermutation().indices()(j))] = 1;
  int di = 0, ii = 0;
  for (int c = 0; c < n; ++c) {
    if (data.is_dependent[static_cast<std::size_t>(c)]) {
      data.dependent[static_cast<std::size_t>(di)] = c;
      data.b_dep.col(di++) = data.b.col(c);
    } else {
      data.independent[static_cast<std::size_t>(ii)] = c;
      data.b_ind.col(ii++) = data.b.col(c);
    }
  }
  data.lu_s.compute(data.b_dep);
  data.X = data.lu_s.solve(data.b_ind);
  // D = [I_k, (-b_dep^-1 b_ind)^T] with its columns put back in the order of q.
  data.D.setZero();
  for (int r = 0; r < k; ++r) {
    data.D(r, data.independent[static_cast<std::size_t>(r)]) = 1.0;
    for (int j = 0; j < s; ++j) data.D(r, data.dependent[static_cast<std::size_t>(j)]) = -data.X(j, r);
  }
  return Status::ok;
}

}  // namespace

Status compute_constraint_basis(const Model& model, Data& data) {
  const int s = model.s();
  const int n = model.n();
  // The coordinates b never touches last, as in the fixed-size kernel (small_dense.hpp,
  // null_space_basis: why; Data::bt_order).
  if (data.bt_in_order)
    data.bt = data.b.transpose();
  else
    for (int j = 0; j < n; ++j) data.bt.row(j) = data.b.col(data.bt_order[static_cast<std::size_t>(j)]).transpose();
  data.qr_bt.compute(data.bt);
  if (!pivots_show_full_rank(data.qr_bt.matrixQR(), s))
    return record_failure(data, Status::dependent_constraints, "constraint matrix b");
  data.qr_bt.householderQ().evalTo(data.Q_full, data.hh_work);
  return Status::ok;
}

double complement_residual(const Data& data) {
  const Eigen::Index s = data.b.rows();
  if (s == 0 || data.D.rows() == 0 || data.D.cols() != data.b.cols()) return 0.0;
  double worst = 0.0;
  for (Eigen::Index i = 0; i < data.D.rows(); ++i) {
    const double d_norm = data.D.row(i).norm();
    for (Eigen::Index j = 0; j < s; ++j) {
      const double scale = d_norm * data.b.row(j).norm();
      if (!(scale > 0.0)) continue;  // a zero row: the rank checks report it
      worst = std::max(worst, std::abs(data.D.row(i).dot(data.b.row(j))) / scale);
    }
  }
  return worst;
}

Status compute_complement(const Model& model, Data& data, Complement complement) {
  if (data.stage < Stage::terms)
    throw std::logic_error("compute_complement: call compute_terms first for the current state");
  const int k = model.k();
  const int s = model.s();
  switch (complement) {
    case Complement::qr: {
      if (s == 0) {
        data.D.setIdentity();
        return Status::ok;
      }
      if (const small::Kernels* kernels = data.small_kernels ? small::find_kernels(model.n(), s) : nullptr) {
        if (!kernels->null_space_basis(data.b.data(), coordinate_order(data), data.D.data()))
          return record_failure(data, Status::dependent_constraints, "constraint matrix b");
        return Status::ok;
      }
      const Status status = compute_constraint_basis(model, data);
      if (status != Status::ok) return status;
      if (data.bt_in_order) {
        data.D = data.Q_full.rightCols(k).transpose();
      } else {
        for (int j = 0; j < model.n(); ++j)
          data.D.col(data.bt_order[static_cast<std::size_t>(j)]) = data.Q_full.row(j).tail(k).transpose();
      }
      return Status::ok;
    }
    case Complement::partition:
      if (s == 0) {
        data.D.setIdentity();
        return Status::ok;
      }
      return compute_partitioned(model, data);
    case Complement::analytic:
      if (!model.evaluator->has_complement())
        throw InputError("model '" + model.name +
                         "' has no analytic D; choose the QR basis (qr) or coordinate partitioning "
                         "(partition) instead");
      model.evaluator->complement(data.t, data.q.data(), data.v.data(), data.scratch.data(), data.D.data());
      if (!data.D.allFinite()) return record_failure(data, Status::non_finite, "complement D");
      // Loading checks the model's D at the initial state only (symbolic/derivation.cpp); one
      // that stops being a complement along the run would give a wrong motion without a sign.
      if (data.check_complement) {
        if (const double residual = complement_residual(data); residual > kComplementTolerance) {
          data.failed_value = residual;
          return record_failure(data, Status::singular_system, "complement D");
        }
      }
      return Status::ok;
  }
  return Status::ok;
}

}  // namespace nhdyn
