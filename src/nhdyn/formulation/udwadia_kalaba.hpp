// Udwadia-Kalaba (docs/notation.md §5): the unconstrained acceleration a = A^-1 (Q + G) corrected by
//     q'' = a + A^(-1/2) (b A^(-1/2))^+ (-b0 - b a),
// with the square root of A^-1 taken from the Cholesky factor of A and the Moore-Penrose inverse
// of the full-row-rank b A^(-1/2) from a column-pivoted QR factorization. It inverts A, which is what the Do Sanh form avoids; kept for comparison.
#pragma once

#include "nhdyn/core/status.hpp"
#include "nhdyn/model/data.hpp"
#include "nhdyn/model/model.hpp"

namespace nhdyn {

// Requires compute_terms. Writes data.qdd, data.R = A (q'' - a), data.lambda with R = b^T lambda.
// Returns Status::inertia_not_positive_definite when an eigenvalue of A is not positive.
Status compute_udwadia_kalaba_acceleration(const Model& model, Data& data);

}  // namespace nhdyn
