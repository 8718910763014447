#include "run_files.hpp"

#include <fmt/format.h>
#include <stdlib.h>

#include <algorithm>
#include <cerrno>
#include <cstring>
#include <system_error>
#include <utility>

#include "nhdyn/core/error.hpp"
#include "nhdyn/io/plot.hpp"
#include "nhdyn/io/run_paths.hpp"

namespace nhdyn::cli {
namespace {

namespace fs = std::filesystem;

// Creates the directory that holds `file` (and its parents), or says why it cannot; the folders
// it made, the deepest first, are appended to `made`.
void make_folder_of(const fs::path& file, const std::string& role, std::vector<fs::path>& made) {
  if (!file.has_parent_path()) return;
  std::error_code ec;
  std::vector<fs::path> missing;
  for (fs::path folder = file.parent_path(); !folder.empty() && !fs::exists(folder, ec); folder = folder.parent_path()) {
    missing.push_back(folder);
    if (folder == folder.parent_path()) break;
  }
  fs::create_directories(file.parent_path(), ec);
  if (!ec) made.insert(made.end(), missing.begin(), missing.end());
  std::error_code is_dir_ec;
  if (ec || !fs::is_directory(file.parent_path(), is_dir_ec))
    throw FileError(fmt::format("cannot create the directory '{}' for {} '{}' ({}); give another path",
                                file.parent_path().string(), role, file.string(),
                                ec ? ec.message() : std::string("not a directory")));
}

// gnuplot with a PNG terminal, and the plot not an input by any name (through a link too).
void require_plot_possible(const fs::path& plot) {
  require_not_input(resolve_links(plot), plot);
  if (!gnuplot_available())
    throw FileError("--plot needs gnuplot, which is not installed: install it (apt-get install gnuplot-nox) "
                    "or run without --plot");
}

}  // namespace

RunFiles::RunFiles(const std::string& model) {
  std::error_code ec;
  if (!model.empty() && fs::is_regular_file(model, ec)) {
    protect_input(model);
    inputs_.emplace_back(model, "the model file");
  }
}

RunFiles::~RunFiles() { discard(); }

void RunFiles::input(const fs::path& path, std::string role) {
  if (!path.empty()) inputs_.emplace_back(path, std::move(role));
}

void RunFiles::output(const fs::path& path, std::string role, Folder folder) {
  if (!path.empty()) listed_.push_back({path, std::move(role), Kind::output, folder});
}

void RunFiles::plot(const fs::path& path, std::string role, Folder folder) {
  if (!path.empty()) listed_.push_back({path, std::move(role), Kind::plot, folder});
}

void RunFiles::page(const fs::path& path, std::string role, Folder folder) {
  if (!path.empty()) listed_.push_back({path, std::move(role), Kind::page, folder});
}

void RunFiles::numbered_outputs(std::size_t count, std::function<fs::path(std::size_t)> name, std::string option) {
  numbered_ = Numbered{count, std::move(name), std::move(option)};
}

void RunFiles::check() {
  RunPaths paths;
  for (const auto& [path, role] : inputs_) paths.input(path, role);
  for (const Listed& out : listed_) paths.output(out.path, out.role);
  paths.check();
  // The numbered outputs against the inputs, by inode or, for a file not there yet, by path.
  if (numbered_)
    for (std::size_t i = 0; i < numbered_->count; ++i) {
      const fs::path out = numbered_->name(i);
      for (const auto& [input, role] : inputs_) {
        if (!fs::exists(input)) continue;
        std::error_code ec;
        if (fs::equivalent(input, out, ec) ||
            (!fs::exists(out) && fs::weakly_canonical(fs::absolute(input)) == fs::weakly_canonical(fs::absolute(out))))
          throw FileError(fmt::format("refusing to write '{}' ({}): it is '{}', an input of this run; give "
                                      "another output directory with -o",
                                      out.string(), numbered_->option, input.string()));
      }
    }
  for (const Listed& out : listed_)
    if (out.kind == Kind::plot) require_plot_possible(out.path);
  // A plot or a page is written by its own writer after the run: its directory is proved
  // writable now by a temporary file that is removed unused. Those in a folder nobody makes are
  // probed first, so that a refused run makes no folder (results/ included); those in a folder
  // made here (a study's plot beside its table in out/), once it is made.
  std::vector<fs::path> made;
  for (const Listed& out : listed_)
    if (out.folder == Folder::make) made.push_back(out.path.parent_path().lexically_normal());
  const auto in_made_folder = [&made](const Listed& out) {
    return out.folder == Folder::make ||
           std::find(made.begin(), made.end(), out.path.parent_path().lexically_normal()) != made.end();
  };
  for (const Listed& out : listed_)
    if (out.kind != Kind::output && !in_made_folder(out)) probes_.push_back(std::make_unique<AtomicFile>(out.path));
  for (const Listed& out : listed_)
    if (out.folder == Folder::make) make_folder_of(out.path, out.role, made_folders_);
  for (const Listed& out : listed_)
    if (out.kind != Kind::output && in_made_folder(out)) probes_.push_back(std::make_unique<AtomicFile>(out.path));
}

AtomicFile& RunFiles::open(const fs::path& path) {
  AtomicFile& file = files_.emplace_back(path);
  opened_.push_back({[&file] { file.finish(); }, [&file] { file.publish(); }});
  return file;
}

CsvWriter& RunFiles::open_csv(const fs::path& path, const std::vector<std::string>& columns,
                              const std::string& preamble) {
  CsvWriter& table = tables_.emplace_back(path, columns, preamble);
  opened_.push_back({[&table] { table.finish(); }, [&table] { table.publish(); }});
  return table;
}

const fs::path& RunFiles::staging_folder(const fs::path& dir, const std::string& option) {
  std::string pattern = (dir / ".nhdyn-batch-XXXXXX").string();
  if (::mkdtemp(pattern.data()) == nullptr)
    throw FileError(fmt::format("{} {}: cannot create a working directory there ({}); check its permissions", option,
                                dir.string(), std::strerror(errno)));
  staging_ = pattern;
  staging_target_ = dir;
  return staging_;
}

void RunFiles::write_now(const fs::path& path, const std::string& text) {
  AtomicFile file(path);
  file.write(text);
  file.commit();
}

fs::path RunFiles::write_scratch(const std::string& name, const std::string& text) {
  const fs::path path = fs::temp_directory_path() / name;
  scratch_.emplace_back(path, register_temporary_file(path));  // first: a signal while writing removes it too
  write_now(path, text);
  return path;
}

void RunFiles::commit() {
  // Everything that can fail for want of space first, for every file; the renames only then.
  for (const Opened& file : opened_) file.finish();
  if (!staging_.empty()) {
    std::error_code ec;
    for (const auto& entry : fs::directory_iterator(staging_)) {
      fs::rename(entry.path(), staging_target_ / entry.path().filename(), ec);
      if (ec)
        throw FileError(fmt::format("cannot move {} into {}: {}", entry.path().string(), staging_target_.string(),
                                    ec.message()));
    }
  }
  for (const Opened& file : opened_) file.publish();
  opened_.clear();
  probes_.clear();
  made_folders_.clear();  // the run's now
}

void RunFiles::discard() {
  opened_.clear();
  probes_.clear();
  tables_.clear();
  files_.clear();
  if (!staging_.empty()) {
    std::error_code ec;
    fs::remove_all(staging_, ec);
    staging_.clear();
  }
  for (const auto& [path, slot] : scratch_) {
    std::error_code ec;
    fs::remove(path, ec);
    release_temporary_file(slot);
  }
  scratch_.clear();
  // The folders check() made for a run that ends without its files, while they are empty (a
  // failed run's FILE.partial.csv keeps its folder).
  for (const fs::path& folder : made_folders_) {
    std::error_code ec;
    if (fs::is_empty(folder, ec) && !ec) fs::remove(folder, ec);
  }
  made_folders_.clear();
}

void check_plot_columns(const std::string& plot, const std::vector<std::string>& columns,
                        const std::vector<std::string>& chosen) {
  if (chosen.empty()) return;
  if (plot.empty())
    throw InputError("--plot-columns chooses what --plot draws; give --plot FILE.png too, or leave --plot-columns out");
  require_plot_columns(columns, chosen);
}

}  // namespace nhdyn::cli
