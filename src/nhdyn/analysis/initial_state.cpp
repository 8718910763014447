#include "nhdyn/analysis/initial_state.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <string>
#include <vector>

#include <Eigen/Dense>

#include "nhdyn/analysis/projection.hpp"
#include "nhdyn/core/error.hpp"
#include "nhdyn/core/join.hpp"
#include "nhdyn/formulation/diagnosis.hpp"
#include "nhdyn/model/contact_modes.hpp"
#include "nhdyn/model/detail/residual_round_off.hpp"
#include "nhdyn/model/terms.hpp"

namespace nhdyn {
namespace {

// The rows of the initial state's conditions: constraint i is row i; with `programs`, program j
// (docs/derivations/program-motion.md) is row s + j after them, since a motion must start on its
// programs as on its constraints.
bool lives_at(ConstraintLevel row_level, ConstraintLevel level) {
  return level == ConstraintLevel::position ? row_level == ConstraintLevel::position
                                            : row_level != ConstraintLevel::acceleration;
}

// Rows (as above) whose residual lives at `level`.
std::vector<int> rows_at(const Model& model, ConstraintLevel level, bool programs = false) {
  std::vector<int> rows;
  for (int i = 0; i < model.s(); ++i)
    if (lives_at(model.constraints[static_cast<std::size_t>(i)].level, level)) rows.push_back(i);
  if (programs)
    for (int j = 0; j < model.m(); ++j)
      if (lives_at(model.program_constraints[static_cast<std::size_t>(j)].level, level)) rows.push_back(model.s() + j);
  return rows;
}

// Whether constraint `row` belongs to a contact that starts in a mode that drops it: its given
// `mode` (a free contact's gap and a sliding one's slip are motion, not constraint error), or, in a
// model whose contacts are never all held (s >= n), a unilateral contact whose gap `phi` (the
// position residuals at the start) is open, as the run starts it free.
bool dropped_at_start(const Model& model, int row, const Vector& phi) {
  if (!model.contact_modes || row >= model.s()) return false;
  for (const ContactModeContact& c : model.contact_modes->contacts) {
    if (c.initial >= 0 && contact_mode_drops_row(c, static_cast<ContactMode>(c.initial), row)) return true;
    if (c.initial < 0 && model.s() >= model.n() && c.unilateral && c.gap_position < phi.size() &&
        phi(c.gap_position) > 1e-9 && contact_mode_drops_row(c, ContactMode::free, row))
      return true;
  }
  return false;
}

// Whether some contact starts in a mode the model decides alone: a given one, or any in a model
// whose contacts are never all held.
bool modes_given(const Model& model) {
  if (!model.contact_modes) return false;
  if (model.s() >= model.n()) return true;
  for (const ContactModeContact& c : model.contact_modes->contacts)
    if (c.initial >= 0) return true;
  return false;
}

// The residual of those rows, in that order.
Vector residual(const Model& model, Data& data, double t, const Vector& q, const Vector& v, ConstraintLevel level,
                bool programs = false) {
  const bool position = level == ConstraintLevel::position;
  const Eigen::Index own = position ? model.position_constraints() : model.velocity_constraints();
  const Eigen::Index of_programs = static_cast<Eigen::Index>(rows_at(model, level, programs).size()) - own;
  Vector r = Vector::Zero(own + of_programs);
  if (own > 0) {
    if (position) model.evaluator->position_residual(t, q.data(), data.scratch.data(), r.data());
    else model.evaluator->velocity_residual(t, q.data(), v.data(), data.scratch.data(), r.data());
  }
  if (of_programs > 0) {
    if (position) model.evaluator->program_constraint_position_residual(t, q.data(), data.scratch.data(), r.data() + own);
    else model.evaluator->program_constraint_velocity_residual(t, q.data(), v.data(), data.scratch.data(), r.data() + own);
  }
  return r;
}

// For each row, its place in the residual of `level` (-1 when it is not of that level).
std::vector<int> residual_rows(const Model& model, ConstraintLevel level, bool programs = false) {
  std::vector<int> out(static_cast<std::size_t>(model.s() + (programs ? model.m() : 0)), -1);
  int j = 0;
  for (int i : rows_at(model, level, programs)) out[static_cast<std::size_t>(i)] = j++;
  return out;
}

// The gradients of the rows at (t, q, v) after compute_terms: b, and with `programs` the programs'
// b_p below it (their rows at acceleration level are their gradients, as b's are). Cold path.
Matrix gradient_rows(const Model& model, Data& data, double t, const Vector& q, const Vector& v, bool programs) {
  const Matrix b = data.sparse ? Matrix(data.b_sparse) : data.b;
  if (!programs || model.m() == 0) return b;
  Matrix b_p(model.m(), model.n()), B(model.n(), model.m());
  Vector b_p0(model.m());
  model.evaluator->program_constraint_terms(t, q.data(), v.data(), data.scratch.data(), b_p.data(), b_p0.data(),
                                            B.data());
  Matrix out(model.s() + model.m(), model.n());
  out << b, b_p;
  return out;
}

// "the constraint 'NAME' (velocity level, file:line)" or "the program 'NAME' (position level)".
std::string row_label(const Model& model, int row, const char* level) {
  if (row < model.s()) {
    const Constraint& c = model.constraints[static_cast<std::size_t>(row)];
    return fmt::format("the constraint '{}' ({} level{})", c.name, level, c.where.empty() ? "" : ", " + c.where);
  }
  return fmt::format("the program '{}' ({} level)", model.program_constraints[static_cast<std::size_t>(row - model.s())].name,
                     level);
}

std::string value_name(const Model& model, int i, ConstraintLevel level) {
  return model.coordinates[static_cast<std::size_t>(i)] + (level == ConstraintLevel::position ? "" : "'");
}

// Newton's method on the residual of `level`, its rows those of the constraints `rows`, moving only
// the entries `free` of q (position) or v (velocity), each step the smallest change weighted by
// A's block of them: [W J^T; J 0] [d; mu] = [0; -r], W = A(free, free), J = b(rows, free), solved
// by a complete orthogonal decomposition (least squares where it is singular). Returns the
// residual of those rows reached (r) and the Newton steps taken.
int restricted_newton(const Model& model, Data& data, double t, Vector& q, Vector& v, ConstraintLevel level,
                      const std::vector<int>& free, const std::vector<int>& rows, double tolerance,
                      int max_iterations, Vector& r, bool programs = false) {
  const std::vector<int> at = residual_rows(model, level, programs);
  const auto m = static_cast<Eigen::Index>(rows.size()), k = static_cast<Eigen::Index>(free.size());
  Vector& x = level == ConstraintLevel::position ? q : v;
  r.resize(m);
  const auto evaluate = [&] {
    const Vector all = residual(model, data, t, q, v, level, programs);
    for (Eigen::Index i = 0; i < m; ++i) r(i) = all(at[static_cast<std::size_t>(rows[static_cast<std::size_t>(i)])]);
    return r.allFinite() ? (m == 0 ? 0.0 : r.cwiseAbs().maxCoeff()) : std::numeric_limits<double>::infinity();
  };
  int iterations = 0;
  double worst = evaluate();
  while (worst > tolerance && iterations < max_iterations && std::isfinite(worst) && k > 0) {
    if (compute_terms(model, data, t, q.data(), v.data()) != Status::ok)
      throw ModelError(fmt::format("model '{}': while moving the initial state onto the constraints: {}", model.name,
                                   explain_failure(model, data)));
    const Matrix A = data.sparse ? Matrix(data.A_sparse) : data.A;
    const Matrix b = gradient_rows(model, data, t, q, v, programs);
    Matrix K = Matrix::Zero(k + m, k + m);
    for (Eigen::Index i = 0; i < k; ++i)
      for (Eigen::Index j = 0; j < k; ++j)
        K(i, j) = A(free[static_cast<std::size_t>(i)], free[static_cast<std::size_t>(j)]);
    for (Eigen::Index i = 0; i < m; ++i)
      for (Eigen::Index j = 0; j < k; ++j)
        K(k + i, j) = K(j, k + i) = b(rows[static_cast<std::size_t>(i)], free[static_cast<std::size_t>(j)]);
    Vector rhs = Vector::Zero(k + m);
    rhs.tail(m) = -r;
    const Vector step = Eigen::CompleteOrthogonalDecomposition<Matrix>(K).solve(rhs);
    if (!step.allFinite()) break;
    double size = 0.0;
    for (Eigen::Index j = 0; j < k; ++j) {
      x(free[static_cast<std::size_t>(j)]) += step(j);
      size = std::max(size, std::abs(x(free[static_cast<std::size_t>(j)])));
    }
    ++iterations;
    worst = evaluate();
    if (step.head(k).cwiseAbs().maxCoeff() <= 64.0 * std::numeric_limits<double>::epsilon() * size) break;
  }
  return iterations;
}

// --fix-initial when [initial] wrote some values: the others move, level by level.
void fix_keeping_written(const Model& model, Data& data, double t, double tolerance, int max_iterations,
                         InitialFix& fix) {
  for (const ConstraintLevel level : {ConstraintLevel::position, ConstraintLevel::velocity}) {
    const std::vector<bool>& written = level == ConstraintLevel::position ? model.q0_written : model.v0_written;
    std::vector<int> free;
    std::vector<std::string> free_names;
    for (int i = 0; i < model.n(); ++i)
      if (static_cast<std::size_t>(i) >= written.size() || !written[static_cast<std::size_t>(i)]) {
        free.push_back(i);
        free_names.push_back(value_name(model, i, level));
      }
    std::vector<int> all = rows_at(model, level, true);
    const Vector phi = residual(model, data, t, fix.q, fix.v, ConstraintLevel::position);
    all.erase(std::remove_if(all.begin(), all.end(), [&](int row) { return dropped_at_start(model, row, phi); }),
              all.end());
    // The constraints and programs none of the free values enter cannot be mended by moving them.
    std::vector<int> movable, fixed_rows;
    if (!all.empty()) {
      if (compute_terms(model, data, t, fix.q.data(), fix.v.data()) != Status::ok)
        throw ModelError(fmt::format("model '{}': while moving the initial state onto the constraints: {}",
                                     model.name, explain_failure(model, data)));
      const Matrix b = gradient_rows(model, data, t, fix.q, fix.v, true);
      for (int row : all) {
        bool enters = false;
        for (int j : free) enters = enters || b(row, j) != 0.0;
        (enters ? movable : fixed_rows).push_back(row);
      }
    }
    Vector r;
    const int iterations =
        restricted_newton(model, data, t, fix.q, fix.v, level, free, movable, tolerance, max_iterations, r, true);
    const Vector whole = residual(model, data, t, fix.q, fix.v, level, true);
    const std::vector<int> at = residual_rows(model, level, true);
    int worst_row = -1;
    double worst = 0.0;
    // Newton aims at `tolerance`; what round-off leaves above it is no reason to refuse: 1e-10, or
    // the round-off of a row's terms where that is larger (model/detail/residual_round_off.hpp),
    // as the check without --fix-initial allows.
    const double refuse_above = std::max(tolerance, 1e-10);
    Matrix b_end;
    for (int row : all) {
      const double value = std::abs(whole(at[static_cast<std::size_t>(row)]));
      if (value <= refuse_above) continue;
      if (b_end.size() == 0 && compute_terms(model, data, t, fix.q.data(), fix.v.data()) == Status::ok)
        b_end = gradient_rows(model, data, t, fix.q, fix.v, true);
      const bool position = level == ConstraintLevel::position;
      if (b_end.rows() > row &&
          value <= residual_round_off(b_end.row(row), position ? fix.q : fix.v, model.n(),
                                      whole(at[static_cast<std::size_t>(row)]), !position))
        continue;
      if (worst_row < 0 || !(value <= worst)) {
        worst_row = row;
        worst = value;
      }
    }
    const char* level_name = level == ConstraintLevel::position ? "position" : "velocity";
    if (worst_row >= 0) {
      const bool alone = std::find(fixed_rows.begin(), fixed_rows.end(), worst_row) != fixed_rows.end();
      const std::string label = row_label(model, worst_row, level_name);
      const double value = whole(at[static_cast<std::size_t>(worst_row)]);
      throw ModelError(fmt::format(
          "model '{}': --fix-initial keeps every value [initial] writes and moves only the others ({}); {}, so the "
          "values written cannot satisfy it. Correct them, or leave out of [initial] a value that --fix-initial may "
          "move.",
          model.name,
          free.empty() ? fmt::format("none is free at {} level", level_name)
                       : fmt::format("free at {} level: {}", level_name, join(free_names)),
          alone ? fmt::format("no free value enters {}, which keeps the residual {:.6g}", label, value)
                : fmt::format("moving them ({} Newton steps), {} keeps the residual {:.6g}", iterations, label, value)));
    }
    (level == ConstraintLevel::position ? fix.position_iterations : fix.velocity_iterations) = iterations;
    (level == ConstraintLevel::position ? fix.position_residual : fix.velocity_residual) =
        whole.size() == 0 ? 0.0 : whole.cwiseAbs().maxCoeff();
  }
}

}  // namespace

void complete_initial_state(const Model& model, Data& data, double t, Vector& q, Vector& v) {
  // The load-time solve's (rolling_contact.cpp) and --fix-initial's tolerance: a model that loads
  // also starts, whatever the size of its coordinates' round-off.
  constexpr double tolerance = 1e-10;
  for (const ContactCoordinates& added : model.contact_coordinates) {
    for (const ConstraintLevel level : {ConstraintLevel::position, ConstraintLevel::velocity}) {
      Vector r;
      restricted_newton(model, data, t, q, v, level, added.coordinates, added.constraints, tolerance, 50, r);
      if (r.size() == 0 || (r.allFinite() && r.cwiseAbs().maxCoeff() <= tolerance)) continue;
      Eigen::Index row = 0;
      if (r.allFinite()) r.cwiseAbs().maxCoeff(&row);
      std::vector<std::string> names;
      for (int i : added.coordinates) names.push_back(value_name(model, i, level));
      throw ModelError(fmt::format(
          "{}contact '{}': cannot find the {} of its contact point ({}) at the start: Newton's method stops with "
          "the constraint '{}' at the residual {:.6g}. The body may be too far from the ground or its shape not "
          "convex there; start the body on the ground, or name the contact point's coordinates and give their "
          "initial values",
          added.where.empty() ? "" : added.where + ": ", added.contact,
          level == ConstraintLevel::position ? "coordinates" : "velocities", join(names),
          model.constraints[static_cast<std::size_t>(added.constraints[static_cast<std::size_t>(row)])].name,
          r.allFinite() ? r(row) : std::numeric_limits<double>::infinity()));
    }
  }
}

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

InitialFix fix_free_initial_values(const Model& model, Data& data, double t, const Vector& q, const Vector& v,
                                   double tolerance, int max_iterations) {
  const auto any = [](const std::vector<bool>& flags) { return std::find(flags.begin(), flags.end(), true) != flags.end(); };
  // The projection knows the constraints only: a model with programs takes the restricted Newton
  // steps, every value free when none is written (the same smallest inertia-weighted change); so
  // does a model whose contacts' modes at t0 are given, which drop some rows.
  if (!any(model.q0_written) && !any(model.v0_written) && model.m() == 0 && !modes_given(model))
    return fix_initial_state(model, data, t, q, v, tolerance, max_iterations);
  InitialFix fix;
  fix.q = q;
  fix.v = v;
  fix_keeping_written(model, data, t, tolerance, max_iterations, fix);
  fix.dq = fix.q - q;
  fix.dv = fix.v - v;
  return fix;
}

namespace {

// Per constraint row (model.s()), the tolerance of its residual at (t, q, v) for `level`: the
// larger of the given one and the round-off of the terms it sums (model/detail/
// residual_round_off.hpp; a pendulum 1500 km long has x^2 + y^2 - l^2 at 5e-4 from rounding
// alone, and an absolute tolerance refused every state it could start from). The given tolerance
// alone where the terms cannot be evaluated (the residual check then names what is wrong).
std::vector<double> residual_tolerances(const Model& model, Data& data, double t, const Vector& q, const Vector& v,
                                        ConstraintLevel level, const Vector& r, double tolerance) {
  std::vector<double> out(static_cast<std::size_t>(model.s()), tolerance);
  if (compute_terms(model, data, t, q.data(), v.data()) != Status::ok) return out;
  const Matrix b = gradient_rows(model, data, t, q, v, false);
  const std::vector<int> rows = rows_at(model, level);
  const bool position = level == ConstraintLevel::position;
  for (std::size_t k = 0; k < rows.size(); ++k) {
    const int i = rows[k];
    out[static_cast<std::size_t>(i)] = std::max(
        tolerance, residual_round_off(b.row(i), position ? q : v, model.n(), r(static_cast<Eigen::Index>(k)), !position));
  }
  return out;
}

}  // namespace

void check_initial_state(const Model& model, Data& data, double t, const Vector& q, const Vector& v,
                         double tolerance) {
  std::string report;
  for (const ConstraintLevel level : {ConstraintLevel::position, ConstraintLevel::velocity}) {
    const Vector r = residual(model, data, t, q, v, level);
    const std::vector<int> rows = rows_at(model, level);
    std::vector<double> allowed;
    for (std::size_t k = 0; k < rows.size(); ++k) {
      const double value = r(static_cast<Eigen::Index>(k));
      if (std::abs(value) <= tolerance) continue;
      if (allowed.empty()) allowed = residual_tolerances(model, data, t, q, v, level, r, tolerance);
      const Constraint& c = model.constraints[static_cast<std::size_t>(rows[k])];
      if (std::abs(value) <= allowed[static_cast<std::size_t>(rows[k])]) continue;
      if (contact_mode_drops(model, data, c.name)) continue;  // a sliding contact's slip, a free one's gap
      // Where it was written, and what it says when that is more than its name (a contact's gap).
      const std::string where = c.where.empty() ? "" : " (" + c.where + ")";
      const std::string says =
          c.expression.rfind("contact '", 0) == 0 || c.expression.rfind("frame '", 0) == 0 ? ": " + c.expression : "";
      report += fmt::format("\n  {} ({} level): residual {:.6g}{}{}", c.name,
                            level == ConstraintLevel::position ? "position" : "velocity", value, where, says);
    }
  }
  if (!report.empty())
    throw ModelError(fmt::format("model '{}': the initial state violates its constraints (tolerance {:g}, or {:g} "
                                 "units of round-off of a constraint's terms where that is larger):{}\n"
                                 "Correct the initial values, or run with --fix-initial to move them onto the "
                                 "constraints with the smallest inertia-weighted change.",
                                 model.name, tolerance, kResidualRoundOffUnits, report));
}

}  // namespace nhdyn
