// Output safety cases of issue 14 that tests/cli/output_safety_test.cpp leaves out: a character
// device named by -o (a copy of /dev/null, and /dev/stdout) is written straight, never replaced by
// a regular file; a model whose name is empty gets the default file name results/model.csv.
#include <gtest/gtest.h>

#include <unistd.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <string>

#include "nhdyn/io/atomic_file.hpp"
#include "support/cli_run.hpp"
#include "support/text.hpp"

namespace nhdyn {
namespace {

namespace fs = std::filesystem;
using nhdyn::test::contains;
using nhdyn::test::run_nhdyn;

class OutputDevices : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() / ("nhdyn-devices-" + std::to_string(::getpid()) + "-" +
                                        ::testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::remove_all(dir_);
    fs::create_directories(dir_);
    fs::copy_file(test::example("appell.toml"), dir_ / "appell.toml");
  }
  void TearDown() override { fs::remove_all(dir_); }
  fs::path dir_;
};

TEST_F(OutputDevices, ACopyOfDevNullStaysACharacterDevice) {
  // cp -a of a device node needs the right to make one (root); elsewhere there is nothing to test.
  const std::string copy = "cp -a /dev/null '" + (dir_ / "devnull").string() + "' 2> /dev/null";
  if (std::system(copy.c_str()) != 0 || !fs::is_character_file(dir_ / "devnull"))
    GTEST_SKIP() << "cannot make a device node here";
  const test::CliOutcome r = run_nhdyn("simulate appell.toml -q -o devnull", dir_);
  EXPECT_EQ(r.exit_code, 0) << r.out;
  EXPECT_TRUE(fs::is_character_file(dir_ / "devnull")) << "the device was replaced by a regular file";
  for (const auto& e : fs::directory_iterator(dir_))
    EXPECT_EQ(e.path().filename().string().find(".tmp"), std::string::npos) << e.path();
}

TEST_F(OutputDevices, DevStdoutGetsTheRows) {
  const test::CliOutcome r = run_nhdyn("simulate appell.toml -q -o /dev/stdout --t-end 0.1 | grep -v '^#' | head -1", dir_);
  EXPECT_TRUE(r.out.rfind("t,x,y,z,", 0) == 0) << r.out;
}

TEST_F(OutputDevices, AnEmptyNameGetsTheDefaultFileName) {
  std::string text = test::read_text(dir_ / "appell.toml");
  const std::size_t at = text.find("\nname = \"");
  ASSERT_NE(at, std::string::npos);
  text.replace(at + 1, text.find('\n', at + 1) - at - 1, "name = \"\"");
  std::ofstream(dir_ / "nameless.toml") << text;
  const test::CliOutcome r = run_nhdyn("simulate nameless.toml -q --t-end 0.1", dir_);
  EXPECT_EQ(r.exit_code, 0) << r.out;
  EXPECT_TRUE(fs::is_regular_file(dir_ / "results/model.csv")) << r.out;
  EXPECT_EQ(make_file_name(""), "model");
  EXPECT_EQ(make_file_name("a b/c"), "a_b_c");
  EXPECT_EQ(make_file_name("../../escape").find('/'), std::string::npos);
}

// A command's files appear together or not at all (apps/nhdyn/run_files.hpp): when the last one
// cannot be written whole (here a link to /dev/full, a device written straight, which refuses
// every byte with ENOSPC at its flush), the ones before it are not renamed into place either.
TEST_F(OutputDevices, SimulateLeavesNoCsvWhenItsEventsFileIsFull) {
  fs::create_symlink("/dev/full", dir_ / "run-events.csv");
  const test::CliOutcome r = run_nhdyn("simulate appell.toml -q --t-end 0.1 --event half=t-0.05 -o run.csv", dir_);
  EXPECT_EQ(r.exit_code, 2) << r.out;
  EXPECT_TRUE(contains(r.out, "writing 'run-events.csv' failed: No space left on device")) << r.out;
  EXPECT_FALSE(fs::exists(dir_ / "run.csv")) << "the rows appeared without their events file";
  for (const auto& e : fs::directory_iterator(dir_))
    EXPECT_EQ(e.path().filename().string().find(".tmp"), std::string::npos) << e.path();
  // With room for both, both appear.
  fs::remove(dir_ / "run-events.csv");
  const test::CliOutcome ok = run_nhdyn("simulate appell.toml -q --t-end 0.1 --event half=t-0.05 -o run.csv", dir_);
  EXPECT_EQ(ok.exit_code, 0) << ok.out;
  EXPECT_TRUE(fs::is_regular_file(dir_ / "run.csv") && fs::is_regular_file(dir_ / "run-events.csv")) << ok.out;
}

TEST_F(OutputDevices, CompareLeavesNoSeriesWhenItsTableIsFull) {
  // compare finishes its series CSV first, then the table (-o), which cannot be written.
  fs::create_symlink("/dev/full", dir_ / "table.csv");
  const test::CliOutcome r = run_nhdyn("compare appell.toml -q --t-end 0.1 -o table.csv", dir_);
  EXPECT_EQ(r.exit_code, 2) << r.out;
  EXPECT_TRUE(contains(r.out, "writing 'table.csv' failed: No space left on device")) << r.out;
  EXPECT_FALSE(fs::exists(dir_ / "table-series.csv")) << "the series appeared without its table";
}

}  // namespace
}  // namespace nhdyn
