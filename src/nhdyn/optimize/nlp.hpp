// A nonlinear program as a solver sees it, in the manner of OdeSystem (integrators/ode.hpp): sizes,
// bounds, a starting point, the objective and its gradient, the constraints and their sparse
// Jacobian (pattern once, values at each call). The transcription of an optimal control problem
// implements it (transcription.hpp); the IPOPT adapter (ipopt/ipopt_solver.hpp) solves it. No
// mechanics here, and no solver types.
//
//     minimize f(x)  subject to  x_lower <= x <= x_upper,  g_lower <= g(x) <= g_upper
#pragma once

#include <string>
#include <vector>

namespace nhdyn {

// Larger than any bound a problem means: the solvers read it as "no bound" (IPOPT's default
// nlp_upper_bound_inf is 1e19).
inline constexpr double kNlpInfinity = 1e20;

class Nlp {
 public:
  virtual ~Nlp() = default;
  virtual int variables() const = 0;
  virtual int constraints() const = 0;
  // variables() entries each in x_lower, x_upper; constraints() each in g_lower, g_upper; an
  // infinite bound is +-kNlpInfinity.
  virtual void bounds(double* x_lower, double* x_upper, double* g_lower, double* g_upper) const = 0;
  virtual void starting_point(double* x) const = 0;
  // Each returns false when it cannot be evaluated at x (a non-finite value, a singular matrix):
  // the solver then shortens its step.
  virtual bool objective(const double* x, double& f) = 0;
  virtual bool gradient(const double* x, double* grad) = 0;
  virtual bool constraint_values(const double* x, double* g) = 0;
  // The Jacobian of g in triplets: jacobian_nonzeros() (row, column) pairs, fixed, and their
  // values in the same order.
  virtual int jacobian_nonzeros() const = 0;
  virtual void jacobian_pattern(int* rows, int* columns) const = 0;
  virtual bool jacobian_values(const double* x, double* values) = 0;
  // The Hessian of the Lagrangian sigma f + lambda^T g, one triangle in triplets: hessian_nonzeros()
  // (row, column) pairs with row >= column, fixed, and their values in the same order. A negative
  // count (the default) says the program gives none: the solver then approximates it.
  virtual int hessian_nonzeros() const { return -1; }
  virtual void hessian_pattern(int* /*rows*/, int* /*columns*/) const {}
  virtual bool hessian_values(const double* /*x*/, double /*sigma*/, const double* /*lambda*/, double* /*values*/) {
    return false;
  }
};

// How a solve ended, in nhdyn's words; the solver's own name of the status is in NlpResult::message.
enum class NlpStatus {
  solved,              // converged to the requested tolerance
  solved_acceptable,   // converged to the solver's "acceptable" level only
  infeasible,          // the constraints could not be satisfied (locally infeasible)
  iteration_limit,     // stopped at the iteration or time limit
  failed,              // the solver stopped on numerical trouble (restoration failed, evaluation errors, ...)
  unavailable,         // nhdyn was built without the solver
};

// "solved", "solved to acceptable level", "infeasible", "iteration limit", "failed", "unavailable".
const char* nlp_status_name(NlpStatus status);
inline bool nlp_converged(NlpStatus status) {
  return status == NlpStatus::solved || status == NlpStatus::solved_acceptable;
}

// Where the Hessian of the Lagrangian comes from (docs/derivations/optimal-programs.md, section 8).
enum class NlpHessian {
  program,         // the program's hessian_values (the transcription: differences of exact first derivatives)
  limited_memory,  // the solver's limited-memory quasi-Newton approximation (L-BFGS)
};

struct NlpOptions {
  NlpHessian hessian = NlpHessian::program;  // limited_memory when the program gives none
  double tolerance = 1e-8;         // IPOPT's tol
  double constraint_tolerance = 1e-8;  // IPOPT's constr_viol_tol
  int max_iterations = 3000;
};

struct NlpResult {
  NlpStatus status = NlpStatus::failed;
  std::string message;              // the solver's words for it
  int iterations = 0;
  double objective = 0.0;
  double constraint_violation = 0.0;  // largest violation of g's bounds (and x's) at x
  std::vector<double> x;            // the last iterate (the solution when converged)
};

// IPOPT with the program's Hessian or its limited-memory quasi-Newton approximation
// (docs/derivations/optimal-programs.md, section 8), printing nothing. Without IPOPT in the build: status unavailable and a message
// that says how to install it.
NlpResult solve_nlp(Nlp& nlp, const NlpOptions& options);

// Whether this build has IPOPT.
bool nlp_solver_available();

}  // namespace nhdyn
