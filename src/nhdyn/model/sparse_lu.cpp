#include "nhdyn/model/sparse_lu.hpp"

#include <klu.h>

#include <stdexcept>

namespace nhdyn {
namespace {

// The reused pivot order is kept while the ratio of the smallest to the largest pivot (klu_rcond)
// stays above this fraction of the ratio the last search gave.
constexpr double kRepivot = 1e-3;

}  // namespace

struct SparseLuFactor::State {
  klu_common common{};
  klu_symbolic* symbolic = nullptr;
  klu_numeric* numeric = nullptr;
  int size = 0;
  double searched_rcond = 0.0;  // klu_rcond after the last factorization that searched for pivots

  State() { klu_defaults(&common); }
  ~State() {
    free_numeric();
    if (symbolic) klu_free_symbolic(&symbolic, &common);
  }
  State(const State&) = delete;
  State& operator=(const State&) = delete;
  void free_numeric() {
    if (numeric) klu_free_numeric(&numeric, &common);
  }
};

SparseLuFactor::SparseLuFactor() = default;
SparseLuFactor::~SparseLuFactor() = default;
SparseLuFactor::SparseLuFactor(SparseLuFactor&&) noexcept = default;
SparseLuFactor& SparseLuFactor::operator=(SparseLuFactor&&) noexcept = default;

void SparseLuFactor::analyze(const SparseMatrix& m) {
  if (m.rows() != m.cols() || !m.isCompressed())
    throw std::logic_error("SparseLuFactor::analyze: the matrix must be square and compressed");
  state_ = std::make_unique<State>();
  state_->size = static_cast<int>(m.rows());
  // KLU's C interface takes the arrays as non-const; it does not write them.
  state_->symbolic = klu_analyze(state_->size, const_cast<int*>(m.outerIndexPtr()),
                                 const_cast<int*>(m.innerIndexPtr()), &state_->common);
  if (!state_->symbolic) throw std::bad_alloc();  // KLU fails here only for want of memory
}

bool SparseLuFactor::factorize(const SparseMatrix& m) {
  if (!state_ || m.rows() != state_->size)
    throw std::logic_error("SparseLuFactor::factorize: analyze the matrix's pattern first");
  State& s = *state_;
  int* p = const_cast<int*>(m.outerIndexPtr());
  int* i = const_cast<int*>(m.innerIndexPtr());
  double* x = const_cast<double*>(m.valuePtr());
  if (s.numeric && klu_refactor(p, i, x, s.symbolic, s.numeric, &s.common) && klu_rcond(s.symbolic, s.numeric, &s.common) &&
      s.common.rcond >= kRepivot * s.searched_rcond) {
    ++reusing_;
    return true;
  }
  s.free_numeric();
  ++pivoting_;
  s.numeric = klu_factor(p, i, x, s.symbolic, &s.common);
  if (!s.numeric) {
    if (s.common.status == KLU_OUT_OF_MEMORY) throw std::bad_alloc();
    return false;  // KLU_SINGULAR: a zero pivot
  }
  if (!klu_rcond(s.symbolic, s.numeric, &s.common) || !(s.common.rcond > 0.0)) {
    s.free_numeric();
    return false;
  }
  s.searched_rcond = s.common.rcond;
  return true;
}

void SparseLuFactor::solve_in_place(double* rhs, Eigen::Index rows, Eigen::Index columns) {
  if (!state_ || !state_->numeric || rows != state_->size)
    throw std::logic_error("SparseLuFactor::solve_in_place: factorize a matrix of this size first");
  if (columns == 0) return;
  klu_solve(state_->symbolic, state_->numeric, state_->size, static_cast<int>(columns), rhs, &state_->common);
}

}  // namespace nhdyn
