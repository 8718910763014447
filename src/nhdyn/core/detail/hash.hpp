// FNV-1a, the hash that names cache files and tells a whole file from a damaged one (the compiled
// models' and the derived models' caches). Not a cryptographic hash: the caches compare the whole
// key before they trust a file, and the hash only names it or guards against damage.
// Internal: used by jit/ and by the frontend's and symbolic layer's caches, not part of the public
// API (nhdyn/nhdyn.hpp).
#pragma once

#include <cstdint>
#include <string_view>

namespace nhdyn {

inline constexpr std::uint64_t kFnvOffset = 0xcbf29ce484222325ULL;
// A second seed: two hashes of the same bytes from the two seeds make 128 bits.
inline constexpr std::uint64_t kFnvOtherOffset = 0x84222325cbf29ce4ULL;

// The FNV-1a hash of `bytes`, continuing from `h`.
inline std::uint64_t fnv1a(std::string_view bytes, std::uint64_t h = kFnvOffset) {
  for (unsigned char ch : bytes) {
    h ^= ch;
    h *= 0x100000001b3ULL;
  }
  return h;
}

}  // namespace nhdyn
