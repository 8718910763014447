// Large outputs are bounded (issue 14): `nhdyn equations` on a model past 1000 coordinates (the
// chain of 334 sleighs, n = 1002) is refused before the derivation with the reason and the way
// out, exit 2, and prints nothing on stdout (10 000 coordinates once took 7.2 GB and wrote 600 MB).
#include <gtest/gtest.h>

#include <sys/wait.h>
#include <unistd.h>

#include <cstdlib>
#include <filesystem>
#include <string>

#include "support/cli_run.hpp"
#include "support/text.hpp"

namespace nhdyn {
namespace {

namespace fs = std::filesystem;

TEST(LargeEquations, PastAThousandCoordinatesIsRefusedWithTheWayOut) {
  const fs::path dir = fs::temp_directory_path() / ("nhdyn-large-eq-" + std::to_string(::getpid()));
  fs::create_directories(dir);
  const test::CliOutcome gen = test::run_nhdyn("example chain --bodies 334 -o chain.toml", dir);
  ASSERT_EQ(gen.exit_code, 0) << gen.out;
  // stdout and stderr to files of their own (run_nhdyn merges them)
  const std::string command = "cd '" + dir.string() + "' && '" + NHDYN_CLI_PATH + "' equations chain.toml >out.txt 2>err.txt";
  const int status = std::system(command.c_str());
  ASSERT_TRUE(WIFEXITED(status));
  EXPECT_EQ(WEXITSTATUS(status), 2);
  EXPECT_TRUE(test::read_text(dir / "out.txt").empty());
  const std::string err = test::read_text(dir / "err.txt");
  EXPECT_TRUE(test::contains(err, "'chain-334' has 1002 coordinates")) << err;
  EXPECT_TRUE(test::contains(err, "up to 1000 coordinates")) << err;
  EXPECT_TRUE(test::contains(err, "nhdyn codegen")) << err;
  fs::remove_all(dir);
}

}  // namespace
}  // namespace nhdyn
