#include "nhdyn/analysis/projection.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

#include "nhdyn/formulation/sanh.hpp"
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

Status project_level(const Model& model, Data& data, double t, double* q, double* v, ConstraintLevel level,
                     const ProjectionOptions& options, int& iterations, double& change, double& residual) {
  const int n = model.n();
  const int s = model.s();
  const Vector& r = level == ConstraintLevel::position ? data.phi : data.f;
  double* x = level == ConstraintLevel::position ? q : v;
  Vector& r_old = data.tmp_s2;
  Vector& scale = data.projection_scale;
  Vector& x_old = data.tmp_n;
  scale.setOnes();
  iterations = 0;
  change = 0.0;
  residual = evaluate_residual(model, data, t, q, v, level);
  while (residual > options.tolerance) {
    if (iterations == options.max_iterations || !std::isfinite(residual)) return fail(data, level, t, residual);
    const Status status = compute_terms(model, data, t, q, v);
    if (status != Status::ok) return status;
    // Constraints of other levels keep a row of the KKT matrix with a unit diagonal and a zero
    // right-hand side: their multiplier is zero and the matrix keeps the size make_data gave it.
    data.K.setZero();
    data.K.topLeftCorner(n, n) = data.A;
    data.kkt_rhs.setZero();
    Eigen::Index j = 0;
    for (int i = 0; i < s; ++i) {
      if (belongs_to(model.constraints[static_cast<std::size_t>(i)].level, level)) {
        data.K.row(n + i).head(n) = data.b.row(i);
        data.K.col(n + i).head(n) = data.b.row(i).transpose();
        data.kkt_rhs(n + i) = -r(j) / scale(j);
        ++j;
      } else {
        data.K(n + i, n + i) = 1.0;
      }
    }
    data.lu_kkt.compute(data.K);
    if (lu_is_singular(data.lu_kkt)) {
      record_failure(data, Status::singular_system, "projection's KKT matrix [A J^T; J 0]");
      data.failed_t = t;
      return Status::singular_system;
    }
    data.kkt_sol = data.lu_kkt.solve(data.kkt_rhs);
    double step = 0.0, size = 0.0;
    for (int i = 0; i < n; ++i) {
      x_old(i) = x[i];
      x[i] += data.kkt_sol(i);
      step = std::max(step, std::abs(data.kkt_sol(i)));
      size = std::max(size, std::abs(x[i]));
    }
    ++iterations;
    r_old.head(r.size()) = r;
    const double previous = residual;
    residual = evaluate_residual(model, data, t, q, v, level);
    // A row of b need only be parallel to the gradient of its constraint (the paper writes
    // Appell's as grad f / (2 z')). The step predicted a change of -r_j / scale_j in b_j dx;
    // the change f_j actually made gives the ratio of the two: a secant estimate of the factor.
    // Steps at the round-off of x cannot lower the residual any further.
    const bool at_round_off = step <= 8.0 * std::numeric_limits<double>::epsilon() * size;
    if (!at_round_off)
      for (Eigen::Index i = 0; i < r.size(); ++i) {
        const double ratio = (r_old(i) - r(i)) / r_old(i);
        if (std::abs(r_old(i)) > options.tolerance && std::isfinite(ratio) && ratio != 0.0) scale(i) *= ratio;
      }
    if (!(residual < previous)) {
      // No progress: take the step back, and try again with the corrected factors unless the
      // step was round-off already.
      for (int i = 0; i < n; ++i) x[i] = x_old(i);
      residual = evaluate_residual(model, data, t, q, v, level);
      if (at_round_off) break;
      continue;
    }
    change = std::max(change, step);
    if (at_round_off) break;
  }
  return Status::ok;
}

}  // namespace

Status compute_projection(const Model& model, Data& data, double t, double* q, double* v,
                          const ProjectionOptions& options, ProjectionResult& result) {
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
