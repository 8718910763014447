#include "nhdyn/frontend/detail/derivation_cache.hpp"

#include <dlfcn.h>
#include <elf.h>
#include <fcntl.h>
#include <link.h>
#include <unistd.h>

#include <fmt/format.h>

#include <algorithm>
#include <atomic>
#include <cctype>
#include <chrono>
#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <optional>
#include <sstream>
#include <system_error>

#include "nhdyn/core/detail/cache_root.hpp"
#include "nhdyn/core/detail/hash.hpp"
#include "nhdyn/symbolic/derivation_archive.hpp"
#include "nhdyn/symbolic/description.hpp"

namespace nhdyn::detail {
namespace {

namespace fs = std::filesystem;

constexpr const char* kHeader = "nhdyn-derivation-cache 1";
// No derivation is near this (the 1000-body chain's is 1.7 MB); a larger file is not one.
constexpr std::uintmax_t kLargestFile = std::uintmax_t{256} << 20;

std::string env(const char* name) {
  const char* value = std::getenv(name);
  return value ? value : "";
}

std::optional<fs::path> cache_directory() {
  if (std::optional<fs::path> root = nhdyn_cache_root()) return *root / "derivations";
  return std::nullopt;
}

void trim(const fs::path& dir);

// The file's whole content: the header, the key's length and the key, then the archive.
class FileStore final : public symbolic::DerivationStore {
 public:
  FileStore(fs::path file, std::string key, bool always)
      : file_(std::move(file)), key_(std::move(key)), always_(always) {}

  // A derivation that took at least 1 ms per coordinate, at its second load: a model with rolling
  // contacts or a long chain of frames (the bicycle, 11 ms per coordinate; the rattleback, 2.5)
  // reads back in a fraction of that, while a large model of simple bodies (the 1000-body chain,
  // 0.1 ms per coordinate) derives about as fast as its archive is read. Writing the archive costs
  // a load too (the bicycle's, a seventh), so the first load of a model leaves
  // only a mark (an empty NAME.seen) and the second one writes: a model loaded once pays nothing,
  // one loaded again reads its derivation from the third load on.
  bool wants(double seconds, int coordinates) const override {
    if (always_) return true;
    if (seconds < 1e-3 * std::max(coordinates, 1)) return false;
    std::error_code error;
    if (fs::is_regular_file(mark(), error)) return true;
    fs::create_directories(file_.parent_path(), error);
    // Made only where nothing is: O_EXCL with O_NOFOLLOW opens no named pipe (which would wait
    // for a reader), no device and no link's target.
    if (!error) {
      const int fd = ::open(mark().c_str(), O_WRONLY | O_CREAT | O_EXCL | O_NOFOLLOW | O_CLOEXEC, 0644);
      if (fd >= 0) ::close(fd);
    }
    return false;
  }

  std::optional<std::string> read() const override {
    // A regular file (after links) of a sane size, nothing else: opening a named pipe waits for a
    // writer, and /dev/zero has no end to read to.
    std::error_code error;
    if (!fs::is_regular_file(file_, error) || fs::file_size(file_, error) > kLargestFile || error) return std::nullopt;
    std::ifstream in(file_, std::ios::binary);
    if (!in) return std::nullopt;
    const std::string header = std::string(kHeader) + "\n" + std::to_string(key_.size()) + "\n" + key_;
    std::string head(header.size(), '\0');
    if (!in.read(head.data(), static_cast<std::streamsize>(head.size())) || head != header) return std::nullopt;
    std::string bytes{std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
    fs::last_write_time(file_, fs::file_time_type::clock::now(), error);  // used: the last to go
    return bytes;
  }

  void write(const std::string& bytes) const override {
    static std::atomic<unsigned> counter{0};
    std::error_code error;
    fs::create_directories(file_.parent_path(), error);
    if (error) return;
    const fs::path temporary =
        file_.parent_path() / fmt::format(".{}.{}-{}.tmp", file_.filename().string(), ::getpid(), counter++);
    {
      std::ofstream out(temporary, std::ios::binary | std::ios::trunc);
      out << kHeader << '\n' << key_.size() << '\n' << key_ << bytes;
      out.flush();
      if (!out) {
        fs::remove(temporary, error);
        return;
      }
    }
    fs::rename(temporary, file_, error);
    if (error) fs::remove(temporary, error);
    fs::remove(mark(), error);
    trim(file_.parent_path());
  }

 private:
  fs::path mark() const {
    fs::path seen = file_;
    return seen.replace_extension(".seen");
  }

  fs::path file_;
  std::string key_;
  bool always_;
};

// At most kMostFiles derivations and marks (NAME.seen): beyond, the least recently used go (a
// shell loop over --set values makes one file per value).
constexpr std::size_t kMostFiles = 200;

// Also removes the temporary files of writers that died before their rename (SIGKILL, a crash),
// once they are an hour old: no live writer takes that long.
void trim(const fs::path& dir) {
  std::error_code error;
  std::vector<std::pair<fs::file_time_type, fs::path>> files;
  const fs::file_time_type stale = fs::file_time_type::clock::now() - std::chrono::hours(1);
  for (fs::directory_iterator it(dir, error), end; !error && it != end; it.increment(error)) {
    const std::string name = it->path().filename().string();
    std::error_code ignored;
    const fs::file_time_type time = fs::last_write_time(it->path(), ignored);
    if (ignored) continue;
    if (it->path().extension() == ".derivation" || it->path().extension() == ".seen")
      files.emplace_back(time, it->path());
    else if (name.starts_with(".") && name.ends_with(".tmp") && time < stale)
      fs::remove(it->path(), ignored);
  }
  if (files.size() <= kMostFiles) return;
  std::sort(files.begin(), files.end());
  for (std::size_t i = 0; i < files.size() - kMostFiles * 3 / 4; ++i) fs::remove(files[i].second, error);
}

// dl_iterate_phdr's walk: the object whose loaded segments hold `address`, and its build-id note.
struct BuildIdSearch {
  std::uintptr_t address = 0;
  std::string id;
};

int find_build_id(dl_phdr_info* info, std::size_t, void* data) {
  auto* search = static_cast<BuildIdSearch*>(data);
  bool holds = false;
  for (int i = 0; i < info->dlpi_phnum && !holds; ++i) {
    const ElfW(Phdr)& p = info->dlpi_phdr[i];
    const std::uintptr_t start = info->dlpi_addr + p.p_vaddr;
    holds = p.p_type == PT_LOAD && search->address >= start && search->address < start + p.p_memsz;
  }
  if (!holds) return 0;
  for (int i = 0; i < info->dlpi_phnum; ++i) {
    const ElfW(Phdr)& p = info->dlpi_phdr[i];
    if (p.p_type != PT_NOTE) continue;
    const auto* at = reinterpret_cast<const unsigned char*>(info->dlpi_addr + p.p_vaddr);
    const unsigned char* end = at + p.p_memsz;
    while (at + sizeof(ElfW(Nhdr)) <= end) {
      ElfW(Nhdr) note;
      std::memcpy(&note, at, sizeof note);
      const unsigned char* name = at + sizeof note;
      const unsigned char* desc = name + ((note.n_namesz + 3) & ~3U);
      if (desc + note.n_descsz > end) break;
      if (note.n_type == NT_GNU_BUILD_ID && note.n_namesz == 4 && std::memcmp(name, "GNU", 4) == 0) {
        for (unsigned k = 0; k < note.n_descsz; ++k) search->id += fmt::format("{:02x}", desc[k]);
        return 1;
      }
      at = desc + ((note.n_descsz + 3) & ~3U);
    }
  }
  return 1;  // the object, without a build-id
}

}  // namespace

std::string build_identity() {
  static const std::string id = [] {
    BuildIdSearch search;
    search.address = reinterpret_cast<std::uintptr_t>(&find_build_id);
    dl_iterate_phdr(find_build_id, &search);
    return search.id;
  }();
  return id;
}

std::shared_ptr<const symbolic::DerivationStore> make_derivation_store(const std::string& text,
                                                                       const std::vector<std::string>& sets) {
  std::string setting = env("NHDYN_DERIVATION_CACHE");
  for (char& c : setting) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  if (setting == "off" || setting == "0" || setting == "false" || setting == "no") return nullptr;
  const std::string id = build_identity();
  const std::optional<fs::path> dir = cache_directory();
  if (id.empty() || !dir) return nullptr;
  // The build, and the libraries that derive (GiNaC and CLN are shared: an upgrade of them is
  // another derivation).
  std::string key = "build " + id + "\nengine " + symbolic::derivation_engine() + "\n";
  for (const std::string& set : sets) key += "set " + set + "\n";
  key += "text\n" + text;
  const std::string name = fmt::format("{:016x}{:016x}.derivation", fnv1a(key, kFnvOffset),
                                       fnv1a(key, kFnvOtherOffset));
  return std::make_shared<FileStore>(*dir / name, std::move(key), setting == "always");
}

}  // namespace nhdyn::detail
