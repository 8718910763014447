// `nhdyn linearize` and `nhdyn sweep` end to end: the printed state matrix and eigenvalues, the
// sweep's CSV (101 rows) and crossings (the benchmark bicycle's weave and capsize speeds to 1e-9),
// the plot when gnuplot is there, and bad input refused with exit code 2 and a message that names
// the value at fault (unknown --param, bad --steps and ranges, unknown --cyclic, not steady).
#include <gtest/gtest.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <complex>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include "linearization/support.hpp"
#include "support/text.hpp"
#include "nhdyn/io/plot.hpp"

namespace {

namespace fs = std::filesystem;

struct CliResult {
  int code = -1;
  std::string out, err;
};

std::string read(const fs::path& p) {
  std::ifstream in(p);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

class CliRun : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() /
           ("nhdyn-lin-" + std::to_string(::getpid()) + "-" +
            ::testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::remove_all(dir_);
    fs::create_directories(dir_);
  }
  void TearDown() override { fs::remove_all(dir_); }
  CliResult run(const std::string& args) {
    const std::string command = "cd '" + dir_.string() + "' && '" + NHDYN_CLI_PATH + "' " + args + " > out.txt 2> err.txt";
    const int status = std::system(command.c_str());
    CliResult r;
    r.code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
    r.out = read(dir_ / "out.txt");
    r.err = read(dir_ / "err.txt");
    return r;
  }
  static std::string example(const std::string& file) { return "'" + nhdyn::testing::example_path(file) + "'"; }
  fs::path dir_;
};

TEST_F(CliRun, LinearizeBicyclePrintsTheStateMatrixAndEigenvalues) {
  const CliResult r = run("linearize " + example("bicycle_linear.toml") + " --set v=5 -o eig.csv");
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_NE(r.out.find("x = (phi, delta, phi', delta')"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("exact (tangent mode"), std::string::npos) << r.out;
  // The weave pair at 5 m/s, -0.775 +- 4.46 i (Meijaard et al. 2007, table 2), to the digits printed.
  const std::vector<std::complex<double>> want = nhdyn::testing::BicycleMatrices().eigenvalues(5.0);
  std::istringstream csv(nhdyn::test::csv_body(read(dir_ / "eig.csv")));
  std::string line;
  std::getline(csv, line);
  EXPECT_EQ(line, "index,real,imag");
  for (const std::complex<double>& e : want) {
    ASSERT_TRUE(std::getline(csv, line));
    double re = 0, im = 0;
    int index = 0;
    ASSERT_EQ(std::sscanf(line.c_str(), "%d,%lf,%lf", &index, &re, &im), 3) << line;
    EXPECT_NEAR(re, e.real(), 1e-10 * std::abs(e));
    EXPECT_NEAR(im, e.imag(), 1e-10 * std::abs(e));
  }
}

TEST_F(CliRun, SweepBicycleFindsWeaveAndCapsizeSpeeds) {
  const CliResult r = run("sweep " + example("bicycle_linear.toml") +
                    " --param v --from 0 --to 10 --steps 101 --eigenvalues -o bike.csv");
  ASSERT_EQ(r.code, 0) << r.err;
  const std::string table = nhdyn::test::csv_body(read(dir_ / "bike.csv"));
  EXPECT_EQ(table.rfind("v,re_1,im_1,re_2,im_2,re_3,im_3,re_4,im_4\n", 0), 0u) << table.substr(0, 80);
  EXPECT_EQ(std::count(table.begin(), table.end(), '\n'), 102);
  std::istringstream crossings(nhdyn::test::csv_body(read(dir_ / "bike-crossings.csv")));
  std::string line;
  std::getline(crossings, line);
  EXPECT_EQ(line, "parameter,value,kind,frequency,unstable_before,unstable_after,bracket");
  std::vector<double> values;
  std::vector<std::string> kinds;
  while (std::getline(crossings, line)) {
    std::vector<std::string> cells;
    std::stringstream s(line);
    for (std::string cell; std::getline(s, cell, ',');) cells.push_back(cell);
    ASSERT_EQ(cells.size(), 7u) << line;
    values.push_back(std::stod(cells[1]));
    kinds.push_back(cells[2]);
  }
  ASSERT_EQ(values.size(), 2u);
  EXPECT_NEAR(values[0], nhdyn::testing::kWeaveSpeed, 1e-9);
  EXPECT_EQ(kinds[0], "complex-pair");
  EXPECT_NEAR(values[1], nhdyn::testing::kCapsizeSpeed, 1e-9);
  EXPECT_EQ(kinds[1], "real");
  EXPECT_NE(r.out.find("v = 4.29238253634"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("v = 6.02426201538"), std::string::npos) << r.out;
}

TEST_F(CliRun, SweepDrawsThePlot) {
  if (!nhdyn::gnuplot_available()) GTEST_SKIP() << "gnuplot with a PNG terminal is not installed";
  const CliResult r = run("sweep " + example("bicycle_linear.toml") +
                    " --param v --from 0 --to 10 --steps 21 --eigenvalues -o b.csv --plot b.png -q");
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_TRUE(r.out.empty()) << r.out;
  ASSERT_TRUE(fs::exists(dir_ / "b.png"));
  EXPECT_GT(fs::file_size(dir_ / "b.png"), 1000u);
}

TEST_F(CliRun, BadInputIsRefusedWithTheValueNamed) {
  const std::string bike = example("bicycle_linear.toml");
  struct Case {
    std::string args;
    std::vector<std::string> message;
  };
  const std::vector<Case> cases = {
      {"sweep " + bike + " --param speed --from 0 --to 10", {"--param speed", "no parameter 'speed'", "v, g, M_pp"}},
      {"sweep " + bike + " --param v --from 0 --to 10 --steps 1", {"--steps 1"}},
      {"sweep " + bike + " --param v --from 0 --to 10 --steps 0", {"--steps 0"}},
      {"sweep " + bike + " --param v --from 10 --to 0", {"--from 10 --to 0"}},
      {"sweep " + bike + " --param v --from 0 --to inf", {"inf"}},
      {"sweep sled --param alpha --from 0 --to 1", {"not a steady motion", "--cyclic"}},
      {"linearize " + bike + " --cyclic roll", {"--cyclic", "'roll'", "phi, delta"}},
      {"linearize " + bike + " --independent steer", {"--independent", "'steer'"}},
      {"sweep " + bike + " --param v --from 0 --to 1 --cyclic roll", {"--cyclic", "'roll'"}},
      {"linearize " + example("pendulum_cartesian.toml"), {"not a steady motion", "acceleration", "''"}},
      {"linearize " + example("hoop_bead.toml"), {"depends on time"}},
      {"linearize " + bike + " --tolerance -1", {"tolerance", "-1"}},
  };
  for (const Case& c : cases) {
    const CliResult r = run(c.args);
    EXPECT_EQ(r.code, 2) << c.args << "\n" << r.out << r.err;
    for (const std::string& m : c.message) EXPECT_NE(r.err.find(m), std::string::npos) << c.args << ": " << r.err;
    EXPECT_FALSE(fs::exists(dir_ / "results")) << c.args;  // nothing written on bad input
  }
}

}  // namespace
