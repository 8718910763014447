// `nhdyn simulate --initial NAME=EXPR` (model/initial_values.hpp, docs/cli.md "Initial values"):
// the run starts from the values given, checked against the closed form of the sled with its
// centre of mass on the blade on a level plane (a = 0, alpha = 0: phi' and the speed stay, the
// path is a circle of radius v / phi'), and every bad input is refused with exit code 2.
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include "support/cli_run.hpp"

namespace fs = std::filesystem;

namespace {

class InitialValuesCli : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() /
           ("nhdyn_initial_" + std::string(::testing::UnitTest::GetInstance()->current_test_info()->name()));
    fs::remove_all(dir_);
    fs::create_directories(dir_);
  }
  void TearDown() override { fs::remove_all(dir_); }
  // The rows of a CSV after its '#' lines and its header.
  std::vector<std::vector<double>> rows(const std::string& name) const {
    std::ifstream in(dir_ / name);
    std::string line;
    while (std::getline(in, line) && line.starts_with('#')) {
    }
    std::vector<std::vector<double>> out;
    while (std::getline(in, line)) {
      std::stringstream cells(line);
      std::vector<double>& row = out.emplace_back();
      for (std::string cell; std::getline(cells, cell, ',');) row.push_back(std::stod(cell));
    }
    return out;
  }
  fs::path dir_;
};

TEST_F(InitialValuesCli, TheRunStartsFromTheGivenValues) {
  const nhdyn::test::CliOutcome r = nhdyn::test::run_nhdyn(
      "simulate sled --set a=0 --set alpha=0 --initial \"phi'=0.5\" --initial \"x'=2\" --t-end 1 --rtol 1e-12 "
      "--atol 1e-12 -q -o c.csv",
      dir_);
  ASSERT_EQ(r.exit_code, 0) << r.out;
  const auto table = rows("c.csv");
  ASSERT_EQ(table.size(), 101u);
  // t, x, y, phi, x', y', phi'
  EXPECT_EQ(table.front()[4], 2.0);
  EXPECT_EQ(table.front()[6], 0.5);
  const std::vector<double>& last = table.back();
  const double v = 2.0, w = 0.5, t = 1.0;
  EXPECT_NEAR(last[1], v / w * std::sin(w * t), 1e-9);
  EXPECT_NEAR(last[2], v / w * (1 - std::cos(w * t)), 1e-9);
  EXPECT_NEAR(last[3], w * t, 1e-9);
  // Batch's spelling x'(0), and an expression in the parameters: phi' = g / (2 * 9.81) = 0.5 exactly.
  const nhdyn::test::CliOutcome same = nhdyn::test::run_nhdyn(
      "simulate sled --set a=0 --set alpha=0 --initial \"phi'(0)=g/(2*9.81)\" --initial \"x'=2\" --t-end 1 --rtol 1e-12 "
      "--atol 1e-12 -q -o d.csv",
      dir_);
  ASSERT_EQ(same.exit_code, 0) << same.out;
  EXPECT_EQ(rows("d.csv"), table);
}

TEST_F(InitialValuesCli, BadInputIsRefusedSayingWhich) {
  const struct {
    const char* initial;
    const char* message;
  } cases[] = {
      {"psi'=0.5", "--initial 'psi'=0.5': 'psi' is not a coordinate of model 'sled' (did you mean 'phi''?); its "
                   "coordinates are x, y, phi"},
      {"phi'", "--initial 'phi'': write it as NAME=VALUE"},
      {"=1", "--initial '=1': write it as NAME=VALUE"},
      {"phi'=foo", "--initial 'phi'=foo': "},
      {"phi'=1/0", "--initial 'phi'=1/0': '1/0' has no finite value: it divides by zero"},
      {"y'=1", "blade (velocity level): residual 1"},
  };
  for (const auto& c : cases) {
    const nhdyn::test::CliOutcome r =
        nhdyn::test::run_nhdyn(std::string("simulate sled --t-end 1 -q -o x.csv --initial \"") + c.initial + "\"", dir_);
    EXPECT_EQ(r.exit_code, 2) << c.initial << ": " << r.out;
    EXPECT_NE(r.out.find(c.message), std::string::npos) << c.initial << ": " << r.out;
    EXPECT_FALSE(fs::exists(dir_ / "x.csv")) << c.initial;
  }
  // y' = 1 breaks the blade at phi = 0; --fix-initial moves it back and says so.
  const nhdyn::test::CliOutcome fixed =
      nhdyn::test::run_nhdyn("simulate sled --t-end 1 -o x.csv --initial \"y'=1\" --fix-initial", dir_);
  EXPECT_EQ(fixed.exit_code, 0) << fixed.out;
  EXPECT_NE(fixed.out.find("    y' = 0 (changed by -1)"), std::string::npos) << fixed.out;
}

}  // namespace
