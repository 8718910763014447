#include "nhdyn/analysis/initial_state.hpp"

#include <fmt/format.h>

#include <cmath>

#include "nhdyn/core/error.hpp"
#include "nhdyn/model/terms.hpp"

namespace nhdyn {
namespace {

// Rows of b (constraint indices) whose residual lives at `level` or below.
std::vector<int> rows_at(const Model& model, ConstraintLevel level) {
  std::vector<int> rows;
  for (int i = 0; i < model.s(); ++i) {
    const ConstraintLevel l = model.constraints[static_cast<std::size_t>(i)].level;
    if (level == ConstraintLevel::position ? l == ConstraintLevel::position : l != ConstraintLevel::acceleration)
      rows.push_back(i);
  }
  return rows;
}

Vector residual(const Model& model, Data& data, double t, const Vector& q, const Vector& v, ConstraintLevel level) {
  Vector r(level == ConstraintLevel::position ? model.position_constraints() : model.velocity_constraints());
  if (r.size() == 0) return r;
  if (level == ConstraintLevel::position)
    model.evaluator->position_residual(t, q.data(), data.scratch.data(), r.data());
  else
    model.evaluator->velocity_residual(t, q.data(), v.data(), data.scratch.data(), r.data());
  return r;
}

double max_abs(const Vector& r) { return r.size() ? r.cwiseAbs().maxCoeff() : 0.0; }

// Newton on r(x) = 0 with minimum-A-norm steps; x is q (position level) or v (velocity level).
int newton(const Model& model, Data& data, double t, Vector& q, Vector& v, ConstraintLevel level, double tolerance,
           int max_iterations, double& final_residual) {
  const std::vector<int> rows = rows_at(model, level);
  if (rows.empty()) return 0;
  const char* what = level == ConstraintLevel::position ? "position" : "velocity";
  Vector r = residual(model, data, t, q, v, level);
  int iteration = 0;
  while (max_abs(r) > tolerance) {
    if (iteration == max_iterations || !r.allFinite()) {
      std::string names;
      for (int row : rows) names += (names.empty() ? "'" : ", '") + model.constraints[static_cast<std::size_t>(row)].name + "'";
      throw ModelError(fmt::format(
          "model '{}': moving the initial state onto the {} constraints ({}) did not converge: the residual "
          "is still {:.3g} after {} Newton steps. The constraints may have no solution near the given state; "
          "correct the initial values by hand.",
          model.name, what, names, max_abs(r), iteration));
    }
    if (compute_terms(model, data, t, q.data(), v.data()) != Status::ok)
      throw ModelError(fmt::format("model '{}': a term is not finite at the initial state ({}) while fixing it",
                                   model.name, data.failed_quantity));
    Matrix J(static_cast<Eigen::Index>(rows.size()), model.n());
    for (std::size_t i = 0; i < rows.size(); ++i) J.row(static_cast<Eigen::Index>(i)) = data.b.row(rows[i]);
    Eigen::LLT<Matrix> llt(data.A);
    if (llt.info() != Eigen::Success)
      throw ModelError(fmt::format("model '{}': the inertia matrix is not positive definite at the initial state",
                                   model.name));
    const Matrix AinvJt = llt.solve(J.transpose());
    const Matrix S = J * AinvJt;
    Eigen::ColPivHouseholderQR<Matrix> qr(S);
    if (qr.rank() < S.rows())
      throw ModelError(fmt::format("model '{}': the {} constraints are dependent at the initial state; "
                                   "fixing it needs independent constraints",
                                   model.name, what));
    const Vector step = -AinvJt * qr.solve(r);
    (level == ConstraintLevel::position ? q : v) += step;
    r = residual(model, data, t, q, v, level);
    ++iteration;
  }
  final_residual = max_abs(r);
  return iteration;
}

}  // namespace

std::vector<ConstraintResidual> calc_initial_residuals(const Model& model, Data& data, double t, const Vector& q,
                                                      const Vector& v) {
  std::vector<ConstraintResidual> out;
  for (ConstraintLevel level : {ConstraintLevel::position, ConstraintLevel::velocity}) {
    const Vector r = residual(model, data, t, q, v, level);
    const std::vector<int> rows = rows_at(model, level);
    for (std::size_t i = 0; i < rows.size(); ++i)
      out.push_back({model.constraints[static_cast<std::size_t>(rows[i])].name, level, r(static_cast<Eigen::Index>(i))});
  }
  return out;
}

InitialFix fix_initial_state(const Model& model, Data& data, double t, const Vector& q, const Vector& v,
                             double tolerance, int max_iterations) {
  InitialFix fix;
  fix.q = q;
  fix.v = v;
  fix.position_iterations =
      newton(model, data, t, fix.q, fix.v, ConstraintLevel::position, tolerance, max_iterations, fix.position_residual);
  // The velocity constraints are taken at the corrected positions.
  fix.velocity_iterations =
      newton(model, data, t, fix.q, fix.v, ConstraintLevel::velocity, tolerance, max_iterations, fix.velocity_residual);
  fix.dq = fix.q - q;
  fix.dv = fix.v - v;
  return fix;
}

void check_initial_state(const Model& model, Data& data, double t, const Vector& q, const Vector& v,
                         double tolerance) {
  std::string report;
  for (const ConstraintResidual& r : calc_initial_residuals(model, data, t, q, v))
    if (!(std::abs(r.value) <= tolerance))
      report += fmt::format("\n  {} ({} level): residual {:.6g}", r.constraint,
                            r.level == ConstraintLevel::position ? "position" : "velocity", r.value);
  if (!report.empty())
    throw ModelError(fmt::format("model '{}': the initial state violates its constraints (tolerance {:g}):{}\n"
                                 "Correct the initial values, or run with --fix-initial to move them onto the "
                                 "constraints with the smallest inertia-weighted change.",
                                 model.name, tolerance, report));
}

}  // namespace nhdyn
