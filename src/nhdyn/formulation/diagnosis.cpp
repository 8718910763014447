#include "nhdyn/formulation/diagnosis.hpp"

#include <fmt/format.h>

#include <Eigen/OrderingMethods>
#include <Eigen/SparseCholesky>
#include <Eigen/SparseQR>
#include <cmath>
#include <algorithm>
#include <limits>
#include <vector>

#include "nhdyn/core/error.hpp"
#include "nhdyn/formulation/program_motion.hpp"
#include "nhdyn/model/terms.hpp"

namespace nhdyn {
namespace {

constexpr double kRankTolerance = 1e-12;

// Beyond this many coordinates, or on the sparse path, the checks take sparse factorizations
// (a sparse QR for the rank of b, a sparse Cholesky factorization for A) instead of the dense SVD
// and eigenvalues, whose O(n^3) cost took minutes at n = 3000 (docs/performance.md).
constexpr int kDenseChecksUpTo = 64;

bool sparse_checks(const Model& model, const Data& data) { return data.sparse || model.n() > kDenseChecksUpTo; }

SparseMatrix sparse_a(const Data& data) { return data.sparse ? data.A_sparse : SparseMatrix(data.A.sparseView()); }
SparseMatrix sparse_b(const Data& data) { return data.sparse ? data.b_sparse : SparseMatrix(data.b.sparseView()); }

// The column-pivoted sparse QR of b^T: its columns are the constraints, so the columns it moves
// behind the rank are the constraints that depend on the others.
struct SparseRank {
  long rank = 0;
  std::vector<int> dependent_rows;  // constraints beyond the rank, in pivot order
  double condition = 0.0;           // |R(0,0)| / |R(r-1,r-1)|, a rough estimate
};

SparseRank calc_sparse_rank(const Data& data) {
  SparseRank out;
  const SparseMatrix bt = sparse_b(data).transpose();
  if (bt.cols() == 0) return out;
  Eigen::SparseQR<SparseMatrix, Eigen::COLAMDOrdering<int>> qr;
  // Eigen's default threshold is 20 (rows + cols) eps max|column|: a rank test of the same order
  // as the dense one (kRankTolerance relative to the largest singular value).
  qr.compute(bt);
  if (qr.info() != Eigen::Success) return out;
  out.rank = qr.rank();
  for (long j = out.rank; j < bt.cols(); ++j) out.dependent_rows.push_back(qr.colsPermutation().indices()(j));
  const SparseMatrix R = qr.matrixR();
  double first = 0.0, last = std::numeric_limits<double>::infinity();
  for (long j = 0; j < out.rank; ++j) {
    const double d = std::abs(R.coeff(j, j));
    first = std::max(first, d);
    last = std::min(last, d);
  }
  out.condition = out.rank > 0 && last > 0.0 ? first / last : std::numeric_limits<double>::infinity();
  return out;
}

std::string explain_dependent_constraints_sparse(const Model& model, const Data& data) {
  const SparseRank r = calc_sparse_rank(data);
  std::string involved;
  for (int i : r.dependent_rows)
    involved += (involved.empty() ? "" : ", ") + ("'" + model.constraints[static_cast<std::size_t>(i)].name + "'");
  return fmt::format(
      "the constraints {} depend on the others or conflict with them at t = {:.6g}: the constraint matrix b has "
      "rank {} below s = {} (a sparse QR with column pivoting; condition estimate of the rest {:.3g}). Remove or "
      "rewrite a redundant constraint, or check that the state does not sit on a singular configuration of the "
      "constraints.",
      involved.empty() ? std::string("(all)") : involved, data.t, r.rank, model.s(), r.condition);
}

// The smallest and largest pivots of an LDL^T factorization of A: of the signs of the eigenvalues
// (Sylvester's law of inertia), without the O(n^3) eigenvalue solver.
std::string explain_inertia_sparse(const Model& model, const Data& data) {
  const SparseMatrix A = sparse_a(data);
  Eigen::SimplicialLDLT<SparseMatrix> ldlt(A);
  double smallest = std::numeric_limits<double>::quiet_NaN(), largest = smallest;
  if (ldlt.info() == Eigen::Success && ldlt.vectorD().size() > 0) {
    smallest = ldlt.vectorD().minCoeff();
    largest = ldlt.vectorD().maxCoeff();
  }
  const double asymmetry = (A - SparseMatrix(A.transpose())).norm();
  return fmt::format(
      "the inertia matrix A is not positive definite at t = {:.6g} (smallest pivot of its LDL^T factorization "
      "{:.6g}, largest {:.6g}; asymmetry |A - A^T| = {:.3g}; n = {} coordinates). Check the kinetic energy: every "
      "coordinate needs a velocity term, and masses and inertias must be positive (a coordinate without inertia "
      "of its own needs constraints that fix it: A may be singular only where [D A; b] is regular).",
      data.t, smallest, largest, asymmetry, model.n());
}

// The rows of b a failed solve held: with contact modes those its modes kept (with s >= n the
// full b is never of rank s, whatever the state), else all of them; and b restricted to them.
std::vector<int> held_rows(const Model& model, const Data& data) {
  if (data.modes.active && !data.modes.kept.empty()) return data.modes.kept;
  std::vector<int> rows;
  for (int i = 0; i < model.s(); ++i) rows.push_back(i);
  return rows;
}

Matrix rows_of_b(const Data& data, const std::vector<int>& rows) {
  Matrix b(static_cast<Eigen::Index>(rows.size()), data.b.cols());
  for (std::size_t k = 0; k < rows.size(); ++k) b.row(static_cast<Eigen::Index>(k)) = data.b.row(rows[k]);
  return b;
}

// A b of full rank once its columns have unit norms: coordinates in units out of proportion (a
// rolling sphere of radius 1e20 m puts r next to 1 in the rows of its contact), which no row
// scaling can mend. The message names the largest and smallest columns, or "" when b stays
// rank-deficient with unit columns (a true dependency).
std::string explain_disproportionate_columns(const Model& model, const Data& data, const std::vector<int>& rows,
                                             const Matrix& b) {
  if (b.rows() == 0 || b.cols() == 0) return "";
  Vector norms(b.cols());
  for (Eigen::Index j = 0; j < b.cols(); ++j) norms(j) = b.col(j).stableNorm();
  Eigen::Index largest = 0, smallest = -1;
  for (Eigen::Index j = 0; j < b.cols(); ++j) {
    if (norms(j) > norms(largest)) largest = j;
    if (norms(j) > 0.0 && (smallest < 0 || norms(j) < norms(smallest))) smallest = j;
  }
  if (smallest < 0 || !(norms(largest) > 1e6 * norms(smallest))) return "";
  Matrix scaled = b;
  for (Eigen::Index j = 0; j < b.cols(); ++j)
    if (norms(j) > 0.0) scaled.col(j) /= norms(j);
  const Vector sv = Eigen::JacobiSVD<Matrix>(scaled).singularValues();
  if (!(sv(sv.size() - 1) > kRankTolerance * sv(0))) return "";
  const auto name = [&](Eigen::Index j) { return model.coordinates[static_cast<std::size_t>(j)]; };
  std::string involved;
  for (Eigen::Index i = 0; i < b.rows(); ++i) {
    if (b(i, largest) == 0.0) continue;
    const Constraint& c = model.constraints[static_cast<std::size_t>(rows[static_cast<std::size_t>(i)])];
    if (involved.find("'" + c.name + "'") == std::string::npos)
      involved += (involved.empty() ? "" : ", ") + ("'" + c.name + "'") + (c.where.empty() ? "" : " (" + c.where + ")");
  }
  const bool one = involved.find("', '") == std::string::npos && involved.find("), '") == std::string::npos;
  return fmt::format(
      "the constraint matrix b is numerically singular at t = {:.6g} in the rows of {} {}, but only through the units "
      "of the coordinates: its column of '{}' is {:.3g} times its column of '{}' (a length of that size against an "
      "angle, say), beyond what double precision separates; with the columns in proportion the constraints are "
      "independent. Rescale the model's lengths (km or mm in place of m) so that its parameters are within a few "
      "orders of magnitude of each other.",
      data.t, one ? "the constraint" : "the constraints", involved, name(largest), norms(largest) / norms(smallest),
      name(smallest));
}

// Singular values of b and, for each small one, the constraints taking part in the dependency.
std::string explain_dependent_constraints(const Model& model, const Data& data) {
  if (sparse_checks(model, data)) return explain_dependent_constraints_sparse(model, data);
  const std::vector<int> rows = held_rows(model, data);
  // A row of b that vanishes: the constraint does not involve q'' there at all, which for one
  // nonlinear in the velocities (x'^2 + y'^2 = 1) happens where they are all 0; no other row is
  // at fault, so "dependent" would mislead.
  for (int row : rows)
    if (data.b.row(row).lpNorm<Eigen::Infinity>() == 0.0) {
      const Constraint& c = model.constraints[static_cast<std::size_t>(row)];
      return fmt::format(
          "the constraint '{}'{} has a zero row of b at t = {:.6g}: it does not involve the accelerations there, so "
          "it cannot be solved for q'' (a constraint nonlinear in the velocities does this where the velocities it "
          "reads are 0, as x'^2 + y'^2 = 1 at rest; a position constraint where its gradient vanishes). Start the "
          "motion where its row of b is not zero, or write it so that its derivative by the velocities does not "
          "vanish.",
          c.name, c.where.empty() ? "" : " (" + c.where + ")", data.t);
    }
  if (std::string units = explain_disproportionate_columns(model, data, rows, rows_of_b(data, rows)); !units.empty())
    return units;
  Eigen::JacobiSVD<Matrix> svd(rows_of_b(data, rows), Eigen::ComputeFullU);
  const Vector& sv = svd.singularValues();
  const double largest = sv.size() > 0 ? sv(0) : 0.0;
  const double smallest = sv.size() > 0 ? sv(sv.size() - 1) : 0.0;
  std::string involved;
  for (Eigen::Index j = 0; j < sv.size(); ++j) {
    if (sv(j) > kRankTolerance * largest && largest > 0.0) continue;
    // A left singular vector with a small singular value combines rows of b to (almost) zero.
    for (std::size_t k = 0; k < rows.size(); ++k)
      if (std::abs(svd.matrixU()(static_cast<Eigen::Index>(k), j)) > 1e-8) {
        const Constraint& c = model.constraints[static_cast<std::size_t>(rows[k])];
        if (involved.find("'" + c.name + "'") == std::string::npos)
          involved += (involved.empty() ? "" : ", ") + ("'" + c.name + "'") +
                      (c.where.empty() ? "" : " (" + c.where + ")");
      }
  }
  const double condition = smallest > 0.0 ? largest / smallest : std::numeric_limits<double>::infinity();
  return fmt::format(
      "the constraints {} are dependent or conflicting at t = {:.6g}: the constraint matrix b has "
      "rank below {} = {} (condition estimate {:.3g}). Remove or rewrite a redundant constraint, or "
      "check that the state does not sit on a singular configuration of the constraints.",
      involved.empty() ? std::string("(all)") : involved, data.t,
      rows.size() == static_cast<std::size_t>(model.s()) ? "s" : "the rows the contacts' modes keep", rows.size(),
      condition);
}

// A singular A whose null directions the constraints do not all remove: the coordinates moving
// along the free direction of N^T A N, or "" when A is not singular that way.
std::string explain_free_massless_motion(const Model& model, const Data& data) {
  if (model.s() == 0 || data.sparse) return "";
  // Only a positive semidefinite A (an indefinite one is a wrong kinetic energy: said below).
  Eigen::SelfAdjointEigenSolver<Matrix> of_a(data.A, Eigen::EigenvaluesOnly);
  const Vector& a_values = of_a.eigenvalues();
  if (a_values.size() == 0 || a_values(0) < -1e-12 * std::max(1.0, std::abs(a_values(a_values.size() - 1))))
    return "";
  Eigen::FullPivLU<Matrix> lu(data.b);
  if (lu.rank() == model.n()) return "";
  const Matrix N = lu.kernel();
  Eigen::SelfAdjointEigenSolver<Matrix> eig(N.transpose() * data.A * N);
  const Vector& values = eig.eigenvalues();
  const double floor = 1e-10 * std::max(1.0, values.size() > 0 ? std::abs(values(values.size() - 1)) : 0.0);
  if (values.size() == 0 || std::abs(values(0)) > floor) return "";
  // Every free direction (the eigenvalues at zero), by the coordinates that carry it.
  Vector weight = Vector::Zero(model.n());
  for (Eigen::Index j = 0; j < values.size() && std::abs(values(j)) <= floor; ++j) {
    const Vector z = N * eig.eigenvectors().col(j);
    weight = weight.cwiseMax(z.cwiseAbs() / z.cwiseAbs().maxCoeff());
  }
  std::string coords;
  for (int i = 0; i < model.n(); ++i)
    if (weight(i) > 0.1) coords += (coords.empty() ? "" : ", ") + model.coordinates[static_cast<std::size_t>(i)];
  return fmt::format(
      "the inertia matrix A is singular at t = {:.6g} and the constraints do not fix the velocities it leaves out: "
      "a motion of {} has no kinetic energy and no constraint holds it, so [D A; b] is singular. A coordinate "
      "without inertia of its own needs constraints that fix it; the contact coordinates of a terrain are fixed "
      "only where the contact point is unique (not where the body is as curved as a hollow of the ground)",
      data.t, coords);
}

std::string explain_inertia(const Model& model, const Data& data) {
  if (sparse_checks(model, data)) return explain_inertia_sparse(model, data);
  if (std::string free = explain_free_massless_motion(model, data); !free.empty()) return free;
  Eigen::SelfAdjointEigenSolver<Matrix> eig(data.A, Eigen::EigenvaluesOnly);
  std::string coords;
  for (const std::string& c : model.coordinates) coords += (coords.empty() ? "" : ", ") + c;
  return fmt::format(
      "the inertia matrix A is not positive definite at t = {:.6g} (smallest eigenvalue {:.6g}, "
      "largest {:.6g}; coordinates {}). Check the kinetic energy: every coordinate needs a "
      "velocity term, and masses and inertias must be positive (a coordinate without inertia of its own needs "
      "constraints that fix it: A may be singular only where [D A; b] is regular).",
      data.t, eig.eigenvalues()(0), eig.eigenvalues()(eig.eigenvalues().size() - 1), coords);
}

bool b_is_rank_deficient(const Model& model, const Data& data) {
  if (model.s() == 0) return false;
  if (sparse_checks(model, data)) return calc_sparse_rank(data).rank < model.s();
  const std::vector<int> rows = held_rows(model, data);
  if (rows.size() > static_cast<std::size_t>(model.n())) return true;
  Eigen::JacobiSVD<Matrix> svd(rows_of_b(data, rows));
  const Vector& sv = svd.singularValues();
  return !(sv(sv.size() - 1) > kRankTolerance * sv(0));
}

bool a_is_positive_definite(const Model& model, const Data& data) {
  if (sparse_checks(model, data)) {
    const SparseMatrix A = sparse_a(data);
    const double asymmetry = (A - SparseMatrix(A.transpose())).norm();
    if (!(asymmetry <= 1e-12 * A.norm())) return false;
    Eigen::SimplicialLLT<SparseMatrix> llt(A);
    return llt.info() == Eigen::Success;
  }
  Eigen::LLT<Matrix> llt(data.A);
  return llt.info() == Eigen::Success && data.A.isApprox(data.A.transpose(), 1e-12);
}

// A singular A that is positive definite on the velocities the constraints allow (N^T A N > 0, N
// a basis of the null space of b) still makes [D A; b] regular for every complement D, and the Do
// Sanh form needs no inverse of A: coordinates with no inertia of their own, held by constraints
// (the surface parameters of a rolling contact, docs/derivations/rolling-bodies.md section 8).
// Checked only when A is not positive definite; dense (O(n^3)).
bool positive_on_the_null_space(const Matrix& A, const Matrix& b, double* smallest) {
  if (!A.isApprox(A.transpose(), 1e-12)) return false;
  Eigen::FullPivLU<Matrix> lu(b);
  if (lu.rank() == A.rows()) return true;  // the constraints fix every velocity
  const Matrix N = lu.kernel();
  const Matrix reduced = N.transpose() * A * N;
  Eigen::LLT<Matrix> llt(reduced);
  if (llt.info() == Eigen::Success) return true;
  if (smallest != nullptr)
    *smallest = Eigen::SelfAdjointEigenSolver<Matrix>(reduced, Eigen::EigenvaluesOnly).eigenvalues()(0);
  return false;
}

bool a_is_positive_definite_on_the_constraints(const Model& model, const Data& data) {
  if (model.s() == 0) return false;
  const Matrix A = data.sparse ? Matrix(data.A_sparse) : data.A;
  const Matrix b = data.sparse ? Matrix(data.b_sparse) : data.b;
  return positive_on_the_null_space(A, b, nullptr);
}

}  // namespace

namespace {

// The stacked (or KKT) matrix singular although A is positive definite on the constraints and b
// has full rank. Inertias many orders of magnitude apart in one model (a 1e-14 kg body beside a
// 1 kg one) leave the lighter body's rows below round-off: say so, with the spread of A's
// diagonal. Otherwise, with a D of the user's own, D is the suspect; without D (lagrange) nothing
// the model says explains it.
std::string explain_singular_with_regular_parts(const Model& model, const Data& data) {
  double largest = 0.0, smallest = std::numeric_limits<double>::infinity();
  const int n = model.n();
  for (int i = 0; i < n; ++i) {
    const double d = data.sparse ? data.A_sparse.coeff(i, i) : data.A(i, i);
    if (!(d > 0.0)) continue;
    largest = std::max(largest, d);
    smallest = std::min(smallest, d);
  }
  const std::string head = fmt::format("the {} is singular at t = {:.6g} although A is positive definite and b has "
                                       "full rank",
                                       data.failed_quantity, data.failed_t);
  if (largest > 0.0 && largest / smallest > 1e12)
    return fmt::format("{}: the diagonal of A spans {:.3g} to {:.3g}, more orders of magnitude than double "
                       "precision resolves beside the constraints' rows; write the model in units that bring "
                       "its masses and inertias within about 1e12 of each other",
                       head, smallest, largest);
  // A nearly singular A passes the Cholesky test: the coordinates near a singular point of the
  // kinetic energy, such as three angles at gimbal lock (a ball rolling in a bowl on Euler angles).
  if (!data.sparse && data.A.rows() == n) {
    // On A with its diagonal scaled to 1 (D^-1/2 A D^-1/2), so that units and mass ratios do not
    // count, only how nearly dependent its columns are.
    const Vector scale = data.A.diagonal().cwiseMax(std::numeric_limits<double>::min()).cwiseSqrt().cwiseInverse();
    const double rcond = Eigen::LLT<Matrix>(scale.asDiagonal() * data.A * scale.asDiagonal()).rcond();
    if (rcond < 1e-8)
      return fmt::format("the {} is singular at t = {:.6g}, and A is nearly singular there (reciprocal condition "
                         "number {:.3g}; b has full rank): the coordinates are near a point where they stop "
                         "describing the motion, such as three angles at gimbal lock (a body's middle angle at "
                         "+-90 degrees); write the orientation as a quaternion (rotations = \"quaternion\", "
                         "docs/multibody.md) or choose angles regular along the motion",
                         data.failed_quantity, data.failed_t, rcond);
  }
  if (data.failed_quantity.find("[D A; b]") != std::string::npos && model.evaluator->has_complement())
    return head + "; this points to a D that is not a complement of b";
  return head + "; the constraints and the inertia are nearly dependent there: check the model's constraints "
                "and masses at that state";
}

// Which entry of the terms named by data.failed_quantity is not finite, and the state there:
// " (Q_x = inf, where x = 2, x' = 0)"; "" for any other quantity, or when none is (sparse terms).
std::string non_finite_entry(const Model& model, const Data& data) {
  const std::string& what = data.failed_quantity;
  const auto coordinate = [&](Eigen::Index i) { return model.coordinates[static_cast<std::size_t>(i)]; };
  const auto constraint = [&](Eigen::Index i) {
    return static_cast<std::size_t>(i) < model.constraints.size() ? model.constraints[static_cast<std::size_t>(i)].name
                                                                  : fmt::format("row {}", i + 1);
  };
  std::string entry;
  double value = 0.0;
  const auto first = [&](const Matrix& m, const auto& name) {
    for (Eigen::Index j = 0; j < m.cols() && entry.empty(); ++j)
      for (Eigen::Index i = 0; i < m.rows() && entry.empty(); ++i)
        if (!std::isfinite(m(i, j))) {
          entry = name(i, j);
          value = m(i, j);
        }
  };
  if (what == "generalized forces Q") first(data.Q, [&](Eigen::Index i, Eigen::Index) { return "Q_" + coordinate(i); });
  else if (what == "velocity terms G") first(data.G, [&](Eigen::Index i, Eigen::Index) { return "G_" + coordinate(i); });
  else if (what == "inertia matrix A" && !data.sparse)
    first(data.A, [&](Eigen::Index i, Eigen::Index j) { return fmt::format("A({}, {})", coordinate(i), coordinate(j)); });
  else if (what == "constraint matrix b" && !data.sparse)
    first(data.b, [&](Eigen::Index i, Eigen::Index j) { return fmt::format("b({}, {})", constraint(i), coordinate(j)); });
  else if (what == "constraint term b0")
    first(data.b0, [&](Eigen::Index i, Eigen::Index) { return fmt::format("b0({})", constraint(i)); });
  if (entry.empty()) return "";
  return fmt::format(" ({} = {}, where {})", entry, std::isnan(value) ? std::string("NaN") : fmt::format("{}", value),
                     describe_state(model, data.q.data(), data.v.data()));
}

}  // namespace

std::string describe_state(const Model& model, const double* q, const double* v) {
  std::string text;
  for (int i = 0; i < model.n(); ++i)
    text += fmt::format("{}{} = {:.6g}", i == 0 ? "" : ", ", model.coordinates[static_cast<std::size_t>(i)], q[i]);
  for (int i = 0; i < model.n(); ++i)
    text += fmt::format(", {}' = {:.6g}", model.coordinates[static_cast<std::size_t>(i)], v[i]);
  return text;
}

std::string explain_failure(const Model& model, const Data& data) {
  switch (data.status) {
    case Status::ok: return "no failure";
    case Status::dependent_constraints: return explain_dependent_constraints(model, data);
    case Status::inertia_not_positive_definite: return explain_inertia(model, data);
    case Status::non_finite:
      return fmt::format("non-finite value (NaN or infinity) in {} at t = {:.6g}{}; the model divides by "
                         "zero or overflows there (for example a constraint written with 1/z' or "
                         "tan(phi) at its singular point)",
                         data.failed_quantity, data.failed_t, non_finite_entry(model, data));
    case Status::singular_system:
      if (data.failed_quantity.rfind("program matrix", 0) == 0) return explain_program_failure(model, data);
      if (data.failed_quantity.rfind("contact '", 0) == 0)  // formulation/contact_modes.cpp
        return fmt::format("{} at t = {:.6g}", data.failed_quantity, data.failed_t);
      if (data.failed_quantity.rfind("the contacts '", 0) == 0)  // the same, contacts held together
        return fmt::format("at t = {:.6g}, {}", data.failed_t, data.failed_quantity);
      if (data.failed_quantity == "complement D")
        return fmt::format("the model's complement D is not a complement of b at t = {:.6g}: the largest "
                           "|D_i . b_j| / (|D_i| |b_j|) is {:.3g} (D b^T must be 0); the rows of D must span "
                           "the velocities the constraints allow there: check D, or use --complement qr",
                           data.failed_t, data.failed_value);
      if (b_is_rank_deficient(model, data)) return explain_dependent_constraints(model, data);
      if (!a_is_positive_definite(model, data)) return explain_inertia(model, data);
      return explain_singular_with_regular_parts(model, data);
    case Status::projection_failed:
      return fmt::format("the projection onto the {} did not converge at t = {:.6g}: the residual is still "
                         "{:.3g} after the Newton iterations. The step left the state too far from the "
                         "constraints for the projection to bring it back: tighten the integrator's "
                         "tolerances (--rtol, --atol), or use --stabilize baumgarte",
                         data.failed_quantity, data.failed_t, data.failed_value);
    default: return fmt::format("{} at t = {:.6g}", describe(data.status), data.failed_t);
  }
}

Status check_terms(const Model& model, Data& data) {
  if (model.s() >= model.n()) return Status::ok;
  if (!a_is_positive_definite(model, data)) {
    // A singular A is judged on the constraints, so dependent constraints are the first thing to say.
    if (model.s() > 0 && b_is_rank_deficient(model, data))
      return record_failure(data, Status::dependent_constraints, "constraint matrix b");
    if (!a_is_positive_definite_on_the_constraints(model, data))
      return record_failure(data, Status::inertia_not_positive_definite, "inertia matrix A");
  }
  if (model.s() > 0 && b_is_rank_deficient(model, data))
    return record_failure(data, Status::dependent_constraints, "constraint matrix b");
  return Status::ok;
}

bool inertia_positive_on_constraints(const Matrix& A, const Matrix& b, double& smallest) {
  Eigen::LLT<Matrix> llt(A);
  if (llt.info() == Eigen::Success && A.isApprox(A.transpose(), 1e-12)) return true;
  smallest = Eigen::SelfAdjointEigenSolver<Matrix>(A, Eigen::EigenvaluesOnly).eigenvalues()(0);
  return b.rows() > 0 && positive_on_the_null_space(A, b, &smallest);
}

void check_state_or_throw(const Model& model, Data& data, double t, const double* q, const double* v) {
  Status status = compute_terms(model, data, t, q, v);
  if (status == Status::ok) status = check_terms(model, data);
  if (status != Status::ok)
    throw ModelError(fmt::format("model '{}': {}", model.name, explain_failure(model, data)));
}

}  // namespace nhdyn
