#include "nhdyn/formulation/diagnosis.hpp"

#include <fmt/format.h>

#include <cmath>
#include <limits>
#include <vector>

#include "nhdyn/core/error.hpp"
#include "nhdyn/model/terms.hpp"

namespace nhdyn {
namespace {

constexpr double kRankTolerance = 1e-12;

// Singular values of b and, for each small one, the constraints taking part in the dependency.
std::string explain_dependent_constraints(const Model& model, const Data& data) {
  Eigen::JacobiSVD<Matrix> svd(data.b, Eigen::ComputeFullU);
  const Vector& sv = svd.singularValues();
  const double largest = sv.size() > 0 ? sv(0) : 0.0;
  const double smallest = sv.size() > 0 ? sv(sv.size() - 1) : 0.0;
  std::string involved;
  for (Eigen::Index j = 0; j < sv.size(); ++j) {
    if (sv(j) > kRankTolerance * largest && largest > 0.0) continue;
    // A left singular vector with a small singular value combines rows of b to (almost) zero.
    for (int i = 0; i < model.s(); ++i)
      if (std::abs(svd.matrixU()(i, j)) > 1e-8) {
        const std::string& name = model.constraints[static_cast<std::size_t>(i)].name;
        if (involved.find("'" + name + "'") == std::string::npos)
          involved += (involved.empty() ? "" : ", ") + ("'" + name + "'");
      }
  }
  const double condition = smallest > 0.0 ? largest / smallest : std::numeric_limits<double>::infinity();
  return fmt::format(
      "the constraints {} are dependent or conflicting at t = {:.6g}: the constraint matrix b has "
      "rank below s = {} (condition estimate {:.3g}). Remove or rewrite a redundant constraint, or "
      "check that the state does not sit on a singular configuration of the constraints.",
      involved.empty() ? std::string("(all)") : involved, data.t, model.s(), condition);
}

std::string explain_inertia(const Model& model, const Data& data) {
  Eigen::SelfAdjointEigenSolver<Matrix> eig(data.A, Eigen::EigenvaluesOnly);
  std::string coords;
  for (const std::string& c : model.coordinates) coords += (coords.empty() ? "" : ", ") + c;
  return fmt::format(
      "the inertia matrix A is not positive definite at t = {:.6g} (smallest eigenvalue {:.6g}, "
      "largest {:.6g}; coordinates {}). Check the kinetic energy: every coordinate needs a "
      "velocity term, and masses and inertias must be positive.",
      data.t, eig.eigenvalues()(0), eig.eigenvalues()(eig.eigenvalues().size() - 1), coords);
}

bool b_is_rank_deficient(const Data& data) {
  if (data.b.rows() == 0) return false;
  Eigen::JacobiSVD<Matrix> svd(data.b);
  const Vector& sv = svd.singularValues();
  return !(sv(sv.size() - 1) > kRankTolerance * sv(0));
}

bool a_is_positive_definite(const Data& data) {
  Eigen::LLT<Matrix> llt(data.A);
  return llt.info() == Eigen::Success && data.A.isApprox(data.A.transpose(), 1e-12);
}

}  // namespace

std::string explain_failure(const Model& model, const Data& data) {
  switch (data.status) {
    case Status::ok: return "no failure";
    case Status::dependent_constraints: return explain_dependent_constraints(model, data);
    case Status::inertia_not_positive_definite: return explain_inertia(model, data);
    case Status::non_finite:
      return fmt::format("non-finite value (NaN or infinity) in {} at t = {:.6g}; the model divides by "
                         "zero or overflows there (for example a constraint written with 1/z' or "
                         "tan(phi) at its singular point)",
                         data.failed_quantity, data.failed_t);
    case Status::singular_system:
      if (b_is_rank_deficient(data)) return explain_dependent_constraints(model, data);
      if (!a_is_positive_definite(data)) return explain_inertia(model, data);
      return fmt::format("the {} is singular at t = {:.6g} although A is positive definite and b has "
                         "full rank; this points to a D that is not a complement of b",
                         data.failed_quantity, data.failed_t);
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
  if (!a_is_positive_definite(data))
    return record_failure(data, Status::inertia_not_positive_definite, "inertia matrix A");
  if (model.s() > 0 && b_is_rank_deficient(data))
    return record_failure(data, Status::dependent_constraints, "constraint matrix b");
  return Status::ok;
}

void check_state_or_throw(const Model& model, Data& data, double t, const double* q, const double* v) {
  Status status = compute_terms(model, data, t, q, v);
  if (status == Status::ok) status = check_terms(model, data);
  if (status != Status::ok)
    throw ModelError(fmt::format("model '{}': {}", model.name, explain_failure(model, data)));
}

}  // namespace nhdyn
