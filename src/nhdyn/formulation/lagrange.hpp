// Lagrange multipliers (docs/notation.md §5): the (n + s) x (n + s) KKT system
//     [ A  b^T ] [ q''     ]   [ Q + G ]
//     [ b  0   ] [ -lambda ] = [ -b0   ],      R = b^T lambda,
// solved by one LU factorization with partial pivoting (the matrix is symmetric indefinite).
#pragma once

#include "nhdyn/core/status.hpp"
#include "nhdyn/model/data.hpp"
#include "nhdyn/model/model.hpp"

namespace nhdyn {

// Requires compute_terms. Writes data.qdd, data.lambda, data.R. Cost O((n + s)^3 / 3).
Status compute_lagrange_acceleration(const Model& model, Data& data);

}  // namespace nhdyn
