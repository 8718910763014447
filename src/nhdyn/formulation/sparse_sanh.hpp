// The Do Sanh formulation on the sparse path (docs/performance.md, "The sparse path"): the stacked
// system
//     [ D A ]        [ D (Q + G) ]
//     [  b  ] q'' =  [   -b0     ]
// with the partitioned D = [I_k, -(b_dep^-1 b_ind)^T] of the coordinates chosen by
// make_sparse_data, solved by block elimination on its lower rows: b q'' = -b0 gives the
// dependent accelerations from the independent ones through one sparse LU of b_dep (s x s),
//     q''_dep = -b_dep^-1 b0 - X q''_ind,   X = b_dep^-1 b_ind,
// and the upper rows become the k x k system (D A D^T) q''_ind = D (Q + G - A c), c the particular
// solution with c_ind = 0, c_dep = -b_dep^-1 b0. D stays k x n (dense rows, but k of them), A and
// b stay sparse; for the chain (k = 2) the work grows linearly in n. The solution is the one of
// the dense sanh formulation with the same partition, to round-off.
#pragma once

#include "nhdyn/core/status.hpp"
#include "nhdyn/model/model.hpp"
#include "nhdyn/model/sparse_data.hpp"

namespace nhdyn {

// Requires compute_sparse_terms for the current state. Writes data.D, data.qdd, data.R.
// Status::singular_system (data.failed says which matrix) when b_dep is singular at this state
// (the partition chosen at the initial state no longer holds) or D A D^T is not positive definite.
Status compute_sparse_sanh_acceleration(const Model& model, SparseData& data);

}  // namespace nhdyn
