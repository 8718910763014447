// The Do Sanh form (docs/notation.md §3, (2.16), (2.5)): the n x n stacked system
//     [ D A ] q'' = [ D (Q + G) ]
//     [  b  ]       [   -b0     ]
// solved by one LU factorization; no inverse of A and no multipliers. R = A q'' - Q - G (2.15).
#pragma once

#include "nhdyn/core/status.hpp"
#include "nhdyn/formulation/formulation.hpp"

namespace nhdyn {

// Requires compute_terms. Writes data.D, data.qdd, data.R. Cost: the complement (a QR of b^T
// by default, O(n^2 s)), the product D A (O(k n^2)) and an LU of n x n (O(n^3 / 3)).
Status compute_sanh_acceleration(const Model& model, Data& data, Complement complement);

// Whether the LU factor in `lu` has a pivot too small against its largest one to be trusted.
bool lu_is_singular(const Eigen::PartialPivLU<Matrix>& lu);

}  // namespace nhdyn
