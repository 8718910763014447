#include "nhdyn/model/terms.hpp"

#include <algorithm>
#include <cstring>

#include "nhdyn/core/detail/finite.hpp"

namespace nhdyn {

Status record_failure(Data& data, Status status, const char* quantity) {
  data.status = status;
  // assign() within the reserved capacity does not allocate.
  data.failed_quantity.assign(quantity, std::min<std::size_t>(std::strlen(quantity), 63));
  data.failed_t = data.t;
  return status;
}

namespace {
bool all_finite(const SparseMatrix& m) { return Eigen::Map<const Vector>(m.valuePtr(), m.nonZeros()).allFinite(); }
}  // namespace

const char* find_non_finite_term(const Data& data) {
  if (!data.A.allFinite() || !all_finite(data.A_sparse)) return "inertia matrix A";
  if (!data.Q.allFinite()) return "generalized forces Q";
  if (!data.G.allFinite()) return "velocity terms G";
  if (!data.b.allFinite() || !all_finite(data.b_sparse)) return "constraint matrix b";
  if (!data.b0.allFinite()) return "constraint term b0";
  return nullptr;
}

namespace {

// The end of compute_terms: `acc` is 0 when the state and every term are finite (finite.hpp),
// else the first non-finite array is named.
Status accept_terms(Data& data, double acc) {
  if (acc != 0.0) {
    if (!data.q.allFinite()) return record_failure(data, Status::non_finite, "coordinates q");
    if (!data.v.allFinite()) return record_failure(data, Status::non_finite, "velocities q'");
    const char* bad = find_non_finite_term(data);
    return record_failure(data, Status::non_finite, bad ? bad : "terms");
  }
  data.status = Status::ok;
  data.stage = Stage::terms;
  return Status::ok;
}

}  // namespace

Status compute_terms(const Model& model, Data& data, double t, const double* q, const double* v) {
  const int n = model.n();
  data.t = t;
  data.stage = Stage::empty;
  if (data.terms_non_finite && !data.sparse) {
    // A small dense model: the terms from the caller's state, which the fixed-size test then
    // stores in Data as it reads it (core/detail/finite.hpp), in place of two calls of memcpy.
    model.evaluator->terms(t, q, v, data.scratch.data(),
                           TermsOut{data.A.data(), data.Q.data(), data.G.data(), data.b.data(), data.b0.data()});
    ++data.term_evaluations;
    const double acc = data.terms_non_finite(q, v, data.A.data(), data.Q.data(), data.G.data(), data.b.data(),
                                             data.b0.data(), data.q.data(), data.v.data());
    return accept_terms(data, acc);
  }
  // Copy only when the caller does not pass Data's own storage.
  if (q != data.q.data()) std::memcpy(data.q.data(), q, sizeof(double) * static_cast<std::size_t>(n));
  if (v != data.v.data()) std::memcpy(data.v.data(), v, sizeof(double) * static_cast<std::size_t>(n));
  // The sparse path (model/data.hpp) receives only the nonzeros of A and b.
  if (data.sparse)
    model.evaluator->sparse_terms(t, data.q.data(), data.v.data(), data.scratch.data(),
                                  TermsOut{data.A_sparse.valuePtr(), data.Q.data(), data.G.data(),
                                           data.b_sparse.valuePtr(), data.b0.data()});
  else
    model.evaluator->terms(t, data.q.data(), data.v.data(), data.scratch.data(),
                           TermsOut{data.A.data(), data.Q.data(), data.G.data(), data.b.data(), data.b0.data()});
  ++data.term_evaluations;
  double acc = 0.0;
  acc = accumulate_non_finite(acc, data.q);
  acc = accumulate_non_finite(acc, data.v);
  acc = accumulate_non_finite(acc, data.A);
  acc = accumulate_non_finite(acc, data.Q);
  acc = accumulate_non_finite(acc, data.G);
  acc = accumulate_non_finite(acc, data.b);
  acc = accumulate_non_finite(acc, data.b0);
  acc = accumulate_non_finite(acc, data.A_sparse.valuePtr(), data.A_sparse.nonZeros());
  acc = accumulate_non_finite(acc, data.b_sparse.valuePtr(), data.b_sparse.nonZeros());
  return accept_terms(data, acc);
}

}  // namespace nhdyn
