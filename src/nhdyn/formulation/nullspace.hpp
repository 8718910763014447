// The null-space (Maggi / Kane) formulation (docs/notation.md §5): q'' = p + D^T w, where p is the
// minimum-norm solution of b p = -b0 and (D A D^T) w = D (Q + G - A p) is the k x k reduced
// system, solved by Cholesky. R = A q'' - Q - G.
#pragma once

#include "nhdyn/core/status.hpp"
#include "nhdyn/formulation/formulation.hpp"

namespace nhdyn {

// Requires compute_terms. Writes data.D, data.p, data.w, data.qdd, data.R. Returns
// Status::inertia_not_positive_definite when D A D^T is not positive definite.
Status compute_nullspace_acceleration(const Model& model, Data& data, Complement complement);

}  // namespace nhdyn
