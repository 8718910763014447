// compute_terms: the first kernel of every evaluation. Stores the state (t, q, q') in Data and
// fills the terms of the equations of motion A, Q, G, b, b0 through the model's Evaluator, then
// checks them for non-finite values so that a NaN never travels silently into a solution.
#pragma once

#include "nhdyn/core/status.hpp"
#include "nhdyn/core/types.hpp"
#include "nhdyn/model/data.hpp"
#include "nhdyn/model/model.hpp"

namespace nhdyn {

// Reads q, v (size n). Writes data.t, q, v, A, Q, G, b, b0 and sets data.stage = Stage::terms.
// Returns Status::non_finite (with data.failed_quantity and data.failed_t) if a term is NaN/inf.
Status compute_terms(const Model& model, Data& data, double t, const double* q, const double* v);

// Records a failure in data (quantity name without allocation beyond make_data's reserve).
Status record_failure(Data& data, Status status, const char* quantity);

// Returns the name of the first non-finite entry among the terms of data, or nullptr.
const char* find_non_finite_term(const Data& data);

}  // namespace nhdyn
