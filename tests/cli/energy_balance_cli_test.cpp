// The energy balance end to end (docs/derivations/energy-balance.md, docs/cli.md "The summary"):
// `nhdyn simulate examples/isokinetic.toml`, whose constraint does work, prints the balance error
// as the accuracy figure, the work by agent and the change of E (no "energy drift"), and the
// summary's figures are those of the CSV's columns.
#include <gtest/gtest.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <regex>
#include <sstream>
#include <string>
#include <vector>
#include "support/text.hpp"

namespace {

namespace fs = std::filesystem;

using nhdyn::test::split;

using nhdyn::test::read_text;

TEST(CliEnergyBalance, TheSummaryReportsTheBalanceAsErrorAndTheWorkAsPhysics) {
  const fs::path dir = fs::temp_directory_path() / ("nhdyn-energy-cli-" + std::to_string(::getpid()));
  fs::remove_all(dir);
  fs::create_directories(dir);
  const std::string model = std::string(NHDYN_SOURCE_DIR) + "/examples/isokinetic.toml";
  const std::string command = "cd '" + dir.string() + "' && '" NHDYN_CLI_PATH "' simulate '" + model +
                              "' -o iso.csv > out.txt 2> err.txt";
  const int status = std::system(command.c_str());
  ASSERT_TRUE(WIFEXITED(status) && WEXITSTATUS(status) == 0) << command << read_text(dir / "err.txt");
  const std::string out = read_text(dir / "out.txt");

  std::ifstream in(dir / "iso.csv");
  std::string line;
  while (std::getline(in, line) && line.starts_with('#')) {
  }  // the provenance header (io/provenance.hpp)
  ASSERT_FALSE(line.empty());
  const std::vector<std::string> header = split(line);
  const auto column = [&](const std::string& name) {
    return static_cast<std::size_t>(std::find(header.begin(), header.end(), name) - header.begin());
  };
  const std::size_t balance = column("balance_error"), work = column("work"), energy = column("energy");
  const std::size_t reactions = column("work_reactions");
  ASSERT_LT(std::max({balance, work, energy, reactions}), header.size()) << line;
  double largest = 0.0, E0 = 0.0, E = 0.0, W = 0.0, WR = 0.0;
  for (bool first = true; std::getline(in, line); first = false) {
    const std::vector<std::string> fields = split(line);
    ASSERT_EQ(fields.size(), header.size());
    largest = std::max(largest, std::abs(std::stod(fields[balance])));
    E = std::stod(fields[energy]);
    if (first) E0 = E;
    W = std::stod(fields[work]);
    WR = std::stod(fields[reactions]);
  }
  fs::remove_all(dir);

  EXPECT_EQ(out.find("energy drift"), std::string::npos) << out;
  std::smatch m;
  ASSERT_TRUE(std::regex_search(out, m, std::regex(R"(energy balance error: (\S+) )"))) << out;
  EXPECT_NEAR(std::stod(m[1]), largest, 0.006 * largest);
  EXPECT_LT(largest, 1e-8);
  ASSERT_TRUE(std::regex_search(out, m, std::regex(R"(work W: (\S+) \(forces (\S+), reactions (\S+), explicit time (\S+)\))")))
      << out;
  EXPECT_NEAR(std::stod(m[1]), W, 1e-9 * std::abs(W));
  EXPECT_EQ(std::stod(m[2]), 0.0);
  EXPECT_NEAR(std::stod(m[3]), WR, 1e-5 * std::abs(WR));
  EXPECT_EQ(std::stod(m[4]), 0.0);
  ASSERT_TRUE(std::regex_search(out, m, std::regex(R"(energy change: E - E0 = (\S+) \(E0 = (\S+)\))"))) << out;
  EXPECT_NEAR(std::stod(m[1]), E - E0, 1e-9 * std::abs(E - E0));
  EXPECT_LT(E - E0, -10.0);  // the particle falls: the change of E is physics, orders above the error
}

}  // namespace
