// The initial state against the constraints: report how far (q0, q0') is from satisfying every
// constraint at position and velocity level, and move it onto them with the smallest
// inertia-weighted change (`--fix-initial`):
//     min 1/2 dq^T A dq  subject to phi(q0 + dq) = 0,   then
//     min 1/2 dv^T A dv  subject to f(q, q0' + dv) = 0,
// each by Newton's method on the constraint with the minimum-A-norm step
//     d = -A^-1 J^T (J A^-1 J^T)^-1 r,
// J the rows of b belonging to those constraints (b = dphi/dq for a position constraint and
// df/dq' for a velocity one, docs/notation.md §2). The same projection (projection.hpp) keeps a
// solution on the constraints with --stabilize projection.
#pragma once

#include <string>
#include <vector>

#include "nhdyn/model/data.hpp"
#include "nhdyn/model/model.hpp"

namespace nhdyn {

struct ConstraintResidual {
  std::string constraint;
  ConstraintLevel level;  // position or velocity: which residual this is
  double value;
};

// The residuals of every position- and velocity-level constraint at (t, q, v).
std::vector<ConstraintResidual> calc_initial_residuals(const Model& model, Data& data, double t, const Vector& q,
                                                      const Vector& v);

struct InitialFix {
  Vector q, v;             // the corrected state
  Vector dq, dv;           // the changes
  int position_iterations = 0;
  int velocity_iterations = 0;
  double position_residual = 0.0;  // max |phi| after the fix
  double velocity_residual = 0.0;  // max |f| after the fix
};

// Moves (q, v) onto the constraints, every value free to move. Throws ModelError when Newton does
// not converge (naming the residual reached and the constraints) or when A or J is singular on
// the way.
InitialFix fix_initial_state(const Model& model, Data& data, double t, const Vector& q, const Vector& v,
                             double tolerance = 1e-13, int max_iterations = 50);

// --fix-initial: the same, but the values the model file wrote (model.q0_written, v0_written) are
// kept and only the others move, with the smallest change weighted by their block of A
// (docs/derivations/rolling-bodies.md section 10). A model's programs at position and velocity
// level are met as its constraints are (a motion starts on its programs). Throws ModelError naming
// the constraint or program, its level, where it was written and its residual when the values
// kept leave it unsatisfied. With none written and no program it is fix_initial_state.
InitialFix fix_free_initial_values(const Model& model, Data& data, double t, const Vector& q, const Vector& v,
                                   double tolerance = 1e-13, int max_iterations = 50);

// Finds the initial values of the coordinates a model added for its contact points
// (model.contact_coordinates, docs/derivations/rolling-bodies.md section 10) from the rest of
// (q, v), in place: Newton's method on the position constraints that hold them, then their
// velocities from those constraints' time derivatives (linear in them). Values already on the
// constraints (as the model's q0, solved when it was made) are left as they are. Throws ModelError
// naming the contact, the constraint and its residual when they cannot be found.
void complete_initial_state(const Model& model, Data& data, double t, Vector& q, Vector& v);

// Throws ModelError listing every residual above `tolerance` and suggesting --fix-initial.
void check_initial_state(const Model& model, Data& data, double t, const Vector& q, const Vector& v,
                         double tolerance);

}  // namespace nhdyn
