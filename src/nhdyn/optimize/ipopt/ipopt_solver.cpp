// solve_nlp (optimize/nlp.hpp) with IPOPT 3.11 (Debian coinor-libipopt-dev, MUMPS as its linear
// solver): a TNLP adapter over Nlp, the options nhdyn sets, and IPOPT's return status in nhdyn's
// words. The only file that includes IPOPT's headers (src/nhdyn/CMakeLists.txt, optimize/ipopt),
// and the whole of the module libnhdyn_ipopt.so, which solver_module.cpp loads when a program is
// first solved: its two entry points (solver_module.hpp) are all it exports.
#include <algorithm>
#include <cmath>
#include <string>
#include <vector>

#include <IpIpoptApplication.hpp>
#include <IpSolveStatistics.hpp>
#include <IpTNLP.hpp>

#include "nhdyn/optimize/ipopt/solver_module.hpp"
#include "nhdyn/optimize/nlp.hpp"

namespace nhdyn {
namespace {

using Ipopt::Index;
using Ipopt::Number;

class Adapter final : public Ipopt::TNLP {
 public:
  Adapter(Nlp& nlp, bool hessian) : nlp_(nlp), hessian_(hessian) {}

  bool get_nlp_info(Index& n, Index& m, Index& nnz_jac_g, Index& nnz_h_lag, IndexStyleEnum& index_style) override {
    n = nlp_.variables();
    m = nlp_.constraints();
    nnz_jac_g = nlp_.jacobian_nonzeros();
    nnz_h_lag = hessian_ ? nlp_.hessian_nonzeros() : 0;  // 0: limited-memory quasi-Newton
    index_style = C_STYLE;
    return true;
  }
  bool get_bounds_info(Index, Number* x_l, Number* x_u, Index, Number* g_l, Number* g_u) override {
    nlp_.bounds(x_l, x_u, g_l, g_u);
    return true;
  }
  bool get_starting_point(Index, bool init_x, Number* x, bool, Number*, Number*, Index, bool, Number*) override {
    if (init_x) nlp_.starting_point(x);
    return true;
  }
  bool eval_f(Index, const Number* x, bool, Number& obj_value) override { return nlp_.objective(x, obj_value); }
  bool eval_grad_f(Index, const Number* x, bool, Number* grad_f) override { return nlp_.gradient(x, grad_f); }
  bool eval_g(Index, const Number* x, bool, Index, Number* g) override { return nlp_.constraint_values(x, g); }
  bool eval_jac_g(Index, const Number* x, bool, Index, Index, Index* iRow, Index* jCol, Number* values) override {
    if (values == nullptr) {
      nlp_.jacobian_pattern(iRow, jCol);
      return true;
    }
    return nlp_.jacobian_values(x, values);
  }
  bool eval_h(Index, const Number* x, bool, Number obj_factor, Index, const Number* lambda, bool, Index,
              Index* iRow, Index* jCol, Number* values) override {
    if (values == nullptr) {
      nlp_.hessian_pattern(iRow, jCol);
      return true;
    }
    return nlp_.hessian_values(x, obj_factor, lambda, values);
  }
  void finalize_solution(Ipopt::SolverReturn, Index n, const Number* x, const Number*, const Number*, Index,
                         const Number*, const Number*, Number obj_value, const Ipopt::IpoptData*,
                         Ipopt::IpoptCalculatedQuantities*) override {
    x_.assign(x, x + n);
    objective_ = obj_value;
  }

  std::vector<double> x_;
  double objective_ = 0.0;

 private:
  Nlp& nlp_;
  bool hessian_;
};

// IPOPT's ApplicationReturnStatus as nhdyn's status and IPOPT's own words for it.
NlpStatus status_of(Ipopt::ApplicationReturnStatus s, std::string& message) {
  switch (s) {
    case Ipopt::Solve_Succeeded: message = "Optimal Solution Found"; return NlpStatus::solved;
    case Ipopt::Solved_To_Acceptable_Level: message = "Solved To Acceptable Level"; return NlpStatus::solved_acceptable;
    case Ipopt::Infeasible_Problem_Detected: message = "Converged to a point of local infeasibility"; return NlpStatus::infeasible;
    case Ipopt::Maximum_Iterations_Exceeded: message = "Maximum Number of Iterations Exceeded"; return NlpStatus::iteration_limit;
    case Ipopt::Maximum_CpuTime_Exceeded: message = "Maximum CPU time exceeded"; return NlpStatus::iteration_limit;
    case Ipopt::Search_Direction_Becomes_Too_Small: message = "Search Direction is becoming Too Small"; return NlpStatus::failed;
    case Ipopt::Diverging_Iterates: message = "Iterates diverging"; return NlpStatus::failed;
    case Ipopt::User_Requested_Stop: message = "Stopping optimization at current point as requested by user"; return NlpStatus::failed;
    case Ipopt::Feasible_Point_Found: message = "Feasible point found"; return NlpStatus::solved_acceptable;
    case Ipopt::Restoration_Failed: message = "Restoration Failed"; return NlpStatus::failed;
    case Ipopt::Error_In_Step_Computation: message = "Error in step computation"; return NlpStatus::failed;
    case Ipopt::Not_Enough_Degrees_Of_Freedom: message = "Problem has too few degrees of freedom"; return NlpStatus::failed;
    case Ipopt::Invalid_Problem_Definition: message = "Invalid problem definition"; return NlpStatus::failed;
    case Ipopt::Invalid_Option: message = "Invalid option"; return NlpStatus::failed;
    case Ipopt::Invalid_Number_Detected: message = "Invalid number in NLP function or derivative detected"; return NlpStatus::failed;
    default: message = "IPOPT error " + std::to_string(static_cast<int>(s)); return NlpStatus::failed;
  }
}

NlpResult solve(Nlp& nlp, const NlpOptions& options) {
  const bool hessian = options.hessian == NlpHessian::program && nlp.hessian_nonzeros() >= 0;
  Ipopt::SmartPtr<Adapter> adapter = new Adapter(nlp, hessian);
  Ipopt::SmartPtr<Ipopt::IpoptApplication> app = IpoptApplicationFactory();
  app->Options()->SetIntegerValue("print_level", 0);
  app->Options()->SetStringValue("sb", "yes");  // no banner: the library never prints
  app->Options()->SetStringValue("hessian_approximation", hessian ? "exact" : "limited-memory");
  app->Options()->SetNumericValue("tol", options.tolerance);
  app->Options()->SetNumericValue("constr_viol_tol", options.constraint_tolerance);
  app->Options()->SetIntegerValue("max_iter", options.max_iterations);
  app->Options()->SetNumericValue("nlp_lower_bound_inf", -0.5 * kNlpInfinity);
  app->Options()->SetNumericValue("nlp_upper_bound_inf", 0.5 * kNlpInfinity);
  // MUMPS's permutation to a heavy diagonal (its maximum weighted matching, ICNTL(6)) grew faster
  // than the collocation's KKT matrix: 2.8x and 4.3x its time as the nodes doubled from 501 to
  // 2001, most of the analysis; without it the analysis and the factorizations grow linearly
  // (docs/performance.md, "The figures"). The scaling (ICNTL(8)) stays.
  app->Options()->SetIntegerValue("mumps_permuting_scaling", 0);
  // MUMPS's working space beyond its estimate (ICNTL(14)): IPOPT's 1000 % made every factorization
  // allocate and clear eleven times what it needs, a third of the 501-node parking's time in page
  // faults and memset (8.1 s against 4.5 s at 50 %, the same iterations and optimum). Too little
  // is not an error: IPOPT doubles it and factorizes again.
  app->Options()->SetIntegerValue("mumps_mem_percent", 50);
  NlpResult result;
  // No options file: the options are the ones above, whatever the working directory holds (an
  // ipopt.opt there would change the results silently).
  if (app->Initialize("") != Ipopt::Solve_Succeeded) {
    result.status = NlpStatus::failed;
    result.message = "IPOPT could not be initialized";
    return result;
  }
  const Ipopt::ApplicationReturnStatus status = app->OptimizeTNLP(Ipopt::GetRawPtr(adapter));
  result.status = status_of(status, result.message);
  if (Ipopt::IsValid(app->Statistics())) result.iterations = app->Statistics()->IterationCount();
  result.x = adapter->x_;
  result.objective = adapter->objective_;
  return result;
}

}  // namespace
}  // namespace nhdyn

// The module's entry points (solver_module.hpp), the only symbols it exports (the target builds with
// hidden visibility).
extern "C" __attribute__((visibility("default"))) const char* nhdyn_ipopt_interface() {
  return nhdyn::ipopt_module::kInterface;
}

extern "C" __attribute__((visibility("default"))) void nhdyn_ipopt_solve(nhdyn::Nlp& nlp,
                                                                        const nhdyn::NlpOptions& options,
                                                                        nhdyn::NlpResult& result) {
  result = nhdyn::solve(nlp, options);
}
