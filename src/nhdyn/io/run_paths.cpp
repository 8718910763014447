#include "nhdyn/io/run_paths.hpp"

#include <fmt/format.h>
#include <sys/stat.h>

#include <system_error>
#include <utility>

#include "nhdyn/core/error.hpp"
#include "nhdyn/io/atomic_file.hpp"

namespace nhdyn {
namespace {

namespace fs = std::filesystem;

// Two paths name one file: the same device and inode when both exist, else the same absolute
// path once the links of the existing part are followed.
bool same_file(const fs::path& a, const fs::path& b) {
  struct stat sa{}, sb{};
  const bool a_exists = ::stat(a.c_str(), &sa) == 0, b_exists = ::stat(b.c_str(), &sb) == 0;
  if (a_exists && b_exists) return sa.st_dev == sb.st_dev && sa.st_ino == sb.st_ino;
  if (a_exists != b_exists) return false;
  std::error_code ea, eb;
  const fs::path ca = fs::weakly_canonical(fs::absolute(a, ea), ea), cb = fs::weakly_canonical(fs::absolute(b, eb), eb);
  return !ea && !eb && ca == cb;
}

// A device, pipe or socket: many outputs may go there (/dev/null twice is fine).
bool special(const fs::path& p) {
  struct stat st{};
  return ::stat(p.c_str(), &st) == 0 && !S_ISREG(st.st_mode) && !S_ISDIR(st.st_mode);
}

}  // namespace

void RunPaths::input(const fs::path& path, std::string role) {
  if (path.empty()) return;
  protect_input(path);
  entries_.push_back({path, std::move(role), false});
}

void RunPaths::output(const fs::path& path, std::string role) {
  if (path.empty()) return;
  entries_.push_back({path, std::move(role), true});
}

void RunPaths::check() const {
  for (std::size_t i = 0; i < entries_.size(); ++i)
    for (std::size_t j = i + 1; j < entries_.size(); ++j) {
      const Entry& a = entries_[i];
      const Entry& b = entries_[j];
      if (!a.output && !b.output) continue;
      if (special(a.path) || !same_file(a.path, b.path)) continue;
      const Entry& out = b.output ? b : a;
      const Entry& other = b.output ? a : b;
      if (!other.output)
        throw FileError(fmt::format("refusing to write {} '{}': it is {} '{}', an input of this run; give another "
                                    "output path",
                                    out.role, out.path.string(), other.role, other.path.string()));
      throw FileError(fmt::format("{} '{}' and {} '{}' are the same file; give them different names", other.role,
                                  other.path.string(), out.role, out.path.string()));
    }
}

}  // namespace nhdyn
