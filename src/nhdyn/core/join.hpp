// Joining names for messages ("the frames are: ground, heading"). Every layer lists names in its
// errors and notes; they share this one function so that lists read the same everywhere.
#pragma once

#include <string>
#include <string_view>
#include <vector>

namespace nhdyn {

// The items with `separator` between consecutive ones; "" for none.
inline std::string join(const std::vector<std::string>& items, std::string_view separator = ", ") {
  std::string out;
  for (std::size_t i = 0; i < items.size(); ++i) {
    if (i > 0) out += separator;
    out += items[i];
  }
  return out;
}

}  // namespace nhdyn
