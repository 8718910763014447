// The one rule every command follows for its files (docs/cli.md, "Output files"): before any work
// starts, a command lists every path it will read and every path it will write, and is refused
// when an output is one of its inputs or two outputs are one file — by name (`./a.csv`, `a.csv`),
// through a symbolic link, or through a hard link (same device and inode). So no output replaces
// an input (the model, a result CSV read by `report`, the --runs table of `batch`) and no output
// of one run replaces another (--html and --plot on one path, a plot onto the events file).
// Devices and pipes (/dev/null, /dev/stdout, a FIFO) are outputs that may be shared.
#pragma once

#include <filesystem>
#include <string>
#include <vector>

namespace nhdyn {

class RunPaths {
 public:
  // A file the command reads; `role` names it in messages ("the model file", "--runs").
  // Also registered with protect_input (io/atomic_file.hpp). A path that does not exist is kept
  // for the comparison by name.
  void input(const std::filesystem::path& path, std::string role);
  // A file the command writes; `role` names it ("-o", "--html", "the events file").
  void output(const std::filesystem::path& path, std::string role);
  // Throws FileError naming both roles and paths when two entries are one file and at least one
  // of them is an output. Call after listing every path, before any work.
  void check() const;

 private:
  struct Entry {
    std::filesystem::path path;
    std::string role;
    bool output = false;
  };
  std::vector<Entry> entries_;
};

}  // namespace nhdyn
