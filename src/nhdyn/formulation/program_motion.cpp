#include "nhdyn/formulation/program_motion.hpp"

#include <fmt/format.h>

#include <Eigen/SVD>
#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <vector>

#include "nhdyn/core/error.hpp"
#include "nhdyn/formulation/complement.hpp"
#include "nhdyn/formulation/diagnosis.hpp"
#include "nhdyn/formulation/detail/row_scaling.hpp"
#include "nhdyn/formulation/sanh.hpp"
#include "nhdyn/model/terms.hpp"

namespace nhdyn {
namespace {

constexpr const char* kProgramMatrix = "program matrix S = b_p P B";

// An actuator whose direction the physical constraints take up entirely, D B_j = 0 (relative to
// |D| |B_j|: D is orthonormal for the QR complement, not for the others).
constexpr double kAbsorbed = 1e-12;
// The scaled S (rows and columns of unit length) is singular when a pivot of its LU falls below
// this: an actuator force about 1e10 times its ordinary size would be needed.
constexpr double kSingularPivot = 1e-10;

// The programs' residuals at the state held in data into w.phi and w.f.
void program_residuals(const Model& model, Data& data) {
  ProgramMotionData& w = data.motion;
  if (w.phi.size() > 0)
    model.evaluator->program_constraint_position_residual(data.t, data.q.data(), data.scratch.data(), w.phi.data());
  if (w.f.size() > 0)
    model.evaluator->program_constraint_velocity_residual(data.t, data.q.data(), data.v.data(), data.scratch.data(),
                                                          w.f.data());
}

}  // namespace

void check_program_feedback(const ProgramFeedback& feedback) {
  for (const auto& [name, value] : {std::pair<const char*, double>{"alpha", feedback.alpha}, {"beta", feedback.beta}})
    if (!std::isfinite(value) || value < 0.0)
      throw InputError(fmt::format("the program feedback gain {} = {} must be finite and non-negative (a rate in "
                                   "1/s, e.g. --program-feedback 10,10)",
                                   name, value));
    else if (value > kMaxProgramFeedback)
      throw InputError(fmt::format("the program feedback gain {} = {:g} 1/s is above {:g} 1/s (a time constant under a "
                                   "nanosecond): the feedback would make the motion stiffer than any step can follow "
                                   "and its terms overflow; use a rate a few times the model's fastest frequency "
                                   "(e.g. --program-feedback 10,10)",
                                   name, value, kMaxProgramFeedback));
}

Status compute_program_motion(const Model& model, Data& data, Complement complement, const ProgramFeedback& feedback) {
  const int n = model.n(), s = model.s(), k = model.k(), m = model.m();
  ProgramMotionData& w = data.motion;
  if (data.stage < Stage::terms)
    throw std::logic_error("compute_program_motion: call compute_terms first for the current state");
  if (m == 0 || w.u.size() != m || data.sparse || data.M.rows() != n)
    throw std::logic_error("compute_program_motion: needs a dense Data made for this model (with its programs) and "
                           "the sanh formulation");
  model.evaluator->program_constraint_terms(data.t, data.q.data(), data.v.data(), data.scratch.data(), w.b_p.data(),
                                            w.b_p0.data(), w.B.data());
  if (!w.b_p.allFinite() || !w.b_p0.allFinite() || !w.B.allFinite())
    return record_failure(data, Status::non_finite, "program terms b_p, b_p0, B");
  w.feedback.setZero();
  if (feedback.enabled) {
    // (P6): 2 alpha f_p for position- and velocity-level programs, beta^2 phi_p for position-level ones.
    program_residuals(model, data);
    Eigen::Index ip = 0, iv = 0;
    for (int j = 0; j < m; ++j) {
      const ConstraintLevel level = model.program_constraints[static_cast<std::size_t>(j)].level;
      if (level == ConstraintLevel::acceleration) continue;
      w.feedback(j) = 2.0 * feedback.alpha * w.f(iv++);
      if (level == ConstraintLevel::position) w.feedback(j) += feedback.beta * feedback.beta * w.phi(ip++);
    }
  }

  const Status status = compute_complement(model, data, complement);
  if (status != Status::ok) return status;
  data.h = data.Q + data.G;
  data.M.topRows(k).noalias() = data.D * data.A;
  data.M.bottomRows(s) = data.b;
  data.rhs.head(k).noalias() = data.D * data.h;
  data.rhs.tail(s) = -data.b0;
  w.DB.topRows(k).noalias() = data.D * w.B;
  w.DB.bottomRows(s).setZero();
  // An actuator that the physical constraints take up entirely (D B_j = 0), judged on D B as it is;
  // norms that do not square their entries, so that an actuator written as 1e200 or 1e-200 times a
  // direction is judged by its direction (a plain norm overflows to inf or underflows to 0 there).
  w.absorbed = -1;
  const double d_norm = data.D.stableNorm();
  for (int j = 0; j < m && w.absorbed < 0; ++j)
    if (!(w.DB.col(j).stableNorm() > kAbsorbed * d_norm * w.B.col(j).stableNorm())) w.absorbed = j;
  // Rows in different units (the masses' --set m=1e-100) scaled exactly first, as sanh does
  // (row_scaling.hpp): D B is a second right-hand side of [D A; b] and takes the same scaling.
  scale_rows_by_powers_of_two(
      n, [&](int i) { return data.M.row(i).cwiseAbs().maxCoeff(); },
      [&](int i, int exponent) {
        const double factor = std::ldexp(1.0, -exponent);
        data.M.row(i) *= factor;
        data.rhs(i) *= factor;
        w.DB.row(i) *= factor;
      });
  data.lu_n.compute(data.M);
  if (lu_is_singular(data.lu_n)) {
    w.absorbed = -1;  // the stacked matrix is at fault, not an actuator
    return record_failure(data, Status::singular_system, "stacked matrix [D A; b]");
  }
  w.qdd0.noalias() = data.lu_n.solve(data.rhs);
  w.PB.noalias() = data.lu_n.solve(w.DB);

  // S = b_p P B (P4), scaled to unit rows and columns before it is judged and solved.
  if (w.absorbed >= 0) return record_failure(data, Status::singular_system, kProgramMatrix);
  // P B scales as 1/mass (1e300 for m = 1e-300): a norm that does not square it into overflow.
  for (int j = 0; j < m; ++j) w.col_scale(j) = w.PB.col(j).stableNorm();
  for (int i = 0; i < m; ++i) w.row_scale(i) = w.b_p.row(i).norm();
  w.S.noalias() = w.b_p * w.PB;
  for (int j = 0; j < m; ++j)
    for (int i = 0; i < m; ++i) w.S_scaled(i, j) = w.S(i, j) / (w.row_scale(i) * w.col_scale(j));
  w.lu_S.compute(w.S_scaled);
  double smallest = std::numeric_limits<double>::infinity();
  const Matrix& LU = w.lu_S.matrixLU();
  for (int i = 0; i < m; ++i) smallest = std::min(smallest, std::abs(LU(i, i)));
  if (!(smallest > kSingularPivot)) return record_failure(data, Status::singular_system, kProgramMatrix);
  if (w.watch_sign) {
    int sign = static_cast<int>(w.lu_S.permutationP().determinant());
    for (int i = 0; i < m; ++i) sign *= LU(i, i) < 0.0 ? -1 : 1;
    if (w.sign != 0 && sign != w.sign && data.t != w.last_t) {
      w.crossed = true;
      return record_failure(data, Status::singular_system, kProgramMatrix);
    }
    w.sign = sign;
    w.last_t = data.t;
  }

  // S u = -(b_p q''_0 + b_p0 + feedback) (P5), solved as S_scaled (C u) = R^-1 rhs.
  w.rhs.noalias() = w.b_p * w.qdd0;
  w.rhs += w.b_p0 + w.feedback;
  for (int i = 0; i < m; ++i) w.rhs(i) = -w.rhs(i) / w.row_scale(i);
  w.u.noalias() = w.lu_S.solve(w.rhs);
  for (int j = 0; j < m; ++j) w.u(j) /= w.col_scale(j);

  data.qdd = w.qdd0;
  data.qdd.noalias() += w.PB * w.u;
  // The physical reactions (P3): the actuator forces are not among them.
  data.R.noalias() = data.A * data.qdd;
  data.R -= data.h;
  data.R.noalias() -= w.B * w.u;
  return Status::ok;
}

void compute_program_residuals(const Model& model, Data& data) {
  if (model.m() == 0) return;
  if (data.stage < Stage::acceleration)
    throw std::logic_error("compute_program_residuals: call compute_acceleration first for the current state");
  ProgramMotionData& w = data.motion;
  program_residuals(model, data);
  w.e = w.b_p0;
  w.e.noalias() += w.b_p * data.qdd;
}

std::string explain_program_failure(const Model& model, const Data& data) {
  const ProgramMotionData& w = data.motion;
  const int m = model.m();
  const auto name = [&](int j) { return model.program_constraints[static_cast<std::size_t>(j)].name; };
  if (w.absorbed >= 0)
    return fmt::format(
        "the actuator of program '{}' ({}) pushes straight into the physical constraints at t = {:.6g}: D B = 0, so "
        "its force is taken up by their reactions and cannot move the system; no force realizes the program "
        "(docs/derivations/program-motion.md section 3). Give the program an actuator that acts along a motion the "
        "constraints allow",
        name(w.absorbed), model.program_constraints[static_cast<std::size_t>(w.absorbed)].actuator, data.failed_t);
  if (w.crossed)
    return fmt::format(
        "the programs cannot be realized between t = {:.6g} and t = {:.6g}: the determinant of the matrix S = b_p P B, "
        "which maps the actuator forces to the program accelerations, changed sign there, so S passed through a "
        "singular state that the fixed step stepped across (an actuator that stops acting on its program); the "
        "motion past it would be meaningless (docs/derivations/program-motion.md section 3)",
        w.last_t, data.failed_t);
  // The programs involved: the largest entries of the left singular vector of the smallest
  // singular value (the rows of S are the programs).
  const Eigen::JacobiSVD<Matrix> svd(w.S_scaled, Eigen::ComputeFullU);
  const Vector sigma = svd.singularValues();
  const Eigen::VectorXd left = svd.matrixU().col(m - 1);
  const double largest = left.cwiseAbs().maxCoeff();
  std::string involved;
  for (int j = 0; j < m; ++j)
    if (std::abs(left(j)) >= 0.1 * largest)
      involved += fmt::format("{}'{}' ({} level, actuator {})", involved.empty() ? "" : ", ", name(j),
                              level_name(model.program_constraints[static_cast<std::size_t>(j)].level),
                              model.program_constraints[static_cast<std::size_t>(j)].actuator);
  return fmt::format(
      "the programs cannot be realized at t = {:.6g}: the matrix S = b_p P B, which maps the actuator forces to the "
      "program accelerations, is singular there (smallest singular value {:.3g} of S with unit rows and columns, "
      "largest {:.3g}). Programs involved: {}. Their actuators do not act on these programs at this state (an "
      "underactuated program, or programs that repeat each other or the constraints); programs that need index "
      "reduction are out of scope (docs/derivations/program-motion.md section 3)",
      data.failed_t, sigma(m - 1), sigma(0), involved);
}

void check_programs_at_initial_state(const Model& model, Data& data, const FormulationOptions& options, double t,
                                     const Vector& q, const Vector& v, double tolerance) {
  if (model.m() == 0) return;
  const Status terms = compute_terms(model, data, t, q.data(), v.data());
  if (terms != Status::ok)
    throw ModelError(fmt::format("model '{}': at the initial state: {}", model.name, explain_failure(model, data)));
  program_residuals(model, data);
  const ProgramMotionData& w = data.motion;
  std::string report;
  Eigen::Index ip = 0, iv = 0;
  for (const ProgramConstraint& p : model.program_constraints) {
    if (p.level == ConstraintLevel::acceleration) continue;
    if (p.level == ConstraintLevel::position) {
      const double r = w.phi(ip++);
      if (!(std::abs(r) <= tolerance)) report += fmt::format("\n  {} (position level): residual {:.6g}", p.name, r);
    }
    const double r = w.f(iv++);
    if (!(std::abs(r) <= tolerance)) report += fmt::format("\n  {} (velocity level): residual {:.6g}", p.name, r);
  }
  if (!report.empty())
    throw ModelError(fmt::format("model '{}': the initial state violates its programs (tolerance {:g}):{}\n"
                                 "Correct the initial values so that the motion starts on its programs (position "
                                 "and velocity levels), consistently with the constraints.",
                                 model.name, tolerance, report));
  const Status status = compute_program_motion(model, data, options.complement, ProgramFeedback{});
  if (status == Status::singular_system && data.failed_quantity == kProgramMatrix)
    throw ModelError(fmt::format("model '{}': at the initial state, {}", model.name,
                                 explain_program_failure(model, data)));
  if (status != Status::ok)
    throw ModelError(fmt::format("model '{}': at the initial state: {}", model.name, explain_failure(model, data)));
}

}  // namespace nhdyn
