// The files of one run of a command, owned in one place: the CSV tables, their companions
// (-events.csv, .partial.csv, -series.csv, -by-tolerance.csv, -crossings.csv, batch's summary and
// run files), the plots and the HTML report. Every command that writes files follows the same
// three steps (docs/cli.md, "Output files" and "One rule for the files of a command"):
//
//   1. list: the model file (and any other input) and every output, each with the name the user
//      knows it by ("-o", "--plot", "the series CSV");
//   2. check(), before any work: no output is an input and no two outputs are one file (by name,
//      link or inode: io/run_paths.hpp), the directories the command makes are made, gnuplot is
//      there when a plot is asked for, and the directory of each plot and report is proved
//      writable; then open() the tables, which writes them to temporaries beside their targets;
//   3. commit() after a run that succeeded: every opened file finished first (flushed and closed:
//      whatever can fail for want of space), then, only when all are, renamed into place in the
//      order opened (batch's staged run files first), so that a disk full at the last file leaves
//      none of them behind, not the first ones alone. A RunFiles destroyed (or discard()ed) without
//      commit removes its temporaries and staging folder, so a refused, failed or interrupted run
//      leaves nothing behind, not even the folders check() made for it while they are empty (the
//      SIGINT/SIGTERM handler of output_guard.hpp removes the
//      temporaries of a process that is killed mid-run).
//
// The library's pieces (AtomicFile, CsvWriter, RunPaths) stay in io/; this is the command line's
// policy over them (option names in messages, which directories a command may create). The
// Python package writes no run's files of its own, so it has no use for it.
#pragma once

#include <cstddef>
#include <deque>
#include <filesystem>
#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "nhdyn/io/atomic_file.hpp"
#include "nhdyn/io/csv.hpp"

namespace nhdyn::cli {

// Whether the directory that holds an output must already exist or is created by check().
// `nhdyn simulate` and `compare` create only their default folder results/ (docs/cli.md: "the
// directory of a path you give must already exist"); the studies, sweep, linearize, optimize and
// batch create the folders of the paths they are given (the studies' docs write into results/).
enum class Folder { must_exist, make };

class RunFiles {
 public:
  // `model`: the MODEL argument. When it names a file, that file is an input of the run: no output
  // may replace it, by whatever name (protect_input, io/atomic_file.hpp). Call before opening any
  // output: constructing is the first thing a command that writes files does.
  explicit RunFiles(const std::string& model);
  ~RunFiles();
  RunFiles(const RunFiles&) = delete;
  RunFiles& operator=(const RunFiles&) = delete;

  // Another file the run reads (`role` names it in messages: "--runs", "the result CSV").
  // An empty path is skipped.
  void input(const std::filesystem::path& path, std::string role);
  // A file the run writes, opened later with open() / open_csv() or written whole by write_now().
  // An empty path is skipped.
  void output(const std::filesystem::path& path, std::string role, Folder folder = Folder::must_exist);
  // A PNG drawn by gnuplot after commit(): check() requires gnuplot and proves its directory
  // writable. An empty path is skipped.
  void plot(const std::filesystem::path& path, std::string role = "--plot", Folder folder = Folder::must_exist);
  // A page or other file written whole by its own writer after commit() (--html, report's -o):
  // check() proves its directory writable. An empty path is skipped.
  void page(const std::filesystem::path& path, std::string role, Folder folder = Folder::must_exist);
  // Outputs too many to list one by one (batch's run_N.csv): name(i) for i < count, each refused
  // when it is an input of the run (they differ from one another and from the listed outputs by
  // their names, inside a folder of their own).
  void numbered_outputs(std::size_t count, std::function<std::filesystem::path(std::size_t)> name,
                        std::string option);

  // Everything listed checked together, before any work: throws FileError (naming both files,
  // with their roles) when an output is an input or two outputs are one file, FileError when a
  // folder cannot be made, gnuplot is missing for a plot, or a plot's or page's directory cannot
  // be written.
  void check();

  // An output listed earlier, written to a temporary beside its target from now on (FileError,
  // naming the path, when it cannot be); renamed into place by commit().
  AtomicFile& open(const std::filesystem::path& path);
  CsvWriter& open_csv(const std::filesystem::path& path, const std::vector<std::string>& columns,
                      const std::string& preamble);
  // A folder inside `dir` where files are written during the run (batch's run files), moved into
  // `dir` by commit(), removed whole otherwise. `option` names `dir` in the message when the
  // folder cannot be made.
  const std::filesystem::path& staging_folder(const std::filesystem::path& dir, const std::string& option);
  // Writes `text` to `path` (a listed output) whole and at once, whatever happens to the rest:
  // the .partial.csv of a failed run.
  void write_now(const std::filesystem::path& path, const std::string& text);
  // A file of the run's own, not an output (the data sweep's plot is drawn from): `text` written
  // to `name` in the temporary directory, removed when the RunFiles goes and by the handler of an
  // interrupted run. Returns its path.
  std::filesystem::path write_scratch(const std::string& name, const std::string& text);

  // The run succeeded: every opened file finished (FileError, and no file renamed, when one of
  // them cannot be written whole), then the staged files moved into their folder and every opened
  // file renamed into place in the order opened; the plots' and pages' probes are released so
  // that their writers can write them.
  void commit();
  // The run is abandoned now (a signal that will end the process with _exit, which runs no
  // destructor): every temporary and the staging folder removed.
  void discard();

 private:
  enum class Kind { output, plot, page };
  struct Listed {
    std::filesystem::path path;
    std::string role;
    Kind kind = Kind::output;
    Folder folder = Folder::must_exist;
  };
  std::vector<Listed> listed_;
  std::vector<std::pair<std::filesystem::path, std::string>> inputs_;
  struct Numbered {
    std::size_t count = 0;
    std::function<std::filesystem::path(std::size_t)> name;
    std::string option;
  };
  std::optional<Numbered> numbered_;
  std::deque<AtomicFile> files_;        // deque: references stay valid as files are added
  std::deque<CsvWriter> tables_;
  struct Opened {
    std::function<void()> finish, publish;
  };
  std::vector<Opened> opened_;  // in the order opened
  std::vector<std::unique_ptr<AtomicFile>> probes_;
  std::filesystem::path staging_, staging_target_;
  std::vector<std::filesystem::path> made_folders_;  // by check(), the deepest first; kept by commit()
  std::vector<std::pair<std::filesystem::path, int>> scratch_;  // path, slot in the table of temporaries
};

// --plot-columns: refused without --plot (InputError saying to give both), and each name checked
// against the columns the plot can draw (require_plot_columns, io/plot.hpp). Nothing when not given.
void check_plot_columns(const std::string& plot, const std::vector<std::string>& columns,
                        const std::vector<std::string>& chosen);

}  // namespace nhdyn::cli
