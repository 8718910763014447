// A file written whole or not at all: output goes to a temporary file beside the target, which is
// renamed onto the target by commit(); destroyed uncommitted, the temporary is removed. Opening
// checks up front that the target's directory can be written, so a run is refused before it
// computes anything.
#pragma once

#include <cstdio>
#include <filesystem>
#include <string_view>

namespace nhdyn {

class AtomicFile {
 public:
  // Creates the temporary file next to `target`. Throws FileError naming the path and the reason
  // (missing directory, no permission, target is a directory).
  explicit AtomicFile(const std::filesystem::path& target);
  ~AtomicFile();
  AtomicFile(const AtomicFile&) = delete;
  AtomicFile& operator=(const AtomicFile&) = delete;

  void write(std::string_view bytes);
  // Flushes, closes and renames onto the target. Throws FileError if any write failed.
  void commit();

  const std::filesystem::path& target() const { return target_; }

 private:
  std::filesystem::path target_;
  std::filesystem::path temporary_;
  std::FILE* file_ = nullptr;
  bool failed_ = false;
};

}  // namespace nhdyn
