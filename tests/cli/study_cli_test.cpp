// End-to-end tests of `nhdyn study spread-masses`: the built binary (NHDYN_CLI_PATH) runs a small
// study in a fresh temporary directory; its table, CSV (columns and values) and plots are checked,
// and bad input is refused with exit code 2, a message naming the value, and no file written.
#include <gtest/gtest.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
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

struct Result {
  int exit_code = -1;
  std::string out, err;
};

using nhdyn::test::read_text;

// A fresh directory per test, removed afterwards.
class StudyCli : public ::testing::Test {
 protected:
  void SetUp() override {
    const auto* info = ::testing::UnitTest::GetInstance()->current_test_info();
    dir_ = fs::temp_directory_path() / (std::string("nhdyn-study-cli-") + info->name() + "-" + std::to_string(::getpid()));
    fs::remove_all(dir_);
    fs::create_directories(dir_);
  }
  void TearDown() override { fs::remove_all(dir_); }

  // Runs `nhdyn ARGS` in the test's directory (arguments are single-quoted for the shell).
  Result nhdyn(const std::vector<std::string>& args) const {
    std::string command = "cd '" + dir_.string() + "' && '" NHDYN_CLI_PATH "'";
    for (const std::string& a : args) command += " '" + a + "'";
    command += " > out.txt 2> err.txt";
    const int status = std::system(command.c_str());
    Result r;
    r.exit_code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
    r.out = read_text(dir_ / "out.txt");
    r.err = read_text(dir_ / "err.txt");
    return r;
  }

  fs::path dir_;
};

const std::string kModel = NHDYN_SOURCE_DIR "/examples/spread_masses.toml";

TEST_F(StudyCli, SpreadMassesWritesTableCsvAndPlots) {
  const Result r = nhdyn({"study", "spread-masses", kModel, "--ratios", "1,1e6,1e12", "--samples", "2", "-o",
                          "out/spread.csv", "--plot", "out/spread.png"});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.out.find("relative error of q''"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("relative error of R"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("udwadia-kalaba"), std::string::npos) << r.out;
  const nhdyn::CsvTable csv = nhdyn::load_csv(dir_ / "out/spread.csv");
  ASSERT_EQ(csv.rows.size(), 3u);
  const int ratio = csv.column("ratio");
  const int sanh = csv.column("error_qdd_sanh-qr");
  const int uk = csv.column("error_R_udwadia-kalaba");
  ASSERT_GE(ratio, 0);
  ASSERT_GE(sanh, 0);
  ASSERT_GE(uk, 0);
  EXPECT_GE(csv.column("solve_error_qdd_nullspace"), 0);
  EXPECT_GE(csv.column("residual_acc_sanh-analytic"), 0);
  EXPECT_EQ(csv.rows[2][static_cast<std::size_t>(ratio)], 1e12);
  // The study's finding at this size (tests/studies/spread_masses_test.cpp has the margins).
  EXPECT_LT(csv.rows[0][static_cast<std::size_t>(sanh)], 1e-14);
  EXPECT_GT(csv.rows[2][static_cast<std::size_t>(sanh)], 1e-13);
  EXPECT_LT(csv.rows[2][static_cast<std::size_t>(uk)], 1e-6);
  EXPECT_GT(fs::file_size(dir_ / "out/spread.png"), 1000u);
  EXPECT_GT(fs::file_size(dir_ / "out/spread-reactions.png"), 1000u);
}

TEST_F(StudyCli, SpreadMassesRefusesBadInput) {
  struct Case {
    std::vector<std::string> args;
    std::string needle;
  };
  const std::vector<Case> cases{
      {{"--ratios", "1,-3"}, "-3"},
      {{"--ratios", "0"}, "0 is not a positive number"},
      {{"--ratios", "1,inf"}, "inf"},
      {{"--samples", "0"}, "--samples 0"},
      {{"--digits", "12"}, "--digits 12"},
      {{"--parameter", "mu"}, "no parameter 'mu'"},
  };
  for (const Case& c : cases) {
    std::vector<std::string> args{"study", "spread-masses", kModel, "-o", "bad.csv"};
    args.insert(args.end(), c.args.begin(), c.args.end());
    const Result r = nhdyn(args);
    EXPECT_EQ(r.exit_code, 2) << c.needle << "\n" << r.out << r.err;
    EXPECT_NE(r.err.find(c.needle), std::string::npos) << r.err;
    EXPECT_FALSE(fs::exists(dir_ / "bad.csv")) << c.needle;
  }
  // A model without the parameter, and a built-in model (no symbolic form).
  Result r = nhdyn({"study", "spread-masses", NHDYN_SOURCE_DIR "/examples/appell.toml", "-o", "bad.csv"});
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.err.find("model 'appell' has no parameter 'ratio'"), std::string::npos) << r.err;
  r = nhdyn({"study", "spread-masses", "sled", "-o", "bad.csv"});
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.err.find("examples/sled.toml"), std::string::npos) << r.err;
  EXPECT_FALSE(fs::exists(dir_ / "bad.csv"));
}

TEST_F(StudyCli, ErrorRelationWritesTableByToleranceAndPlot) {
  const Result r = nhdyn({"study", "error-relation", "appell", "--tolerances", "1e-3,1e-6", "--methods",
                          "sanh-qr,lagrange", "--integrators", "dopri5,cvode-bdf", "-o", "out/er.csv", "--plot",
                          "out/er.png"});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.out.find("the model's exact solution"), std::string::npos) << r.out;
  const std::string table = nhdyn::test::csv_body(read_text(dir_ / "out/er.csv"));
  EXPECT_EQ(std::count(table.begin(), table.end(), '\n'), 9);  // header and 2 x 2 x 2 runs
  EXPECT_EQ(table.rfind("formulation,integrator,rtol,atol,max_error_q", 0), 0u) << table;
  const nhdyn::CsvTable by_tolerance = nhdyn::load_csv(dir_ / "out/er-by-tolerance.csv");
  ASSERT_EQ(by_tolerance.rows.size(), 2u);
  const int bdf = by_tolerance.column("error_sanh-qr_cvode-bdf");
  const int bdf_residual = by_tolerance.column("residual_vel_sanh-qr_cvode-bdf");
  ASSERT_GE(bdf, 0);
  ASSERT_GE(bdf_residual, 0);
  // The study's finding on Appell (tests/studies/error_relation_test.cpp has the margins).
  EXPECT_GT(by_tolerance.rows[0][static_cast<std::size_t>(bdf)],
            1e4 * by_tolerance.rows[0][static_cast<std::size_t>(bdf_residual)]);
  EXPECT_GT(fs::file_size(dir_ / "out/er.png"), 1000u);
}

TEST_F(StudyCli, ErrorRelationRefusesBadInput) {
  struct Case {
    std::vector<std::string> args;
    std::string needle;
  };
  const std::vector<Case> cases{
      {{"--tolerances", "1e-3,-1e-6"}, "-1e-06"},
      {{"--methods", "sanh-svd"}, "sanh-svd"},
      {{"--methods", "kane"}, "kane"},
      {{"--integrators", "euler"}, "euler"},
      {{"--atol-factor", "0"}, "atol factor 0"},
      {{"--t-end", "-1"}, "--t-end -1"},
      {{"--methods", "sanh-analytic"}, "no analytic complement"},
  };
  for (const Case& c : cases) {
    std::vector<std::string> args{"study", "error-relation", NHDYN_SOURCE_DIR "/examples/knife_edge.toml", "-o",
                                  "bad.csv"};
    args.insert(args.end(), c.args.begin(), c.args.end());
    const Result r = nhdyn(args);
    EXPECT_EQ(r.exit_code, 2) << c.needle << "\n" << r.out << r.err;
    EXPECT_NE(r.err.find(c.needle), std::string::npos) << r.err;
    EXPECT_FALSE(fs::exists(dir_ / "bad.csv")) << c.needle;
    EXPECT_FALSE(fs::exists(dir_ / "bad-by-tolerance.csv")) << c.needle;
  }
}

}  // namespace
