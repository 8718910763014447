// `nhdyn --version`: the version of the generated header nhdyn/core/version.hpp, which is the
// project(VERSION) of the top CMakeLists.txt, and the commit (12 hex digits, or "unknown" outside
// git); it exits 0 although the command otherwise requires a subcommand.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <regex>
#include <sstream>
#include <string>

#include "nhdyn/core/version.hpp"
#include "support/cli_run.hpp"

namespace {

TEST(VersionCli, PrintsTheVersionAndTheCommit) {
  const nhdyn::test::CliOutcome run = nhdyn::test::run_nhdyn("--version", std::filesystem::temp_directory_path());
  EXPECT_EQ(run.exit_code, 0) << run.out;
  EXPECT_EQ(run.out, std::string("nhdyn ") + NHDYN_VERSION + " (commit " + NHDYN_GIT_COMMIT + ")\n");
  EXPECT_TRUE(std::regex_match(std::string(NHDYN_GIT_COMMIT), std::regex("[0-9a-f]{12}|unknown"))) << NHDYN_GIT_COMMIT;
}

TEST(VersionCli, TheMacrosAreTheProjectVersion) {
  std::ifstream in(std::filesystem::path(NHDYN_SOURCE_DIR) / "CMakeLists.txt");
  std::stringstream text;
  text << in.rdbuf();
  std::smatch m;
  const std::string s = text.str();
  ASSERT_TRUE(std::regex_search(s, m, std::regex(R"(project\(nhdyn VERSION (\d+)\.(\d+)\.(\d+))")));
  EXPECT_EQ(std::stoi(m[1]), NHDYN_VERSION_MAJOR);
  EXPECT_EQ(std::stoi(m[2]), NHDYN_VERSION_MINOR);
  EXPECT_EQ(std::stoi(m[3]), NHDYN_VERSION_PATCH);
  EXPECT_EQ(m[1].str() + "." + m[2].str() + "." + m[3].str(), NHDYN_VERSION);
  EXPECT_EQ(NHDYN_VERSION_NUMBER, NHDYN_VERSION_MAJOR * 10000 + NHDYN_VERSION_MINOR * 100 + NHDYN_VERSION_PATCH);
}

}  // namespace
