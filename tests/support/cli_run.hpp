// Runs the nhdyn command in a child process for the tests that check it as a user runs it: the
// exit code and everything it printed (stdout and stderr together).
#pragma once

#include <sys/wait.h>

#include <array>
#include <cstdio>
#include <filesystem>
#include <string>

namespace nhdyn::test {

struct CliOutcome {
  int exit_code = -1;
  std::string out;  // stdout and stderr together
};

#ifdef NHDYN_CLI_PATH
// `nhdyn ARGS` run by the shell in `dir` (ARGS as a shell would read them).
inline CliOutcome run_nhdyn(const std::string& args, const std::filesystem::path& dir) {
  const std::string command = "cd '" + dir.string() + "' && '" + NHDYN_CLI_PATH + "' " + args + " 2>&1";
  CliOutcome outcome;
  FILE* pipe = ::popen(command.c_str(), "r");
  if (pipe == nullptr) return outcome;
  std::array<char, 4096> buffer{};
  while (std::size_t got = std::fread(buffer.data(), 1, buffer.size(), pipe)) outcome.out.append(buffer.data(), got);
  const int status = ::pclose(pipe);
  outcome.exit_code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  return outcome;
}
#endif

}  // namespace nhdyn::test
