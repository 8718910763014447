// End-to-end runs of the commands that read model files: simulate FILE.toml (with --set and
// --fix-initial), equations (text and LaTeX) and codegen, and their refusals of bad input.
#include <gtest/gtest.h>
#include <sys/wait.h>

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

using nhdyn::test::example;

class ModelFileCli : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() /
           ("nhdyn_mfcli_" + std::to_string(::getpid()) + "_" +
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

TEST_F(ModelFileCli, SimulatesAModelFileLikeTheBuiltInModel) {
  const Outcome file = run_nhdyn("simulate " + example("sled.toml") + " --t-end 1 -o file.csv", dir_);
  ASSERT_EQ(file.exit_code, 0) << file.out;
  const Outcome builtin = run_nhdyn("simulate sled --t-end 1 -o builtin.csv", dir_);
  ASSERT_EQ(builtin.exit_code, 0) << builtin.out;
  // Same header, and the file model's energy balance after it (docs/derivations/energy-balance.md;
  // built-in models have none); the last rows agree to the integrator's tolerance (the file model
  // is interpreted, the built-in one hand-written, so round-off may differ).
  const std::string a = read("file.csv"), b = read("builtin.csv");
  const auto header = [](const std::string& csv) {  // after the provenance header (io/provenance.hpp)
    const std::size_t at = csv.find("\nt,") + 1;
    return csv.substr(at, csv.find('\n', at) - at);
  };
  EXPECT_EQ(header(a),
            header(b) + ",energy_function,power,work_forces,work_reactions,work_time,work,balance_error");
  auto last_x = [](const std::string& csv) {
    const std::string last = csv.substr(csv.rfind('\n', csv.size() - 2) + 1);
    std::stringstream s(last);
    std::string t, x;
    std::getline(s, t, ',');
    std::getline(s, x, ',');
    return std::stod(x);
  };
  EXPECT_NEAR(last_x(a), last_x(b), 1e-7 * (1.0 + std::abs(last_x(b))));
}

TEST_F(ModelFileCli, SetOverridesAParameterAndRefusesUnknownOnes) {
  const Outcome heavy = run_nhdyn("simulate " + example("sled.toml") + " --set alpha=0 --t-end 1 -o flat.csv", dir_);
  ASSERT_EQ(heavy.exit_code, 0) << heavy.out;
  const Outcome typo = run_nhdyn("simulate " + example("sled.toml") + " --set rh=1", dir_);
  EXPECT_EQ(typo.exit_code, 2);
  EXPECT_NE(typo.out.find("did you mean 'rho'"), std::string::npos) << typo.out;
  const Outcome nan = run_nhdyn("simulate " + example("sled.toml") + " --set rho=abc", dir_);
  EXPECT_EQ(nan.exit_code, 2);
  EXPECT_NE(nan.out.find("'abc'"), std::string::npos) << nan.out;  // --set takes expressions: an unknown name
  // Built-in models take --set too (parameters are data, docs/cli.md "Parameters").
  const Outcome builtin = run_nhdyn("simulate sled --set rho=1 --t-end 1 -o builtin.csv", dir_);
  EXPECT_EQ(builtin.exit_code, 0) << builtin.out;
}

TEST_F(ModelFileCli, ViolatedInitialStateIsRefusedOrFixed) {
  std::ifstream in(example("sled.toml"));
  std::stringstream text;
  text << in.rdbuf();
  std::string toml = text.str();
  // A sideways initial velocity: the blade forbids it.
  const std::string from = "velocity = { x = 1.0, y = 0, phi = 1.0 }";
  const std::size_t at = toml.find(from);
  ASSERT_NE(at, std::string::npos) << "examples/sled.toml changed its initial velocity";
  toml.replace(at, from.size(), "velocity = { x = 1.0, y = 0.3, phi = 1.0 }");
  std::ofstream(dir_ / "bad.toml") << toml;
  const Outcome refused = run_nhdyn("simulate bad.toml --t-end 1 -o out.csv", dir_);
  EXPECT_EQ(refused.exit_code, 2) << refused.out;
  EXPECT_NE(refused.out.find("blade (velocity level): residual 0.3"), std::string::npos) << refused.out;
  EXPECT_FALSE(fs::exists(dir_ / "out.csv"));
  // --fix-initial keeps the values [initial] writes: all three velocities are written, so it refuses.
  const Outcome kept = run_nhdyn("simulate bad.toml --t-end 1 -o out.csv --fix-initial", dir_);
  EXPECT_EQ(kept.exit_code, 2) << kept.out;
  EXPECT_NE(kept.out.find("'blade' (velocity level"), std::string::npos) << kept.out;
  EXPECT_NE(kept.out.find("residual 0.3"), std::string::npos) << kept.out;
  // With y' left out (and the sled turned by 0.5 rad) it moves y' only, to x' tan(phi).
  std::string free_toml = toml;
  free_toml.replace(free_toml.find("velocity = { x = 1.0, y = 0.3, phi = 1.0 }"), 42, "velocity = { x = 1.0, phi = 1.0 }");
  free_toml.replace(free_toml.find("position = { x = 0, y = 0, phi = 0 }"), 36, "position = { x = 0, y = 0, phi = 0.5 }");
  std::ofstream(dir_ / "free.toml") << free_toml;
  const Outcome fixed = run_nhdyn("simulate free.toml --t-end 1 -o out.csv --fix-initial", dir_);
  EXPECT_EQ(fixed.exit_code, 0) << fixed.out;
  EXPECT_NE(fixed.out.find("y' = 0.546302489844 (changed by +0.546), was 0"), std::string::npos) << fixed.out;
}

TEST_F(ModelFileCli, EquationsInTextAndLatex) {
  const Outcome text = run_nhdyn("equations " + example("sled_paper.toml"), dir_);
  ASSERT_EQ(text.exit_code, 0) << text.out;
  EXPECT_NE(text.out.find("m x'' + m tan(phi) y''"), std::string::npos) << text.out;
  const Outcome latex = run_nhdyn("equations " + example("sled_paper.toml") + " --format latex", dir_);
  ASSERT_EQ(latex.exit_code, 0) << latex.out;
  EXPECT_NE(latex.out.find("\\ddot"), std::string::npos);
  const Outcome bad = run_nhdyn("equations " + example("sled.toml") + " --format pdf", dir_);
  EXPECT_EQ(bad.exit_code, 2);
  const Outcome builtin = run_nhdyn("equations appell", dir_);
  EXPECT_EQ(builtin.exit_code, 2);
  EXPECT_NE(builtin.out.find("examples/appell.toml"), std::string::npos) << builtin.out;
}

TEST_F(ModelFileCli, CodegenWritesAHeaderOrNothing) {
  const Outcome ok = run_nhdyn("codegen " + example("appell.toml") + " -o appell_model.hpp", dir_);
  ASSERT_EQ(ok.exit_code, 0) << ok.out;
  const std::string header = read("appell_model.hpp");
  EXPECT_NE(header.find("make_appell_model"), std::string::npos);
  EXPECT_EQ(header.find("ginac"), std::string::npos);
  const Outcome missing = run_nhdyn("codegen nosuch.toml -o x.hpp", dir_);
  EXPECT_EQ(missing.exit_code, 2) << missing.out;
  EXPECT_FALSE(fs::exists(dir_ / "x.hpp"));
  const Outcome nodir = run_nhdyn("codegen " + example("appell.toml") + " -o nodir/x.hpp", dir_);
  EXPECT_EQ(nodir.exit_code, 2) << nodir.out;
}

}  // namespace
