#include "nhdyn/io/atomic_file.hpp"

#include <fmt/format.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <cstdlib>
#include <cstring>
#include <string>
#include <system_error>

#include "nhdyn/core/error.hpp"

namespace nhdyn {

AtomicFile::AtomicFile(const std::filesystem::path& target) : target_(target) {
  namespace fs = std::filesystem;
  std::error_code ec;
  if (fs::is_directory(target, ec))
    throw FileError(fmt::format("cannot write '{}': it is a directory; give a file name", target.string()));
  const fs::path dir = target.has_parent_path() ? target.parent_path() : fs::path(".");
  if (!fs::is_directory(dir, ec))
    throw FileError(fmt::format("cannot write '{}': the directory '{}' does not exist; create it first",
                                target.string(), dir.string()));
  // fmt rather than operator+ on strings: GCC 12 at -O3 warns falsely (-Wrestrict) on the latter.
  std::string pattern = (dir / fmt::format(".{}.tmp.XXXXXX", target.filename().string())).string();
  const int fd = ::mkstemp(pattern.data());
  if (fd < 0)
    throw FileError(fmt::format("cannot write '{}': {} (check the directory's permissions)", target.string(),
                                std::strerror(errno)));
  temporary_ = pattern;
  file_ = ::fdopen(fd, "w");
  if (!file_) {
    ::close(fd);
    fs::remove(temporary_, ec);
    throw FileError(fmt::format("cannot write '{}': {}", target.string(), std::strerror(errno)));
  }
  // mkstemp creates the file 0600; results are ordinary files for their owner and group to read.
  ::fchmod(fd, 0644);
}

AtomicFile::~AtomicFile() {
  if (file_) {
    std::fclose(file_);
    std::error_code ec;
    std::filesystem::remove(temporary_, ec);
  }
}

void AtomicFile::write(std::string_view bytes) {
  if (failed_ || !file_) return;
  if (std::fwrite(bytes.data(), 1, bytes.size(), file_) != bytes.size()) failed_ = true;
}

void AtomicFile::commit() {
  if (!file_) throw FileError(fmt::format("'{}' was already committed", target_.string()));
  const bool flushed = std::fflush(file_) == 0;
  const bool closed = std::fclose(file_) == 0;
  file_ = nullptr;
  std::error_code ec;
  if (failed_ || !flushed || !closed) {
    std::filesystem::remove(temporary_, ec);
    throw FileError(fmt::format("writing '{}' failed (disk full?); nothing was written", target_.string()));
  }
  std::filesystem::rename(temporary_, target_, ec);
  if (ec) {
    std::filesystem::remove(temporary_, ec);
    throw FileError(fmt::format("cannot create '{}': {}", target_.string(), ec.message()));
  }
}

}  // namespace nhdyn
