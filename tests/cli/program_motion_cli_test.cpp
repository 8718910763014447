// End-to-end runs of `nhdyn simulate` on models with [[programs]] (docs/derivations/program-motion.md):
// the actuator forces and the programs' residuals as CSV columns, --program-feedback, and each
// refusal of bad input with exit code 2 and a message naming what is at fault.
#include <gtest/gtest.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <array>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include "support/cli_run.hpp"
#include "support/text.hpp"

namespace {

namespace fs = std::filesystem;

using Outcome = nhdyn::test::CliOutcome;

using nhdyn::test::run_nhdyn;

using nhdyn::test::example;
using nhdyn::test::split;

// A point mass in the plane with a program on each coordinate; `extra` goes at the end.
std::string plane_model(const std::string& programs, const std::string& constraints = "") {
  return "name = \"plane\"\n"
         "coordinates = [\"x\", \"y\"]\n"
         "kinetic_energy = \"m/2 * (x'^2 + y'^2)\"\n"
         "[parameters]\n"
         "m = { value = 2.0 }\n" +
         constraints + programs;
}

class ProgramCli : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() / ("nhdyn_progcli_" + std::to_string(::getpid()) + "_" +
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
  void write(const std::string& file, const std::string& text) { std::ofstream(dir_ / file) << text; }
  fs::path dir_;
};

TEST_F(ProgramCli, WritesTheActuatorForcesAndProgramResiduals) {
  const Outcome run = run_nhdyn("simulate " + example("sled_heading_program.toml") + " --t-end 1 -o out.csv", dir_);
  ASSERT_EQ(run.exit_code, 0) << run.out;
  const std::string csv = read("out.csv");
  const std::size_t names = csv.find("\nt,") + 1;  // after the provenance header (io/provenance.hpp)
  const std::string header = csv.substr(names, csv.find('\n', names) - names);
  EXPECT_NE(header.find(",u_heading,residual_pos_heading,residual_vel_heading,residual_acc_heading"),
            std::string::npos)
      << header;
  EXPECT_NE(run.out.find("programs: 1, max residual: position"), std::string::npos) << run.out;
}

// compare: programs are solved by sanh alone, so by default it is the one method run (with a
// note), against the tight reference; another method asked for by name is refused, nothing written.
TEST_F(ProgramCli, CompareRunsSanhAloneAndRefusesAnotherMethodByName) {
  const Outcome run = run_nhdyn("compare " + example("sled_heading_program.toml") +
                                    " --t-end 1 --integrators dopri5,dop853 -q -o table.csv",
                                dir_);
  ASSERT_EQ(run.exit_code, 0) << run.out;
  EXPECT_NE(run.out.find("comparing sanh alone"), std::string::npos) << run.out;
  std::istringstream table(nhdyn::test::csv_body(read("table.csv")));
  std::string header, line;
  std::getline(table, header);
  const auto columns = split(header);
  const std::size_t error_q = static_cast<std::size_t>(
      std::find(columns.begin(), columns.end(), "max_error_q") - columns.begin());
  ASSERT_LT(error_q, columns.size()) << header;
  std::vector<std::string> cases;
  while (std::getline(table, line)) {
    const auto cells = split(line);
    cases.push_back(cells[0] + "," + cells[1]);
    // rtol 1e-8 against the reference at 1e-13.
    EXPECT_LT(std::stod(cells[error_q]), 1e-6) << line;
  }
  EXPECT_EQ(cases, (std::vector<std::string>{"sanh,dopri5", "sanh,dop853"}));

  const Outcome refused =
      run_nhdyn("compare " + example("sled_heading_program.toml") + " --methods sanh,lagrange -o other.csv", dir_);
  EXPECT_EQ(refused.exit_code, 2) << refused.out;
  EXPECT_NE(refused.out.find("--methods lagrange"), std::string::npos) << refused.out;
  EXPECT_NE(refused.out.find("give --methods sanh"), std::string::npos) << refused.out;
  EXPECT_FALSE(fs::exists(dir_ / "other.csv"));
}

// A method or integrator named twice would run one case twice and write two columns of one
// name: refused with the name, nothing written (sanh twice on a model with programs too).
TEST_F(ProgramCli, CompareRefusesANameGivenTwice) {
  for (const std::string& options : {std::string(" --methods sanh,sanh"), std::string(" --integrators dopri5,rk4,dopri5")}) {
    const Outcome refused = run_nhdyn("compare " + example("sled_heading_program.toml") + options + " -o twice.csv", dir_);
    EXPECT_EQ(refused.exit_code, 2) << options << ": " << refused.out;
    EXPECT_NE(refused.out.find("named twice"), std::string::npos) << refused.out;
    EXPECT_NE(refused.out.find(options.find("sanh") != std::string::npos ? "'sanh'" : "'dopri5'"), std::string::npos)
        << refused.out;
    EXPECT_FALSE(fs::exists(dir_ / "twice.csv"));
    EXPECT_FALSE(fs::exists(dir_ / "twice-series.csv"));
  }
}

TEST_F(ProgramCli, BatchRunFilesCarryTheActuatorForcesAsSimulateDoes) {
  // A batch of one run (omega = 1, the file's value) writes the same file as simulate.
  const Outcome batch = run_nhdyn("batch " + example("sled_heading_program.toml") +
                                  " --grid omega=1:1:1 --write-runs -o runs --t-end 1 -q",
                              dir_);
  ASSERT_EQ(batch.exit_code, 0) << batch.out;
  const Outcome run = run_nhdyn("simulate " + example("sled_heading_program.toml") + " --t-end 1 -o out.csv -q", dir_);
  ASSERT_EQ(run.exit_code, 0) << run.out;
  const std::string simulated = read("out.csv");
  ASSERT_NE(simulated.find(",u_heading,"), std::string::npos);
  // The same rows (each file has its provenance header first, io/provenance.hpp).
  EXPECT_EQ(nhdyn::test::csv_body(read("runs/run_0.csv")), nhdyn::test::csv_body(simulated));
}

TEST_F(ProgramCli, TrackingStudyWritesTableByToleranceAndPlot) {
  const Outcome run = run_nhdyn("study tracking " + example("arm_circle_program.toml") +
                                " --tolerances 1e-5,1e-8 --gains 0,10 -o t.csv --plot t.png",
                            dir_);
  ASSERT_EQ(run.exit_code, 0) << run.out;
  const std::string table = nhdyn::test::csv_body(read("t.csv"));
  EXPECT_EQ(table.substr(0, table.find('\n')),
            "gain,rtol,atol,max_error_q,max_error_v,max_residual_pos,max_residual_vel,max_residual_acc,steps,"
            "rhs_evaluations,status");
  EXPECT_EQ(std::count(table.begin(), table.end(), '\n'), 5);  // header and 2 gains x 2 tolerances
  const std::string series = nhdyn::test::csv_body(read("t-by-tolerance.csv"));
  EXPECT_EQ(series.substr(0, series.find('\n')), "tolerance,error_gain_none,residual_gain_none,error_gain_10,residual_gain_10");
  EXPECT_GT(fs::file_size(dir_ / "t.png"), 1000u);
  // Without programs, or without an exact solution, there is nothing to study: exit 2, no file.
  const Outcome none = run_nhdyn("study tracking " + example("sled.toml") + " -o none.csv", dir_);
  EXPECT_EQ(none.exit_code, 2) << none.out;
  EXPECT_NE(none.out.find("no programs"), std::string::npos) << none.out;
  const Outcome unsolved = run_nhdyn("study tracking " + example("cart_pendulum_program.toml") + " -o none.csv", dir_);
  EXPECT_EQ(unsolved.exit_code, 2) << unsolved.out;
  EXPECT_NE(unsolved.out.find("[solution]"), std::string::npos) << unsolved.out;
  EXPECT_FALSE(fs::exists(dir_ / "none.csv"));
}

TEST_F(ProgramCli, FeedbackIsReportedAndItsGainsChecked) {
  const Outcome run = run_nhdyn("simulate " + example("sled_heading_program.toml") +
                                " --t-end 1 -o out.csv --program-feedback 10,10",
                            dir_);
  ASSERT_EQ(run.exit_code, 0) << run.out;
  EXPECT_NE(run.out.find("feedback alpha 10 1/s, beta 10 1/s"), std::string::npos) << run.out;
  const Outcome bad = run_nhdyn("simulate " + example("sled_heading_program.toml") + " --program-feedback 10", dir_);
  EXPECT_EQ(bad.exit_code, 2) << bad.out;
  EXPECT_NE(bad.out.find("alpha,beta"), std::string::npos) << bad.out;
  const Outcome negative =
      run_nhdyn("simulate " + example("sled_heading_program.toml") + " --program-feedback 10,-1", dir_);
  EXPECT_EQ(negative.exit_code, 2) << negative.out;
  EXPECT_NE(negative.out.find("beta = -1"), std::string::npos) << negative.out;
  const Outcome none = run_nhdyn("simulate " + example("sled.toml") + " --program-feedback 1,1", dir_);
  EXPECT_EQ(none.exit_code, 2) << none.out;
  EXPECT_NE(none.out.find("has none"), std::string::npos) << none.out;
}

TEST_F(ProgramCli, SingularProgramIsRefusedNamingIt) {
  const Outcome run = run_nhdyn("simulate " + example("cart_pendulum_program.toml") + " --set theta0=pi/2", dir_);
  EXPECT_EQ(run.exit_code, 2) << run.out;
  EXPECT_NE(run.out.find("'swing'"), std::string::npos) << run.out;
  EXPECT_NE(run.out.find("S = b_p P B"), std::string::npos) << run.out;
  EXPECT_NE(run.out.find("singular"), std::string::npos) << run.out;
}

TEST_F(ProgramCli, ARunThatReachesASingularStateStopsThere) {
  // theta = 0.3 + 0.2 t reaches pi/2 at t = (pi/2 - 0.3) / 0.2 = 6.354.
  const Outcome run = run_nhdyn("simulate " + example("cart_pendulum_program.toml") + " --t-end 10 -o out.csv", dir_);
  EXPECT_EQ(run.exit_code, 1) << run.out;
  EXPECT_NE(run.out.find("failed at t = 6.35"), std::string::npos) << run.out;
  EXPECT_NE(run.out.find("'swing'"), std::string::npos) << run.out;
}

TEST_F(ProgramCli, UnknownActuatorCoordinateIsNamed) {
  write("m.toml", plane_model("[[programs]]\nname = \"px\"\nposition = \"x - t\"\nactuator = \"xx\"\n"));
  const Outcome run = run_nhdyn("simulate m.toml", dir_);
  EXPECT_EQ(run.exit_code, 2) << run.out;
  EXPECT_NE(run.out.find("m.toml:"), std::string::npos) << run.out;
  EXPECT_NE(run.out.find("program 'px'"), std::string::npos) << run.out;
  EXPECT_NE(run.out.find("the actuator 'xx' is not a coordinate"), std::string::npos) << run.out;
  EXPECT_NE(run.out.find("did you mean 'x'"), std::string::npos) << run.out;
}

TEST_F(ProgramCli, MoreProgramsThanDegreesOfFreedomSaysHowManyArePossible) {
  write("m.toml", plane_model("[[programs]]\nname = \"p1\"\nposition = \"x - t\"\nactuator = \"x\"\n"
                              "[[programs]]\nname = \"p2\"\nposition = \"y - t\"\nactuator = \"y\"\n",
                              "[[constraints]]\nname = \"line\"\nposition = \"y - x\"\n"));
  const Outcome run = run_nhdyn("simulate m.toml", dir_);
  EXPECT_EQ(run.exit_code, 2) << run.out;
  EXPECT_NE(run.out.find("2 programs for k = n - s = 2 - 1 = 1 degrees of freedom: at most 1 programs are possible"),
            std::string::npos)
      << run.out;
  EXPECT_NE(run.out.find("'p2'"), std::string::npos) << run.out;
}

TEST_F(ProgramCli, ZeroActuatorDirectionIsRefused) {
  write("m.toml", plane_model("[[programs]]\nname = \"px\"\nposition = \"x - t\"\nactuator = [0, \"0*m\"]\n"));
  const Outcome run = run_nhdyn("simulate m.toml", dir_);
  EXPECT_EQ(run.exit_code, 2) << run.out;
  EXPECT_NE(run.out.find("program 'px': its actuator direction ([0, 0*m]) is zero"), std::string::npos) << run.out;
}

TEST_F(ProgramCli, ActuatorThatTheConstraintsAbsorbIsRefused) {
  // The constraint y = 0 holds the mass on the x axis; a force along y pushes into it.
  write("m.toml", plane_model("[[programs]]\nname = \"px\"\nposition = \"x - t\"\nactuator = \"y\"\n"
                              "[initial]\nposition = { x = 0, y = 0 }\nvelocity = { x = 1, y = 0 }\n",
                              "[[constraints]]\nname = \"rail\"\nposition = \"y\"\n"));
  const Outcome run = run_nhdyn("simulate m.toml", dir_);
  EXPECT_EQ(run.exit_code, 2) << run.out;
  EXPECT_NE(run.out.find("the actuator of program 'px' (y) pushes straight into the physical constraints"),
            std::string::npos)
      << run.out;
}

// An actuator written as 1e-200 times a direction acts along that direction: the motion is the
// plain actuator's and its force u is 1e200 times larger (the test of D B = 0 squared the entries,
// which underflowed to 0 and blamed the constraints).
TEST_F(ProgramCli, AnActuatorOfTinyMagnitudeActsAlongItsDirection) {
  // Weight along -y; the slope x' + y' = 0 and the program x - y = t hold x'' = y'' = 0, so the
  // slope's reaction carries the weight, lambda = m g, and the actuator balances it: u = -m g.
  const std::string program = "[forces]\ny = \"-9.81*m\"\n"
                              "[[programs]]\nname = \"px\"\nposition = \"x - y - t\"\nactuator = [{}, 0]\n"
                              "[initial]\nposition = { x = 0, y = 0 }\nvelocity = { x = 0.5, y = -0.5 }\n";
  const auto with = [&](const std::string& magnitude) {
    std::string text = program;
    text.replace(text.find("{}"), 2, magnitude);
    return plane_model(text, "[[constraints]]\nname = \"slope\"\nvelocity = \"x' + y'\"\n");
  };
  write("plain.toml", with("1"));
  write("tiny.toml", with("\"1e-200\""));
  const Outcome plain = run_nhdyn("simulate plain.toml --t-end 1 -q -o plain.csv", dir_);
  ASSERT_EQ(plain.exit_code, 0) << plain.out;
  const Outcome tiny = run_nhdyn("simulate tiny.toml --t-end 1 -q -o tiny.csv", dir_);
  ASSERT_EQ(tiny.exit_code, 0) << tiny.out;
  const auto last_row = [&](const std::string& file) {
    const std::string body = nhdyn::test::csv_body(read(file));
    std::istringstream lines(body);
    std::string header, line, last;
    std::getline(lines, header);
    while (std::getline(lines, line)) last = line;
    return std::pair{split(header), split(last)};
  };
  const auto [names, a] = last_row("plain.csv");
  const auto [names_tiny, b] = last_row("tiny.csv");
  ASSERT_EQ(names, names_tiny);
  ASSERT_EQ(a.size(), names.size());
  ASSERT_EQ(b.size(), names.size());
  for (std::size_t i = 0; i < names.size(); ++i) {
    const double x = std::stod(a[i]), y = std::stod(b[i]);
    if (names[i] == "u_px") {
      EXPECT_NEAR(x, -9.81 * 2.0, 1e-9) << "the plain actuator's force";
      EXPECT_NEAR(y * 1e-200, x, 1e-9 * std::abs(x)) << names[i];
    } else if (names[i] == "x" || names[i] == "y" || names[i] == "x'" || names[i] == "y'") {
      EXPECT_NEAR(y, x, 1e-9 * (1.0 + std::abs(x))) << names[i];
    }
  }
}

TEST_F(ProgramCli, ProgramsInConflictWithTheConstraintsAreReportedWithTheirResiduals) {
  // The rail holds y = 0; the program asks for y = 1 + t: violated at the initial state.
  write("m.toml", plane_model("[[programs]]\nname = \"lift\"\nposition = \"y - 1 - t\"\nactuator = \"y\"\n"
                              "[initial]\nposition = { x = 0, y = 0 }\nvelocity = { x = 1, y = 0 }\n",
                              "[[constraints]]\nname = \"rail\"\nposition = \"y\"\n"));
  const Outcome run = run_nhdyn("simulate m.toml", dir_);
  EXPECT_EQ(run.exit_code, 2) << run.out;
  EXPECT_NE(run.out.find("violates its programs"), std::string::npos) << run.out;
  EXPECT_NE(run.out.find("lift (position level): residual -1"), std::string::npos) << run.out;
  EXPECT_NE(run.out.find("lift (velocity level): residual -1"), std::string::npos) << run.out;
}

TEST_F(ProgramCli, ProgramRepeatingAConstraintIsSingular) {
  // Met at the initial state, but the program asks for what the constraint already enforces.
  write("m.toml", plane_model("[[programs]]\nname = \"same\"\nposition = \"y\"\nactuator = \"x\"\n"
                              "[initial]\nposition = { x = 0, y = 0 }\nvelocity = { x = 1, y = 0 }\n",
                              "[[constraints]]\nname = \"rail\"\nposition = \"y\"\n"));
  const Outcome run = run_nhdyn("simulate m.toml", dir_);
  EXPECT_EQ(run.exit_code, 2) << run.out;
  EXPECT_NE(run.out.find("Programs involved: 'same'"), std::string::npos) << run.out;
}

TEST_F(ProgramCli, ProgramsNeedTheSanhFormulation) {
  const Outcome run = run_nhdyn("simulate " + example("sled_heading_program.toml") + " --method lagrange", dir_);
  EXPECT_EQ(run.exit_code, 2) << run.out;
  EXPECT_NE(run.out.find("only the sanh formulation solves"), std::string::npos) << run.out;
}

}  // namespace
