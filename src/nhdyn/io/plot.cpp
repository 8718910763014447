// write_plot: reads the CSV header (and first data row), writes a gnuplot script next to the
// target PNG, runs gnuplot on it through posix_spawnp (no shell) with stderr captured, and
// renames gnuplot's output onto the target only when gnuplot succeeded.
#include "nhdyn/io/plot.hpp"
#include "nhdyn/io/xy_plot.hpp"

#include <fcntl.h>
#include <fmt/format.h>
#include <signal.h>
#include <spawn.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <charconv>
#include <cmath>
#include <cstdint>
#include <fstream>
#include <functional>
#include <iterator>
#include <random>
#include <string_view>
#include <system_error>

#include "nhdyn/core/error.hpp"
#include "nhdyn/io/atomic_file.hpp"

extern char** environ;

namespace nhdyn {
namespace {

namespace fs = std::filesystem;

// A time-series panel is ~550 px wide; 50 000 points per curve is ~90 per pixel column, enough
// for any curve that the picture can resolve, and keeps gnuplot well under 1 s per curve.
constexpr std::uintmax_t max_rows_per_curve = 50000;
// Tail of gnuplot's stderr quoted in an error message (its error comes last, after warnings).
constexpr std::size_t max_quoted_stderr = 4000;

constexpr std::string_view install_hint =
    "install gnuplot, e.g. `apt-get install gnuplot-nox`, or run without --plot";

std::string errno_text(int err) { return std::error_code(err, std::generic_category()).message(); }

// ---------------------------------------------------------------------------------------------
// Quoting for gnuplot.

// A label (title, legend entry) on one line: control characters become spaces.
std::string one_line(std::string_view text) {
  std::string out(text);
  for (char& c : out) {
    const auto byte = static_cast<unsigned char>(c);
    if (byte < 0x20 || byte == 0x7f) c = ' ';
  }
  return out;
}

// A gnuplot string expression whose value is exactly `text` (for file names and labels).
// Single-quoted gnuplot strings take every byte literally: no backslash escapes, no `backquote`
// command substitution, no @macro expansion. The quote itself is joined in as a double-quoted
// "'" ('it'."'".'s'): gnuplot's doubled quote ('it''s') works for one quote but not for two in a
// row (q''). A control character, which cannot sit inside a single-quoted string on one script
// line, is joined in as a double-quoted octal escape ('a'."\012".'b').
std::string gp_string(std::string_view text) {
  std::string out = "'";
  for (char c : text) {
    const auto byte = static_cast<unsigned char>(c);
    if (c == '\'') {
      out += "'.\"'\".'";
    } else if (byte < 0x20 || byte == 0x7f) {
      out += fmt::format("'.\"\\{:03o}\".'", static_cast<unsigned>(byte));
    } else {
      out += c;
    }
  }
  out += '\'';
  return out;
}

// A label as a gnuplot string literal.
std::string gp_label(std::string_view text) { return gp_string(one_line(text)); }

// ---------------------------------------------------------------------------------------------
// The CSV: header names, the first data row, and the number of data rows (for thinning).

struct CsvHead {
  std::vector<std::string> names;      // header row, in column order (column 1 = time)
  std::vector<std::string> first_row;  // fields of the first data row
  std::uintmax_t rows = 0;             // estimated number of data rows
  int header_lines = 1;                // lines taken by the header (a quoted name may hold \n)
};

std::string trim(std::string_view s) {
  const auto blank = [](char c) { return c == ' ' || c == '\t' || c == '\r' || c == '\n'; };
  while (!s.empty() && blank(s.front())) s.remove_prefix(1);
  while (!s.empty() && blank(s.back())) s.remove_suffix(1);
  return std::string(s);
}

// Splits a CSV record on commas, as CsvWriter quotes it: a field in double quotes may hold
// commas, newlines and doubled quotes ("" -> "). Carriage returns outside quotes are dropped.
std::vector<std::string> split_csv_record(std::string_view record) {
  std::vector<std::string> fields;
  std::string field;
  bool quoted = false;
  for (std::size_t i = 0; i < record.size(); ++i) {
    const char c = record[i];
    if (quoted) {
      if (c == '"' && i + 1 < record.size() && record[i + 1] == '"') {
        field += record[++i];
      } else if (c == '"') {
        quoted = false;
      } else {
        field += c;
      }
    } else if (c == '"') {
      quoted = true;
    } else if (c == ',') {
      fields.push_back(std::move(field));
      field.clear();
    } else if (c != '\r') {
      field += c;
    }
  }
  fields.push_back(std::move(field));
  return fields;
}

// Reads one CSV record: a line, continued over newlines that sit inside double quotes.
bool read_csv_record(std::istream& in, std::string& record) {
  if (!std::getline(in, record)) return false;
  std::string more;
  while (std::count(record.begin(), record.end(), '"') % 2 == 1 && std::getline(in, more)) {
    record += '\n';
    record += more;
  }
  return true;
}

// Number of data rows after byte `data_start` of a file of `size` bytes: counted in a small
// file, estimated in a large one from the mean length of the rows in three 64 KiB windows (at
// 1/4, 1/2 and 3/4 of the rows), as reading a million rows only to count them would cost
// more than the thinning saves. Not from the first rows alone: they are short ("0,1,0,...")
// and would overestimate the count tenfold.
std::uintmax_t count_rows(std::istream& in, std::uintmax_t data_start, std::uintmax_t size) {
  constexpr std::uintmax_t window = 1 << 16;
  std::vector<char> buffer(window);
  const auto newlines_in = [&](std::uintmax_t from, std::uintmax_t length) {
    in.clear();
    in.seekg(static_cast<std::streamoff>(from));
    std::uintmax_t newlines = 0;
    while (length > 0 && in) {
      in.read(buffer.data(), static_cast<std::streamsize>(std::min(length, window)));
      const auto got = static_cast<std::uintmax_t>(in.gcount());
      if (got == 0) break;
      newlines += static_cast<std::uintmax_t>(
          std::count(buffer.begin(), buffer.begin() + static_cast<std::ptrdiff_t>(got), '\n'));
      length -= got;
    }
    return newlines;
  };
  if (size <= data_start) return 1;
  const std::uintmax_t body = size - data_start;
  if (body <= 4 * window) return std::max<std::uintmax_t>(1, newlines_in(data_start, body));
  std::uintmax_t sampled = 0;
  for (std::uintmax_t quarter = 1; quarter <= 3; ++quarter) {
    sampled += newlines_in(data_start + body / 4 * quarter, window);
  }
  return std::max<std::uintmax_t>(1, body / (3 * window) * sampled);
}

CsvHead read_csv_head(const fs::path& csv) {
  errno = 0;
  std::ifstream in(csv, std::ios::binary);
  if (!in) {
    const int err = errno;
    throw FileError(fmt::format("cannot read the CSV file '{}' to plot ({}); check the path",
                                csv.string(), err != 0 ? errno_text(err) : "open failed"));
  }
  std::string header;
  std::string row;
  if (!read_csv_record(in, header) || trim(header).empty()) {
    throw InputError(fmt::format(
        "the CSV file '{}' has no header row; expected column names on its first line, as "
        "nhdyn writes them",
        csv.string()));
  }
  const std::streamoff data_start = in.tellg();
  if (!read_csv_record(in, row) || trim(row).empty()) {
    throw InputError(fmt::format(
        "the CSV file '{}' has a header but no data rows; there is nothing to plot (did the "
        "run stop before its first output?)",
        csv.string()));
  }
  if (header.starts_with("\xEF\xBB\xBF")) header.erase(0, 3);  // UTF-8 byte order mark

  CsvHead head;
  head.header_lines = 1 + static_cast<int>(std::count(header.begin(), header.end(), '\n'));
  head.names = split_csv_record(header);
  head.first_row = split_csv_record(row);
  for (std::string& field : head.first_row) field = trim(field);
  std::error_code ec;
  const std::uintmax_t size = fs::file_size(csv, ec);
  head.rows =
      ec || data_start < 0 ? 1 : count_rows(in, static_cast<std::uintmax_t>(data_start), size);
  return head;
}

// 1-based gnuplot column index of `name`; `role` says which list of the request named it.
int column_of(const CsvHead& head, const fs::path& csv, const std::string& name,
              std::string_view role) {
  for (std::size_t i = 0; i < head.names.size(); ++i) {
    if (head.names[i] == name) return static_cast<int>(i) + 1;
  }
  constexpr std::size_t shown = 40;
  std::string known;
  for (std::size_t i = 0; i < head.names.size() && i < shown; ++i) {
    known += (i == 0 ? "" : ", ") + head.names[i];
  }
  if (head.names.size() > shown) known += fmt::format(", ... ({} in all)", head.names.size());
  throw InputError(fmt::format(
      "cannot plot {} column '{}': the CSV file '{}' has no column of that name; its columns "
      "are {}; use one of these names",
      role, name, csv.string(), known));
}

// ---------------------------------------------------------------------------------------------
// Files and processes.

// Closes a file descriptor when it goes out of scope.
class UniqueFd {
 public:
  explicit UniqueFd(int fd = -1) : fd_(fd) {}
  UniqueFd(const UniqueFd&) = delete;
  UniqueFd& operator=(const UniqueFd&) = delete;
  ~UniqueFd() { reset(); }
  int get() const { return fd_; }
  void reset(int fd = -1) {
    if (fd_ >= 0) ::close(fd_);
    fd_ = fd;
  }

 private:
  int fd_;
};

// A new file, created exclusively under a fresh random name ".<base>.<random><suffix>" in
// `dir`, and removed when this object goes away unless keep() was called. Created with mode
// 0666 so that the umask, not this code, decides who may read the final picture.
class TempFile {
 public:
  TempFile(const fs::path& dir, const std::string& base, std::string_view suffix) {
    thread_local std::mt19937_64 random{std::random_device{}()};
    for (int attempt = 0; attempt < 100; ++attempt) {
      const fs::path candidate =
          dir / fmt::format(".{}.{:016x}{}", base, static_cast<std::uint64_t>(random()), suffix);
      const int fd = ::open(candidate.c_str(), O_WRONLY | O_CREAT | O_EXCL | O_CLOEXEC, 0666);
      if (fd >= 0) {
        fd_.reset(fd);
        path_ = candidate;
        slot_ = register_temporary_file(path_);  // removed if the run is interrupted
        return;
      }
      const int err = errno;
      if (err != EEXIST) {
        throw FileError(fmt::format(
            "cannot write the plot into the directory '{}' ({}); create it, make it writable, "
            "or choose another path for the plot",
            dir.string(), errno_text(err)));
      }
    }
    throw FileError(fmt::format(
        "cannot create a temporary file in '{}' (100 names taken); remove stale '.{}.*' files",
        dir.string(), base));
  }
  TempFile(const TempFile&) = delete;
  TempFile& operator=(const TempFile&) = delete;
  ~TempFile() {
    fd_.reset();
    if (!path_.empty()) {
      std::error_code ignored;
      fs::remove(path_, ignored);
    }
    release_temporary_file(slot_);
  }
  const fs::path& path() const { return path_; }
  int fd() const { return fd_.get(); }
  void close() { fd_.reset(); }
  void keep() { path_.clear(); }

 private:
  UniqueFd fd_;
  fs::path path_;
  int slot_ = -1;
};

void write_all(int fd, std::string_view text, const fs::path& path) {
  while (!text.empty()) {
    const ssize_t n = ::write(fd, text.data(), text.size());
    if (n < 0) {
      const int err = errno;
      if (err == EINTR) continue;
      throw FileError(
          fmt::format("cannot write the gnuplot script '{}' ({}); free some space "
                      "or choose another directory for the plot",
                      path.string(), errno_text(err)));
    }
    text.remove_prefix(static_cast<std::size_t>(n));
  }
}

struct GnuplotRun {
  bool exited = false;  // exited normally (else killed by signal `code`)
  int code = 0;         // exit status, or the signal number
  std::string stderr_text;
};

// Runs `gnuplot args...` found on PATH, without a shell: stdin and stdout on /dev/null, stderr
// captured. Throws FileError with the install hint if there is no gnuplot.
GnuplotRun run_gnuplot(const std::vector<std::string>& args) {
  int pipe_fds[2];
  if (::pipe2(pipe_fds, O_CLOEXEC) != 0) {
    throw FileError(
        fmt::format("cannot start gnuplot: no pipe for its messages ({})", errno_text(errno)));
  }
  UniqueFd read_end(pipe_fds[0]);
  UniqueFd write_end(pipe_fds[1]);

  posix_spawn_file_actions_t actions;
  posix_spawn_file_actions_init(&actions);
  posix_spawn_file_actions_addopen(&actions, 0, "/dev/null", O_RDONLY, 0);
  posix_spawn_file_actions_addopen(&actions, 1, "/dev/null", O_WRONLY, 0);
  posix_spawn_file_actions_adddup2(&actions, write_end.get(), 2);
  // The child starts with no blocked signals and SIGPIPE at its default, whatever the caller
  // did to its own.
  posix_spawnattr_t attributes;
  posix_spawnattr_init(&attributes);
  sigset_t signals;
  sigemptyset(&signals);
  posix_spawnattr_setsigmask(&attributes, &signals);
  sigaddset(&signals, SIGPIPE);
  posix_spawnattr_setsigdefault(&attributes, &signals);
  posix_spawnattr_setflags(&attributes, POSIX_SPAWN_SETSIGMASK | POSIX_SPAWN_SETSIGDEF);

  std::vector<std::string> argv_storage{"gnuplot"};
  argv_storage.insert(argv_storage.end(), args.begin(), args.end());
  std::vector<char*> argv;
  for (std::string& arg : argv_storage) argv.push_back(arg.data());
  argv.push_back(nullptr);

  pid_t pid = 0;
  const int spawn_error =
      posix_spawnp(&pid, "gnuplot", &actions, &attributes, argv.data(), environ);
  posix_spawn_file_actions_destroy(&actions);
  posix_spawnattr_destroy(&attributes);
  write_end.reset();  // else the read below never sees end-of-file
  if (spawn_error == ENOENT) {
    throw FileError(fmt::format("cannot plot: gnuplot is not on PATH; {}", install_hint));
  }
  if (spawn_error != 0) {
    throw FileError(
        fmt::format("cannot start gnuplot ({}); check its installation, or run "
                    "without --plot",
                    errno_text(spawn_error)));
  }

  GnuplotRun run;
  char buffer[4096];
  while (true) {
    const ssize_t n = ::read(read_end.get(), buffer, sizeof buffer);
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) break;
    run.stderr_text.append(buffer, static_cast<std::size_t>(n));
    // Keep memory bounded if gnuplot warns on every row; only the tail is ever quoted.
    if (run.stderr_text.size() > (1u << 20)) run.stderr_text.erase(0, 1u << 19);
  }
  int status = 0;
  pid_t waited = 0;
  do {
    waited = ::waitpid(pid, &status, 0);
  } while (waited < 0 && errno == EINTR);
  if (waited < 0) {
    throw FileError(fmt::format("lost track of gnuplot (waitpid: {})", errno_text(errno)));
  }
  run.exited = WIFEXITED(status);
  run.code = run.exited ? WEXITSTATUS(status) : WTERMSIG(status);
  return run;
}

bool probe_gnuplot() {
  try {
    // -d: ignore the user's ~/.gnuplot. Exits 3 if this gnuplot has neither png terminal.
    const GnuplotRun run = run_gnuplot(
        {"-d", "-e", "if (strstrt(' '.GPVAL_TERMINALS.' ', ' png') == 0) { exit status 3 }"});
    return run.exited && run.code == 0;
  } catch (const FileError&) {
    return false;
  }
}

// ---------------------------------------------------------------------------------------------
// The script.

struct Column {
  int index;         // 1-based, as gnuplot counts
  std::string name;  // as in the header
};

// One curve: `rows` selects the rows (" skip 1 every 20"), `using_spec` the columns.
std::string plot_clause(std::string_view rows, std::string_view using_spec, std::string_view style,
                        std::string_view title) {
  return fmt::format("csv_file{} using {} with {} title {}", rows, using_spec, style,
                     gp_label(title));
}

std::string join_clauses(const std::vector<std::string>& clauses) {
  std::string out = "plot ";
  for (std::size_t i = 0; i < clauses.size(); ++i) {
    out += (i == 0 ? "" : ", \\\n     ") + clauses[i];
  }
  return out + "\n";
}

struct ScriptInput {
  std::string title;
  std::string time_name;
  fs::path csv;     // absolute
  fs::path output;  // absolute, the temporary file
  std::vector<Column> coordinates, reactions, residuals, actuators;
  std::optional<std::pair<Column, Column>> path;
  std::optional<Column> energy;
  double energy0 = 0.0;
  int header_lines = 1;       // lines before the first data row
  std::uintmax_t stride = 1;  // draw every stride-th row
};

std::string make_script(const ScriptInput& in) {
  const int panels =
      static_cast<int>(!in.coordinates.empty()) + static_cast<int>(!in.reactions.empty()) +
      static_cast<int>(!in.residuals.empty()) + static_cast<int>(in.path.has_value()) +
      static_cast<int>(in.energy.has_value()) + static_cast<int>(!in.actuators.empty());
  const int layout_columns = panels == 1 ? 1 : 2;
  const int layout_rows = (panels + layout_columns - 1) / layout_columns;
  // gnuplot skips the header lines; `every` also thins the rows, `all` takes them all.
  const std::string all = fmt::format(" skip {}", in.header_lines);
  const std::string every = in.stride > 1 ? fmt::format("{} every {}", all, in.stride) : all;
  const std::string thinned = in.stride > 1 ? fmt::format(" (1 row in {} drawn)", in.stride) : "";

  std::string s;
  s += "# Written by nhdyn (src/nhdyn/io/plot.cpp) for one plot; deleted after the run.\n";
  s += "set encoding utf8\n";
  s += "if (strstrt(' '.GPVAL_TERMINALS.' ', ' pngcairo ') > 0) {\n";
  s += "  set terminal pngcairo size 1200,900 font 'Sans,10' noenhanced\n";
  s += "} else {\n";
  s += "  set terminal png size 1200,900 noenhanced\n";
  s += "}\n";
  // Names such as residual_vel_blade or x' are drawn as written, not as enhanced-text markup.
  s += "set termoption noenhanced\n";
  // Absolute paths, so no file name can read as one of gnuplot's special files
  // ('-', '+', '<command', '~/...').
  s += fmt::format("csv_file = {}\n", gp_string(in.csv.string()));
  s += fmt::format("output_file = {}\n", gp_string(in.output.string()));
  s += "set output output_file\n";
  s += "set datafile separator comma\n";
  s += "set grid\n";
  s += "set key below horizontal height 1\n";  // a little air between x label and legend
  s += fmt::format("set multiplot layout {},{} title {} font ',13'\n", layout_rows, layout_columns,
                   gp_label(in.title));

  const auto time_series = [&](std::string_view heading, const std::vector<Column>& columns) {
    if (columns.empty()) return;
    s += fmt::format("set title {}\n", gp_label(fmt::format("{}{}", heading, thinned)));
    s += fmt::format("set xlabel {}\nset ylabel ''\n", gp_label(in.time_name));
    std::vector<std::string> clauses;
    for (const Column& c : columns) {
      clauses.push_back(plot_clause(every, fmt::format("1:{}", c.index), "lines", c.name));
    }
    s += join_clauses(clauses);
  };
  time_series("coordinates", in.coordinates);
  time_series("reactions", in.reactions);
  time_series("actuator forces u", in.actuators);

  if (!in.residuals.empty()) {
    // A residual that is exactly zero (at t = 0, or a constraint met to the last bit) has no
    // logarithm. It is left out (mapped to NaN, which gnuplot skips, leaving a gap in the
    // line) rather than clamped to a floor such as 1e-300, which would stretch the axis over
    // 300 empty decades and draw a comb of spikes down to it. If no drawn row has a nonzero
    // residual, gnuplot would stop on "all points y value undefined": a first pass (stats)
    // finds the largest |r| over the rows drawn, and when it is 0 the panel shows |r| on a
    // linear axis instead. Expressions are written inline: calling a user-defined gnuplot
    // function costs several times more per row.
    std::string largest = "largest = 0";
    for (const Column& c : in.residuals) {
      largest += fmt::format(
          ", largest = (abs(column({0})) > largest ? abs(column({0})) : largest)", c.index);
    }
    s += fmt::format("stats csv_file{} using ({}, largest) nooutput\n", every, largest);
    s += fmt::format("set xlabel {}\nset ylabel ''\n", gp_label(in.time_name));
    std::vector<std::string> log_clauses;
    std::vector<std::string> linear_clauses;
    for (const Column& c : in.residuals) {
      log_clauses.push_back(
          plot_clause(every, fmt::format("1:(column({0}) != 0 ? abs(column({0})) : NaN)", c.index),
                      "lines", c.name));
      linear_clauses.push_back(
          plot_clause(every, fmt::format("1:(abs(column({})))", c.index), "lines", c.name));
    }
    s += "if (STATS_max > 0) {\n";
    s += fmt::format(
        "set title {}\n",
        gp_label(fmt::format("|residual|, log scale, exact zeros left out{}", thinned)));
    s += "set logscale y\n";
    s += join_clauses(log_clauses);
    s += "unset logscale y\n";
    s += "} else {\n";
    s += fmt::format("set title {}\n",
                     gp_label(fmt::format("|residual|, every value exactly 0{}", thinned)));
    s += join_clauses(linear_clauses);
    s += "}\n";
  }

  if (in.path) {
    const auto& [x, y] = *in.path;
    // Equal scales (ratio -1) make the panel narrow: choose an x tic step giving ~4 intervals
    // so the tic labels do not run into each other.
    s += fmt::format("stats csv_file{} using {} nooutput\n", every, x.index);
    s += "if (STATS_max > STATS_min) {\n";
    s += "  path_step = (STATS_max - STATS_min) / 4.0\n";
    s += "  path_unit = 10.0**floor(log10(path_step))\n";
    s += "  path_f = path_step / path_unit\n";
    s += "  path_tic = (path_f < 1.5 ? 1 : path_f < 3.5 ? 2 : path_f < 7.5 ? 5 : 10) * path_unit\n";
    s += "  set xtics path_tic\n";  // not "set xtics (...)": that would read as a list of tics
    s += "}\n";
    s += fmt::format("set title {}\n",
                     gp_label(fmt::format("path {}({}), equal scales{}", y.name, x.name, thinned)));
    s += fmt::format("set xlabel {}\nset ylabel {}\n", gp_label(x.name), gp_label(y.name));
    s += "set size ratio -1\n";
    s += join_clauses({plot_clause(every, fmt::format("{}:{}", x.index, y.index), "lines", "path"),
                       fmt::format("csv_file{} every ::0::0 using {}:{} with points pt 7 ps 1.2 "
                                   "title 'start'",
                                   all, x.index, y.index)});
    s += "set size noratio\nset xtics autofreq\n";
  }

  if (in.energy) {
    const Column& e = *in.energy;
    // Exponent form: always a gnuplot float (a bare "1" would be an integer), all 17 digits.
    s += fmt::format("energy0 = {:.16e}\n", in.energy0);
    s += fmt::format("set title {}\n", gp_label(fmt::format("{}{}", e.name == "balance_error" ? "energy balance error h - h0 - W" : "energy drift", thinned)));
    s += fmt::format("set xlabel {}\nset ylabel ''\n", gp_label(in.time_name));
    s += join_clauses({plot_clause(every, fmt::format("1:(column({}) - energy0)", e.index), "lines",
                                   fmt::format("{0}(t) - {0}(0)", e.name))});
  }

  s += "unset multiplot\n";
  s += "set output\n";  // closes and flushes the PNG
  return s;
}

std::string quoted_stderr(const std::string& text) {
  std::string tail = trim(text);
  if (tail.size() > max_quoted_stderr) {
    tail = "...\n" + tail.substr(tail.size() - max_quoted_stderr);
  }
  return tail.empty() ? "(gnuplot wrote nothing on stderr)" : tail;
}

// The part every plot shares: writes the script that `script(output)` returns next to `png`, runs
// gnuplot on it, and renames gnuplot's output (a temporary file) onto `target` = absolute `png`
// only when gnuplot succeeded. `csv` is named in the error messages.
void render(const fs::path& png, const fs::path& named_target, const fs::path& csv,
            const std::function<std::string(const fs::path& output)>& script) {
  std::error_code ec;
  // Through a symbolic link to the file it names (io/atomic_file.hpp); never onto an input.
  const fs::path target = resolve_links(named_target);
  require_not_input(target, png);
  struct stat existing{};
  const bool exists = ::stat(target.c_str(), &existing) == 0;
  if (fs::is_directory(target, ec)) {
    throw FileError(
        fmt::format("cannot write the plot to '{}': it is a directory; give a file "
                    "name such as '{}'",
                    png.string(), (png / "plot.png").string()));
  }
  if (!gnuplot_available()) {
    throw FileError(
        fmt::format("cannot plot into '{}': gnuplot is not installed or has no PNG terminal; {}",
                    png.string(), install_hint));
  }

  const fs::path directory = target.parent_path();
  const std::string base = target.filename().string();
  TempFile output(directory, base, ".tmp");
  output.close();  // gnuplot opens it by name
  TempFile script_file(directory, base, ".gp");
  write_all(script_file.fd(), script(output.path()), script_file.path());
  script_file.close();

  // -d: ignore the user's ~/.gnuplot, so the picture does not depend on who draws it.
  const GnuplotRun run = run_gnuplot({"-d", script_file.path().string()});
  if (!run.exited || run.code != 0) {
    throw FileError(fmt::format(
        "gnuplot failed to draw '{}' from '{}' ({} {}); check that the CSV holds numeric rows. "
        "gnuplot said:\n{}",
        png.string(), csv.string(), run.exited ? "exit status" : "killed by signal",
        run.code, quoted_stderr(run.stderr_text)));
  }
  if (fs::file_size(output.path(), ec) == 0 || ec) {
    throw FileError(
        fmt::format("gnuplot exited normally but wrote no image for '{}'; gnuplot "
                    "said:\n{}",
                    png.string(), quoted_stderr(run.stderr_text)));
  }
  if (exists && !S_ISREG(existing.st_mode) && !S_ISDIR(existing.st_mode)) {
    // A device or pipe: copy the picture into it rather than replace it by a regular file.
    std::ifstream in(output.path(), std::ios::binary);
    const std::string bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    const UniqueFd fd(::open(target.c_str(), O_WRONLY | O_CLOEXEC));
    if (fd.get() < 0)
      throw FileError(fmt::format("cannot write the plot to '{}' ({})", png.string(), errno_text(errno)));
    write_all(fd.get(), bytes, target);
    return;
  }
  if (exists) ::chmod(output.path().c_str(), existing.st_mode & 07777);  // a replaced file keeps its mode
  fs::rename(output.path(), target, ec);
  if (ec) {
    throw FileError(
        fmt::format("cannot move the finished plot onto '{}' ({}); check that it "
                    "is writable",
                    png.string(), ec.message()));
  }
  output.keep();
}

}  // namespace

bool gnuplot_available() {
  static const bool available = probe_gnuplot();
  return available;
}

void write_plot(const PlotRequest& request, const std::filesystem::path& png) {
  if (request.coordinates.empty() && request.reactions.empty() && request.residuals.empty() &&
      request.actuators.empty() && !request.path && !request.energy) {
    throw InputError(fmt::format(
        "nothing to plot into '{}': the request names no coordinate, reaction, residual, path "
        "or energy column",
        png.string()));
  }
  std::error_code ec;
  ScriptInput in;
  in.csv = fs::absolute(request.csv, ec);
  if (ec) {
    throw FileError(
        fmt::format("cannot resolve the CSV path '{}' ({})", request.csv.string(), ec.message()));
  }
  const fs::path target = fs::absolute(png, ec);
  if (ec) {
    throw FileError(
        fmt::format("cannot resolve the plot path '{}' ({})", png.string(), ec.message()));
  }
  const CsvHead head = read_csv_head(request.csv);

  const auto lookup = [&](const std::string& name, std::string_view role) {
    return Column{column_of(head, request.csv, name, role), name};
  };
  for (const std::string& name : request.coordinates) {
    in.coordinates.push_back(lookup(name, "coordinate"));
  }
  for (const std::string& name : request.reactions) {
    in.reactions.push_back(lookup(name, "reaction"));
  }
  for (const std::string& name : request.residuals) {
    in.residuals.push_back(lookup(name, "residual"));
  }
  for (const std::string& name : request.actuators) {
    in.actuators.push_back(lookup(name, "actuator force"));
  }
  if (request.path) {
    Column x = lookup(request.path->first, "path x");
    Column y = lookup(request.path->second, "path y");
    in.path.emplace(std::move(x), std::move(y));
  }
  if (request.energy) {
    in.energy = lookup(*request.energy, "energy");
    const std::size_t i = static_cast<std::size_t>(in.energy->index) - 1;
    const std::string field = i < head.first_row.size() ? head.first_row[i] : "";
    const auto [end, err] = std::from_chars(field.data(), field.data() + field.size(), in.energy0);
    if (err != std::errc{} || end != field.data() + field.size() || !std::isfinite(in.energy0)) {
      throw InputError(fmt::format(
          "cannot plot the energy drift: the first value '{}' of column '{}' in '{}' is not a "
          "finite number; check the CSV, or plot without the energy",
          field, *request.energy, request.csv.string()));
    }
  }
  in.title = request.title;
  in.time_name = head.names.front();
  in.header_lines = head.header_lines;
  if (head.rows > max_rows_per_curve) {
    in.stride = (head.rows + max_rows_per_curve - 1) / max_rows_per_curve;
  }

  render(png, target, request.csv, [&](const fs::path& output) {
    in.output = output;
    return make_script(in);
  });
}

}  // namespace nhdyn

namespace nhdyn {

void write_xy_plot(const XyPlotRequest& request, const std::filesystem::path& png) {
  if (request.y.empty())
    throw InputError(fmt::format("nothing to plot into '{}': the request names no y column", png.string()));
  std::error_code ec;
  const fs::path csv = fs::absolute(request.csv, ec);
  if (ec) throw FileError(fmt::format("cannot resolve the CSV path '{}' ({})", request.csv.string(), ec.message()));
  const fs::path target = fs::absolute(png, ec);
  if (ec) throw FileError(fmt::format("cannot resolve the plot path '{}' ({})", png.string(), ec.message()));
  const CsvHead head = read_csv_head(request.csv);
  if (!request.x_of_curve.empty() && request.x_of_curve.size() != request.y.size())
    throw InputError(fmt::format("plot '{}': {} x columns for {} curves; give one per curve or none", png.string(),
                                 request.x_of_curve.size(), request.y.size()));
  if (!request.titles.empty() && request.titles.size() != request.y.size())
    throw InputError(fmt::format("plot '{}': {} titles for {} curves; give one per curve or none", png.string(),
                                 request.titles.size(), request.y.size()));
  std::vector<Column> xs, ys;
  for (std::size_t i = 0; i < request.y.size(); ++i) {
    const std::string& x_name = request.x_of_curve.empty() ? request.x : request.x_of_curve[i];
    xs.push_back(Column{column_of(head, request.csv, x_name, "x"), x_name});
    ys.push_back(Column{column_of(head, request.csv, request.y[i], "y"),
                        request.titles.empty() ? request.y[i] : request.titles[i]});
  }

  render(png, target, request.csv, [&](const fs::path& output) {
    // Values without a logarithm become NaN, which gnuplot skips; a first pass (stats) finds
    // whether anything is left to draw on each logarithmic axis.
    // `log_x` and `log_y` are set by the script once it knows whether anything is left to draw
    // on a logarithmic axis (else the axis is linear and every value is drawn).
    const auto value = [](int column, const char* log) {
      return fmt::format("(({1} && column({0}) <= 0) ? NaN : column({0}))", column, log);
    };
    std::string s;
    s += "# Written by nhdyn (src/nhdyn/io/plot.cpp, write_xy_plot) for one plot; deleted after the run.\n";
    s += "set encoding utf8\n";
    s += "if (strstrt(' '.GPVAL_TERMINALS.' ', ' pngcairo ') > 0) {\n";
    s += "  set terminal pngcairo size 1000,700 font 'Sans,10' noenhanced\n";
    s += "} else {\n";
    s += "  set terminal png size 1000,700 noenhanced\n";
    s += "}\n";
    s += "set termoption noenhanced\n";
    s += fmt::format("csv_file = {}\n", gp_string(csv.string()));
    s += fmt::format("output_file = {}\n", gp_string(output.string()));
    s += "set output output_file\n";
    s += "set datafile separator comma\n";
    s += "set grid\n";
    s += "set key outside right top vertical\n";
    s += fmt::format("set title {}\n", gp_label(request.title));
    s += fmt::format("set xlabel {}\nset ylabel {}\n", gp_label(request.x_label.empty() ? request.x : request.x_label),
                     gp_label(request.y_label));
    const std::string skip = fmt::format(" skip {}", head.header_lines);
    s += "log_x = 0\nlog_y = 0\n";
    if (request.log_x) {
      std::string largest = "largest = 0";
      for (const Column& c : xs)
        largest += fmt::format(", largest = (column({0}) > largest ? column({0}) : largest)", c.index);
      s += "undefine STATS_*\n";
      s += fmt::format("stats csv_file{} using ({}, largest) nooutput\n", skip, largest);
      s += "log_x = exists('STATS_max') && STATS_max > 0\n";
      s += "if (log_x) { set logscale x; set format x '1e%L' }\n";
    }
    if (request.log_y) {
      std::string largest = "largest = 0";
      for (const Column& c : ys)
        largest += fmt::format(", largest = (column({0}) > largest ? column({0}) : largest)", c.index);
      s += "undefine STATS_*\n";
      s += fmt::format("stats csv_file{} using ({}, largest) nooutput\n", skip, largest);
      s += "log_y = exists('STATS_max') && STATS_max > 0\n";
      s += "if (log_y) { set logscale y; set format y '1e%L' }\n";
    }
    std::vector<std::string> clauses;
    for (std::size_t i = 0; i < ys.size(); ++i)
      clauses.push_back(plot_clause(skip,
                                    fmt::format("{}:{}", value(xs[i].index, "log_x"), value(ys[i].index, "log_y")),
                                    "linespoints", ys[i].name));
    if (request.diagonal) clauses.push_back("x with lines dashtype 2 linecolor 'gray40' title 'y = x'");
    s += join_clauses(clauses);
    s += "set output\n";
    return s;
  });
}

}  // namespace nhdyn
