// The numeric face of a mechanical system: at (t, q, q') an Evaluator yields the terms of the
// equations of motion (A, Q, G, b, b0), optionally an analytic complement D, the residuals of
// the constraints at the level they were given, the energy, and optionally an exact solution. Built-in C++ models implement it by
// hand; model files (through the symbolic compiler) and generated code are other implementations.
// It is stateless: any workspace it needs is the `scratch` array that Data owns. It computes with
// one set of parameter values (those of Model::parameters, in order) and never changes: new
// values give a new evaluator (with_parameters), so Model copies on several threads can share one.
#pragma once

#include <cstddef>
#include <memory>

#include "nhdyn/model/sparsity.hpp"

namespace nhdyn {

// Where an Evaluator writes the terms. All matrices are column-major and contiguous, with a
// leading dimension equal to their number of rows (the layout of Eigen::MatrixXd).
struct TermsOut {
  double* A;   // n x n inertia matrix, d2T/dq'2 (docs/notation.md (2.4))
  double* Q;   // n generalized forces, -dV/dq + nonconservative forces
  double* G;   // n velocity terms of the kinetic energy (docs/notation.md section 1)
  double* b;   // s x n constraint matrix at acceleration level, b q'' + b0 = 0 (2.5)
  double* b0;  // s
};

class Evaluator {
 public:
  virtual ~Evaluator() = default;

  // This model's evaluator computing with parameter values `values` (`count` of them, in the
  // order of Model::parameters): what depends on the parameters only is computed here, once, not
  // at every call. nullptr when the evaluator's parameters are fixed (the default). Throws
  // InputError for values the model refuses, naming them. Called by set_parameter
  // (parameters.hpp), not in the time loop (it allocates).
  virtual std::shared_ptr<const Evaluator> with_parameters(const double* /*values*/, std::size_t /*count*/) const {
    return nullptr;
  }
  // Whether the model's initial state depends on its parameters: initial_state() then writes q0
  // and q'0 (n values each) for the values this evaluator computes with; `scratch` has
  // scratch_size() entries.
  virtual bool has_initial_state() const { return false; }
  virtual void initial_state(double* /*scratch*/, double* /*q0*/, double* /*v0*/) const {}

  // Number of doubles of workspace every call below needs (0 for hand-written models).
  virtual std::size_t scratch_size() const { return 0; }

  // Fills every entry of A, Q, G, b and b0.
  virtual void terms(double t, const double* q, const double* v, double* scratch,
                     const TermsOut& out) const = 0;

  // The structural nonzeros of A and b when the evaluator can write only those (a model compiled
  // sparse, symbolic/compile.hpp); nullptr otherwise.
  virtual const TermsSparsity* sparsity() const { return nullptr; }
  // Like terms(), but out.A and out.b receive only the nonzeros, in the order of sparsity()
  // (compressed columns). Only for an evaluator whose sparsity() is not null.
  virtual void sparse_terms(double /*t*/, const double* /*q*/, const double* /*v*/, double* /*scratch*/,
                            const TermsOut& /*out*/) const {}

  // Whether complement() is implemented (the model carries an analytic D).
  virtual bool has_complement() const { return false; }
  // D: k x n (k = n - s), column-major, rank k, D b^T = 0 (2.8).
  virtual void complement(double /*t*/, const double* /*q*/, const double* /*v*/,
                          double* /*scratch*/, double* /*D*/) const {}

  // phi(t, q): one value per constraint given at position level, in constraint order.
  virtual void position_residual(double /*t*/, const double* /*q*/, double* /*scratch*/,
                                 double* /*phi*/) const {}
  // One value per constraint given at position or velocity level, in constraint order:
  // d phi/dt = phi_q q' + phi_t for a position-level one, f(t, q, q') for a velocity-level one.
  virtual void velocity_residual(double /*t*/, const double* /*q*/, const double* /*v*/,
                                 double* /*scratch*/, double* /*f*/) const {}

  // Programs (docs/derivations/program-motion.md), m = Model::m() of them. Whether the terms
  // below are computed (a model with programs must say yes).
  virtual bool has_program_constraints() const { return false; }
  // b_p (m x n, column-major), b_p0 (m): the programs at acceleration level, b_p q'' + b_p0 = 0;
  // B (n x m, column-major): the actuator matrix, column j the generalized force direction of
  // program j.
  virtual void program_constraint_terms(double /*t*/, const double* /*q*/, const double* /*v*/,
                                        double* /*scratch*/, double* /*b_p*/, double* /*b_p0*/,
                                        double* /*B*/) const {}
  // The programs' residuals as for the constraints: one per position-level program, and one per
  // position- or velocity-level program, in program order.
  virtual void program_constraint_position_residual(double /*t*/, const double* /*q*/, double* /*scratch*/,
                                                    double* /*phi*/) const {}
  virtual void program_constraint_velocity_residual(double /*t*/, const double* /*q*/, const double* /*v*/,
                                                    double* /*scratch*/, double* /*f*/) const {}

  // Whether energy() is defined: E = T + V (of any system when has_energy_balance(); built-in
  // models define it only where their other forces do no work).
  virtual bool has_energy() const { return false; }
  virtual double energy(double /*t*/, const double* /*q*/, const double* /*v*/,
                        double* /*scratch*/) const {
    return 0.0;
  }
  // Whether energy_function() and power() are defined (docs/derivations/energy-balance.md):
  // h = q' . dT/dq' - T + V (E2), and out[0] = Q_nc . q' (the power of the nonconservative forces),
  // out[1] = -dL/dt|explicit (of the explicit time dependence of T and V); the power of the
  // reactions R . q' (E3) is computed from R (analysis/residuals.hpp).
  virtual bool has_energy_balance() const { return false; }
  // Whether h = E identically (T quadratic in the velocities, T = T2).
  virtual bool energy_function_is_energy() const { return true; }
  virtual double energy_function(double t, const double* q, const double* v, double* scratch) const {
    return energy(t, q, v, scratch);
  }
  virtual void power(double /*t*/, const double* /*q*/, const double* /*v*/, double* /*scratch*/,
                     double* out) const {
    out[0] = out[1] = 0.0;
  }
  // Whether power() gives 0 at every state (no nonconservative forces, no explicit time
  // dependence: most models): compute_power then leaves it uncalled, at every stage of a run.
  virtual bool power_is_zero() const { return false; }

  // Whether solution() is defined: the model knows its exact motion from its own initial state
  // (a closed form), which `nhdyn compare --reference analytic` measures the runs against.
  virtual bool has_solution() const { return false; }
  // q(t), q'(t) and q''(t) one after the other in `qva` (3 n values); `scratch` has
  // scratch_size() entries. Only for a model that has_solution(); the default fills nothing, so
  // callers ask has_solution() first (analysis/exact_solution.hpp checks it).
  virtual void solution(double /*t*/, double* /*scratch*/, double* /*qva*/) const {}
};

}  // namespace nhdyn
