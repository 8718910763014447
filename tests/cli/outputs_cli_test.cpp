// Derived outputs end to end (docs/model-format.md [outputs], docs/multibody.md "Positions and
// velocities"): the built binary (NHDYN_CLI_PATH) writes each output as a column after the
// standard ones, --set changes the parameters an output reads, --stop-when may name an output,
// a multibody model's points and frame origins are columns without a word written, and bad
// outputs (an unknown symbol, a name taken by another column, an expression that does not parse)
// are refused with exit 2 before anything is written.
#include <gtest/gtest.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include "nhdyn/io/csv.hpp"
#include "support/text.hpp"

namespace {

namespace fs = std::filesystem;

struct OutputsOutcome {
  int exit_code = -1;
  std::string out, err;
};

using nhdyn::test::read_text;

const std::string examples = std::string(NHDYN_SOURCE_DIR) + "/examples/";

class CliOutputs : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() /
           ("nhdyn-outputs-cli-" + std::to_string(::getpid()) + "-" +
            ::testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::remove_all(dir_);
    fs::create_directories(dir_);
  }
  void TearDown() override { fs::remove_all(dir_); }

  OutputsOutcome nhdyn(const std::string& args) const {
    const std::string command =
        "cd '" + dir_.string() + "' && '" NHDYN_CLI_PATH "' " + args + " > out.txt 2> err.txt";
    const int status = std::system(command.c_str());
    OutputsOutcome run;
    run.exit_code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
    run.out = read_text(dir_ / "out.txt");
    run.err = read_text(dir_ / "err.txt");
    return run;
  }

  // examples/pendulum_cartesian.toml with an [outputs] table appended; returns its path.
  std::string pendulum_with(const std::string& outputs) const {
    const fs::path path = dir_ / "p.toml";
    std::ofstream(path) << read_text(examples + "pendulum_cartesian.toml") << "\n[outputs]\n" << outputs;
    return path.string();
  }

  fs::path dir_;
};

TEST_F(CliOutputs, ColumnsAfterTheStandardOnesAndParametersAsData) {
  // The first command of examples/pendulum_outputs.toml.
  OutputsOutcome run = nhdyn("simulate " + examples + "pendulum_outputs.toml -q -o r.csv");
  ASSERT_EQ(run.exit_code, 0) << run.err;
  const nhdyn::CsvTable table = nhdyn::load_csv(dir_ / "r.csv");
  const std::vector<std::string> outputs = {"total_energy", "tension", "tension_closed_form", "theta", "speed"};
  ASSERT_GE(table.header.size(), outputs.size());
  EXPECT_EQ(std::vector<std::string>(table.header.end() - 5, table.header.end()), outputs);
  EXPECT_GE(table.column("balance_error"), 0);  // the standard columns are all there, before
  // The slack event's rows are in the CSV and FILE-events.csv.
  EXPECT_NE(read_text(dir_ / "r-events.csv").find("slack,"), std::string::npos);
  const int E = table.column("total_energy"), N = table.column("tension"), y = table.column("y");
  const double m = 0.5, g = 9.81, l = 1.5, theta0 = 2.0;
  for (const std::vector<double>& row : table.rows) {
    EXPECT_NEAR(row[static_cast<std::size_t>(E)], -m * g * l * std::cos(theta0), 1e-7);
    EXPECT_NEAR(row[static_cast<std::size_t>(N)], m * g * (3 * -row[static_cast<std::size_t>(y)] / l - 2 * std::cos(theta0)),
                1e-6);
  }
  // --set m=2: the outputs read the new mass (a parameter is data, no recompilation).
  run = nhdyn("simulate " + examples + "pendulum_outputs.toml --set m=2 --t-end 0.5 -q -o r2.csv");
  ASSERT_EQ(run.exit_code, 0) << run.err;
  const nhdyn::CsvTable heavy = nhdyn::load_csv(dir_ / "r2.csv");
  EXPECT_NEAR(heavy.rows.front()[static_cast<std::size_t>(heavy.column("total_energy"))], -2 * g * l * std::cos(theta0),
              1e-12);
  // --stop-when on an output: the run ends where the speed reaches 4 m/s.
  run = nhdyn("simulate " + examples + "pendulum_outputs.toml --stop-when 'speed > 4' -q -o r3.csv");
  ASSERT_EQ(run.exit_code, 0) << run.err;
  const nhdyn::CsvTable stopped = nhdyn::load_csv(dir_ / "r3.csv");
  EXPECT_NEAR(stopped.rows.back()[static_cast<std::size_t>(stopped.column("speed"))], 4.0, 1e-9);
}

TEST_F(CliOutputs, MultibodyPointsAreColumns) {
  const OutputsOutcome run = nhdyn("simulate " + examples + "rolling_disk_bodies.toml --t-end 0.5 -q -o d.csv");
  ASSERT_EQ(run.exit_code, 0) << run.err;
  const nhdyn::CsvTable table = nhdyn::load_csv(dir_ / "d.csv");
  const int z = table.column("disk_z"), theta = table.column("theta");
  ASSERT_GE(z, 0);
  ASSERT_GE(table.column("disk_vx"), 0);
  EXPECT_EQ(table.column("lean_x"), -1);  // turns about the heading's origin: no columns of its own
  for (const std::vector<double>& row : table.rows)
    EXPECT_NEAR(row[static_cast<std::size_t>(z)], 0.2 * std::cos(row[static_cast<std::size_t>(theta)]), 1e-13);
}

TEST_F(CliOutputs, BadOutputsAreRefusedBeforeTheRun) {
  struct Case {
    std::string outputs;
    std::vector<std::string> said;
  };
  const std::vector<Case> cases = {
      {"E = \"m*gg*y\"\n", {"p.toml:", ":8: unknown symbol 'gg'; did you mean 'g'?"}},
      {"energy = \"x\"\n", {"output 'energy' is named like the results' column 'energy'"}},
      {"R_y = \"x\"\n", {"output 'R_y'", "reaction on 'y'"}},
      {"E = \"x +\"\n", {"p.toml:", "syntax error"}},
      {"E = \"sin(x\"\n", {"p.toml:", "syntax error"}},
  };
  for (const Case& c : cases) {
    const OutputsOutcome run = nhdyn("simulate " + pendulum_with(c.outputs) + " -o r.csv");
    EXPECT_EQ(run.exit_code, 2) << c.outputs << "\n" << run.err;
    for (const std::string& s : c.said) EXPECT_NE(run.err.find(s), std::string::npos) << c.outputs << "\n" << run.err;
    EXPECT_FALSE(fs::exists(dir_ / "r.csv")) << c.outputs;
  }
  // An event or a --stop-when naming an unknown output.
  const OutputsOutcome run = nhdyn("simulate " + examples + "pendulum_outputs.toml --stop-when 'sped > 4' -o r.csv");
  EXPECT_EQ(run.exit_code, 2) << run.err;
  EXPECT_NE(run.err.find("did you mean 'speed'?"), std::string::npos) << run.err;
}

}  // namespace
