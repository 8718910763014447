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
#include <array>
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
  // Comment lines before the header (the provenance of io/provenance.hpp) are skipped here and,
  // counted in header_lines, by gnuplot's `skip`.
  int comment_lines = 0;
  while (read_csv_record(in, header) && header.starts_with('#')) ++comment_lines;
  if (!in || trim(header).empty() || header.starts_with('#')) {
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
  head.header_lines = comment_lines + 1 + static_cast<int>(std::count(header.begin(), header.end(), '\n'));
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

// The range of a column over the drawn rows, for the panel rule and the shared log range.
struct Range {
  double min = NAN, max = NAN;     // finite values only
  double min_abs_positive = NAN;   // smallest nonzero |value|
  double max_abs = NAN;
};

// Reads every `stride`-th data row (as gnuplot's `every` does) and returns the range of each
// 1-based column in `indices`. Fields that are not numbers are skipped (gnuplot skips them too).
std::vector<Range> read_ranges(const fs::path& csv, int header_lines, const std::vector<int>& indices,
                               std::uintmax_t stride) {
  std::vector<Range> out(indices.size());
  std::ifstream in(csv, std::ios::binary);
  if (!in) {
    throw FileError(fmt::format("cannot read the CSV file '{}' to plot ({}); check the path", csv.string(),
                                errno_text(errno)));
  }
  std::string line;
  for (int i = 0; i < header_lines && std::getline(in, line); ++i) {
  }
  int widest = 0;
  for (int index : indices) widest = std::max(widest, index);
  std::vector<std::string_view> fields;
  std::uintmax_t row = 0;
  while (std::getline(in, line)) {
    if (row++ % stride != 0) continue;
    fields.clear();
    std::string_view rest(line);
    while (static_cast<int>(fields.size()) < widest) {
      const std::size_t comma = rest.find(',');
      fields.push_back(rest.substr(0, comma));
      if (comma == std::string_view::npos) break;
      rest.remove_prefix(comma + 1);
    }
    for (std::size_t k = 0; k < indices.size(); ++k) {
      const auto i = static_cast<std::size_t>(indices[k] - 1);
      if (i >= fields.size()) continue;
      std::string_view field = fields[i];
      while (!field.empty() && (field.front() == ' ' || field.front() == '+')) field.remove_prefix(1);
      while (!field.empty() && (field.back() == ' ' || field.back() == '\r')) field.remove_suffix(1);
      double value = 0.0;
      const auto [end, err] = std::from_chars(field.data(), field.data() + field.size(), value);
      if (err != std::errc{} || end != field.data() + field.size() || !std::isfinite(value)) continue;
      Range& r = out[k];
      r.min = std::isnan(r.min) ? value : std::min(r.min, value);
      r.max = std::isnan(r.max) ? value : std::max(r.max, value);
      const double a = std::abs(value);
      r.max_abs = std::isnan(r.max_abs) ? a : std::max(r.max_abs, a);
      if (a > 0.0) r.min_abs_positive = std::isnan(r.min_abs_positive) ? a : std::min(r.min_abs_positive, a);
    }
  }
  return out;
}

// Colours of the event lines, one per event name in order of first appearance: dark enough
// on white, distinct from gnuplot's first curve colours.
constexpr std::array<std::string_view, 6> event_colours = {"#c00000", "#7030a0", "#c07000",
                                                           "#006060", "#606060", "#a00060"};
// With more events than this, the lines carry no text (the legend names them).
constexpr std::size_t max_labelled_events = 8;
// Vertical lines drawn at most; a run that records thousands of crossings gets a thinned comb.
constexpr std::size_t max_drawn_events = 400;

struct ScriptPanel {
  PlotPanel panel;
  std::vector<Column> curves;  // resolved columns; for a path {x, y}
};

struct ScriptInput {
  std::string title;
  std::string time_name;
  fs::path csv;     // absolute
  fs::path output;  // absolute, the temporary file
  std::vector<ScriptPanel> panels;
  std::vector<PlotEvent> events;
  std::vector<double> drift0;  // first value of each drift panel's column, in panel order
  std::optional<std::pair<double, double>> log_range;  // shared |value| range of the log panels
  int header_lines = 1;       // lines before the first data row
  std::uintmax_t stride = 1;  // draw every stride-th row
  int layout_columns = 0;     // 0: from the number of panels
};

std::string make_script(const ScriptInput& in) {
  const int panels = static_cast<int>(in.panels.size());
  const int layout_columns =
      in.layout_columns > 0 ? std::min(in.layout_columns, panels) : panels == 1 ? 1 : panels <= 4 ? 2 : 3;
  const int layout_rows = (panels + layout_columns - 1) / layout_columns;
  const int width = layout_columns == 1 ? 1000 : 620 * layout_columns;
  const int height = 80 + 340 * layout_rows;
  // gnuplot skips the header lines; `every` also thins the rows, `all` takes them all.
  const std::string all = fmt::format(" skip {}", in.header_lines);
  const std::string every = in.stride > 1 ? fmt::format("{} every {}", all, in.stride) : all;
  const std::string thinned = in.stride > 1 ? fmt::format(" (1 row in {} drawn)", in.stride) : "";

  // Events: one colour per name; the names in order of first appearance.
  std::vector<std::string> event_names;
  for (const PlotEvent& e : in.events)
    if (std::find(event_names.begin(), event_names.end(), e.name) == event_names.end())
      event_names.push_back(e.name);
  const auto colour_of = [&](const std::string& name) {
    const auto at = std::find(event_names.begin(), event_names.end(), name) - event_names.begin();
    return event_colours[static_cast<std::size_t>(at) % event_colours.size()];
  };
  const std::size_t event_step =
      in.events.size() > max_drawn_events ? (in.events.size() + max_drawn_events - 1) / max_drawn_events : 1;
  const bool label_events = in.events.size() <= max_labelled_events;

  std::string s;
  s += "# Written by nhdyn (src/nhdyn/io/plot.cpp) for one plot; deleted after the run.\n";
  s += "set encoding utf8\n";
  s += "if (strstrt(' '.GPVAL_TERMINALS.' ', ' pngcairo ') > 0) {\n";
  s += fmt::format("  set terminal pngcairo size {},{} font 'Sans,10' noenhanced\n", width, height);
  s += "} else {\n";
  s += fmt::format("  set terminal png size {},{} noenhanced\n", width, height);
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

  // The events on a time axis: dashed vertical lines (arrows from the bottom to the top of the
  // graph), their names written along them when there are few, and one legend entry per name.
  const auto mark_events = [&](std::vector<std::string>& clauses) {
    if (in.events.empty()) return;
    int tag = 1;
    for (std::size_t i = 0; i < in.events.size(); i += event_step) {
      const PlotEvent& e = in.events[i];
      s += fmt::format("set arrow {} from {:.17g}, graph 0 to {:.17g}, graph 1 nohead dashtype 2 lw 1.2 "
                       "linecolor rgb '{}' front\n",
                       tag, e.t, e.t, colour_of(e.name));
      if (label_events)
        s += fmt::format("set label {} {} at {:.17g}, graph 0.97 rotate by 90 right offset character -0.7,0 "
                         "font ',8' textcolor rgb '{}' front\n",
                         tag, gp_label(e.name), e.t, colour_of(e.name));
      ++tag;
    }
    for (const std::string& name : event_names)
      clauses.push_back(fmt::format("NaN with lines dashtype 2 lw 1.2 linecolor rgb '{}' title {}", colour_of(name),
                                    gp_label("event " + name)));
  };
  const auto clear_marks = [&] { s += "unset arrow\nunset label\n"; };
  const auto title_of = [&](const ScriptPanel& p, std::size_t i) {
    return p.panel.labels.size() == p.curves.size() ? p.panel.labels[i] : p.curves[i].name;
  };

  std::size_t drift_index = 0;
  for (const ScriptPanel& p : in.panels) {
    switch (p.panel.kind) {
      case PanelKind::lines: {
        s += fmt::format("set title {}\n", gp_label(fmt::format("{}{}", p.panel.title, thinned)));
        s += fmt::format("set xlabel {}\nset ylabel ''\n", gp_label(in.time_name));
        std::vector<std::string> clauses;
        for (std::size_t i = 0; i < p.curves.size(); ++i)
          clauses.push_back(plot_clause(every, fmt::format("1:{}", p.curves[i].index), "lines", title_of(p, i)));
        mark_events(clauses);
        if (p.panel.y_range)
          s += fmt::format("set yrange [{:.17g}:{:.17g}]\n", p.panel.y_range->first, p.panel.y_range->second);
        s += join_clauses(clauses);
        if (p.panel.y_range) s += "set autoscale y\n";
        clear_marks();
        break;
      }
      case PanelKind::drift: {
        const Column& e = p.curves.front();
        // Exponent form: always a gnuplot float (a bare "1" would be an integer), all 17 digits.
        s += fmt::format("drift0 = {:.16e}\n", in.drift0[drift_index++]);
        s += fmt::format("set title {}\n", gp_label(fmt::format("{}{}", p.panel.title, thinned)));
        s += fmt::format("set xlabel {}\nset ylabel ''\n", gp_label(in.time_name));
        std::vector<std::string> clauses{plot_clause(every, fmt::format("1:(column({}) - drift0)", e.index), "lines",
                                                     in.drift0[drift_index - 1] == 0.0
                                                         ? title_of(p, 0)
                                                         : fmt::format("{0}(t) - {0}(t0)", title_of(p, 0)))};
        mark_events(clauses);
        s += join_clauses(clauses);
        clear_marks();
        break;
      }
      case PanelKind::log_abs: {
        // A value that is exactly zero (at t = 0, or a constraint met to the last bit) has no
        // logarithm. It is left out (mapped to NaN, which gnuplot skips, leaving a gap in the
        // line) rather than clamped to a floor such as 1e-300, which would stretch the axis over
        // 300 empty decades and draw a comb of spikes down to it. If no drawn row has a nonzero
        // value, gnuplot would stop on "all points y value undefined": a first pass (stats)
        // finds the largest |r| over the rows drawn, and when it is 0 the panel shows |r| on a
        // linear axis instead. Expressions are written inline: calling a user-defined gnuplot
        // function costs several times more per row.
        std::string largest = "largest = 0";
        for (const Column& c : p.curves)
          largest += fmt::format(", largest = (abs(column({0})) > largest ? abs(column({0})) : largest)", c.index);
        s += fmt::format("stats csv_file{} using ({}, largest) nooutput\n", every, largest);
        s += fmt::format("set xlabel {}\nset ylabel ''\n", gp_label(in.time_name));
        std::vector<std::string> log_clauses;
        std::vector<std::string> linear_clauses;
        for (std::size_t i = 0; i < p.curves.size(); ++i) {
          const Column& c = p.curves[i];
          log_clauses.push_back(plot_clause(
              every, fmt::format("1:(column({0}) != 0 ? abs(column({0})) : NaN)", c.index), "lines", title_of(p, i)));
          linear_clauses.push_back(
              plot_clause(every, fmt::format("1:(abs(column({})))", c.index), "lines", title_of(p, i)));
        }
        mark_events(log_clauses);
        mark_events(linear_clauses);
        s += "if (STATS_max > 0) {\n";
        s += fmt::format("set title {}\n",
                         gp_label(fmt::format("{}, log scale, exact zeros left out{}", p.panel.title, thinned)));
        s += "set logscale y\nset format y '1e%L'\n";
        if (in.log_range)
          s += fmt::format("set yrange [{:.17g}:{:.17g}]\n", in.log_range->first, in.log_range->second);
        s += join_clauses(log_clauses);
        s += "unset logscale y\nset format y '% h'\nset autoscale y\n";
        s += "} else {\n";
        s += fmt::format("set title {}\n",
                         gp_label(fmt::format("{}, every value exactly 0{}", p.panel.title, thinned)));
        s += join_clauses(linear_clauses);
        s += "}\n";
        clear_marks();
        break;
      }
      case PanelKind::path: {
        const Column& x = p.curves[0];
        const Column& y = p.curves[1];
        s += fmt::format("set title {}\n",
                         gp_label(fmt::format("{}{}{}", p.panel.title,
                                              p.panel.equal_axes ? ", equal scales" : ", scales not equal", thinned)));
        s += fmt::format("set xlabel {}\nset ylabel {}\n", gp_label(x.name), gp_label(y.name));
        if (p.panel.equal_axes) {
          // Equal scales make the panel narrow: choose an x tic step giving ~4 intervals so the
          // tic labels do not run into each other.
          s += fmt::format("stats csv_file{} using {} nooutput\n", every, x.index);
          s += "if (STATS_max > STATS_min) {\n";
          s += "  path_step = (STATS_max - STATS_min) / 4.0\n";
          s += "  path_unit = 10.0**floor(log10(path_step))\n";
          s += "  path_f = path_step / path_unit\n";
          s += "  path_tic = (path_f < 1.5 ? 1 : path_f < 3.5 ? 2 : path_f < 7.5 ? 5 : 10) * path_unit\n";
          s += "  set xtics path_tic\n";  // not "set xtics (...)": that would read as a list of tics
          s += "}\n";
          s += "set size ratio -1\n";
        } else {
          // Each axis on its own scale, with a margin so the path does not run along the frame.
          s += "set offsets graph 0.05, graph 0.05, graph 0.05, graph 0.05\n";
        }
        // The events where the state is known: a circle at (x, y), named when there are few.
        int tag = 1;
        for (std::size_t i = 0; i < in.events.size(); i += event_step) {
          const PlotEvent& e = in.events[i];
          std::optional<double> ex, ey;
          for (const auto& [name, value] : e.state) {
            if (name == x.name) ex = value;
            if (name == y.name) ey = value;
          }
          if (!ex || !ey) continue;
          s += fmt::format("set label {} {} at {:.17g}, {:.17g} point pointtype 6 pointsize 1.6 linecolor rgb '{}' "
                           "offset character 0.8,0.8 font ',8' textcolor rgb '{}' front\n",
                           tag++, gp_label(label_events ? e.name : ""), *ex, *ey, colour_of(e.name),
                           colour_of(e.name));
        }
        s += join_clauses({plot_clause(every, fmt::format("{}:{}", x.index, y.index), "lines", "path"),
                           fmt::format("csv_file{} every ::0::0 using {}:{} with points pt 7 ps 1.2 title 'start'",
                                       all, x.index, y.index)});
        s += "set size noratio\nset xtics autofreq\nset offsets 0, 0, 0, 0\n";
        clear_marks();
        break;
      }
    }
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

// ---------------------------------------------------------------------------------------------
// Which panel a column goes to (pure; docs/cli.md, "What --plot draws").

// A curve joins a panel only if the panel's range, with it, spans at most this many times the
// curve's own span: every curve then fills at least a tenth of its panel's height.
constexpr double scale_ratio = 10.0;
// The path is drawn with equal axes when its span ratio y/x lies in this interval: a panel is
// about 620 x 300 px, so both sides of the drawn box keep at least a third of the panel.
constexpr double path_ratio_low = 0.2;
constexpr double path_ratio_high = 1.5;

// The coordinate a velocity (x') or a reaction (R_x) belongs to.
std::string_view base_coordinate(const PlotColumn& c) {
  std::string_view name = c.name;
  if (c.role == PlotRole::velocity)
    while (!name.empty() && name.back() == '\'') name.remove_suffix(1);
  if (c.role == PlotRole::reaction && name.starts_with("R_")) name.remove_prefix(2);
  return name;
}

// A column whose values vary by no more than this fraction of the largest magnitude among the
// columns of its role is constant to round-off: a reaction that is zero up to 1e-17 is drawn as
// the zero it is, not magnified into noise. Below the tolerance of any run (rtol 1e-8 by
// default), such a variation is the integrator's error, not the motion.
constexpr double round_off = 1e-9;

struct ScaleGroup {
  std::vector<std::string> names;
  std::optional<std::pair<double, double>> y_range;  // set for a group of constants
};

// Splits columns of like units into groups of like scale (scale_ratio). Largest spans first,
// so a group's first member sets its range; each group keeps the columns in their given order,
// and the groups come in the order of their first column. `role_scale` is the largest |value|
// among the columns of their role (round_off).
std::vector<ScaleGroup> split_by_scale(const std::vector<const PlotColumn*>& columns, double role_scale) {
  const auto span = [&](const PlotColumn* c) {
    const double s = c->max - c->min;
    if (!std::isfinite(s)) return 0.0;
    return s <= round_off * role_scale ? 0.0 : s;
  };
  std::vector<std::size_t> order(columns.size());
  for (std::size_t i = 0; i < order.size(); ++i) order[i] = i;
  std::stable_sort(order.begin(), order.end(),
                   [&](std::size_t a, std::size_t b) { return span(columns[a]) > span(columns[b]); });
  struct Group {
    double lo = NAN, hi = NAN;
    double smallest = INFINITY;  // smallest positive span of a member
    std::vector<std::size_t> members;
  };
  std::vector<Group> groups;
  for (std::size_t i : order) {
    const PlotColumn* c = columns[i];
    const bool finite = std::isfinite(c->min) && std::isfinite(c->max);
    Group* home = nullptr;
    for (Group& g : groups) {
      if (!finite || std::isnan(g.lo)) {  // no values to place: any group will do
        home = &g;
        break;
      }
      const double lo = std::min(g.lo, c->min), hi = std::max(g.hi, c->max);
      const double smallest = span(c) > 0.0 ? std::min(g.smallest, span(c)) : g.smallest;
      // A group of constants takes any other constant: flat lines at their levels read well.
      if (!std::isfinite(smallest) || hi - lo <= scale_ratio * smallest) {
        home = &g;
        break;
      }
    }
    if (!home) home = &groups.emplace_back();
    home->members.push_back(i);
    if (finite) {
      home->lo = std::isnan(home->lo) ? c->min : std::min(home->lo, c->min);
      home->hi = std::isnan(home->hi) ? c->max : std::max(home->hi, c->max);
      if (span(c) > 0.0) home->smallest = std::min(home->smallest, span(c));
    }
  }
  // Each group's members in their given order; the groups in the order of their first member
  // (the first member of a group is its smallest index).
  std::vector<std::pair<std::size_t, std::size_t>> first;  // (first member, group)
  for (std::size_t k = 0; k < groups.size(); ++k) {
    std::sort(groups[k].members.begin(), groups[k].members.end());
    first.emplace_back(groups[k].members.front(), k);
  }
  std::sort(first.begin(), first.end());
  std::vector<ScaleGroup> out;
  for (const auto& [unused, k] : first) {
    const Group& g = groups[k];
    ScaleGroup& group = out.emplace_back();
    for (std::size_t i : g.members) group.names.push_back(columns[i]->name);
    if (std::isfinite(g.smallest) || std::isnan(g.lo)) continue;
    // Constants: a range around them wide enough that round-off does not show, and that holds
    // every level with a margin.
    const double mid = 0.5 * (g.lo + g.hi);
    double half = std::max({0.6 * (g.hi - g.lo), 0.5 * std::abs(mid), 0.1 * role_scale});
    if (!(half > 0.0)) half = 1.0;
    group.y_range.emplace(mid - half, mid + half);
  }
  return out;
}

std::string join_names(const std::vector<std::string>& names) {
  std::string out;
  for (std::size_t i = 0; i < names.size(); ++i) out += (i == 0 ? "" : ", ") + names[i];
  return out;
}

}  // namespace

bool is_angle_name(std::string_view coordinate) {
  std::string_view stem = coordinate.substr(0, coordinate.find_first_of("_0123456789'"));
  while (!stem.empty() && stem.back() >= 'A' && stem.back() <= 'Z') stem.remove_suffix(1);
  static constexpr std::array<std::string_view, 13> angles = {
      "alpha", "beta", "gamma", "delta", "theta", "vartheta", "th", "phi", "varphi", "chi", "psi", "angle", "ang"};
  return std::find(angles.begin(), angles.end(), stem) != angles.end();
}

std::vector<PlotPanel> calc_plot_panels(const std::vector<PlotColumn>& columns,
                                        const std::optional<std::pair<PlotColumn, PlotColumn>>& path,
                                        const std::vector<std::string>& angles) {
  const auto is_angle = [&](std::string_view coordinate) {
    return is_angle_name(coordinate) || std::find(angles.begin(), angles.end(), coordinate) != angles.end();
  };
  std::vector<PlotPanel> panels;
  const auto lines = [&](PlotRole role, int which, std::string_view title) {
    // which: 1 only the angles, 0 only the others, -1 every column of the role.
    std::vector<const PlotColumn*> chosen;
    double role_scale = 0.0;
    // Reactions and actuator forces are both generalized forces: one scale for the two roles.
    const auto same_scale = [&](PlotRole r) {
      const auto forces = [](PlotRole x) { return x == PlotRole::reaction || x == PlotRole::actuator; };
      return r == role || (forces(r) && forces(role));
    };
    for (const PlotColumn& c : columns) {
      if (same_scale(c.role) && std::isfinite(c.max - c.min))
        role_scale = std::max({role_scale, std::abs(c.min), std::abs(c.max)});
      if (c.role != role) continue;
      if (which >= 0 && is_angle(base_coordinate(c)) != (which == 1)) continue;
      chosen.push_back(&c);
    }
    for (ScaleGroup& group : split_by_scale(chosen, role_scale)) {
      PlotPanel& p = panels.emplace_back(PlotPanel{std::string(title), PanelKind::lines, std::move(group.names)});
      p.y_range = group.y_range;
      if (p.y_range) p.title += ", constant to round-off";
    }
  };
  lines(PlotRole::coordinate, 1, "angles");
  lines(PlotRole::coordinate, 0, "coordinates");
  lines(PlotRole::velocity, 1, "angular velocities");
  lines(PlotRole::velocity, 0, "velocities");
  if (path) {
    const double xs = path->first.max - path->first.min;
    const double ys = path->second.max - path->second.min;
    const double scale = std::max({std::abs(path->first.min), std::abs(path->first.max), std::abs(path->second.min),
                                   std::abs(path->second.max)});
    if (std::isfinite(xs) && std::isfinite(ys) && xs > round_off * scale && ys > round_off * scale) {
      const double ratio = ys / xs;
      PlotPanel p{fmt::format("path {}({})", path->second.name, path->first.name), PanelKind::path,
                  {path->first.name, path->second.name}};
      p.equal_axes = ratio >= path_ratio_low && ratio <= path_ratio_high;
      panels.push_back(std::move(p));
    }
  }
  lines(PlotRole::reaction, 1, "reactions on angles");
  lines(PlotRole::reaction, 0, "reactions");
  lines(PlotRole::actuator, -1, "actuator forces u");
  lines(PlotRole::other, -1, "other columns");
  std::vector<std::string> residuals;
  for (const PlotColumn& c : columns)
    if (c.role == PlotRole::residual) residuals.push_back(c.name);
  if (!residuals.empty()) panels.push_back(PlotPanel{"|residual|", PanelKind::log_abs, residuals});
  for (const PlotColumn& c : columns) {
    if (c.role != PlotRole::energy_error) continue;
    panels.push_back(PlotPanel{c.name == "balance_error" ? "energy balance error h - h0 - W" : "energy drift",
                               PanelKind::drift, {c.name}});
  }
  return panels;
}

void require_plot_columns(const std::vector<std::string>& all, const std::vector<std::string>& chosen,
                          std::string_view option) {
  for (const std::string& name : chosen) {
    if (std::find(all.begin(), all.end(), name) != all.end()) continue;
    throw InputError(fmt::format("{} names the column '{}', which this run does not write; its columns are: {}; "
                                 "choose among them (comma-separated)",
                                 option, name, join_names(all)));
  }
}

void select_plot_columns(PlotRequest& request, const std::vector<std::string>& all,
                         const std::vector<std::string>& chosen, std::string_view option) {
  if (chosen.empty()) return;
  require_plot_columns(all, chosen, option);
  const auto is_chosen = [&](const std::string& name) {
    return std::find(chosen.begin(), chosen.end(), name) != chosen.end();
  };
  std::vector<std::string> placed;
  for (std::vector<std::string>* role : {&request.coordinates, &request.velocities, &request.reactions,
                                         &request.actuators, &request.residuals, &request.others}) {
    std::erase_if(*role, [&](const std::string& name) { return !is_chosen(name); });
    placed.insert(placed.end(), role->begin(), role->end());
  }
  if (request.energy && !is_chosen(*request.energy)) request.energy.reset();
  if (request.energy) placed.push_back(*request.energy);
  if (request.path && !(is_chosen(request.path->first) && is_chosen(request.path->second))) request.path.reset();
  for (const std::string& name : chosen)
    if (std::find(placed.begin(), placed.end(), name) == placed.end()) {
      request.others.push_back(name);
      placed.push_back(name);
    }
}

std::vector<PlotPanel> calc_comparison_panels(const std::vector<std::string>& methods,
                                              const std::vector<std::string>& integrators,
                                              const std::vector<std::string>& quantities) {
  const auto column = [](const std::string& quantity, const std::string& method, const std::string& integrator) {
    return fmt::format("{}_{}_{}", quantity, method, integrator);
  };
  std::vector<PlotPanel> panels;
  if (integrators.size() == 1 || methods.size() == 1) {
    const bool by_method = integrators.size() == 1;
    for (const std::string& outer : by_method ? methods : integrators) {
      PlotPanel& p = panels.emplace_back();
      p.kind = PanelKind::log_abs;
      p.title = by_method ? fmt::format("{} ({})", outer, integrators.front())
                          : fmt::format("{} ({})", outer, methods.front());
      for (const std::string& q : quantities) {
        p.columns.push_back(by_method ? column(q, outer, integrators.front()) : column(q, methods.front(), outer));
        p.labels.push_back(q);
      }
    }
    return panels;
  }
  for (const std::string& q : quantities)
    for (const std::string& m : methods) {
      PlotPanel& p = panels.emplace_back();
      p.kind = PanelKind::log_abs;
      p.title = fmt::format("{}: {}", q, m);
      for (const std::string& i : integrators) {
        p.columns.push_back(column(q, m, i));
        p.labels.push_back(i);
      }
    }
  return panels;
}

void select_panel_columns(std::vector<PlotPanel>& panels, const std::vector<std::string>& chosen) {
  if (chosen.empty()) return;
  for (PlotPanel& p : panels) {
    for (std::size_t i = p.columns.size(); i-- > 0;) {
      if (std::find(chosen.begin(), chosen.end(), p.columns[i]) != chosen.end()) continue;
      p.columns.erase(p.columns.begin() + static_cast<std::ptrdiff_t>(i));
      if (i < p.labels.size()) p.labels.erase(p.labels.begin() + static_cast<std::ptrdiff_t>(i));
    }
  }
  std::erase_if(panels, [](const PlotPanel& p) { return p.columns.empty(); });
}

namespace {

// Resolves the panels' columns, reads what the script needs from the CSV and draws it.
void draw_panels(const std::string& title, const fs::path& csv, const CsvHead& head, std::vector<PlotPanel> panels,
                 const std::vector<PlotEvent>& events, bool same_log_range, int layout_columns,
                 const fs::path& png) {
  std::error_code ec;
  ScriptInput in;
  in.csv = fs::absolute(csv, ec);
  if (ec) throw FileError(fmt::format("cannot resolve the CSV path '{}' ({})", csv.string(), ec.message()));
  const fs::path target = fs::absolute(png, ec);
  if (ec) throw FileError(fmt::format("cannot resolve the plot path '{}' ({})", png.string(), ec.message()));
  in.title = title;
  in.time_name = head.names.front();
  in.header_lines = head.header_lines;
  in.events = events;
  in.layout_columns = layout_columns;
  if (head.rows > max_rows_per_curve) in.stride = (head.rows + max_rows_per_curve - 1) / max_rows_per_curve;
  std::vector<int> log_indices;
  for (PlotPanel& p : panels) {
    ScriptPanel& sp = in.panels.emplace_back();
    for (const std::string& name : p.columns) sp.curves.push_back(Column{column_of(head, csv, name, "a"), name});
    if (p.kind == PanelKind::log_abs)
      for (const Column& c : sp.curves) log_indices.push_back(c.index);
    if (p.kind == PanelKind::drift) {
      const std::string& name = p.columns.front();
      const std::size_t i = static_cast<std::size_t>(sp.curves.front().index) - 1;
      const std::string field = i < head.first_row.size() ? head.first_row[i] : "";
      double first = 0.0;
      const auto [end, err] = std::from_chars(field.data(), field.data() + field.size(), first);
      if (err != std::errc{} || end != field.data() + field.size() || !std::isfinite(first)) {
        throw InputError(fmt::format(
            "cannot plot the energy drift: the first value '{}' of column '{}' in '{}' is not a "
            "finite number; check the CSV, or plot without the energy",
            field, name, csv.string()));
      }
      in.drift0.push_back(first);
    }
    sp.panel = std::move(p);
  }
  if (same_log_range && !log_indices.empty()) {
    double lo = INFINITY, hi = 0.0;
    for (const Range& r : read_ranges(csv, head.header_lines, log_indices, in.stride)) {
      if (std::isfinite(r.min_abs_positive)) lo = std::min(lo, r.min_abs_positive);
      if (std::isfinite(r.max_abs)) hi = std::max(hi, r.max_abs);
    }
    if (std::isfinite(lo) && hi > 0.0) {
      const double low = std::pow(10.0, std::floor(std::log10(lo)));
      double high = std::pow(10.0, std::ceil(std::log10(hi)));
      if (high <= low) high = low * 10.0;
      in.log_range.emplace(low, high);
    }
  }
  render(png, target, csv, [&](const fs::path& output) {
    in.output = output;
    return make_script(in);
  });
}

}  // namespace

bool gnuplot_available() {
  static const bool available = probe_gnuplot();
  return available;
}

void write_plot(const PlotRequest& request, const std::filesystem::path& png) {
  if (request.coordinates.empty() && request.reactions.empty() && request.residuals.empty() &&
      request.actuators.empty() && request.velocities.empty() && request.others.empty() && !request.path &&
      !request.energy) {
    throw InputError(fmt::format(
        "nothing to plot into '{}': the request names no coordinate, velocity, reaction, residual, path, "
        "energy or other column",
        png.string()));
  }
  const CsvHead head = read_csv_head(request.csv);
  std::vector<PlotColumn> columns;
  std::vector<int> indices;
  const auto add = [&](const std::vector<std::string>& names, PlotRole role, std::string_view what) {
    for (const std::string& name : names) {
      indices.push_back(column_of(head, request.csv, name, what));
      columns.push_back(PlotColumn{name, role});
    }
  };
  add(request.coordinates, PlotRole::coordinate, "coordinate");
  add(request.velocities, PlotRole::velocity, "velocity");
  add(request.reactions, PlotRole::reaction, "reaction");
  add(request.actuators, PlotRole::actuator, "actuator force");
  add(request.others, PlotRole::other, "a");
  add(request.residuals, PlotRole::residual, "residual");
  if (request.energy) add({*request.energy}, PlotRole::energy_error, "energy");
  std::optional<std::pair<PlotColumn, PlotColumn>> path;
  if (request.path) {
    indices.push_back(column_of(head, request.csv, request.path->first, "path x"));
    indices.push_back(column_of(head, request.csv, request.path->second, "path y"));
    path.emplace(PlotColumn{request.path->first, PlotRole::coordinate},
                 PlotColumn{request.path->second, PlotRole::coordinate});
  }
  const std::uintmax_t stride =
      head.rows > max_rows_per_curve ? (head.rows + max_rows_per_curve - 1) / max_rows_per_curve : 1;
  const std::vector<Range> ranges = read_ranges(request.csv, head.header_lines, indices, stride);
  for (std::size_t i = 0; i < columns.size(); ++i) {
    columns[i].min = ranges[i].min;
    columns[i].max = ranges[i].max;
  }
  if (path) {
    path->first.min = ranges[columns.size()].min;
    path->first.max = ranges[columns.size()].max;
    path->second.min = ranges[columns.size() + 1].min;
    path->second.max = ranges[columns.size() + 1].max;
  }
  std::vector<PlotPanel> panels = calc_plot_panels(columns, path, request.angles);
  if (panels.empty()) {
    throw InputError(fmt::format("nothing to plot into '{}': the path {}({}) is a line or a point in '{}'; plot "
                                 "its columns against time instead",
                                 png.string(), request.path->second, request.path->first, request.csv.string()));
  }
  draw_panels(request.title, request.csv, head, std::move(panels), request.events, false, 0, png);
}

void write_panel_plot(const PanelPlotRequest& request, const std::filesystem::path& png) {
  if (request.panels.empty())
    throw InputError(fmt::format("nothing to plot into '{}': the request has no panel", png.string()));
  for (const PlotPanel& p : request.panels) {
    if (p.columns.empty() || (p.kind == PanelKind::path && p.columns.size() != 2) ||
        (p.kind == PanelKind::drift && p.columns.size() != 1))
      throw InputError(fmt::format("plot '{}': the panel '{}' has {} columns; a path takes 2, a drift 1, "
                                   "any other panel at least 1",
                                   png.string(), p.title, p.columns.size()));
    if (!p.labels.empty() && p.labels.size() != p.columns.size())
      throw InputError(fmt::format("plot '{}': the panel '{}' has {} labels for {} columns; give one per column "
                                   "or none",
                                   png.string(), p.title, p.labels.size(), p.columns.size()));
  }
  const CsvHead head = read_csv_head(request.csv);
  draw_panels(request.title, request.csv, head, request.panels, request.events, request.same_log_range,
              request.layout_columns, png);
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
