// The gnuplot runner (gnuplot.hpp): posix_spawnp without a shell, stderr captured through a pipe,
// the script and gnuplot's own output in exclusive temporary files beside the target, and the
// finished picture committed through an AtomicFile.
#include "nhdyn/io/detail/gnuplot.hpp"

#include <fcntl.h>
#include <fmt/format.h>
#include <signal.h>
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cerrno>
#include <cstdint>
#include <fstream>
#include <iterator>
#include <random>
#include <string_view>
#include <system_error>
#include <vector>

#include "nhdyn/core/error.hpp"
#include "nhdyn/io/atomic_file.hpp"
#include "nhdyn/io/plot.hpp"

extern char** environ;

namespace nhdyn {
namespace {
namespace fs = std::filesystem;
}  // namespace

namespace gnuplot_runner {  // named: the io sources are one unity build

// Tail of gnuplot's stderr quoted in an error message (its error comes last, after warnings).
constexpr std::size_t max_quoted_stderr = 4000;

constexpr std::string_view install_hint =
    "install gnuplot, e.g. `apt-get install gnuplot-nox`, or run without --plot";

std::string errno_text(int err) { return std::error_code(err, std::generic_category()).message(); }

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

// A scratch file for gnuplot (its script, its picture), created exclusively under a fresh random
// name ".<base>.<random><suffix>" in `dir` and removed when this object goes away. Not an
// AtomicFile: it is never renamed onto anything, and gnuplot opens it by name.
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

std::string quoted_stderr(const std::string& text) {
  constexpr std::string_view blank = " \t\r\n";
  const std::size_t first = text.find_first_not_of(blank);
  std::string tail = first == std::string::npos ? "" : text.substr(first, text.find_last_not_of(blank) - first + 1);
  if (tail.size() > max_quoted_stderr) {
    tail = "...\n" + tail.substr(tail.size() - max_quoted_stderr);
  }
  return tail.empty() ? "(gnuplot wrote nothing on stderr)" : tail;
}

}  // namespace gnuplot_runner

bool gnuplot_available() {
  static const bool available = gnuplot_runner::probe_gnuplot();
  return available;
}

void render_with_gnuplot(const fs::path& png, const fs::path& absolute_png, const fs::path& csv,
                         const std::function<std::string(const fs::path& output)>& script) {
  std::error_code ec;
  // Through a symbolic link to the file it names (io/atomic_file.hpp); never onto an input.
  const fs::path target = resolve_links(absolute_png);
  require_not_input(target, png);
  if (fs::is_directory(target, ec)) {
    throw FileError(
        fmt::format("cannot write the plot to '{}': it is a directory; give a file "
                    "name such as '{}'",
                    png.string(), (png / "plot.png").string()));
  }
  if (!gnuplot_available()) {
    throw FileError(
        fmt::format("cannot plot into '{}': gnuplot is not installed or has no PNG terminal; {}",
                    png.string(), gnuplot_runner::install_hint));
  }

  // gnuplot draws into a file of its own, opened by name; the picture reaches `png` through an
  // AtomicFile only once gnuplot has succeeded, so a failed run leaves the old picture in place.
  const fs::path directory = target.parent_path();
  const std::string base = target.filename().string();
  gnuplot_runner::TempFile output(directory, base, ".tmp");
  output.close();
  gnuplot_runner::TempFile script_file(directory, base, ".gp");
  gnuplot_runner::write_all(script_file.fd(), script(output.path()), script_file.path());
  script_file.close();
  AtomicFile picture(png);

  // -d: ignore the user's ~/.gnuplot, so the picture does not depend on who draws it.
  const gnuplot_runner::GnuplotRun run = gnuplot_runner::run_gnuplot({"-d", script_file.path().string()});
  if (!run.exited || run.code != 0) {
    throw FileError(fmt::format(
        "gnuplot failed to draw '{}' from '{}' ({} {}); check that the CSV holds numeric rows. "
        "gnuplot said:\n{}",
        png.string(), csv.string(), run.exited ? "exit status" : "killed by signal",
        run.code, gnuplot_runner::quoted_stderr(run.stderr_text)));
  }
  if (fs::file_size(output.path(), ec) == 0 || ec) {
    throw FileError(
        fmt::format("gnuplot exited normally but wrote no image for '{}'; gnuplot "
                    "said:\n{}",
                    png.string(), gnuplot_runner::quoted_stderr(run.stderr_text)));
  }
  std::ifstream in(output.path(), std::ios::binary);
  const std::string bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  if (!in.good() && !in.eof())
    throw FileError(fmt::format("cannot read back the picture gnuplot drew for '{}'", png.string()));
  picture.write(bytes);
  picture.commit();
}

}  // namespace nhdyn
