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

// Factors M into `lu` and says whether it is regular, independently of the units of its rows
// (docs/cli.md, "What bad input gets"): when the largest entries of two rows differ by more than
// kRowScaleRatio (row_scaling.hpp), each row of M and of rhs is first scaled exactly by a power
// of two to a largest entry near 1, so that a well-posed system with huge or tiny parameters
// (--set m=1e100) is solved and a singular one still refused (without it, pivots 1e100 apart
// looked singular, and a singular system of such rows could pass). Solve with lu.solve(rhs)
// afterwards. Cost: O(n^2) and one LU; allocates nothing.
bool factor_equilibrated(Matrix& M, Vector& rhs, Eigen::PartialPivLU<Matrix>& lu);

}  // namespace nhdyn
