// The rule for a derived output ([outputs]) or an event function that becomes NaN or infinite
// during a run (docs/cli.md, "What bad input gets"): the run ends there with exit code 1 and a
// message naming the output or event, its expression, t and the state; the rows before are kept in
// FILE.partial.csv and no NaN is ever written as a value. The model is the oscillator x = cos t, so
// sqrt(x) is defined until t = pi/2.
#include <gtest/gtest.h>
#include <unistd.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <limits>
#include <numbers>
#include <string>
#include <vector>

#include "nhdyn/io/csv.hpp"
#include "support/cli_process.hpp"
#include "support/models.hpp"
#include "support/text.hpp"

namespace {

namespace fs = std::filesystem;
using nhdyn::test::contains;
using nhdyn::test::ProcessRun;
using nhdyn::test::run_process;

constexpr const char* kSqrtOscillator = R"(name = "oscillator"
coordinates = ["x"]
kinetic_energy = "m/2 * x'^2"
potential_energy = "k/2 * x^2"
[parameters]
m = 1.0
k = 1.0
[initial]
position = { x = 1 }
velocity = { x = 0 }
)";

class NonFinite : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() / ("nhdyn-non-finite-" + std::to_string(::getpid()) + "-" +
                                        ::testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::remove_all(dir_);
    fs::create_directories(dir_);
  }
  void TearDown() override { fs::remove_all(dir_); }
  ProcessRun nhdyn(const std::vector<std::string>& args) const { return run_process(args, dir_); }
  // The number after "t = " in the first line of `text` that names `what`.
  static double time_in(const std::string& text, const std::string& what) {
    const std::size_t at = text.find(what);
    if (at == std::string::npos) return std::nan("");
    const std::size_t t = text.find(" at t = ", at);
    return t == std::string::npos ? std::nan("") : std::stod(text.substr(t + 8));
  }
  fs::path dir_;
};

TEST_F(NonFinite, DerivedOutputEndsTheRunNamingItAndKeepsTheRowsBefore) {
  std::ofstream(dir_ / "o.toml") << kSqrtOscillator << "[outputs]\nroot = \"sqrt(x)\"\n";
  const ProcessRun r = nhdyn({"simulate", "o.toml", "--t-end", "3", "--output-step", "0.1", "--rtol", "1e-10",
                              "--atol", "1e-12", "-q", "-o", "o.csv"});
  EXPECT_EQ(r.code, 1) << r.err;
  EXPECT_TRUE(contains(r.err, "derived output 'root' (sqrt(x)) is NaN")) << r.err;
  // The first output time past pi/2 is 1.6, where x = cos 1.6 = -0.0292.
  EXPECT_NEAR(time_in(r.err, "derived output 'root'"), 1.6, 1e-9) << r.err;
  EXPECT_TRUE(contains(r.err, "where x = -0.0291995")) << r.err;
  EXPECT_TRUE(contains(r.err, "o.toml:")) << r.err;  // where it was written
  EXPECT_FALSE(fs::exists(dir_ / "o.csv"));
  const nhdyn::CsvTable partial = nhdyn::load_csv(dir_ / "o.partial.csv");
  const int t = partial.column("t"), x = partial.column("x"), root = partial.column("root");
  ASSERT_GE(root, 0);
  ASSERT_EQ(partial.rows.size(), 16u);  // t = 0, 0.1, ..., 1.5
  for (const auto& row : partial.rows) {
    const double tr = row[static_cast<std::size_t>(t)];
    EXPECT_NEAR(row[static_cast<std::size_t>(x)], std::cos(tr), 1e-7);
    EXPECT_NEAR(row[static_cast<std::size_t>(root)], std::sqrt(row[static_cast<std::size_t>(x)]), 1e-14);
  }
}

TEST_F(NonFinite, EventEndsTheRunNamingIt) {
  std::ofstream(dir_ / "o.toml") << kSqrtOscillator;
  const ProcessRun r = nhdyn({"simulate", "o.toml", "--t-end", "3", "--output-step", "0.1", "--event",
                              "z=sqrt(x)", "-q", "-o", "e.csv"});
  EXPECT_EQ(r.code, 1) << r.err;
  EXPECT_TRUE(contains(r.err, "event 'z' (sqrt(x)) is NaN")) << r.err;
  // First met at a step's end past pi/2, where x < 0 (and within a step or so of it).
  const double t = time_in(r.err, "event 'z'");
  EXPECT_GT(t, std::numbers::pi / 2) << r.err;
  EXPECT_LT(t, 3.0) << r.err;
  EXPECT_TRUE(contains(r.err, "where x = -")) << r.err;
  EXPECT_FALSE(fs::exists(dir_ / "e.csv"));
  const nhdyn::CsvTable partial = nhdyn::load_csv(dir_ / "e.partial.csv");
  ASSERT_FALSE(partial.rows.empty());
  EXPECT_LE(partial.rows.back()[static_cast<std::size_t>(partial.column("t"))], t);
}

TEST_F(NonFinite, AnInfiniteEventEndsTheRunToo) {
  // g = exp(1000 t) overflows to infinity once t > log(DBL_MAX)/1000 = 0.70978.
  std::ofstream(dir_ / "o.toml") << kSqrtOscillator;
  const ProcessRun r = nhdyn({"simulate", "o.toml", "--t-end", "2", "--output-step", "0.5", "--event",
                              "p=exp(1000*t)", "-q", "-o", "p.csv"});
  EXPECT_EQ(r.code, 1) << r.err;
  EXPECT_TRUE(contains(r.err, "event 'p' (exp(1000*t)) is inf")) << r.err;
  const double t = time_in(r.err, "event 'p'");
  EXPECT_GT(t, std::log(std::numeric_limits<double>::max()) / 1000) << r.err;
  EXPECT_LT(t, 2.0) << r.err;
  const nhdyn::CsvTable partial = nhdyn::load_csv(dir_ / "p.partial.csv");
  ASSERT_FALSE(partial.rows.empty());
  EXPECT_LE(partial.rows.back()[static_cast<std::size_t>(partial.column("t"))], t);
}

// A ball rolling towards a pole of its terrain, z = 0.001 / (X - 0.3): the equations stay finite
// (they read the surface at the contact point's own coordinates) while the gap's rate, the velocity
// residual of the contact, is -inf; the run went on to its end with exit 0 and -inf in 11 rows.
TEST_F(NonFinite, AConstraintResidualThatIsNotFiniteEndsTheRun) {
  std::ofstream(dir_ / "pole.toml") << nhdyn::test::ball_on_terrain(
      "0.001/(X-0.3)", "[initial]\nposition = { x = 0, y = 0, psi = 0, theta = 0, phi = 0 }\nvelocity = { x = 0.3 }\n");
  const ProcessRun r = nhdyn({"simulate", "pole.toml", "--fix-initial", "--t-end", "1.5", "--output-step", "0.01",
                              "-q", "-o", "pole.csv"});
  EXPECT_EQ(r.code, 1) << r.err;
  EXPECT_TRUE(contains(r.err, "pole.toml:24:1: the velocity residual of constraint 'ball_contact'")) << r.err;
  EXPECT_TRUE(contains(r.err, ") is -inf at t = ")) << r.err;
  EXPECT_FALSE(fs::exists(dir_ / "pole.csv"));
  const nhdyn::CsvTable partial = nhdyn::load_csv(dir_ / "pole.partial.csv");
  ASSERT_FALSE(partial.rows.empty());
  for (std::size_t c = 0; c < partial.header.size(); ++c) {
    if (!partial.header[c].starts_with("residual_")) continue;
    for (const auto& row : partial.rows) EXPECT_TRUE(std::isfinite(row[c])) << partial.header[c];
  }
}

}  // namespace
