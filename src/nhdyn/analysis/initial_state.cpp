#include "nhdyn/analysis/initial_state.hpp"

#include <fmt/format.h>

#include <cmath>

#include "nhdyn/analysis/projection.hpp"
#include "nhdyn/core/error.hpp"
#include "nhdyn/formulation/diagnosis.hpp"
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
  ProjectionResult result;
  const Status status = compute_projection(model, data, t, fix.q.data(), fix.v.data(),
                                           ProjectionOptions{tolerance, max_iterations}, result);
  if (status == Status::projection_failed) {
    const ConstraintLevel level =
        data.failed_quantity.rfind("position", 0) == 0 ? ConstraintLevel::position : ConstraintLevel::velocity;
    std::string names;
    for (int row : rows_at(model, level))
      names += (names.empty() ? "'" : ", '") + model.constraints[static_cast<std::size_t>(row)].name + "'";
    throw ModelError(fmt::format(
        "model '{}': moving the initial state onto the {} ({}) did not converge: the residual is still {:.3g} "
        "after {} Newton steps. The constraints may have no solution near the given state; correct the "
        "initial values by hand.",
        model.name, data.failed_quantity, names, data.failed_value, max_iterations));
  }
  if (status != Status::ok)
    throw ModelError(fmt::format("model '{}': while moving the initial state onto the constraints: {}", model.name,
                                 explain_failure(model, data)));
  fix.position_iterations = result.position_iterations;
  fix.velocity_iterations = result.velocity_iterations;
  fix.position_residual = result.position_residual;
  fix.velocity_residual = result.velocity_residual;
  fix.dq = fix.q - q;
  fix.dv = fix.v - v;
  return fix;
}

void check_initial_state(const Model& model, Data& data, double t, const Vector& q, const Vector& v,
                         double tolerance) {
  std::string report;
  for (const ConstraintResidual& r : calc_initial_residuals(model, data, t, q, v)) {
    if (std::abs(r.value) <= tolerance) continue;
    if (contact_mode_drops(model, data, r.constraint)) continue;  // a sliding contact's slip, a free one's gap
    // Where it was written, and what it says when that is more than its name (a contact's gap).
    std::string where, says;
    for (const Constraint& c : model.constraints)
      if (c.name == r.constraint) {
        if (!c.where.empty()) where = " (" + c.where + ")";
        if (c.expression.rfind("contact '", 0) == 0 || c.expression.rfind("frame '", 0) == 0) says = ": " + c.expression;
      }
    report += fmt::format("\n  {} ({} level): residual {:.6g}{}{}", r.constraint,
                          r.level == ConstraintLevel::position ? "position" : "velocity", r.value, where, says);
  }
  if (!report.empty())
    throw ModelError(fmt::format("model '{}': the initial state violates its constraints (tolerance {:g}):{}\n"
                                 "Correct the initial values, or run with --fix-initial to move them onto the "
                                 "constraints with the smallest inertia-weighted change.",
                                 model.name, tolerance, report));
}

}  // namespace nhdyn
