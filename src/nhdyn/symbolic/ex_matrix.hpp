// A matrix of expressions that stores only the entries that were set: the derivation's A (n x n)
// and b (s x n). A dense GiNaC::matrix of a large model is mostly zeros and costs n^2 expressions
// to make, touch and free: 144 MB and most of a second for a 1000-body chain (n = 3000), 7 GB for
// 10 000 free particles (n = 30 000), which never loaded. Reading an entry that was not set gives
// 0, so code that reads entries by (row, column) works unchanged; matrix algebra goes through the
// dense GiNaC::matrix (dense(), or the implicit conversion), which only small models need.
#pragma once

#include <ginac/ginac.h>

#include <map>
#include <ostream>
#include <vector>

namespace nhdyn::symbolic {

class ExMatrix {
 public:
  ExMatrix() = default;
  ExMatrix(unsigned rows, unsigned cols) : rows_(rows), cols_(cols), columns_(cols) {}
  // Implicit, so that hand-built derivations (tests, codegen) assign GiNaC matrices as before.
  ExMatrix(const GiNaC::matrix& m);  // NOLINT(google-explicit-constructor)

  unsigned rows() const { return rows_; }
  unsigned cols() const { return cols_; }
  // Entry (r, c): 0 when it was never set.
  const GiNaC::ex& operator()(unsigned r, unsigned c) const;
  // Entry (r, c) for writing: set from now on (as 0 until assigned).
  GiNaC::ex& operator()(unsigned r, unsigned c);
  // The entries of column c that were set, by row, ascending (some may be zero).
  const std::map<unsigned, GiNaC::ex>& column(unsigned c) const { return columns_.at(c); }

  // The same matrix as a dense GiNaC::matrix: rows x cols expressions.
  GiNaC::matrix dense() const;
  operator GiNaC::matrix() const { return dense(); }  // NOLINT(google-explicit-constructor)
  GiNaC::matrix sub(const GiNaC::matrix& other) const { return dense().sub(other); }
  GiNaC::matrix mul(const GiNaC::matrix& other) const { return dense().mul(other); }
  GiNaC::matrix transpose() const { return dense().transpose(); }

 private:
  unsigned rows_ = 0, cols_ = 0;
  std::vector<std::map<unsigned, GiNaC::ex>> columns_;  // per column: row -> entry
};

// Prints as the dense GiNaC::matrix prints.
std::ostream& operator<<(std::ostream& out, const ExMatrix& m);

}  // namespace nhdyn::symbolic
