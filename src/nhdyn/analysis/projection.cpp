#include "nhdyn/analysis/projection.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

#include <stdexcept>

#include "nhdyn/formulation/sanh.hpp"
#include "nhdyn/formulation/sparse_lagrange.hpp"
#include "nhdyn/model/terms.hpp"

namespace nhdyn {
namespace {

bool belongs_to(ConstraintLevel constraint, ConstraintLevel level) {
  return level == ConstraintLevel::position ? constraint == ConstraintLevel::position
                                            : constraint != ConstraintLevel::acceleration;
}

// The residual of `level` at (t, q, v) into data.phi or data.f; returns max |r|.
double evaluate_residual(const Model& model, Data& data, double t, const double* q, const double* v,
                         ConstraintLevel level) {
  Vector& r = level == ConstraintLevel::position ? data.phi : data.f;
  if (r.size() == 0) return 0.0;
  if (level == ConstraintLevel::position)
    model.evaluator->position_residual(t, q, data.scratch.data(), r.data());
  else
    model.evaluator->velocity_residual(t, q, v, data.scratch.data(), r.data());
  double worst = 0.0;
  for (Eigen::Index i = 0; i < r.size(); ++i) {
    if (!std::isfinite(r(i))) return std::numeric_limits<double>::infinity();
    worst = std::max(worst, std::abs(r(i)));
  }
  return worst;
}

Status fail(Data& data, ConstraintLevel level, double t, double residual) {
  record_failure(data, Status::projection_failed,
                 level == ConstraintLevel::position ? "position constraints" : "velocity constraints");
  data.failed_t = t;
  data.failed_value = residual;
  return Status::projection_failed;
}

// A row of b need only be parallel to the gradient of its constraint (the paper writes Appell's
// as grad f / (2 z')). Along the first Newton step dx, a forward difference of the residual gives
// grad r_j . dx; against b_j . dx it gives the factor between the two (it may change with the
// state, so every Newton step measures it anew). Constraints whose row hardly moves along dx
// keep the factor 1.
void estimate_scale(const Model& model, Data& data, double t, double* q, double* v, ConstraintLevel level,
                    double* x, double x_size, double step_size) {
  const int n = model.n();
  Vector& r = level == ConstraintLevel::position ? data.phi : data.f;
  Vector& r0 = data.tmp_s2;
  Vector& scale = data.projection_scale;
  const Eigen::Index m = r.size();
  r0.head(m) = r;
  // b dx (tmp_s) and the largest entry of each row of b (tmp_s3), on either path.
  Vector& predicted_all = data.tmp_s;
  Vector& row_scale = data.tmp_s3;
  if (data.sparse) {
    predicted_all.noalias() = data.b_sparse * data.kkt_sol.head(n);
    row_scale.setZero();
    for (int j = 0; j < n; ++j)
      for (SparseMatrix::InnerIterator it(data.b_sparse, j); it; ++it)
        row_scale(it.row()) = std::max(row_scale(it.row()), std::abs(it.value()));
  } else {
    predicted_all.noalias() = data.b * data.kkt_sol.head(n);
    for (int i = 0; i < model.s(); ++i) row_scale(i) = data.b.row(i).cwiseAbs().maxCoeff();
  }
  const double h = std::min(1.0, 1e-7 * std::max(1.0, x_size) / step_size);
  for (int i = 0; i < n; ++i) x[i] += h * data.kkt_sol(i);
  evaluate_residual(model, data, t, q, v, level);
  for (int i = 0; i < n; ++i) x[i] -= h * data.kkt_sol(i);
  Eigen::Index j = 0;
  for (int i = 0; i < model.s(); ++i) {
    if (!belongs_to(model.constraints[static_cast<std::size_t>(i)].level, level)) continue;
    const double predicted = predicted_all(i);
    const double actual = (r(j) - r0(j)) / h;
    const double ratio = actual / predicted;
    const bool measurable = std::abs(predicted) > 1e-8 * row_scale(i) * step_size &&
                            std::abs(r(j) - r0(j)) > 1e-6 * std::abs(r0(j));
    // Within the accuracy of the difference, 1 is 1: rows that are the gradients keep the exact
    // Newton step (one step for a constraint linear in x).
    // A difference lost in round-off keeps the factor measured before.
    if (measurable && std::isfinite(ratio) && ratio != 0.0) scale(j) = std::abs(ratio - 1.0) > 1e-6 ? ratio : 1.0;
    ++j;
  }
  r.head(m) = r0.head(m);
}

Status project_level(const Model& model, Data& data, double t, double* q, double* v, ConstraintLevel level,
                     const ProjectionOptions& options, int& iterations, double& change, double& residual) {
  const int n = model.n();
  const int s = model.s();
  const Vector& r = level == ConstraintLevel::position ? data.phi : data.f;
  double* x = level == ConstraintLevel::position ? q : v;
  Vector& scale = data.projection_scale;
  Vector& x_start = data.tmp_n2;
  scale.setOnes();
  for (int i = 0; i < n; ++i) x_start(i) = x[i];
  iterations = 0;
  change = 0.0;
  residual = evaluate_residual(model, data, t, q, v, level);
  while (residual > options.tolerance) {
    if (iterations == options.max_iterations || !std::isfinite(residual)) return fail(data, level, t, residual);
    const Status status = compute_terms(model, data, t, q, v);
    if (status != Status::ok) return status;
    // Constraints of other levels keep a row of the KKT matrix with a unit diagonal and a zero
    // right-hand side: their multiplier is zero and the matrix keeps the size make_data gave it.
    bool singular = false;
    if (data.sparse) {
      for (int i = 0; i < s; ++i)
        data.projection_rows[static_cast<std::size_t>(i)] =
            belongs_to(model.constraints[static_cast<std::size_t>(i)].level, level) ? 1 : 0;
      fill_sparse_kkt(data, data.projection_rows.data());
      singular = !data.lu_kkt_sparse.factorize(data.K_sparse);
    } else {
      data.K.setZero();
      data.K.topLeftCorner(n, n) = data.A;
      for (int i = 0; i < s; ++i) {
        if (belongs_to(model.constraints[static_cast<std::size_t>(i)].level, level)) {
          data.K.row(n + i).head(n) = data.b.row(i);
          data.K.col(n + i).head(n) = data.b.row(i).transpose();
        } else {
          data.K(n + i, n + i) = 1.0;
        }
      }
      data.lu_kkt.compute(data.K);
      singular = lu_is_singular(data.lu_kkt);
    }
    if (singular) {
      record_failure(data, Status::singular_system, "projection's KKT matrix [A J^T; J 0]");
      data.failed_t = t;
      return Status::singular_system;
    }
    for (int pass = 0; pass < 2; ++pass) {
      data.kkt_rhs.setZero();
      Eigen::Index j = 0;
      for (int i = 0; i < s; ++i)
        if (belongs_to(model.constraints[static_cast<std::size_t>(i)].level, level)) {
          data.kkt_rhs(n + i) = -r(j) / scale(j);
          ++j;
        }
      if (data.sparse) {
        data.kkt_sol = data.kkt_rhs;
        data.lu_kkt_sparse.solve_in_place(data.kkt_sol);
      } else
        data.kkt_sol = data.lu_kkt.solve(data.kkt_rhs);
      if (pass == 0) {
        double step = 0.0, size = 0.0;
        for (int i = 0; i < n; ++i) {
          step = std::max(step, std::abs(data.kkt_sol(i)));
          size = std::max(size, std::abs(x[i]));
        }
        if (!(step > 0.0)) break;
        estimate_scale(model, data, t, q, v, level, x, size, step);
      }
    }
    double step = 0.0, size = 0.0;
    for (int i = 0; i < n; ++i) {
      x[i] += data.kkt_sol(i);
      step = std::max(step, std::abs(data.kkt_sol(i)));
      size = std::max(size, std::abs(x[i]));
    }
    ++iterations;
    residual = evaluate_residual(model, data, t, q, v, level);
    // Steps at the round-off of x cannot lower the residual any further.
    if (step <= 64.0 * std::numeric_limits<double>::epsilon() * size) break;
  }
  for (int i = 0; i < n; ++i) change = std::max(change, std::abs(x[i] - x_start(i)));
  return Status::ok;
}

}  // namespace

Status compute_projection(const Model& model, Data& data, double t, double* q, double* v,
                          const ProjectionOptions& options, ProjectionResult& result) {
  if (!data.projection_workspace)
    throw std::logic_error("compute_projection: this Data was made without the projection's workspace "
                           "(DataOptions::projection)");
  result = ProjectionResult{};
  Status status = project_level(model, data, t, q, v, ConstraintLevel::position, options,
                                result.position_iterations, result.position_change, result.position_residual);
  if (status != Status::ok) return status;
  // The velocity constraints are taken at the projected positions.
  status = project_level(model, data, t, q, v, ConstraintLevel::velocity, options, result.velocity_iterations,
                         result.velocity_change, result.velocity_residual);
  return status;
}

}  // namespace nhdyn
