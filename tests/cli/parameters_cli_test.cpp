// `--set NAME=EXPR` end to end (docs/cli.md, "Parameters"): expressions, built-in models, derived
// parameters of a file, and the refusals (unknown, cyclic, subnormal, too large) with exit code 2
// and a message that names what is wrong. And `nhdyn sweep` on a model compiled once.
#include <gtest/gtest.h>

#include <sys/wait.h>
#include <unistd.h>

#include <array>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <string>
#include "support/text.hpp"

namespace {

namespace fs = std::filesystem;

struct ParametersRun {
  int code = -1;
  std::string output;  // stdout and stderr
};

ParametersRun run(const std::string& arguments) {
  const std::string command = std::string("'") + NHDYN_CLI_PATH + "' " + arguments + " 2>&1";
  ParametersRun r;
  FILE* pipe = ::popen(command.c_str(), "r");
  if (pipe == nullptr) return r;
  std::array<char, 4096> buffer{};
  std::size_t got;
  while ((got = std::fread(buffer.data(), 1, buffer.size(), pipe)) > 0) r.output.append(buffer.data(), got);
  const int status = ::pclose(pipe);
  r.code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  return r;
}

bool has(const ParametersRun& r, const std::string& part) { return r.output.find(part) != std::string::npos; }

using nhdyn::test::example;

fs::path scratch_dir() {
  const fs::path dir = fs::temp_directory_path() / ("nhdyn-parameters-cli-" + std::to_string(::getpid()));
  fs::create_directories(dir);
  return dir;
}

TEST(ParametersCli, BuiltinModelsTakeExpressions) {
  const fs::path dir = scratch_dir();
  const ParametersRun r = run("simulate sled --set alpha=pi/10 --set m=2*rho --t-end 0.1 -q -o '" + (dir / "s.csv").string() +
                    "'");
  EXPECT_EQ(r.code, 0) << r.output;
  fs::remove_all(dir);
}

TEST(ParametersCli, RefusalsSayWhatIsWrong) {
  const ParametersRun subnormal = run("simulate sled --set m=1e-320 --t-end 0.1 -q");
  EXPECT_EQ(subnormal.code, 2) << subnormal.output;
  EXPECT_TRUE(has(subnormal, "subnormal")) << subnormal.output;
  const ParametersRun large = run("simulate '" + example("sled.toml") + "' --set m=1e308 --t-end 0.1 -q");
  EXPECT_EQ(large.code, 2) << large.output;
  EXPECT_TRUE(has(large, "too large")) << large.output;
  const ParametersRun unknown = run("simulate sled --set rh0=1 --t-end 0.1 -q");
  EXPECT_EQ(unknown.code, 2) << unknown.output;
  EXPECT_TRUE(has(unknown, "'rh0'") && has(unknown, "did you mean 'rho'")) << unknown.output;
  const ParametersRun cycle = run("simulate sled --set m=2*a --set a=m/4 --t-end 0.1 -q");
  EXPECT_EQ(cycle.code, 2) << cycle.output;
  EXPECT_TRUE(has(cycle, "cycle") && has(cycle, "m = \"2*a\"") && has(cycle, "a = \"m/4\"")) << cycle.output;
  const ParametersRun broken = run("simulate sled --set a=0.9 --t-end 0.1 -q");
  EXPECT_EQ(broken.code, 2) << broken.output;
  EXPECT_TRUE(has(broken, "rho > a")) << broken.output;
}

// A contact's size or a body's mass that a --set makes negative is refused at the line that
// writes it (the load judged the file's values only, and a ball of radius -0.1 ran with exit 0),
// and the run writes nothing.
TEST(ParametersCli, SizesAndMassesMadeNegativeAreRefusedAtTheirLine) {
  const fs::path dir = scratch_dir();
  const std::string out = (dir / "out.csv").string();
  const ParametersRun radius = run("simulate '" + example("ball_in_bowl.toml") + "' --set r=-0.1 -q -o '" + out + "'");
  EXPECT_EQ(radius.code, 2) << radius.output;
  EXPECT_TRUE(has(radius, "ball_in_bowl.toml:38:") && has(radius, "contact 'ball': sphere r") &&
              has(radius, "\"r\" must be positive, but it is -0.1"))
      << radius.output;
  const ParametersRun wheel = run("simulate '" + example("whipple_bicycle.toml") + "' --set rR=-1 -q -o '" + out + "'");
  EXPECT_EQ(wheel.code, 2) << wheel.output;
  EXPECT_TRUE(has(wheel, "wheel 'rear': radius") && has(wheel, "\"rR\" must be positive, but it is -1")) << wheel.output;
  const ParametersRun mass = run("simulate '" + example("ball_in_bowl.toml") + "' --set m=0 -q -o '" + out + "'");
  EXPECT_EQ(mass.code, 2) << mass.output;
  EXPECT_TRUE(has(mass, "body 'ball': mass") && has(mass, "\"m\" must be positive, but it is 0")) << mass.output;
  EXPECT_FALSE(fs::exists(out));
  const ParametersRun fine = run("simulate '" + example("ball_in_bowl.toml") + "' --set r=0.04 --t-end 0.01 -q -o '" + out + "'");
  EXPECT_EQ(fine.code, 0) << fine.output;
  fs::remove_all(dir);
}

TEST(ParametersCli, DerivedParameterOfAFileFollowsItsBase) {
  const fs::path dir = scratch_dir();
  const fs::path file = dir / "spring.toml";
  {
    std::ofstream out(file);
    out << "name = \"spring\"\ncoordinates = [\"x\"]\nkinetic_energy = \"m/2 * x'^2\"\n"
           "potential_energy = \"k/2 * x^2\"\n[parameters]\nm = 1.0\nk = \"4*m\"\n[initial]\nposition = { x = 1 }\n";
  }
  // Period 2 pi sqrt(m/k) = pi whatever m: at t = pi/2, half a period, x = -1.
  for (const char* m : {"1", "9"}) {
    const fs::path csv = dir / (std::string("spring-") + m + ".csv");
    const ParametersRun r = run("simulate '" + file.string() + "' --set m=" + m + " --t-end 1.5707963267948966 --output-step "
                      "1.5707963267948966 --rtol 1e-12 --atol 1e-12 -q -o '" + csv.string() + "'");
    ASSERT_EQ(r.code, 0) << r.output;
    std::ifstream in(csv);
    std::string header, first, last, line;
    while (std::getline(in, header) && header.starts_with('#')) {
    }  // the provenance header (io/provenance.hpp)
    std::getline(in, first);
    while (std::getline(in, line)) last = line;
    // t,x,... : the coordinate follows the time column.
    const std::size_t comma = last.find(',');
    ASSERT_NE(comma, std::string::npos) << last;
    EXPECT_NEAR(std::stod(last.substr(comma + 1)), -1.0, 1e-8) << "m = " << m << ": " << last;
  }
  fs::remove_all(dir);
}

TEST(ParametersCli, SweepSetsTheParameterInsteadOfRecompiling) {
  const fs::path dir = scratch_dir();
  const ParametersRun r = run("sweep '" + example("bicycle_linear.toml") + "' --param v --from 0 --to 10 --steps 21 -q -o '" +
                    (dir / "sweep.csv").string() + "'");
  ASSERT_EQ(r.code, 0) << r.output;
  std::ifstream in(dir / "sweep-crossings.csv");
  std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  // The benchmark bicycle's weave speed, 4.292 m/s, and capsize speed, 6.024 m/s (Meijaard et al. 2007).
  EXPECT_NE(text.find("v,4.29"), std::string::npos) << text;
  EXPECT_NE(text.find("v,6.02"), std::string::npos) << text;
  fs::remove_all(dir);
}

}  // namespace
