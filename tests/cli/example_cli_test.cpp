// End-to-end runs of `nhdyn example`: the chain's model file, on stdout or with -o, runs with
// `nhdyn simulate`; the list of examples; bad --bodies, --set and names refused with exit 2, the
// value and the limit named, and no output file left behind. The free particles' file follows
// their closed-form motion.
#include <gtest/gtest.h>
#include <sys/wait.h>
#include <unistd.h>

#include <array>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include "support/cli_run.hpp"
#include "support/text.hpp"

namespace {

namespace fs = std::filesystem;

using Outcome = nhdyn::test::CliOutcome;

using nhdyn::test::run_nhdyn;

class ExampleCli : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() /
           ("nhdyn_excli_" + std::to_string(::getpid()) + "_" +
            ::testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::create_directories(dir_);
  }
  void TearDown() override { fs::remove_all(dir_); }
  std::string read(const std::string& file) {
    std::ifstream in(dir_ / file);
    std::stringstream s;
    s << in.rdbuf();
    return s.str();
  }
  fs::path dir_;
};

TEST_F(ExampleCli, ChainOnStdoutRunsWithSimulate) {
  // stderr kept out of the file (a sanitizer's exit report would land there) and shown after.
  const Outcome gen = run_nhdyn("example chain --bodies 4 > chain4.toml 2> gen.err && cat gen.err", dir_);
  ASSERT_EQ(gen.exit_code, 0) << gen.out;
  const Outcome sim = run_nhdyn("simulate chain4.toml --t-end 1 --output-step 0.1 -q -o out.csv", dir_);
  ASSERT_EQ(sim.exit_code, 0) << sim.out;
  const std::string csv = read("out.csv");
  EXPECT_NE(csv.find("# end of provenance\nt,x1,y1,theta1,x2,"), std::string::npos) << csv.substr(0, 800);
  EXPECT_NE(csv.find("theta4"), std::string::npos);
}

TEST_F(ExampleCli, ChainWithOutputFileAndSetRunsWithSimulate) {
  const Outcome gen = run_nhdyn("example chain --bodies 2 --set m=2 --set w0=0.25 -o chain2.toml", dir_);
  ASSERT_EQ(gen.exit_code, 0) << gen.out;
  EXPECT_EQ(gen.out.find("error"), std::string::npos) << gen.out;  // silent (a sanitizer may report)
  const std::string text = read("chain2.toml");
  EXPECT_NE(text.find("m = { value = 2.0"), std::string::npos);
  EXPECT_NE(text.find("w0 = { value = 0.25"), std::string::npos);
  const Outcome sim = run_nhdyn("simulate chain2.toml --t-end 0.5 -q -o out.csv", dir_);
  EXPECT_EQ(sim.exit_code, 0) << sim.out;
  const Outcome shipped =
      run_nhdyn("simulate '" + std::string(NHDYN_SOURCE_DIR) + "/examples/chain.toml' --t-end 0.5 -q -o shipped.csv", dir_);
  EXPECT_EQ(shipped.exit_code, 0) << shipped.out;
}

TEST_F(ExampleCli, ListsTheExamples) {
  const Outcome none = run_nhdyn("example", dir_);
  EXPECT_EQ(none.exit_code, 0) << none.out;
  EXPECT_NE(none.out.find("chain"), std::string::npos) << none.out;
  const Outcome unknown = run_nhdyn("example trailer", dir_);
  EXPECT_EQ(unknown.exit_code, 2) << unknown.out;
  EXPECT_NE(unknown.out.find("unknown example 'trailer'"), std::string::npos) << unknown.out;
  EXPECT_NE(unknown.out.find("chain"), std::string::npos) << unknown.out;
}

TEST_F(ExampleCli, RefusesBadBodiesWithTheLimitAndNoFile) {
  for (const std::string value : {"0", "-3", "=-3", "abc", "1e9", "10001", "99999999999999999999", "2.5"}) {
    const std::string option = value[0] == '=' ? "--bodies" + value : "--bodies " + value;
    const Outcome out = run_nhdyn("example chain " + option + " -o chain.toml", dir_);
    EXPECT_EQ(out.exit_code, 2) << value << ": " << out.out;
    const std::string shown = value[0] == '=' ? value.substr(1) : value;
    EXPECT_NE(out.out.find(shown), std::string::npos) << value << ": " << out.out;
    EXPECT_NE(out.out.find("from 1 to 10000"), std::string::npos) << value << ": " << out.out;
    EXPECT_FALSE(fs::exists(dir_ / "chain.toml")) << value;
    EXPECT_EQ(std::distance(fs::directory_iterator(dir_), fs::directory_iterator{}), 0) << value;
  }
}

// Particle i starts at (i - 1, 0, 0) with velocity (0, v0, v0) under gravity g along -z: at t,
// x = i - 1, y = v0 t, z = v0 t - g t^2 / 2, which dopri5 reproduces to its tolerance (the motion
// is a quadratic polynomial in t, which the fifth-order step integrates exactly but for round-off).
TEST_F(ExampleCli, ParticlesFollowTheirFreeFall) {
  const Outcome gen = run_nhdyn("example particles --bodies 3 --set g=2 --set v0=1.5 -o particles.toml", dir_);
  ASSERT_EQ(gen.exit_code, 0) << gen.out;
  const Outcome sim = run_nhdyn("simulate particles.toml -q -o out.csv", dir_);
  ASSERT_EQ(sim.exit_code, 0) << sim.out;
  std::istringstream csv(nhdyn::test::read_text(dir_ / "out.csv"));
  std::string line, last;
  while (std::getline(csv, line) && line.starts_with('#')) {
  }  // the provenance header (io/provenance.hpp)
  const std::vector<std::string> header = nhdyn::test::split(line);
  while (std::getline(csv, line))
    if (!line.empty()) last = line;
  const std::vector<std::string> row = nhdyn::test::split(last);
  const auto value = [&](const std::string& name) {
    for (std::size_t i = 0; i < header.size(); ++i)
      if (header[i] == name) return std::stod(row.at(i));
    ADD_FAILURE() << "no column " << name << " in " << header.size() << " columns";
    return 0.0;
  };
  const double t = value("t");
  EXPECT_DOUBLE_EQ(t, 1.0);
  for (int i = 1; i <= 3; ++i) {
    const std::string k = std::to_string(i);
    EXPECT_NEAR(value("x" + k), i - 1.0, 1e-9) << k;
    EXPECT_NEAR(value("y" + k), 1.5 * t, 1e-9) << k;
    EXPECT_NEAR(value("z" + k), 1.5 * t - 2.0 * t * t / 2.0, 1e-9) << k;
  }
  const Outcome bad = run_nhdyn("example particles --set J=1 -o p.toml", dir_);
  EXPECT_EQ(bad.exit_code, 2) << bad.out;
  EXPECT_NE(bad.out.find("no parameter 'J'"), std::string::npos) << bad.out;
  EXPECT_FALSE(fs::exists(dir_ / "p.toml"));
}

TEST_F(ExampleCli, RefusesBadParametersWithNoFile) {
  const Outcome zero = run_nhdyn("example chain --set m=0 -o chain.toml", dir_);
  EXPECT_EQ(zero.exit_code, 2) << zero.out;
  EXPECT_NE(zero.out.find("mass m = 0"), std::string::npos) << zero.out;
  const Outcome unknown = run_nhdyn("example chain --set rho=1 -o chain.toml", dir_);
  EXPECT_EQ(unknown.exit_code, 2) << unknown.out;
  EXPECT_NE(unknown.out.find("no parameter 'rho'"), std::string::npos) << unknown.out;
  const Outcome text = run_nhdyn("example chain --set f=long -o chain.toml", dir_);
  EXPECT_EQ(text.exit_code, 2) << text.out;
  EXPECT_FALSE(fs::exists(dir_ / "chain.toml"));
}

}  // namespace
