// Words for numerical trouble: turns the Status a kernel recorded in Data into a message a user
// can act on (which constraints are dependent and how badly, the smallest eigenvalue of A, which
// quantity went non-finite at which t), and checks a state before a run starts. This is the cold
// path: it may allocate.
#pragma once

#include <string>

#include "nhdyn/core/status.hpp"
#include "nhdyn/model/data.hpp"
#include "nhdyn/model/model.hpp"

namespace nhdyn {

// Explains data.status for the state held in data (terms must have been computed for it).
std::string explain_failure(const Model& model, const Data& data);

// "x = 1, phi = 0.5, x' = 0, phi' = 2": a state as the messages of failures show it.
std::string describe_state(const Model& model, const double* q, const double* v);

// Checks the terms in data (after compute_terms): A symmetric positive definite, or, where it is
// singular, positive definite on the velocities the constraints allow ([D A; b] regular), and b
// of full row rank. Returns the first problem found, recording it in data, or Status::ok. A model
// with s >= n (contacts never all held) is checked by its mode solve, on the rows its modes keep.
Status check_terms(const Model& model, Data& data);

// compute_terms at (t, q, v) then check_terms; throws ModelError with explain_failure's words.
void check_state_or_throw(const Model& model, Data& data, double t, const double* q, const double* v);

// The inertia test of check_terms on dense matrices: A (n x n) symmetric positive definite, or
// positive definite on the velocities b (s x n) allows, N^T A N with N a basis of null(b). False
// otherwise, with the smallest eigenvalue of the matrix tested (A, or N^T A N) in `smallest`.
bool inertia_positive_on_constraints(const Matrix& A, const Matrix& b, double& smallest);

}  // namespace nhdyn
