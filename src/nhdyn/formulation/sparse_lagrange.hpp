// The Lagrange multiplier (KKT) formulation on the sparse path, the yardstick of the sparse sanh
// solve: one sparse LU (KLU, model/sparse_lu.hpp, like sparse_sanh.hpp) of
//     [ A  b^T ] [ q''    ]   [ Q + G ]
//     [ b   0  ] [ lambda ] = [ -b0   ],   R = -b^T lambda as in formulation/lagrange.hpp,
// an (n + s)-square matrix whose pattern make_data analyses once (Data::K_sparse, shared with the
// projection, which puts ones on the diagonal of the rows it leaves out).
#pragma once

#include "nhdyn/core/status.hpp"
#include "nhdyn/model/data.hpp"
#include "nhdyn/model/model.hpp"

namespace nhdyn {

// Requires compute_terms on a sparse Data (data.sparse). Writes data.qdd, data.lambda, data.R.
// Status::singular_system when the KKT matrix is singular. Allocates nothing once the first
// factorization has sized KLU's factors (a new search for pivots may size them again).
Status compute_sparse_lagrange_acceleration(const Model& model, Data& data);

// Fills data.K_sparse from A and b: the rows of b whose flag in `keep` is 1 (all when `keep` is
// null) with their transposes, a unit diagonal for the others, zero on the kept diagonal.
void fill_sparse_kkt(Data& data, const char* keep);

}  // namespace nhdyn
