// The structural nonzeros of the inertia matrix A and the constraint matrix b of a model, for the
// sparse path: a chain of a thousand bodies has n = 3000 coordinates, but each row of A and b
// touches a handful of them. The layout is Eigen's compressed columns, so that an
// Eigen::SparseMatrix built on this pattern takes the evaluator's values as they come.
#pragma once

#include <vector>

namespace nhdyn {

// Entry k of the values lies in row inner[k]; column j holds entries outer[j] .. outer[j + 1] - 1,
// rows ascending.
struct SparsityPattern {
  int rows = 0;
  int cols = 0;
  std::vector<int> outer;  // cols + 1 offsets
  std::vector<int> inner;  // one row index per nonzero

  int nonzeros() const { return outer.empty() ? 0 : outer.back(); }
};

struct TermsSparsity {
  SparsityPattern A;  // n x n, symmetric pattern
  SparsityPattern b;  // s x n
};

// Throws std::invalid_argument when the pattern is not a well-formed rows x cols pattern (offsets
// not ascending, rows out of range or not ascending within a column).
void check_pattern(const SparsityPattern& pattern, int rows, int cols, const char* what);

}  // namespace nhdyn
