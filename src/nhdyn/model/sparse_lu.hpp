// The sparse LU factorizations of the sparse path: b_dep (formulation/sparse_sanh.hpp) and the KKT
// matrix [A b^T; b C] (sparse_lagrange.hpp, the projection): square matrices whose pattern is fixed
// and whose values change at every right-hand side.
// It is SuiteSparse's KLU, kept behind this class so that its headers stay in sparse_lu.cpp. KLU
// analyses the pattern once (a block triangular form, then an ordering for each block: the chain's
// 2998 x 2998 b_dep has 998 blocks), and after the first factorization each one reuses the pivot
// order of the last factorization that searched for pivots (klu_refactor: no search, no
// allocation, ten times faster than a supernodal LU that searches again). A search is partial
// pivoting proper (each pivot the largest of its column), and it searches again as soon as the
// reused order has become poorer: its pivot growth or the ratio of its smallest to its largest
// pivot worse by half than what the search gave (docs/design.md, "The sparse path").
#pragma once

#include <Eigen/SparseCore>
#include <memory>

#include "nhdyn/core/types.hpp"

namespace nhdyn {

using SparseMatrix = Eigen::SparseMatrix<double, Eigen::ColMajor, int>;

class SparseLuFactor {
 public:
  SparseLuFactor();
  ~SparseLuFactor();
  SparseLuFactor(SparseLuFactor&&) noexcept;
  SparseLuFactor& operator=(SparseLuFactor&&) noexcept;

  // The pattern of `m` (square, compressed), analysed; forgets any factorization.
  void analyze(const SparseMatrix& m);
  // The factorization of `m`, whose pattern is the analysed one. False when `m` is singular (a
  // zero pivot even with a search for pivots).
  bool factorize(const SparseMatrix& m);
  // rhs := m^-1 rhs, every column, after a successful factorize.
  void solve_in_place(Matrix& rhs) { solve_in_place(rhs.data(), rhs.rows(), rhs.cols()); }
  void solve_in_place(Vector& rhs) { solve_in_place(rhs.data(), rhs.rows(), 1); }
  // How many factorizations searched for pivots (the first after analyze, and each change of the
  // pivot order), and how many reused the order: for tests and the performance page.
  long pivoting_factorizations() const { return pivoting_; }
  long reusing_factorizations() const { return reusing_; }

 private:
  void solve_in_place(double* rhs, Eigen::Index rows, Eigen::Index columns);
  struct State;  // KLU's objects (sparse_lu.cpp)
  std::unique_ptr<State> state_;
  long pivoting_ = 0;
  long reusing_ = 0;
};

}  // namespace nhdyn
