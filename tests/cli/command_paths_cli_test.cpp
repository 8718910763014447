// The one rule for a command's files (docs/cli.md, "One rule for the files of a command") in the
// commands besides simulate, report and batch: compare, sweep, study, linearize and codegen refuse,
// with exit code 2 and before any work, an output that is the model file (by name, a symbolic link
// or a hard link) and two outputs that are one file, naming both; the files are left as they were.
#include <gtest/gtest.h>
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
using nhdyn::test::ProcessRun;
using nhdyn::test::read_whole;
using nhdyn::test::run_process;

class CommandPaths : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() / ("nhdyn-command-paths-" + std::to_string(::getpid()) + "-" +
                                        ::testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::remove_all(dir_);
    fs::create_directories(dir_);
    for (const char* name : {"sled.toml", "appell.toml", "rolling_disk_upright.toml", "spread_masses.toml",
                             "sled_heading_program.toml"})
      fs::copy_file(fs::path(NHDYN_SOURCE_DIR) / "examples" / name, dir_ / name);
    fs::create_symlink("sled.toml", dir_ / "sled-link.toml");
    fs::create_hard_link(dir_ / "sled.toml", dir_ / "sled-hard.toml");
  }
  void TearDown() override { fs::remove_all(dir_); }
  ProcessRun nhdyn(const std::vector<std::string>& args) const { return run_process(args, dir_); }
  // The run is refused with exit code 2, its message names both files, and nothing was written.
  void expect_refused(const std::vector<std::string>& args, const std::string& first, const std::string& second,
                      const std::string& kind) const {
    const std::string before = read_whole(dir_ / "sled.toml");
    const ProcessRun r = nhdyn(args);
    std::string line;
    for (const std::string& a : args) line += a + " ";
    EXPECT_EQ(r.code, 2) << line << "\n" << r.err;
    EXPECT_TRUE(contains(r.err, kind)) << line << "\n" << r.err;
    EXPECT_TRUE(contains(r.err, first)) << line << "\n" << r.err;
    EXPECT_TRUE(contains(r.err, second)) << line << "\n" << r.err;
    EXPECT_EQ(read_whole(dir_ / "sled.toml"), before) << line;
    for (const auto& entry : fs::directory_iterator(dir_))
      EXPECT_FALSE(entry.path().extension() == ".csv" || entry.path().extension() == ".png" ||
                   entry.path().extension() == ".hpp")
          << line << ": wrote " << entry.path();
  }
  fs::path dir_;
};

constexpr const char* kIsAnInput = "an input of this run";
constexpr const char* kIsSameFile = "are the same file";

TEST_F(CommandPaths, Compare) {
  expect_refused({"compare", "sled.toml", "--t-end", "0.2", "-o", "./sled.toml"}, "the model file 'sled.toml'",
                 "'./sled.toml'", kIsAnInput);
  expect_refused({"compare", "sled.toml", "--t-end", "0.2", "-o", "sled-link.toml"}, "the model file 'sled.toml'",
                 "the table CSV 'sled-link.toml'", kIsAnInput);
  // The series CSV goes beside the table: c.csv -> c-series.csv; --plot onto it.
  expect_refused({"compare", "sled.toml", "--t-end", "0.2", "-o", "c.csv", "--plot", "c-series.csv"},
                 "the series CSV 'c-series.csv'", "--plot 'c-series.csv'", kIsSameFile);
}

TEST_F(CommandPaths, Sweep) {
  const std::vector<std::string> sweep{"sweep", "rolling_disk_upright.toml", "--cyclic", "psi", "--param", "w",
                                       "--from", "1", "--to", "2", "--steps", "2"};
  auto with = [&](std::vector<std::string> more) {
    std::vector<std::string> args = sweep;
    args.insert(args.end(), more.begin(), more.end());
    return args;
  };
  expect_refused(with({"-o", "rolling_disk_upright.toml"}), "the model file",
                 "the eigenvalue CSV 'rolling_disk_upright.toml'", kIsAnInput);
  expect_refused(with({"-o", "s.csv", "--plot", "./s-crossings.csv"}), "the crossings CSV 's-crossings.csv'",
                 "--plot './s-crossings.csv'", kIsSameFile);
}

TEST_F(CommandPaths, Study) {
  expect_refused({"study", "error-relation", "appell.toml", "-o", "appell.toml"}, "the model file", "appell.toml",
                 kIsAnInput);
  expect_refused({"study", "error-relation", "appell.toml", "-o", "e.csv", "--plot", "e-by-tolerance.csv"},
                 "the by-tolerance CSV 'e-by-tolerance.csv'", "--plot", kIsSameFile);
  expect_refused({"study", "tracking", "sled_heading_program.toml", "-o", "t.csv", "--plot", "t.csv"},
                 "the table CSV 't.csv'", "--plot 't.csv'", kIsSameFile);
  // The plot of R goes beside the plot of q'': p.png -> p-reactions.png.
  expect_refused({"study", "spread-masses", "spread_masses.toml", "--plot", "p.png", "-o", "p-reactions.png"},
                 "the table CSV 'p-reactions.png'", "the reactions plot", kIsSameFile);
  expect_refused({"study", "spread-masses", "spread_masses.toml", "-o", "spread_masses.toml"}, "the model file",
                 "the table CSV", kIsAnInput);
}

TEST_F(CommandPaths, Linearize) {
  expect_refused({"linearize", "rolling_disk_upright.toml", "--cyclic", "psi", "-o", "./rolling_disk_upright.toml"},
                 "the model file", "-o './rolling_disk_upright.toml'", kIsAnInput);
}

TEST_F(CommandPaths, Codegen) {
  expect_refused({"codegen", "sled.toml", "-o", "sled-hard.toml"}, "the model file 'sled.toml'",
                 "-o 'sled-hard.toml'", kIsAnInput);
  expect_refused({"codegen", "sled-link.toml", "-o", "sled.toml"}, "the model file 'sled-link.toml'",
                 "-o 'sled.toml'", kIsAnInput);
  // A distinct output is written as before.
  const ProcessRun ok = nhdyn({"codegen", "sled.toml", "-o", "sled.hpp"});
  EXPECT_EQ(ok.code, 0) << ok.err;
  EXPECT_TRUE(fs::exists(dir_ / "sled.hpp"));
}

}  // namespace
