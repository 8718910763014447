#include "nhdyn/model/sparsity.hpp"

#include <stdexcept>
#include <string>

namespace nhdyn {

void check_pattern(const SparsityPattern& pattern, int rows, int cols, const char* what) {
  const auto fail = [&](const std::string& why) {
    throw std::invalid_argument(std::string("sparsity pattern of ") + what + ": " + why);
  };
  if (pattern.rows != rows || pattern.cols != cols)
    fail("is " + std::to_string(pattern.rows) + " x " + std::to_string(pattern.cols) + ", expected " +
         std::to_string(rows) + " x " + std::to_string(cols));
  if (static_cast<int>(pattern.outer.size()) != cols + 1 || pattern.outer.front() != 0)
    fail("needs cols + 1 column offsets starting at 0");
  if (static_cast<int>(pattern.inner.size()) != pattern.outer.back()) fail("offsets and row indices disagree");
  for (int j = 0; j < cols; ++j) {
    if (pattern.outer[j + 1] < pattern.outer[j]) fail("column offsets decrease");
    for (int k = pattern.outer[j]; k < pattern.outer[j + 1]; ++k) {
      const int r = pattern.inner[static_cast<std::size_t>(k)];
      if (r < 0 || r >= rows) fail("row index out of range in column " + std::to_string(j));
      if (k > pattern.outer[j] && r <= pattern.inner[static_cast<std::size_t>(k - 1)])
        fail("row indices not ascending in column " + std::to_string(j));
    }
  }
}

}  // namespace nhdyn
