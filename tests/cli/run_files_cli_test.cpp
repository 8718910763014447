// The files of a run (apps/nhdyn/run_files.hpp) in the commands besides simulate, whose cases
// tests/cli/output_safety_test.cpp tries: a compare whose reference run fails, and one interrupted
// mid-run, leave an existing table as it was and no file of their own (no series, no temporary);
// a --plot into a folder that does not exist is refused before any run by compare and the studies,
// as by simulate (it used to be found only after the runs, once the tables were written).
#include <gtest/gtest.h>
#include <signal.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include "support/cli_process.hpp"
#include "support/text.hpp"

namespace {

namespace fs = std::filesystem;
using nhdyn::test::contains;
using nhdyn::test::ProcessOptions;
using nhdyn::test::ProcessRun;
using nhdyn::test::read_whole;
using nhdyn::test::run_process;

class RunFilesCli : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() / ("nhdyn-run-files-" + std::to_string(::getpid()) + "-" +
                                        ::testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::remove_all(dir_);
    fs::create_directories(dir_ / "out");
    for (const char* name : {"sled.toml", "appell.toml"})
      fs::copy_file(fs::path(NHDYN_SOURCE_DIR) / "examples" / name, dir_ / name);
    // An attracting pole at x = 1: the particle reaches it at t = pi/(2 sqrt 2) = 1.1107, where
    // every integrator's step underflows.
    std::ofstream(dir_ / "blow.toml") << "name = \"blow-up\"\ncoordinates = [\"x\"]\nkinetic_energy = \"x'^2/2\"\n"
                                         "potential_energy = \"-1/(1 - x)\"\n[initial]\nposition = { x = 0 }\n"
                                         "velocity = { x = 0 }\n";
    std::ofstream(dir_ / "out" / "c.csv") << "an earlier table\n";
  }
  void TearDown() override { fs::remove_all(dir_); }
  ProcessRun nhdyn(const std::vector<std::string>& args, const ProcessOptions& options = {}) const {
    return run_process(args, dir_, options);
  }
  // out/ holds the earlier table, unchanged, and nothing else.
  void expect_out_untouched(const std::string& what) const {
    EXPECT_EQ(read_whole(dir_ / "out" / "c.csv"), "an earlier table\n") << what;
    for (const auto& entry : fs::directory_iterator(dir_ / "out"))
      EXPECT_EQ(entry.path().filename(), "c.csv") << what << ": left " << entry.path();
  }
  fs::path dir_;
};

TEST_F(RunFilesCli, CompareWhoseReferenceFailsLeavesNothing) {
  const ProcessRun r = nhdyn({"compare", "blow.toml", "--t-end", "5", "-q", "-o", "out/c.csv"});
  EXPECT_EQ(r.code, 2) << r.err;
  EXPECT_TRUE(contains(r.err, "the reference run (sanh, dopri5, rtol 1e-13) failed at t = 1.11")) << r.err;
  expect_out_untouched("a failed reference");
}

TEST_F(RunFilesCli, InterruptedCompareLeavesNothing) {
  fs::create_directories(dir_ / "run");
  ProcessOptions options;
  options.signal = SIGINT;
  options.after = std::chrono::milliseconds(300);
  options.signal_when_written = dir_ / "run";  // once the table's and the series' temporaries are there
  options.deadline = 60;
  const ProcessRun r =
      nhdyn({"compare", "sled.toml", "--t-end", "10000", "--methods", "sanh", "-q", "-o", "run/c.csv"}, options);
  EXPECT_EQ(r.code, 128 + SIGINT) << r.err;
  EXPECT_TRUE(contains(r.err, "interrupted by SIGINT")) << r.err;
  EXPECT_TRUE(fs::is_empty(dir_ / "run"));
}

TEST_F(RunFilesCli, APlotIntoAMissingFolderIsRefusedBeforeAnyRun) {
  const std::vector<std::vector<std::string>> commands{
      {"compare", "sled.toml", "--t-end", "0.2", "-q", "-o", "out/c.csv", "--plot", "nodir/c.png"},
      {"study", "error-relation", "appell.toml", "--tolerances", "1e-3", "-q", "-o", "out/c.csv", "--plot",
       "nodir/e.png"},
  };
  for (const std::vector<std::string>& args : commands) {
    const ProcessRun r = nhdyn(args);
    EXPECT_EQ(r.code, 2) << args[0] << ": " << r.err;
    EXPECT_TRUE(contains(r.err, "nodir") || contains(r.err, "gnuplot")) << r.err;
    EXPECT_FALSE(fs::exists(dir_ / "nodir")) << args[0];
    expect_out_untouched(args[0] + " --plot nodir/");
  }
}

}  // namespace
