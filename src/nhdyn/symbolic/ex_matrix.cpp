#include "nhdyn/symbolic/ex_matrix.hpp"

#include <stdexcept>

namespace nhdyn::symbolic {
namespace {

void check_index(unsigned r, unsigned c, unsigned rows, unsigned cols) {
  if (r >= rows || c >= cols) throw std::range_error("ExMatrix: index out of range");
}

}  // namespace

ExMatrix::ExMatrix(const GiNaC::matrix& m) : rows_(m.rows()), cols_(m.cols()), columns_(m.cols()) {
  for (unsigned c = 0; c < cols_; ++c)
    for (unsigned r = 0; r < rows_; ++r)
      if (!m(r, c).is_zero()) columns_[c].emplace(r, m(r, c));
}

const GiNaC::ex& ExMatrix::operator()(unsigned r, unsigned c) const {
  static const GiNaC::ex zero = 0;
  check_index(r, c, rows_, cols_);
  const std::map<unsigned, GiNaC::ex>& column = columns_[c];
  const auto it = column.find(r);
  return it == column.end() ? zero : it->second;
}

GiNaC::ex& ExMatrix::operator()(unsigned r, unsigned c) {
  check_index(r, c, rows_, cols_);
  return columns_[c].try_emplace(r, 0).first->second;
}

GiNaC::matrix ExMatrix::dense() const {
  GiNaC::matrix out(rows_, cols_);
  for (unsigned c = 0; c < cols_; ++c)
    for (const auto& [r, e] : columns_[c]) out(r, c) = e;
  return out;
}

std::ostream& operator<<(std::ostream& out, const ExMatrix& m) { return out << GiNaC::ex(m.dense()); }

}  // namespace nhdyn::symbolic
