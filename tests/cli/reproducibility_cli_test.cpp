// Same input, same bytes: the built binary (NHDYN_CLI_PATH) is run several times in separate
// processes on the same model and options, with address-space layout randomisation as the system
// has it (on by default: each process then loads GiNaC, whose hashes of sums and products derive
// from an address, somewhere else), and the files it writes must agree byte for byte.
// docs/design.md ("Reproducibility") says what ordered by address and how the compiler's
// canonical form removes it, and how the equations printer chooses its signs. The bicycle (terms
// left as derived, GiNaC's signs and term order visible to the compiler and the printer) and the
// double pendulum's generated code are the cases that parted before.
#include <gtest/gtest.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cstdlib>
#include <stdlib.h>
#include <filesystem>
#include <fstream>
#include <optional>
#include <sstream>
#include <string>
#include <vector>
#include "support/text.hpp"

namespace {

namespace fs = std::filesystem;

constexpr int kRuns = 4;

using nhdyn::test::read_text;

using nhdyn::test::example;

// Whether the kernel randomises where shared libraries are loaded (the condition under which the
// differences showed; with it off every process would see the same addresses).
bool aslr_on() {
  std::ifstream in("/proc/sys/kernel/randomize_va_space");
  int level = 0;
  return (in >> level) && level > 0;
}

class Reproducible : public ::testing::Test {
 protected:
  void SetUp() override {
    const auto* info = ::testing::UnitTest::GetInstance()->current_test_info();
    dir_ = fs::temp_directory_path() /
           (std::string("nhdyn-repro-") + info->name() + "-" + std::to_string(::getpid()));
    fs::remove_all(dir_);
    fs::create_directories(dir_);
    // Every run derives its model: read from the cache of derived models, the runs after the
    // first would share the first one's derivation, and prove nothing of GiNaC's order.
    const char* setting = std::getenv("NHDYN_DERIVATION_CACHE");
    setting_ = setting ? std::optional<std::string>(setting) : std::nullopt;
    ::setenv("NHDYN_DERIVATION_CACHE", "off", 1);
    const char* cache = std::getenv("XDG_CACHE_HOME");
    cache_ = cache ? std::optional<std::string>(cache) : std::nullopt;
  }
  void TearDown() override {
    fs::remove_all(dir_);
    restore("NHDYN_DERIVATION_CACHE", setting_);
    restore("XDG_CACHE_HOME", cache_);
  }
  static void restore(const char* name, const std::optional<std::string>& value) {
    if (value)
      ::setenv(name, value->c_str(), 1);
    else
      ::unsetenv(name);
  }

  // Runs `nhdyn ARGS` in the test's directory (each argument single-quoted for the shell) and
  // returns its exit code; stdout and stderr go to out.txt and err.txt there.
  int nhdyn(const std::vector<std::string>& args) const {
    std::string command = "cd '" + dir_.string() + "' && '" NHDYN_CLI_PATH "'";
    for (const std::string& a : args) command += " '" + a + "'";
    command += " > out.txt 2> err.txt";
    const int status = std::system(command.c_str());
    return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  }

  // Runs `nhdyn ARGS -o run<i>.EXT` kRuns times and expects every file equal to the first; with no
  // extension, runs `nhdyn ARGS` and compares what it prints.
  void expect_same_bytes(std::vector<std::string> args, const std::string& extension, int runs = kRuns) {
    std::vector<std::string> outputs;
    for (int i = 0; i < runs; ++i) {
      const std::string file = extension.empty() ? "out.txt" : "run" + std::to_string(i) + "." + extension;
      std::vector<std::string> run_args = args;
      if (!extension.empty()) run_args.insert(run_args.end(), {"-o", file});
      ASSERT_EQ(nhdyn(run_args), 0) << read_text(dir_ / "err.txt");
      outputs.push_back(read_text(dir_ / file));
      ASSERT_FALSE(outputs.back().empty());
    }
    for (int i = 1; i < runs; ++i) {
      if (outputs[static_cast<std::size_t>(i)] == outputs[0]) continue;
      // Name the first line that differs, so that a failure says where the runs part.
      std::istringstream a(outputs[0]), b(outputs[static_cast<std::size_t>(i)]);
      std::string line_a, line_b;
      int line = 0;
      while (std::getline(a, line_a) && std::getline(b, line_b) && line_a == line_b) ++line;
      ADD_FAILURE() << "run " << i << " differs from run 0 at line " << line + 1 << ":\n  "
                    << line_a << "\n  " << line_b;
    }
  }

  fs::path dir_;
  std::optional<std::string> setting_, cache_;
};

TEST_F(Reproducible, AslrIsOnForTheseTests) {
  if (!aslr_on()) GTEST_SKIP() << "address-space randomisation is off: the runs below prove less";
  SUCCEED();
}

TEST_F(Reproducible, BicycleSimulation) {
  expect_same_bytes({"simulate", example("whipple_bicycle.toml"), "--t-end", "3", "-q"}, "csv");
}

TEST_F(Reproducible, BicycleSimulationWithDop853) {
  expect_same_bytes({"simulate", example("whipple_bicycle.toml"), "--t-end", "3", "--integrator",
                     "dop853", "--rtol", "1e-12", "--atol", "1e-14", "-q"},
                    "csv");
}

// The compiled evaluator (docs/cli.md, "The evaluator") prints the same operations in the same order
// without fused multiply-adds: its runs agree with each other and with the interpreter's byte for
// byte. The cache is the test's own directory (the first run compiles, the others load).
TEST_F(Reproducible, BicycleSimulationCompiledAsInterpreted) {
  ::setenv("XDG_CACHE_HOME", (dir_ / "cache").c_str(), 1);
  const std::vector<std::string> args{"simulate", example("whipple_bicycle.toml"), "--t-end", "3", "-q"};
  std::vector<std::string> compiled = args;
  compiled.insert(compiled.end(), {"--evaluator", "compiled", "-o", "probe.csv"});
  if (nhdyn(compiled) != 0) {
    const std::string err = read_text(dir_ / "err.txt");
    ::unsetenv("XDG_CACHE_HOME");
    if (err.find("cannot be run") != std::string::npos) GTEST_SKIP() << "no C++ compiler: " << err;
    FAIL() << err;
  }
  compiled.resize(compiled.size() - 2);
  expect_same_bytes(compiled, "csv");
  std::vector<std::string> interpreted = args;
  interpreted.insert(interpreted.end(), {"-o", "interpreted.csv"});
  ASSERT_EQ(nhdyn(interpreted), 0) << read_text(dir_ / "err.txt");
  ::unsetenv("XDG_CACHE_HOME");
  // The same rows; the provenance headers differ in the evaluator's name only.
  const auto rows = [](const std::string& csv) { return csv.substr(csv.find("# end of provenance\n")); };
  EXPECT_EQ(rows(read_text(dir_ / "interpreted.csv")), rows(read_text(dir_ / "run0.csv")));
}

// A batch compiles once and rebinds the object to each run's parameters: the runs agree with the
// interpreter's to the byte.
TEST_F(Reproducible, BatchCompiledAsInterpreted) {
  ::setenv("XDG_CACHE_HOME", (dir_ / "cache").c_str(), 1);
  const std::vector<std::string> args{"batch", example("double_pendulum.toml"), "--grid", "m2=0.5:1.5:3", "--grid",
                                      "l2=0.4:0.9:2", "--t-end", "2", "--threads", "2", "-q"};
  std::vector<std::string> compiled = args;
  compiled.insert(compiled.end(), {"--evaluator", "compiled", "-o", "compiled"});
  const int status = nhdyn(compiled);
  const std::string err = read_text(dir_ / "err.txt");
  ::unsetenv("XDG_CACHE_HOME");
  if (status != 0 && err.find("cannot be run") != std::string::npos) GTEST_SKIP() << "no C++ compiler: " << err;
  ASSERT_EQ(status, 0) << err;
  std::vector<std::string> interpreted = args;
  interpreted.insert(interpreted.end(), {"-o", "interpreted"});
  ASSERT_EQ(nhdyn(interpreted), 0) << read_text(dir_ / "err.txt");
  const std::string summary = read_text(dir_ / "interpreted" / "summary.csv");
  EXPECT_FALSE(summary.empty());
  // The same rows; the provenance headers differ in the evaluator's name only.
  EXPECT_EQ(nhdyn::test::csv_body(read_text(dir_ / "compiled" / "summary.csv")), nhdyn::test::csv_body(summary));
}

TEST_F(Reproducible, RollingDiskFromBodies) {
  expect_same_bytes({"simulate", example("rolling_disk_bodies.toml"), "--t-end", "3", "-q"}, "csv");
}

TEST_F(Reproducible, GeneratedChain) {
  ASSERT_EQ(nhdyn({"example", "chain", "--bodies", "4", "-o", "chain.toml"}), 0)
      << read_text(dir_ / "err.txt");
  expect_same_bytes({"simulate", "chain.toml", "--t-end", "2", "-q"}, "csv");
}

TEST_F(Reproducible, ModelFiles) {
  for (const char* file : {"knife_edge.toml", "chaplygin_sleigh.toml", "double_pendulum.toml",
                           "slider_crank.toml", "rolling_disk.toml", "diff_drive.toml"}) {
    SCOPED_TRACE(file);
    expect_same_bytes({"simulate", example(file), "--t-end", "2", "-q"}, "csv");
  }
}

TEST_F(Reproducible, GeneratedCode) {
  for (const char* file : {"rolling_disk_bodies.toml", "slider_crank.toml", "knife_edge.toml"}) {
    SCOPED_TRACE(file);
    expect_same_bytes({"codegen", example(file)}, "hpp");
  }
}

// GiNaC holds q[2] - q[0] in some processes and q[0] - q[2] in others (under cos and sin); the
// code must say the same in all.
TEST_F(Reproducible, DoublePendulumGeneratedCode) {
  expect_same_bytes({"codegen", example("double_pendulum.toml")}, "hpp");
}

TEST_F(Reproducible, BicycleGeneratedCode) {
  expect_same_bytes({"codegen", example("whipple_bicycle.toml")}, "hpp");
}

// The printer chooses the sign of every sum inside a product itself (symbolic/equations.cpp); the
// bicycle's entries are printed as derived, so GiNaC's choices would show there first.
TEST_F(Reproducible, BicycleEquations) {
  for (const char* format : {"text", "latex"}) {
    SCOPED_TRACE(format);
    expect_same_bytes({"equations", example("whipple_bicycle.toml"), "--format", format}, "");
  }
}

// A ground held by coordinates divides its rows by |grad g| at the start: as a float, that factor
// combined with the exact coefficients in GiNaC's order of the process ("-1.0 ball_gx" in one run,
// "-ball_gx" in another); it is an exact rational (rolling_contact.cpp, exact_scale).
TEST_F(Reproducible, BallInAParaboloidEquations) {
  expect_same_bytes({"equations", example("ball_in_paraboloid.toml")}, "");
}

// A rolling contact's rows and their derivatives compile as derived where that is smaller than
// simplified (symbolic/simplify.hpp, smaller_form): GiNaC holds them with signs that change from
// process to process, and neither the choice nor the tape may follow them.
TEST_F(Reproducible, RollingRowsAsDerived) {
  for (const char* file : {"ball_on_sphere.toml", "rattleback.toml", "ball_in_bowl.toml"}) {
    SCOPED_TRACE(file);
    expect_same_bytes({"codegen", example(file)}, "hpp");
  }
  expect_same_bytes({"simulate", example("ball_on_sphere.toml"), "--t-end", "3", "-q"}, "csv");
}

// A sum under a square root and beside it with the other sign: GiNaC merges (y - x - 2) and
// sqrt(x - y + 2) into -(x - y + 2)^(3/2) in the processes where its term order writes the first
// as -(x - y + 2), and keeps the product in the others (about one process in five); the compiler
// merges the powers of one base itself (compile.cpp, merge_powers), so b is computed the same way
// in every process. 16 runs: with one in five the odd one, all 16 alike by chance is 3 %.
TEST_F(Reproducible, APowerOfASumBesideTheSumWithTheOtherSign) {
  std::ofstream(dir_ / "probe.toml") << R"toml(name = "probe"
coordinates = ["x", "y", "phi"]
kinetic_energy = "m/2 * (x'^2 + y'^2) + m/2 * phi'^2"

[parameters]
m = 2.0

[[constraints]]
name = "c1"
velocity = "(y - x - 2)*sqrt(x - y + 2)*x' + y'"

[initial]
position = { x = 0, y = 0, phi = 0 }
velocity = { x = 1, y = "2*sqrt(2)", phi = 1 }

[simulation]
t_end = 1.0
output_step = 0.1
)toml";
  expect_same_bytes({"codegen", "probe.toml"}, "hpp", 16);
  expect_same_bytes({"simulate", "probe.toml", "-q"}, "csv", 16);
}

// A disk leaned in a bowl: nhdyn adds the contact point's coordinates on the ground and finds
// them at the start by Newton's method, whose values GiNaC evaluates summing in its term order;
// with the parameters as doubles that evaluation rounded as a double, and a coordinate that is 0
// there came out as -1.3146e-18 in one process and -1.2992e-18 in another (every run a different
// CSV). The values are exact and evaluated to 40 digits now (rolling_contact.cpp, contact_value).
TEST_F(Reproducible, AContactPointFoundAtTheStartOnASurface) {
  std::ofstream(dir_ / "disk.toml") << R"toml(name = "disk-in-bowl"
coordinates = ["x", "y", "z", "psi", "theta", "phi"]
gravity = [0, 0, "-g"]

[parameters]
m = 2.0
J = 0.09
K = 0.045
R = 0.3
g = 9.81
Rb = 1.0
lean = 0.5

[[frames]]
name = "wheel"
translation = ["x", "y", "z"]
rotations = [["z", "psi"], ["x", "theta"], ["y", "phi"]]

[[bodies]]
name = "wheel"
frame = "wheel"
mass = "m"
inertia = ["K", "J", "K"]

[[contacts]]
name = "rim"
body = "wheel"
shape = { disk = "R", axis = "y" }
ground = { surface = "X^2 + Y^2 + (Z - Rb)^2 - Rb^2", side = "inside" }

[initial]
position = { x = 0, y = "-R*sin(lean)", z = "R*cos(lean)", psi = 0, theta = "lean", phi = 0 }
)toml";
  expect_same_bytes({"codegen", "disk.toml"}, "hpp", 8);
  expect_same_bytes({"simulate", "disk.toml", "--t-end", "0.2", "-q"}, "csv", 8);
}

// The 50-digit reference's own error estimate (a column of the CSV): its terms summed in GiNaC's
// order at 50 digits parted in the last digits from run to run, before they were summed with
// guard digits and rounded (symbolic/precise_reference.cpp).
TEST_F(Reproducible, SpreadMassesReference) {
  expect_same_bytes({"study", "spread-masses", example("spread_masses.toml"), "--ratios", "1,1e6", "-q"}, "csv");
}

// The report's scene (positions of the bodies, the contact point, the shapes) from the model's own
// canonical compiler: emitted in GiNaC's order, the rattleback's report differed in the last bits
// of a contact point's height from run to run.
TEST_F(Reproducible, RattlebackReport) {
  ASSERT_EQ(nhdyn({"simulate", example("rattleback.toml"), "--t-end", "1", "-q", "-o", "r.csv"}), 0);
  expect_same_bytes({"report", "r.csv", "--model", example("rattleback.toml")}, "html");
}

TEST_F(Reproducible, BicycleLinearization) {
  expect_same_bytes({"linearize", example("whipple_bicycle.toml"), "--cyclic", "thetaR,thetaF"},
                    "csv");
}

}  // namespace
