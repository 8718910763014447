// The checks of transcription.hpp that run before IPOPT: the start's points described, the path
// constraints at the fixed ends, the model's terms and the problem's expressions on the first guess,
// the controls that act, and the final values the constraints determine (released, or refused
// when the others contradict them).
#include "nhdyn/optimize/transcription.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <string>
#include <vector>

#include "nhdyn/core/error.hpp"
#include "nhdyn/core/join.hpp"
#include "nhdyn/formulation/diagnosis.hpp"
#include "nhdyn/model/detail/tape_tangent.hpp"

namespace nhdyn {

std::string Transcription::describe_point(int p, const double* x) const {
  const Model& model = problem_.model;
  std::string out = fmt::format("t = {}", time(p, x));
  for (int i = 0; i < n_; ++i) out += fmt::format(", {} = {}", model.coordinates[static_cast<std::size_t>(i)], x[q_index(p, i)]);
  for (int i = 0; i < n_; ++i) out += fmt::format(", {}' = {}", model.coordinates[static_cast<std::size_t>(i)], x[v_index(p, i)]);
  for (int j = 0; j < m_; ++j) out += fmt::format(", {} = {}", problem_.controls[static_cast<std::size_t>(j)].name, x[u_index(p, j)]);
  return out;
}

void Transcription::require_path_at_fixed_ends() {
  if (path_count_ == 0) return;
  const Model& model = problem_.model;
  std::vector<double> g(static_cast<std::size_t>(path_count_));
  for (const int p : {0, points_ - 1}) {
    layout_inputs(p, start_.data());
    problem_.path.run(time(p, start_.data()), layout_q_.data(), layout_v_.data(), other_registers_.data(), g.data());
    for (int k = 0; k < path_count_; ++k) {
      const PathConstraint& c = problem_.path_constraints[static_cast<std::size_t>(k)];
      if (c.reads_time && problem_.free_time && p > 0) continue;  // t_end is not known
      if (c.reads.size() != static_cast<std::size_t>(2 * n_ + m_)) continue;  // what it reads is not known
      std::vector<std::string> read;
      bool decided = true;
      for (int v = 0; v < 2 * n_ + m_ && decided; ++v) {
        if (!c.reads[static_cast<std::size_t>(v)]) continue;
        const int index = v < n_ ? q_index(p, v) : v < 2 * n_ ? v_index(p, v - n_) : u_index(p, v - 2 * n_);
        decided = x_lower_[static_cast<std::size_t>(index)] == x_upper_[static_cast<std::size_t>(index)];
        const std::string name = v < n_    ? model.coordinates[static_cast<std::size_t>(v)]
                                 : v < 2 * n_ ? model.coordinates[static_cast<std::size_t>(v - n_)] + "'"
                                              : problem_.controls[static_cast<std::size_t>(v - 2 * n_)].name;
        read.push_back(fmt::format("{} = {}", name, start_[static_cast<std::size_t>(index)]));
      }
      const double value = g[static_cast<std::size_t>(k)];
      // Not finite: require_defined_at_start names it with the point.
      if (!decided || !std::isfinite(value) || (value >= c.lower - 1e-8 && value <= c.upper + 1e-8)) continue;
      throw InputError(fmt::format(
          "{}{}the path constraint \"{}\" cannot hold at t = {}: {}, its left side less its right side is {:.6g}, "
          "which must be {} 0; change the {} values or the constraint",
          c.where, c.where.empty() ? "" : ": ", c.text, time(p, start_.data()),
          read.empty() ? std::string("it reads no coordinate, velocity or control (a condition fixed in advance)")
                       : fmt::format("with the fixed {} values {}", p == 0 ? "initial" : "final", join(read)),
          value, std::isfinite(c.lower) ? ">=" : "<=", p == 0 ? "initial" : "final"));
    }
  }
}

// Entry k of terms_out_ by name: A (n x n), Q, G (n), b (s x n), b0 (s), each column-major.
std::string Transcription::term_name(int k) const {
  const auto& model = problem_.model;
  const auto coordinate = [&](int i) { return model.coordinates[static_cast<std::size_t>(i)]; };
  const auto constraint = [&](int i) { return model.constraints[static_cast<std::size_t>(i)].name; };
  if (k < n_ * n_) return fmt::format("A({}, {})", coordinate(k % n_), coordinate(k / n_));
  k -= n_ * n_;
  if (k < n_) return "Q_" + coordinate(k);
  k -= n_;
  if (k < n_) return "G_" + coordinate(k);
  k -= n_;
  if (k < s_ * n_) return fmt::format("b({}, {})", constraint(k % s_), coordinate(k / s_));
  k -= s_ * n_;
  return fmt::format("b0({})", constraint(k));
}

void Transcription::require_defined_at_start() {
  const double* x = start_.data();
  const std::string what_to_do =
      "give a first guess where it is defined (--guess FILE.csv), bounds that keep the motion there, or another "
      "expression";
  const auto undefined = [&](const std::string& what, const std::string& where, double value, int p) {
    return InputError(fmt::format("{}{}{} is not finite ({}) at the first guess's point {}: {}", where,
                                  where.empty() ? "" : ": ", what, std::isnan(value) ? std::string("NaN") : fmt::format("{}", value),
                                  describe_point(p, x), what_to_do));
  };
  std::vector<double> g(static_cast<std::size_t>(std::max(path_count_, 1))),
      columns(static_cast<std::size_t>(n_ * m_));
  double value = 0.0;
  for (int p = 0; p < points_; ++p) {
    const double t = time(p, x);
    terms_->run(t, x + q_index(p, 0), x + v_index(p, 0), terms_registers_.data(), terms_out_.data());
    for (std::size_t k = 0; k < terms_out_.size(); ++k)
      if (!std::isfinite(terms_out_[k]))
        throw undefined(fmt::format("the model's term {} (from its kinetic and potential energy, forces and "
                                    "constraints)",
                                    term_name(static_cast<int>(k))),
                        "", terms_out_[k], p);
    // An inertia that is not positive on the motions the constraints allow (a mass set to 0 or
    // -1) makes no dynamics: simulate refuses it; the transcription solved it (F = 0 moving x).
    if (p == 0) {
      const Eigen::Map<const Eigen::MatrixXd> A(terms_out_.data(), n_, n_);
      const Eigen::Map<const Eigen::MatrixXd> b(terms_out_.data() + n_ * n_ + 2 * n_, s_, n_);
      double smallest = 0.0;
      if (!inertia_positive_on_constraints(A, b, smallest))
        throw InputError(fmt::format(
            "the inertia matrix A of model '{}' is not positive definite on the motions its constraints allow at "
            "the first guess's point {} (smallest eigenvalue {:.6g}): every coordinate needs a positive mass or "
            "inertia (a mass of 0 or below moves under no force); simulate refuses it too",
            problem_.model.name, describe_point(p, x), smallest));
    }
    layout_inputs(p, x);
    problem_.integrand.run(t, layout_q_.data(), layout_v_.data(), other_registers_.data(), &value);
    if (!std::isfinite(value))
      throw undefined(fmt::format("the objective \"{}\"", problem_.objective_text), problem_.objective_where, value, p);
    if (problem_.final_term && p == points_ - 1) {
      problem_.final_term->run(t, layout_q_.data(), layout_v_.data(), other_registers_.data(), &value);
      if (!std::isfinite(value)) throw undefined("objective_final", problem_.final_term_where, value, p);
    }
    if (path_count_ > 0) {
      problem_.path.run(t, layout_q_.data(), layout_v_.data(), other_registers_.data(), g.data());
      for (int k = 0; k < path_count_; ++k)
        if (!std::isfinite(g[static_cast<std::size_t>(k)])) {
          const PathConstraint& c = problem_.path_constraints[static_cast<std::size_t>(k)];
          throw undefined(fmt::format("the path constraint \"{}\"", c.text), c.where, g[static_cast<std::size_t>(k)], p);
        }
    }
    if (m_ > 0) {
      problem_.actuators.run(t, layout_q_.data(), layout_v_.data(), other_registers_.data(), columns.data());
      for (int j = 0; j < m_; ++j)
        for (int i = 0; i < n_; ++i) {
          const double b = columns[static_cast<std::size_t>(j * n_ + i)];
          if (std::isfinite(b)) continue;
          const OptimizeControl& c = problem_.controls[static_cast<std::size_t>(j)];
          throw undefined(fmt::format("the actuator {} of control '{}' (its entry on {})", c.actuator, c.name,
                                      problem_.model.coordinates[static_cast<std::size_t>(i)]),
                          c.where, b, p);
        }
    }
  }
}

// A control whose force the constraints absorb (D B_j = 0: it pushes along a constrained
// direction) does not act on the system: refuse it, at the first point of the starting point.
void Transcription::check_controls_act() {
  if (m_ == 0 || !evaluate_point(0, start_.data())) return;
  std::vector<double> zero_n(static_cast<std::size_t>(n_), 0.0), e_m(static_cast<std::size_t>(m_), 0.0),
      column(static_cast<std::size_t>(n_), 0.0), dynamics(static_cast<std::size_t>(n_));
  dynamics_values(0, start_.data(), dynamics.data());
  for (int j = 0; j < m_; ++j) {
    std::fill(e_m.begin(), e_m.end(), 0.0);
    e_m[static_cast<std::size_t>(j)] = 1.0;
    dynamics_direction(0, start_.data(), 0.0, zero_n.data(), zero_n.data(), e_m.data(), column.data());
    double force = 0.0, acting = 0.0;
    for (int i = 0; i < n_; ++i) force = std::max(force, std::abs(dforce_[static_cast<std::size_t>(i)]));
    for (int l = 0; l < k_; ++l) acting = std::max(acting, std::abs(column[static_cast<std::size_t>(l)]));
    if (force > 0.0 && acting <= 1e-12 * force)
      throw InputError(fmt::format("the control '{}' does not act on the system: the constraints absorb its force "
                                   "(D B = 0 at t = {}); give its actuator a direction the constraints leave free",
                                   problem_.controls[static_cast<std::size_t>(j)].name, problem_.t0));
  }
}

// The rank rule at t_end (docs/derivations/optimal-programs.md, section 5, item 1): a combination
// of the constraints (position and velocity level, linearized at the final state of the starting
// point) that involves only final values the user fixed is a relation among them which the exact
// motion meets for free but the discrete one only up to its drift. Such final values are released
// (one per relation, the pivots of a column-pivoted QR of the relations), and the summary says so.
void Transcription::release_determined_final_values() {
  const Model& model = problem_.model;
  const int pcount = model.position_constraints(), rcount = model.velocity_constraints();
  const int rows = pcount + rcount;
  if (rows == 0 || problem_.final.empty()) return;
  const int last = points_ - 1;
  const double* x = start_.data();
  // The starting point's final state with the fixed values in it.
  std::vector<double> q(x + q_index(last, 0), x + q_index(last, 0) + n_), v(x + v_index(last, 0), x + v_index(last, 0) + n_);
  for (const BoundaryValue& b : problem_.final) (b.velocity ? v : q)[static_cast<std::size_t>(b.index)] = b.value;
  std::vector<double> values;
  Eigen::MatrixXd C;
  constraint_rows(problem_.t_end, q.data(), v.data(), values, C);
  std::vector<int> fixed_columns, free_columns;
  for (int c = 0; c < 2 * n_; ++c) {
    const bool fixed = std::any_of(problem_.final.begin(), problem_.final.end(), [&](const BoundaryValue& b) {
      return b.index + (b.velocity ? n_ : 0) == c;
    });
    (fixed ? fixed_columns : free_columns).push_back(c);
  }
  Eigen::MatrixXd Cfree(rows, static_cast<Eigen::Index>(free_columns.size())), Cfixed(rows, static_cast<Eigen::Index>(fixed_columns.size()));
  for (std::size_t c = 0; c < free_columns.size(); ++c) Cfree.col(static_cast<Eigen::Index>(c)) = C.col(free_columns[c]);
  for (std::size_t c = 0; c < fixed_columns.size(); ++c) Cfixed.col(static_cast<Eigen::Index>(c)) = C.col(fixed_columns[c]);
  // The combinations z of the constraint rows with z^T Cfree = 0: a basis of the left null space.
  Eigen::MatrixXd Z;
  if (Cfree.cols() == 0) {
    Z = Eigen::MatrixXd::Identity(rows, rows);
  } else {
    const Eigen::JacobiSVD<Eigen::MatrixXd> svd(Cfree, Eigen::ComputeFullU);
    const double tol = 1e-9 * std::max(1.0, svd.singularValues().size() ? svd.singularValues()(0) : 0.0);
    int rank = 0;
    for (Eigen::Index i = 0; i < svd.singularValues().size(); ++i) rank += svd.singularValues()(i) > tol ? 1 : 0;
    Z = svd.matrixU().rightCols(rows - rank);
  }
  if (Z.cols() == 0) return;
  const Eigen::MatrixXd relations = Z.transpose() * Cfixed;  // relations among the fixed final values
  require_final_values_agree(Z, relations, values, fixed_columns);
  const Eigen::ColPivHouseholderQR<Eigen::MatrixXd> qr(relations);
  const double tol = 1e-9 * std::max(1.0, relations.cwiseAbs().maxCoeff());
  int count = 0;
  for (Eigen::Index i = 0; i < std::min(relations.rows(), relations.cols()); ++i)
    count += std::abs(qr.matrixR()(i, i)) > tol ? 1 : 0;
  std::vector<std::string> names;
  for (const Constraint& c : model.constraints)
    if (c.level != ConstraintLevel::acceleration) names.push_back(c.name);
  for (int i = 0; i < count; ++i) {
    const int column = fixed_columns[static_cast<std::size_t>(qr.colsPermutation().indices()(i))];
    const std::size_t at = static_cast<std::size_t>(column < n_ ? q_index(last, column) : v_index(last, column - n_));
    const std::string name = model.coordinates[static_cast<std::size_t>(column % n_)] + (column < n_ ? "" : "'");
    x_lower_[at] = nlp_bound(problem_.state_lower[static_cast<std::size_t>(column)]);
    x_upper_[at] = nlp_bound(problem_.state_upper[static_cast<std::size_t>(column)]);
    notes_.push_back(fmt::format("the final {} is determined by the constraints ({}) with the other final values: "
                                 "left free, it meets its value up to the discretization's drift",
                                 name, join(names)));
  }
}

// Before a determined final value is released, the relation must hold with the values the user
// gave: a released value is then met up to the drift. One that does not hold is a contradiction
// (x - y = 0 with x = 1, y = 0 at t_end), which releasing would hide: the result met another
// value than the one asked, with exit 0. Refused as the initial values are (the residual beyond
// round-off of the values, 1e-8 (1 + largest |value|)).
void Transcription::require_final_values_agree(const Eigen::MatrixXd& Z, const Eigen::MatrixXd& relations,
                                               const std::vector<double>& residuals,
                                               const std::vector<int>& fixed_columns) const {
  const Model& model = problem_.model;
  const std::vector<std::string> rows = residual_row_names();
  double largest = 0.0;
  for (const BoundaryValue& b : problem_.final) largest = std::max(largest, std::abs(b.value));
  const Eigen::Map<const Eigen::VectorXd> r(residuals.data(), static_cast<Eigen::Index>(residuals.size()));
  // A constraint not defined at the final values (sqrt of a negative number) says nothing of
  // agreement: named as such, before any combination of the rows.
  for (std::size_t i = 0; i < residuals.size() && i < rows.size(); ++i)
    if (!std::isfinite(residuals[i]))
      throw InputError(fmt::format(
          "the constraint {} is not defined at the final values of [optimize] and the straight line's other final "
          "values (its residual at t_end is {}): give final values where the model is defined, or a first guess "
          "(--guess FILE.csv) that ends there",
          rows[i], std::isnan(residuals[i]) ? std::string("NaN") : fmt::format("{}", residuals[i])));
  for (Eigen::Index k = 0; k < Z.cols(); ++k) {
    const double residual = Z.col(k).dot(r);
    if (std::abs(residual) <= 1e-8 * (1.0 + largest)) continue;
    std::vector<std::string> names, values;
    std::string where;  // the first of the values' places in the file
    for (Eigen::Index i = 0; i < Z.rows(); ++i)
      if (std::abs(Z(i, k)) > 1e-6) names.push_back(rows[static_cast<std::size_t>(i)]);
    const double scale = relations.row(k).cwiseAbs().maxCoeff();
    for (std::size_t c = 0; c < fixed_columns.size(); ++c) {
      if (scale > 0.0 && std::abs(relations(k, static_cast<Eigen::Index>(c))) <= 1e-9 * scale) continue;
      const int column = fixed_columns[c];
      for (const BoundaryValue& b : problem_.final)
        if (b.index + (b.velocity ? n_ : 0) == column) {
          values.push_back(fmt::format("{}{} = {}", model.coordinates[static_cast<std::size_t>(b.index)],
                                       b.velocity ? "'" : "", b.value));
          if (where.empty() && !b.where.empty()) where = b.where + ": ";
        }
    }
    throw InputError(fmt::format(
        "{}the final values of [optimize] violate the constraint{} {}: with {} its residual at t_end is {:.3e}, and no "
        "free final value can change it; give final values on the constraint, or leave one of them out of final",
        where, names.size() > 1 ? "s" : "", join(names, " and "), join(values), residual));
  }
}

}  // namespace nhdyn
