// Projection onto the constraint manifold (docs/stabilization.md §3): moves a state (q, q') that
// an integration step left slightly off the constraints back onto them with the smallest
// inertia-weighted change, first the positions, then the velocities at the new positions:
//     min 1/2 dq^T A dq  subject to phi(t, q + dq) = 0,
//     min 1/2 dv^T A dv  subject to f(t, q, q' + dv) = 0.
// Each is Newton's method on the residual; a step solves the KKT system
//     [ A  J^T ] [ d  ]   [  0 ]
//     [ J   0  ] [ mu ] = [ -r ]
// with J the rows of b that belong to the constraints of that level (b = dphi/dq for a position
// constraint, df/dq' for a position or velocity one, docs/notation.md §2), so no inverse of A is
// formed. A row of b need only be parallel to its constraint's gradient (a model may scale it, as
// the paper does Appell's); the factor is estimated at every Newton step by a forward difference
// of the residual along the step, which is then solved again with it.
// When the rows are the gradients, constraints linear in the velocities converge in one step.
#pragma once

#include "nhdyn/core/status.hpp"
#include "nhdyn/model/data.hpp"
#include "nhdyn/model/model.hpp"

namespace nhdyn {

struct ProjectionOptions {
  // A level counts as satisfied when every residual is at most this, or when Newton's steps
  // have shrunk to round-off of the coordinates (the residual then is as small as doubles allow).
  double tolerance = 1e-13;
  int max_iterations = 10;  // Newton steps per level
};

struct ProjectionResult {
  int position_iterations = 0;   // Newton steps taken at position level
  int velocity_iterations = 0;   // ... and at velocity level
  double position_change = 0.0;  // max |dq|
  double velocity_change = 0.0;  // max |dv|
  double position_residual = 0.0;  // max |phi| after the projection
  double velocity_residual = 0.0;  // max |f| after the projection
  bool changed() const { return position_iterations + velocity_iterations > 0; }
};

// Projects (q, v) in place at time t. Uses data.A, b, phi, f, K, lu_kkt, kkt_rhs, kkt_sol and
// tmp_n as scratch (overwrites the terms of Data: call compute_terms again before a formulation).
// Returns Status::ok, or Status::projection_failed (data.failed_quantity names the level,
// data.failed_value the residual reached), or the status of a failed evaluation or of a singular
// KKT matrix. Allocates nothing.
Status compute_projection(const Model& model, Data& data, double t, double* q, double* v,
                          const ProjectionOptions& options, ProjectionResult& result);

}  // namespace nhdyn
