// The derivation of the equations of motion from a Spec (docs/notation.md sections 1-3), with
// GiNaC: A = d2T/dq'2, G = dT/dq - (d2T/dq'dq) q' - d2T/dq'dt, Q = -dV/dq + forces, and every
// constraint at acceleration level b q'' + b0 = 0 (position level differentiated twice, velocity
// level once, explicit time dependence included). D is the user's analytic one, or the
// partitioned one when the user names the independent coordinates. Expressions keep the
// parameters as symbols (so that `nhdyn equations` shows them); compile_model substitutes values.
#pragma once

#include <optional>
#include <vector>

#include "nhdyn/symbolic/ex_matrix.hpp"
#include "nhdyn/symbolic/spec.hpp"

namespace nhdyn::symbolic {

struct Derivation {
  ExMatrix A;                       // n x n, the entries that may be nonzero (ex_matrix.hpp)
  GiNaC::matrix Q;                  // n x 1
  GiNaC::matrix G;                  // n x 1
  ExMatrix b;                       // s x n, likewise
  GiNaC::matrix b0;                 // s x 1
  std::optional<GiNaC::matrix> D;   // k x n: analytic (spec.complement) or partitioned (spec.independent)
  std::vector<GiNaC::ex> phi;       // position-level residuals, one per position constraint
  std::vector<GiNaC::ex> f;         // velocity-level residuals, one per position or velocity constraint
  // Programs (docs/derivations/program-motion.md), m of them: b_p q'' + b_p0 = 0 and the actuator
  // matrix B whose column j is program j's generalized force direction; residuals as for phi, f.
  GiNaC::matrix b_p = GiNaC::matrix(0, 0);   // m x n
  GiNaC::matrix b_p0 = GiNaC::matrix(0, 1);  // m x 1
  GiNaC::matrix B = GiNaC::matrix(0, 0);     // n x m
  std::vector<GiNaC::ex> phi_p;              // one per position-level program
  std::vector<GiNaC::ex> f_p;                // one per position- or velocity-level program
  // The energy balance (docs/derivations/energy-balance.md): E = T + V for every model, the energy
  // function h = q' . dT/dq' - T + V (E2) when it differs from E (T has parts of degree 1 or 0 in
  // the velocities; otherwise h = E and this is empty), and the two symbolic parts of the power
  // (E3): Q_nc . q' (the nonconservative forces) and -dL/dt|explicit = -dT/dt + dV/dt (explicit
  // time). The power of the reactions, R . q', is numeric (analysis/residuals.hpp).
  std::optional<GiNaC::ex> energy;  // E = T + V
  std::optional<GiNaC::ex> energy_function;
  GiNaC::ex power_forces = 0;
  GiNaC::ex power_time = 0;
  bool conservative = false;  // no nonconservative forces and T, V free of t: E can change only by R . q'
};

// Throws ModelError naming the constraint (and its location) that does not involve the
// velocities or accelerations after differentiation, or a kinetic energy that is not quadratic
// in the velocities (A depends on the velocities).
Derivation derive(const Spec& spec);

// The partitioned complement D = [I_k, (-b_d^-1 b_i)^T] in the original coordinate order
// (docs/notation.md section 3, choice 2): rows in the order of `independent` (k indices into q,
// ascending), the other s columns dependent. std::nullopt when the s x s block b_d of the dependent
// columns is singular (its determinant simplifies to 0). Entries simplified (simplify.hpp).
std::optional<GiNaC::matrix> partitioned_complement(const GiNaC::matrix& b, const std::vector<int>& independent);

// A0 = D A and C = D (Q + G) (docs/notation.md (2.17)); requires derivation.D.
GiNaC::matrix reduced_inertia(const Derivation& derivation);
GiNaC::matrix reduced_forces(const Derivation& derivation);

}  // namespace nhdyn::symbolic
