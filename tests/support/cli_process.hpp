// Runs the nhdyn command in a child process with its arguments as an argv (no shell, so that an
// argument may be megabytes long or hold any byte), extra environment variables, and optionally a
// signal sent some time into the run, a limit on the size of the files it writes (a full disk, as
// the process sees it): for the tests that try hostile input and interruptions.
#pragma once

#include <fcntl.h>
#include <signal.h>
#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <thread>
#include <utility>
#include <vector>

namespace nhdyn::test {

struct ProcessRun {
  int code = -1;  // exit status, or 128 + signal, or -1 when killed on the deadline
  std::string out, err;
  long max_rss_kb = 0;  // the child's peak resident memory (getrusage's ru_maxrss)
};

struct ProcessOptions {
  std::vector<std::pair<std::string, std::string>> env;  // set in the child
  int signal = 0;                                          // sent `after` into the run
  std::chrono::milliseconds after{0};
  // When set, the signal waits (past `after`) until this folder exists and holds something: the
  // run has begun writing, whatever the machine's load made of its start-up.
  std::filesystem::path signal_when_written;
  double deadline = 120.0;  // seconds, then SIGKILL
  // When > 0, the largest file the child may write (RLIMIT_FSIZE, SIGXFSZ ignored): a write past it
  // fails with EFBIG, as a write to a full disk fails with ENOSPC.
  long file_size_limit = 0;
};

inline std::string read_whole(const std::filesystem::path& p) {
  std::ifstream in(p, std::ios::binary);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

#ifdef NHDYN_CLI_PATH
inline ProcessRun run_process(const std::vector<std::string>& args, const std::filesystem::path& cwd,
                              const ProcessOptions& options = {}) {
  namespace fs = std::filesystem;
  static int counter = 0;
  const fs::path logs = fs::temp_directory_path() / ("nhdyn-process-logs-" + std::to_string(::getpid()));
  fs::create_directories(logs);
  ++counter;
  const fs::path out = logs / (std::to_string(counter) + ".out"), err = logs / (std::to_string(counter) + ".err");
  std::vector<std::string> strings{NHDYN_CLI_PATH};
  strings.insert(strings.end(), args.begin(), args.end());
  std::vector<char*> argv;
  for (std::string& s : strings) argv.push_back(s.data());
  argv.push_back(nullptr);
  const auto start = std::chrono::steady_clock::now();
  const pid_t pid = ::fork();
  if (pid == 0) {
    const int o = ::open(out.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
    const int e = ::open(err.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
    const int n = ::open("/dev/null", O_RDONLY);
    if (o < 0 || e < 0 || n < 0 || ::dup2(o, 1) < 0 || ::dup2(e, 2) < 0 || ::dup2(n, 0) < 0 ||
        ::chdir(cwd.c_str()) != 0)
      ::_exit(126);
    for (const auto& [name, value] : options.env) ::setenv(name.c_str(), value.c_str(), 1);
    if (options.file_size_limit > 0) {
      ::signal(SIGXFSZ, SIG_IGN);
      const rlimit limit{static_cast<rlim_t>(options.file_size_limit), static_cast<rlim_t>(options.file_size_limit)};
      if (::setrlimit(RLIMIT_FSIZE, &limit) != 0) ::_exit(126);
    }
    ::execv(argv[0], argv.data());
    ::_exit(127);
  }
  ProcessRun r;
  bool signalled = false;
  int status = 0;
  for (;;) {
    rusage usage{};
    if (::wait4(pid, &status, WNOHANG, &usage) == pid) {
      r.max_rss_kb = usage.ru_maxrss;
      break;
    }
    const auto elapsed = std::chrono::steady_clock::now() - start;
    const auto begun = [&] {
      std::error_code ec;
      return options.signal_when_written.empty() ||
             (std::filesystem::is_directory(options.signal_when_written, ec) &&
              !std::filesystem::is_empty(options.signal_when_written, ec));
    };
    if (options.signal && !signalled && elapsed >= options.after && begun()) {
      ::kill(pid, options.signal);
      signalled = true;
    }
    if (elapsed > std::chrono::duration<double>(options.deadline)) {
      ::kill(pid, SIGKILL);
      ::waitpid(pid, &status, 0);
      r.out = read_whole(out);
      r.err = read_whole(err);
      return r;
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(5));
  }
  r.code = WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status);
  r.out = read_whole(out);
  r.err = read_whole(err);
  return r;
}
#endif

}  // namespace nhdyn::test
