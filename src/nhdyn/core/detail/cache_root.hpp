// The folder of nhdyn's caches, the compiled models' and the derived models': $XDG_CACHE_HOME/nhdyn,
// else $HOME/.cache/nhdyn. As the XDG Base Directory rules say, a relative path in either is
// ignored: a cache would otherwise appear in whatever folder a command runs from. One place for
// both caches, so that they are always side by side.
// Internal: used by jit/ and the frontend's cache, not part of the public API (nhdyn/nhdyn.hpp).
#pragma once

#include <cstdlib>
#include <filesystem>
#include <optional>

namespace nhdyn {

// Empty when neither variable holds an absolute path.
inline std::optional<std::filesystem::path> nhdyn_cache_root() {
  const char* xdg = std::getenv("XDG_CACHE_HOME");
  if (xdg != nullptr && *xdg != '\0' && std::filesystem::path(xdg).is_absolute())
    return std::filesystem::path(xdg) / "nhdyn";
  const char* home = std::getenv("HOME");
  if (home == nullptr || *home == '\0' || !std::filesystem::path(home).is_absolute()) return std::nullopt;
  return std::filesystem::path(home) / ".cache" / "nhdyn";
}

}  // namespace nhdyn
