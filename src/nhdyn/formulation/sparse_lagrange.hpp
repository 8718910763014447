// The Lagrange multiplier (KKT) formulation on the sparse path, the yardstick of the sparse sanh
// solve: one sparse LU (Eigen's SparseLU, like sparse_sanh.hpp) of
//     [ A  b^T ] [ q''    ]   [ Q + G ]
//     [ b   0  ] [ lambda ] = [ -b0   ],   R = -b^T lambda as in formulation/lagrange.hpp,
// an (n + s)-square matrix whose pattern make_sparse_data analyses once.
#pragma once

#include "nhdyn/core/status.hpp"
#include "nhdyn/model/model.hpp"
#include "nhdyn/model/sparse_data.hpp"

namespace nhdyn {

// Requires compute_sparse_terms for the current state. Writes data.qdd, data.lambda, data.R.
Status compute_sparse_lagrange_acceleration(const Model& model, SparseData& data);

}  // namespace nhdyn
