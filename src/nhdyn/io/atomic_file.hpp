// A file written whole or not at all, and the rules every output of nhdyn follows so that it
// never destroys what is not its own (docs/cli.md, "Output files"):
// - output goes to a temporary file beside the target, renamed onto it by commit(); destroyed
//   uncommitted (or the process interrupted: remove_temporary_files), the temporary is removed;
// - commit() is two steps, finish() and publish(), for the writers of several files: finish()
//   does all that can fail for want of space (flushing and closing the temporary), publish() only
//   the rename, which within one directory fails only when the directory itself was changed
//   meanwhile. Finishing every file before publishing any makes a group of files appear together
//   or not at all when one of them cannot be written (apps/nhdyn/run_files.hpp);
// - a symbolic link is written through to its target; a character device, pipe or socket is
//   written straight (no temporary, no rename): /dev/stdout and a FIFO work as outputs;
// - an existing file keeps its permission bits (its other hard links keep the old content: the
//   name is given a new file);
// - a file registered with protect_input (the model file of the run) is never an output.
// Opening checks up front that the target can be written, so a run is refused before it
// computes anything.
#pragma once

#include <cstdio>
#include <filesystem>
#include <string>
#include <string_view>

namespace nhdyn {

class AtomicFile {
 public:
  // Creates the temporary file next to `target` (or, for a device or pipe, opens it). Throws
  // FileError naming the path and the reason (missing directory, no permission, target is a
  // directory, target is a protected input).
  explicit AtomicFile(const std::filesystem::path& target);
  ~AtomicFile();
  AtomicFile(const AtomicFile&) = delete;
  AtomicFile& operator=(const AtomicFile&) = delete;

  void write(std::string_view bytes);
  // The bytes written so far, read back from the temporary (flushed first): what a run that failed
  // leaves of its table in a file of its own (FILE.partial.csv) without keeping a copy in memory.
  // Empty for a device or pipe written straight, and after finish().
  std::string written() const;
  // The first step of commit: flushes and closes the temporary (or the device or pipe written
  // straight). Throws FileError, the temporary removed, if a write, the flush or the close failed
  // (disk full, file too large): nothing of this file appears. The target is not touched yet.
  // Not synced to the disk (no fsync): a local file system reports a lack of space at the write,
  // and a run's outputs are recomputed rather than recovered after a power loss.
  void finish();
  // The second step: renames the finished temporary onto the target (nothing for a device or
  // pipe). Throws FileError if the rename fails (the directory changed since the temporary was
  // made in it), the temporary then removed. Call after finish().
  void publish();
  // finish() then publish(): the file appears whole, or FileError.
  void commit();

  const std::filesystem::path& target() const { return target_; }
  // Whether the target is a device or pipe written straight (no temporary file).
  bool straight() const { return temporary_.empty(); }

 private:
  enum class Stage { writing, finished, published };
  std::filesystem::path target_;     // as the user named it (messages)
  std::filesystem::path resolved_;   // symbolic links followed: the file that is replaced
  std::filesystem::path temporary_;  // empty when writing straight to a device or pipe
  std::FILE* file_ = nullptr;
  int slot_ = -1;  // in the table of temporaries removed on interruption
  Stage stage_ = Stage::writing;
  bool failed_ = false;  // a write failed; write_error_ is its errno
  int write_error_ = 0;
  void remove_temporary();
};

// Registers `input` (a file the run reads) so that no AtomicFile, CSV or plot may replace it,
// whatever name reaches it (the same file through a link is recognized by device and inode).
// A path that does not exist is ignored. For the CLI, which knows its inputs.
void protect_input(const std::filesystem::path& input);
// Throws FileError when `output` (links followed) is a protected input, naming both.
// `named`, when given, is the name the user gave (a link to `output`), for the message.
void require_not_input(const std::filesystem::path& output, const std::filesystem::path& named = {});
// `path` with its symbolic links followed (up to 40), the way open() would; a dangling link
// gives the path it points to. Throws FileError on a loop.
std::filesystem::path resolve_links(const std::filesystem::path& path);

// Temporary files under way, removed by remove_temporary_files(). register_temporary_file
// returns a slot (-1 when the table is full: the file is then only removed by its owner).
int register_temporary_file(const std::filesystem::path& path);
void release_temporary_file(int slot);
// Unlinks every registered temporary file. Async-signal-safe: for a SIGINT/SIGTERM handler.
void remove_temporary_files() noexcept;

// A plain file name made from a model's `name` for a default output: letters, digits and
// `-_.+` (and non-ASCII bytes) kept, anything else (`/`, `\`, spaces, control characters)
// replaced by `_`, leading dots removed (no `..`, no hidden file), at most 120 bytes; empty
// gives `fallback`.
std::string make_file_name(std::string_view name, std::string_view fallback = "model");

}  // namespace nhdyn
