// The Do Sanh formulation on the sparse path (docs/performance.md, "The sparse path"): the stacked
// system
//     [ D A ]        [ D (Q + G) ]
//     [  b  ] q'' =  [   -b0     ]
// with the partitioned D = [I_k, -(b_dep^-1 b_ind)^T] of the dependent coordinates that make_data
// chose, solved by block elimination on its lower rows: b q'' = -b0 gives the dependent
// accelerations from the independent ones through one sparse LU of b_dep (s x s),
//     q''_dep = -b_dep^-1 b0 - X q''_ind,   X = b_dep^-1 b_ind,
// and the upper rows become the k x k system (D A D^T) q''_ind = D (Q + G - A c), c the particular
// solution with c_ind = 0, c_dep = -b_dep^-1 b0. D stays k x n (dense rows, but k of them), A and
// b stay sparse; for the chain (k = 2) the work grows linearly in n. Without constraints (s = 0)
// it is one sparse Cholesky factorization of A. The solution is the one of the dense sanh
// formulation, to round-off.
#pragma once

#include "nhdyn/core/status.hpp"
#include "nhdyn/model/data.hpp"
#include "nhdyn/model/model.hpp"

namespace nhdyn {

// Requires compute_terms on a sparse Data (data.sparse). Writes data.D, data.qdd, data.R.
// When b_dep is singular at this state, or so ill-conditioned that X has entries above 1e6 (the
// partition chosen earlier no longer suits the configuration), it chooses the dependent
// coordinates anew (compute_sparse_partition: allocates, counted in data.partition_changes) and
// solves again. Status::dependent_constraints when b has rank below s, Status::singular_system
// when b_dep stays singular, Status::inertia_not_positive_definite when D A D^T (or A, for s = 0)
// is not positive definite. Allocates nothing else once the first factorization has sized KLU's
// factors of b_dep (model/sparse_lu.hpp; a new search for pivots may size them again); for s = 0,
// Eigen's SimplicialLLT allocates its factors at each call.
Status compute_sparse_sanh_acceleration(const Model& model, Data& data);

}  // namespace nhdyn
