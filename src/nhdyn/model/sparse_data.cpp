#include "nhdyn/model/sparse_data.hpp"

#include <fmt/format.h>

#include <Eigen/OrderingMethods>
#include <Eigen/SparseQR>
#include <algorithm>
#include <cstring>

#include "nhdyn/core/error.hpp"

namespace nhdyn {
namespace {

// A sparse matrix on `pattern` (values zero), built without triplets: the pattern is already in
// compressed columns.
SparseMatrix on_pattern(const SparsityPattern& pattern) {
  SparseMatrix m(pattern.rows, pattern.cols);
  m.resizeNonZeros(pattern.nonzeros());
  std::copy(pattern.outer.begin(), pattern.outer.end(), m.outerIndexPtr());
  std::copy(pattern.inner.begin(), pattern.inner.end(), m.innerIndexPtr());
  std::fill(m.valuePtr(), m.valuePtr() + pattern.nonzeros(), 0.0);
  return m;
}

// The coordinates whose columns of b are independent: the first s columns of a sparse QR with
// column pivoting (Eigen moves columns whose remaining norm is negligible to the end).
std::vector<int> choose_dependent(const Model& model, const SparseMatrix& b) {
  const int s = model.s();
  std::vector<int> dependent;
  if (s == 0) return dependent;
  Eigen::SparseQR<SparseMatrix, Eigen::COLAMDOrdering<int>> qr;
  qr.compute(b);
  if (qr.info() != Eigen::Success || qr.rank() < s)
    throw ModelError(fmt::format("model '{}': the constraint matrix b has rank {} < s = {} at the initial state; "
                                 "the constraints are not independent there, so no coordinates can be chosen as "
                                 "dependent (check the initial state and the constraints)",
                                 model.name, qr.info() == Eigen::Success ? qr.rank() : 0, s));
  const auto& permutation = qr.colsPermutation().indices();
  for (int i = 0; i < s; ++i) dependent.push_back(permutation[i]);
  std::sort(dependent.begin(), dependent.end());
  return dependent;
}

}  // namespace

SparseData make_sparse_data(const Model& model) {
  const TermsSparsity* sparsity = model.evaluator ? model.evaluator->sparsity() : nullptr;
  if (sparsity == nullptr)
    throw ModelError(fmt::format("model '{}' was not compiled sparse: the sparse formulations need a model "
                                 "compiled with TermsLayout::sparse (symbolic/compile.hpp; automatic does so for large sparse models)",
                                 model.name));
  const int n = model.n(), s = model.s(), k = model.k();
  SparseData d;
  d.q = model.q0;
  d.v = model.v0;
  d.A = on_pattern(sparsity->A);
  d.b = on_pattern(sparsity->b);
  d.Q = Vector::Zero(n);
  d.G = Vector::Zero(n);
  d.b0 = Vector::Zero(s);
  d.qdd = Vector::Zero(n);
  d.R = Vector::Zero(n);
  d.lambda = Vector::Zero(s);
  d.failed.reserve(64);
  d.scratch.assign(model.evaluator->scratch_size(), 0.0);
  if (compute_sparse_terms(model, d, model.t0, model.q0.data(), model.v0.data()) != Status::ok)
    throw ModelError(fmt::format("model '{}': the {} is not finite at the initial state", model.name, d.failed));

  // Partition, and the pattern of b_dep with the source of each value.
  d.dependent = choose_dependent(model, d.b);
  d.column_slot.assign(static_cast<std::size_t>(n), -1);
  std::vector<char> is_dependent(static_cast<std::size_t>(n), 0);
  for (int j = 0; j < s; ++j) {
    is_dependent[static_cast<std::size_t>(d.dependent[static_cast<std::size_t>(j)])] = 1;
    d.column_slot[static_cast<std::size_t>(d.dependent[static_cast<std::size_t>(j)])] = j;
  }
  for (int j = 0; j < n; ++j)
    if (!is_dependent[static_cast<std::size_t>(j)]) {
      d.column_slot[static_cast<std::size_t>(j)] = static_cast<int>(d.independent.size());
      d.independent.push_back(j);
    }
  d.b_dep.resize(s, s);
  {
    std::vector<Eigen::Triplet<double, int>> entries;
    for (int jj = 0; jj < s; ++jj) {
      const int j = d.dependent[static_cast<std::size_t>(jj)];
      for (int m = d.b.outerIndexPtr()[j]; m < d.b.outerIndexPtr()[j + 1]; ++m)
        entries.emplace_back(d.b.innerIndexPtr()[m], jj, static_cast<double>(m));
    }
    d.b_dep.setFromTriplets(entries.begin(), entries.end());
    d.b_dep_source.resize(static_cast<std::size_t>(d.b_dep.nonZeros()));
    for (int m = 0; m < d.b_dep.nonZeros(); ++m)
      d.b_dep_source[static_cast<std::size_t>(m)] = static_cast<int>(d.b_dep.valuePtr()[m]);
  }
  d.b_ind = Matrix::Zero(s, k + 1);
  d.X = Matrix::Zero(s, k + 1);
  d.D = Matrix::Zero(k, n);
  d.AD = Matrix::Zero(n, k);
  d.DAD = Matrix::Zero(k, k);
  // Factor an identity once rather than assign a default-constructed LLT, whose status is
  // uninitialized (copying or moving it is undefined behaviour); the storage is sized either way.
  d.llt_k.compute(Matrix::Identity(k, k));
  d.h = Vector::Zero(n);
  d.c = Vector::Zero(n);
  d.tmp_n = Vector::Zero(n);
  d.w = Vector::Zero(k);
  d.lu_dep = std::make_unique<SparseLU>();
  if (s > 0) d.lu_dep->analyzePattern(d.b_dep);

  // KKT pattern [A b^T; b 0], each value's source coded as A's index (>= 0) or ~b's index.
  {
    std::vector<Eigen::Triplet<double, int>> entries;
    for (int j = 0; j < n; ++j) {
      for (int m = d.A.outerIndexPtr()[j]; m < d.A.outerIndexPtr()[j + 1]; ++m)
        entries.emplace_back(d.A.innerIndexPtr()[m], j, static_cast<double>(m));
      for (int m = d.b.outerIndexPtr()[j]; m < d.b.outerIndexPtr()[j + 1]; ++m) {
        const int r = d.b.innerIndexPtr()[m];
        entries.emplace_back(n + r, j, static_cast<double>(~m));  // b
        entries.emplace_back(j, n + r, static_cast<double>(~m));  // b^T
      }
    }
    d.K.resize(n + s, n + s);
    d.K.setFromTriplets(entries.begin(), entries.end());
    d.K_source.resize(static_cast<std::size_t>(d.K.nonZeros()));
    for (int m = 0; m < d.K.nonZeros(); ++m) d.K_source[static_cast<std::size_t>(m)] = static_cast<int>(d.K.valuePtr()[m]);
    d.lu_kkt = std::make_unique<SparseLU>();
    d.lu_kkt->analyzePattern(d.K);
  }
  d.kkt_rhs = Vector::Zero(n + s);
  d.kkt_sol = Vector::Zero(n + s);
  return d;
}

Status compute_sparse_terms(const Model& model, SparseData& data, double t, const double* q, const double* v) {
  const int n = model.n();
  data.t = t;
  if (q != data.q.data()) std::memcpy(data.q.data(), q, sizeof(double) * static_cast<std::size_t>(n));
  if (v != data.v.data()) std::memcpy(data.v.data(), v, sizeof(double) * static_cast<std::size_t>(n));
  data.has_terms = false;
  const TermsOut out{data.A.valuePtr(), data.Q.data(), data.G.data(), data.b.valuePtr(), data.b0.data()};
  model.evaluator->sparse_terms(t, data.q.data(), data.v.data(), data.scratch.data(), out);
  const auto finite = [](const double* x, Eigen::Index size) {
    return Eigen::Map<const Vector>(x, size).allFinite();
  };
  const char* bad = !finite(data.A.valuePtr(), data.A.nonZeros()) ? "inertia matrix A"
                    : !data.Q.allFinite()                         ? "generalized forces Q"
                    : !data.G.allFinite()                         ? "velocity terms G"
                    : !finite(data.b.valuePtr(), data.b.nonZeros()) ? "constraint matrix b"
                    : !data.b0.allFinite()                        ? "constraint term b0"
                                                                  : nullptr;
  if (bad != nullptr) {
    data.failed.assign(bad);
    return Status::non_finite;
  }
  data.has_terms = true;
  return Status::ok;
}

}  // namespace nhdyn
