#include "nhdyn/io/atomic_file.hpp"

#include <fmt/format.h>
#include <sys/stat.h>
#include <unistd.h>

#include <array>
#include <atomic>
#include <cerrno>
#include <climits>
#include <cstdlib>
#include <cstring>
#include <mutex>
#include <stdexcept>
#include <string>
#include <system_error>
#include <vector>

#include "nhdyn/core/error.hpp"

namespace nhdyn {
namespace {

namespace fs = std::filesystem;

// The temporaries a signal handler must remove. Fixed storage, because the handler may neither
// allocate nor lock: a slot's path is written before `used` is set (release) and the handler
// reads `used` first (acquire).
struct TemporarySlot {
  std::atomic<bool> used{false};
  std::array<char, PATH_MAX> path{};
};
constexpr int temporary_slots = 64;
std::array<TemporarySlot, temporary_slots> temporaries;
std::mutex temporaries_mutex;  // serializes claiming a slot (not taken by the handler)

struct ProtectedInput {
  dev_t device;
  ino_t inode;
  std::string name;
};
std::mutex inputs_mutex;
std::vector<ProtectedInput> protected_inputs;

mode_t creation_mode() {
  // What open(..., 0666) would give: the umask is read by setting it, so set it back at once.
  static const mode_t mode = [] {
    const mode_t mask = ::umask(022);
    ::umask(mask);
    return static_cast<mode_t>(0666 & ~mask);
  }();
  return mode;
}

}  // namespace

fs::path resolve_links(const fs::path& path) {
  fs::path current = path;
  for (int hop = 0; hop < 40; ++hop) {
    std::error_code ec;
    if (!fs::is_symlink(fs::symlink_status(current, ec))) return current;
    const fs::path next = fs::read_symlink(current, ec);
    if (ec) return current;
    current = next.is_absolute() ? next : current.parent_path() / next;
  }
  throw FileError(fmt::format("cannot write '{}': too many levels of symbolic links (a loop?)", path.string()));
}

void protect_input(const fs::path& input) {
  struct stat st{};
  if (::stat(input.c_str(), &st) != 0) return;
  const std::lock_guard lock(inputs_mutex);
  protected_inputs.push_back({st.st_dev, st.st_ino, input.string()});
}

void require_not_input(const fs::path& output, const fs::path& named) {
  struct stat st{};
  if (::stat(output.c_str(), &st) != 0) return;  // does not exist (or unreachable): not an input
  const std::lock_guard lock(inputs_mutex);
  for (const ProtectedInput& in : protected_inputs)
    if (in.device == st.st_dev && in.inode == st.st_ino)
      throw FileError(fmt::format("refusing to write '{}': it is '{}', an input of this run (the model file); "
                                  "give another output path",
                                  (named.empty() ? output : named).string(), in.name));
}

int register_temporary_file(const fs::path& path) {
  const std::string& text = path.native();
  if (text.size() + 1 > PATH_MAX) return -1;
  const std::lock_guard lock(temporaries_mutex);
  for (int i = 0; i < temporary_slots; ++i) {
    TemporarySlot& slot = temporaries[static_cast<std::size_t>(i)];
    if (slot.used.load(std::memory_order_acquire)) continue;
    std::memcpy(slot.path.data(), text.c_str(), text.size() + 1);
    slot.used.store(true, std::memory_order_release);
    return i;
  }
  return -1;
}

void release_temporary_file(int slot) {
  if (slot >= 0 && slot < temporary_slots) temporaries[static_cast<std::size_t>(slot)].used.store(false, std::memory_order_release);
}

void remove_temporary_files() noexcept {
  for (TemporarySlot& slot : temporaries)
    if (slot.used.load(std::memory_order_acquire)) ::unlink(slot.path.data());
}

std::string make_file_name(std::string_view name, std::string_view fallback) {
  std::string out;
  for (const char c : name) {
    const auto u = static_cast<unsigned char>(c);
    const bool keep = (u >= 0x80) || (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || (c >= '0' && c <= '9') ||
                      c == '-' || c == '_' || c == '.' || c == '+';
    out += keep ? c : '_';
  }
  const std::size_t first = out.find_first_not_of('.');
  out.erase(0, first == std::string::npos ? out.size() : first);
  if (out.size() > 120) out.resize(120);
  // A cut inside a multi-byte UTF-8 character would leave an invalid name: drop its lead bytes.
  while (!out.empty() && (static_cast<unsigned char>(out.back()) & 0xC0) == 0xC0) out.pop_back();
  if (out.empty() || out.find_first_not_of('_') == std::string::npos) return std::string(fallback);
  return out;
}

AtomicFile::AtomicFile(const fs::path& target) : target_(target) {
  // A device or pipe reached through the kernel's own links (/dev/stdout -> /proc/self/fd/1 ->
  // "pipe:[...]") is opened by the name given; only links to regular files are followed by hand.
  struct stat st{};
  const bool special = ::stat(target.c_str(), &st) == 0 && !S_ISREG(st.st_mode) && !S_ISDIR(st.st_mode);
  resolved_ = special ? target : resolve_links(target);
  require_not_input(resolved_, target);
  std::error_code ec;
  const bool exists = ::stat(resolved_.c_str(), &st) == 0;
  if (exists && S_ISDIR(st.st_mode))
    throw FileError(fmt::format("cannot write '{}': it is a directory; give a file name", target.string()));
  if (exists && !S_ISREG(st.st_mode)) {
    // A device, pipe or socket: there is nothing to replace, and renaming a regular file onto it
    // would destroy it. Write to it as it is.
    file_ = std::fopen(resolved_.c_str(), "w");
    if (!file_)
      throw FileError(fmt::format("cannot write '{}': {}", target.string(), std::strerror(errno)));
    return;
  }
  const fs::path dir = resolved_.has_parent_path() ? resolved_.parent_path() : fs::path(".");
  if (!fs::is_directory(dir, ec))
    throw FileError(fmt::format("cannot write '{}': the directory '{}' does not exist; create it first",
                                target.string(), dir.string()));
  // fmt rather than operator+ on strings: GCC 12 at -O3 warns falsely (-Wrestrict) on the latter.
  // The temporary's name is the target's with 12 bytes more: near the file system's limit on a
  // name (NAME_MAX, 255 on most) the target's is cut for it, so that any name the file system
  // takes can be written; a target's name beyond the limit is refused in words.
  const long name_max_read = ::pathconf(dir.c_str(), _PC_NAME_MAX);
  const std::size_t name_max = name_max_read > 0 ? static_cast<std::size_t>(name_max_read) : 255;
  std::string name = resolved_.filename().string();
  if (name.size() > name_max)
    throw FileError(fmt::format("cannot write '{}': its name is {} bytes, above the file system's limit of {}; "
                                "choose a shorter name",
                                target.string(), name.size(), name_max));
  constexpr std::size_t kTemporaryExtra = 12;  // "." + ".tmp.XXXXXX"
  if (name.size() + kTemporaryExtra > name_max) name.resize(name_max - kTemporaryExtra);
  std::string pattern = (dir / fmt::format(".{}.tmp.XXXXXX", name)).string();
  const int fd = ::mkstemp(pattern.data());
  if (fd < 0)
    throw FileError(fmt::format("cannot write '{}': {} (check the directory's permissions)", target.string(),
                                std::strerror(errno)));
  temporary_ = pattern;
  slot_ = register_temporary_file(temporary_);
  file_ = ::fdopen(fd, "w");
  if (!file_) {
    const int err = errno;
    ::close(fd);
    release_temporary_file(slot_);
    fs::remove(temporary_, ec);
    throw FileError(fmt::format("cannot write '{}': {}", target.string(), std::strerror(err)));
  }
  // mkstemp creates the file 0600: a replaced file keeps its mode, a new one gets what open()
  // would have given it.
  ::fchmod(fd, exists ? (st.st_mode & 07777) : creation_mode());
}

AtomicFile::~AtomicFile() {
  if (file_) std::fclose(file_);
  if (stage_ != Stage::published) remove_temporary();
}

void AtomicFile::remove_temporary() {
  if (temporary_.empty()) return;
  std::error_code ec;
  std::filesystem::remove(temporary_, ec);
  release_temporary_file(slot_);
  temporary_.clear();
}

void AtomicFile::write(std::string_view bytes) {
  if (failed_ || !file_) return;
  if (std::fwrite(bytes.data(), 1, bytes.size(), file_) != bytes.size()) {
    failed_ = true;
    write_error_ = errno;
  }
}

std::string AtomicFile::written() const {
  if (!file_ || temporary_.empty() || std::fflush(file_) != 0) return {};
  std::FILE* in = std::fopen(temporary_.c_str(), "rb");
  if (!in) return {};
  std::string bytes;
  std::array<char, 1 << 16> chunk;
  std::size_t n = 0;
  while ((n = std::fread(chunk.data(), 1, chunk.size(), in)) > 0) bytes.append(chunk.data(), n);
  std::fclose(in);
  return bytes;
}

void AtomicFile::finish() {
  if (stage_ != Stage::writing) throw std::logic_error(fmt::format("AtomicFile: '{}' was already finished", target_.string()));
  int error = failed_ ? write_error_ : 0;
  if (std::fflush(file_) != 0 && error == 0) error = errno;
  if (std::fclose(file_) != 0 && error == 0) error = errno;
  const bool ok = !failed_ && error == 0;
  file_ = nullptr;
  stage_ = Stage::finished;
  if (ok) return;
  if (temporary_.empty())
    throw FileError(fmt::format("writing '{}' failed: {}", target_.string(), std::strerror(error)));
  remove_temporary();
  throw FileError(fmt::format("writing '{}' failed (disk full?); nothing was written", target_.string()));
}

void AtomicFile::publish() {
  if (stage_ != Stage::finished)
    throw std::logic_error(fmt::format("AtomicFile: '{}' published before finish() or twice", target_.string()));
  stage_ = Stage::published;
  if (temporary_.empty()) return;
  std::error_code ec;
  std::filesystem::rename(temporary_, resolved_, ec);
  if (ec) {
    remove_temporary();
    throw FileError(fmt::format("cannot create '{}': {}", target_.string(), ec.message()));
  }
  release_temporary_file(slot_);
  temporary_.clear();
}

void AtomicFile::commit() {
  finish();
  publish();
}

}  // namespace nhdyn
