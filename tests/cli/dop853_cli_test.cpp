// `--integrator dop853` end to end: the built binary (NHDYN_CLI_PATH) compares dop853 with dopri5
// on the knife edge of examples/knife_edge.toml against its closed-form [solution]
// (`nhdyn compare --reference analytic`): dop853 meets the tolerance's accuracy with far fewer
// right-hand sides.
#include <gtest/gtest.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <map>
#include <sstream>
#include <string>
#include <vector>
#include "support/text.hpp"

namespace {

namespace fs = std::filesystem;

using nhdyn::test::split;

TEST(CliDop853, KnifeEdgeMatchesItsClosedFormWithFewerRhsThanDopri5) {
  const fs::path dir =
      fs::temp_directory_path() / ("nhdyn-dop853-cli-" + std::to_string(::getpid()));
  fs::remove_all(dir);
  fs::create_directories(dir);
  const std::string model = std::string(NHDYN_SOURCE_DIR) + "/examples/knife_edge.toml";
  const std::string command = "cd '" + dir.string() + "' && '" NHDYN_CLI_PATH "' compare '" +
                              model +
                              "' --reference analytic --methods sanh --integrators dopri5,dop853 "
                              "--rtol 1e-12 --atol 1e-14 -q -o table.csv > out.txt 2> err.txt";
  const int status = std::system(command.c_str());
  ASSERT_TRUE(WIFEXITED(status) && WEXITSTATUS(status) == 0) << command;

  std::istringstream in(nhdyn::test::csv_body(nhdyn::test::read_text(dir / "table.csv")));  // after the provenance
  std::string line;
  ASSERT_TRUE(std::getline(in, line));
  const std::vector<std::string> header = split(line);
  std::map<std::string, std::map<std::string, std::string>> rows;  // integrator -> column -> value
  while (std::getline(in, line)) {
    const std::vector<std::string> fields = split(line);
    ASSERT_EQ(fields.size(), header.size()) << line;
    for (std::size_t i = 0; i < header.size(); ++i) rows[fields[1]][header[i]] = fields[i];
  }
  fs::remove_all(dir);
  ASSERT_EQ(rows.count("dop853"), 1u);
  ASSERT_EQ(rows.count("dopri5"), 1u);
  const auto& dop853 = rows["dop853"];
  EXPECT_EQ(dop853.at("status"), "ok");
  // Against the file's exact motion (the skate on the inclined plane, docs/gallery/knife_edge.md),
  // over its 10 s: within 1000 times the tolerance, the bound the Kepler exams use (4e-11 here).
  EXPECT_LT(std::stod(dop853.at("max_error_q")), 1e-9);
  EXPECT_LT(std::stod(dop853.at("max_error_v")), 1e-9);
  // About 4 times fewer right-hand sides than dopri5 at rtol 1e-12.
  EXPECT_LT(3.0 * std::stod(dop853.at("rhs_evaluations")),
            std::stod(rows["dopri5"].at("rhs_evaluations")));
}

}  // namespace
