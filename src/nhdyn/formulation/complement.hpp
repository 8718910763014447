// The complement D of the constraint matrix b: a k x n matrix of rank k with D b^T = 0 (2.8),
// whose rows span the admissible directions of acceleration. Three choices (docs/notation.md §3):
// the model's analytic D, coordinate partitioning, and an orthonormal basis of null(b) from a
// column-pivoted QR factorization of b^T (the default: well conditioned whatever the coordinates).
#pragma once

#include "nhdyn/core/status.hpp"
#include "nhdyn/formulation/formulation.hpp"
#include "nhdyn/model/data.hpp"
#include "nhdyn/model/model.hpp"

namespace nhdyn {

// Requires compute_terms. Writes data.D (and data.independent for partitioning).
// Returns Status::dependent_constraints when b has rank below s. Throws InputError when the
// analytic D is asked of a model that has none. Allocates nothing.
// With data.check_complement (on in debug builds) the analytic D is checked at every evaluation: when
// complement_residual exceeds kComplementTolerance it returns Status::singular_system with the
// quantity "complement D" and the residual in data.failed_value (explain_failure words it).
Status compute_complement(const Model& model, Data& data, Complement complement);

// How far data.D is from a complement of data.b on the dense path: the largest |D_i . b_j| over
// |D_i| |b_j| (rows D_i of D, b_j of b), 0 for a D with D b^T = 0. 0 when there is nothing to
// compare (no constraint, or the sparse path). Allocates nothing.
double complement_residual(const Data& data);
inline constexpr double kComplementTolerance = 1e-8;

// The column-pivoted QR factorization b^T P = Q [R1; 0] in data.qr_bt and the full orthogonal
// factor in data.Q_full (n x n): its first s columns span range(b^T), the last k span null(b).
// Its rows are the coordinates in data.bt_order (those b touches first; 0 .. n-1 when
// data.bt_in_order), as are those of data.bt. Returns Status::dependent_constraints when b has
// rank below s. Allocates nothing.
Status compute_constraint_basis(const Model& model, Data& data);

// The order in which the QR of b^T takes the coordinates (Data::bt_order), or null where it is
// their own: what the fixed-size kernels take (small_dense.hpp, null_space_basis).
inline const int* coordinate_order(const Data& data) {
  return data.bt_in_order ? nullptr : data.bt_order.data();
}

}  // namespace nhdyn
