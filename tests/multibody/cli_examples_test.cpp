// The multibody examples run from the command line as docs/multibody.md says:
// `nhdyn simulate examples/<name>.toml -o FILE.csv` exits 0 and writes the model's coordinates.
#include <gtest/gtest.h>
#include <unistd.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <string>
#include <utility>

namespace {

namespace fs = std::filesystem;

TEST(MultibodyCli, TheExamplesRunFromTheCommandLine) {
  const fs::path dir = fs::temp_directory_path() / ("nhdyn-multibody-" + std::to_string(::getpid()));
  fs::create_directories(dir);
  const std::pair<std::string, std::string> examples[] = {
      {"rolling_disk_bodies", "t,x,y,psi,theta,phi,"},
      {"whipple_bicycle", "t,x,y,psi,phi,theta,delta,thetaR,thetaF,"}};
  for (const auto& [name, header] : examples) {
    const fs::path csv = dir / (name + ".csv");
    const std::string command = std::string("'") + NHDYN_CLI_PATH + "' simulate '" + NHDYN_SOURCE_DIR +
                                "/examples/" + name + ".toml' --t-end 0.5 --output-step 0.1 -q -o '" +
                                csv.string() + "'";
    EXPECT_EQ(std::system(command.c_str()), 0) << command;
    std::ifstream in(csv);
    std::string line;
    ASSERT_TRUE(std::getline(in, line)) << csv;
    EXPECT_EQ(line.rfind(header, 0), 0u) << line;
    int rows = 0;
    while (std::getline(in, line)) ++rows;
    EXPECT_EQ(rows, 6) << name;  // t = 0, 0.1, ..., 0.5
  }
  fs::remove_all(dir);
}

}  // namespace
