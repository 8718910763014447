// Events end to end (docs/cli.md "Events", docs/model-format.md [[events]]): the built binary
// (NHDYN_CLI_PATH) locates crossings whose times are known in closed form — the Cartesian
// pendulum's period from its events against 4 sqrt(l/g) K(sin(theta0/2)), the Chaplygin sleigh's
// reversal against -c0/k (docs/gallery/chaplygin_sleigh.md) — the Whipple bicycle is stopped when
// it has fallen at 2 m/s and never at 5 m/s, every event is a row of the CSV and of
// FILE-events.csv, the bytes repeat, a failed run leaves FILE.partial.csv with its reason first,
// and bad input (unknown symbols, malformed conditions, events at zero at the start, a step
// budget below 1, rk4) is refused with exit 2 before anything is written.
#include <gtest/gtest.h>
#include <sys/wait.h>
#include <unistd.h>

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

struct EventsOutcome {
  int exit_code = -1;
  std::string out, err;
};

using nhdyn::test::read_text;

class CliEvents : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() /
           ("nhdyn-events-cli-" + std::to_string(::getpid()) + "-" +
            ::testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::remove_all(dir_);
    fs::create_directories(dir_);
  }
  void TearDown() override { fs::remove_all(dir_); }

  // Runs `nhdyn ARGS` in the test's directory; ARGS is shell text.
  EventsOutcome nhdyn(const std::string& args) const {
    const std::string command =
        "cd '" + dir_.string() + "' && '" NHDYN_CLI_PATH "' " + args + " > out.txt 2> err.txt";
    const int status = std::system(command.c_str());
    EventsOutcome run;
    run.exit_code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
    run.out = read_text(dir_ / "out.txt");
    run.err = read_text(dir_ / "err.txt");
    return run;
  }

  // A copy of an example with `text` appended, or with `from` replaced by `to` first.
  std::string example_copy(const std::string& example, const std::string& append, const std::string& from = "",
                           const std::string& to = "") const {
    std::string text = read_text(fs::path(NHDYN_SOURCE_DIR) / "examples" / example);
    if (!from.empty()) {
      const std::size_t at = text.find(from);
      EXPECT_NE(at, std::string::npos) << from;
      if (at != std::string::npos) text.replace(at, from.size(), to);
    }
    text += append;
    const fs::path path = dir_ / example;
    std::ofstream(path) << text;
    return path.string();
  }

  fs::path dir_;
};

const std::string examples = std::string(NHDYN_SOURCE_DIR) + "/examples/";

// FILE-events.csv: a header, then per event its name and numbers (t, q, q'). The names here have
// no commas or quotes.
struct EventsTable {
  std::vector<std::string> header;
  std::vector<std::string> names;
  std::vector<std::vector<double>> rows;  // t, q, q' (the columns after the name)
  int column(const std::string& name) const {
    for (std::size_t i = 1; i < header.size(); ++i)
      if (header[i] == name) return static_cast<int>(i) - 1;
    return -1;
  }
};

EventsTable load_events(const fs::path& path) {
  EventsTable table;
  std::ifstream in(path);
  std::string line;
  while (std::getline(in, line) && line.starts_with('#')) {
  }  // the provenance header (io/provenance.hpp)
  EXPECT_FALSE(line.empty()) << path;
  std::stringstream header(line);
  for (std::string cell; std::getline(header, cell, ',');) table.header.push_back(cell);
  while (std::getline(in, line)) {
    std::stringstream row(line);
    std::string cell;
    std::getline(row, cell, ',');
    table.names.push_back(cell);
    std::vector<double> values;
    while (std::getline(row, cell, ',')) values.push_back(std::stod(cell));
    EXPECT_EQ(values.size() + 1, table.header.size()) << line;
    table.rows.push_back(values);
  }
  return table;
}

TEST_F(CliEvents, PendulumPeriodFromItsEvents) {
  // x crosses zero at the bottom, alternately rising and falling: crossings k and k + 2 are one
  // period apart. examples/pendulum_cartesian.toml: l = 1.5 m, g = 9.81 m/s^2, theta0 = 2 rad.
  // The second command of docs/cli.md, "Events".
  const EventsOutcome run = nhdyn("simulate " + examples +
                            "pendulum_cartesian.toml --event bottom=x --integrator dop853 --rtol 1e-13 --atol 1e-15 "
                            "-o p.csv");
  ASSERT_EQ(run.exit_code, 0) << run.err;
  const EventsTable events = load_events(dir_ / "p-events.csv");
  ASSERT_EQ(events.header.size(), 6u);
  EXPECT_EQ(events.header[0], "event");
  EXPECT_EQ(events.header[1], "t");
  EXPECT_EQ(events.header[2], "x");
  EXPECT_EQ(events.header[5], "y'");
  for (const std::string& name : events.names) EXPECT_EQ(name, "bottom");
  ASSERT_EQ(events.rows.size(), 6u);  // 10 s is just over three periods of 3.265 s
  const double period = 4.0 * std::sqrt(1.5 / 9.81) * std::comp_ellint_1(std::sin(1.0));
  for (std::size_t k = 0; k + 2 < events.rows.size(); ++k)
    EXPECT_NEAR(events.rows[k + 2][0] - events.rows[k][0], period, 1e-10) << k;
  // The first crossing: a quarter period after the release at rest.
  EXPECT_NEAR(events.rows[0][0], period / 4.0, 1e-10);
  // Each event is a row of the CSV, at its time, with x at the crossing.
  const nhdyn::CsvTable rows = nhdyn::load_csv(dir_ / "p.csv");
  const int x = rows.column("x");
  for (const std::vector<double>& e : events.rows) {
    bool found = false;
    for (const std::vector<double>& r : rows.rows)
      if (r[0] == e[0]) {
        found = true;
        EXPECT_LT(std::abs(r[static_cast<std::size_t>(x)]), 1e-13);
        EXPECT_EQ(r[static_cast<std::size_t>(x)], e[1]);  // the same state in both files
      }
    EXPECT_TRUE(found) << "no row at the event time " << e[0];
  }
  // Rows stay in time order with the events among them: 1001 output rows plus 6 events.
  EXPECT_EQ(rows.rows.size(), 1007u);
  for (std::size_t i = 1; i < rows.rows.size(); ++i) EXPECT_LT(rows.rows[i - 1][0], rows.rows[i][0]);
  EXPECT_NE(run.out.find("events: 6 located"), std::string::npos) << run.out;
}

TEST_F(CliEvents, CvodeLocatesThePendulumCrossingsWithItsRootFinding) {
  const EventsOutcome run = nhdyn("simulate " + examples +
                        "pendulum_cartesian.toml --event bottom=x --integrator cvode-adams --rtol 1e-12 --atol 1e-14 "
                        "--t-end 5 -o p.csv");
  ASSERT_EQ(run.exit_code, 0) << run.err;
  const EventsTable events = load_events(dir_ / "p-events.csv");
  ASSERT_EQ(events.rows.size(), 3u);
  const double period = 4.0 * std::sqrt(1.5 / 9.81) * std::comp_ellint_1(std::sin(1.0));
  EXPECT_NEAR(events.rows[0][0], period / 4.0, 1e-8);
  EXPECT_NEAR(events.rows[2][0] - events.rows[0][0], period, 1e-8);
}

// The [[events]] block of docs/model-format.md.
const std::string sleigh_events = R"(
[[events]]
name = "turned"
when = "cos(phi)*x' + sin(phi)*y'"   # the speed of P along the blade
direction = "rising"
action = "stop"
)";

TEST_F(CliEvents, ChaplyginSleighStopsWhenItHasTurned) {
  // The speed of the contact point along the blade, v(t) = V tanh(k t + c0), changes sign at
  // t = -c0 / k (docs/gallery/chaplygin_sleigh.md (2)), with V^2 = v0^2 + rho^2 w0^2,
  // k = a V / rho^2, sinh(c0) = v0 / (rho w0).
  const std::string model = example_copy("chaplygin_sleigh.toml", sleigh_events);
  const EventsOutcome run = nhdyn("simulate '" + model + "' -o s.csv");
  ASSERT_EQ(run.exit_code, 0) << run.err;
  const double a = 0.3, rho = 0.5, v0 = -1.0, w0 = 1.0;
  const double V = std::sqrt(v0 * v0 + rho * rho * w0 * w0);
  const double k = a * V / (rho * rho);
  const double c0 = std::asinh(v0 / (rho * w0));
  const EventsTable events = load_events(dir_ / "s-events.csv");
  ASSERT_EQ(events.rows.size(), 1u);
  EXPECT_EQ(events.names[0], "turned");
  EXPECT_NEAR(events.rows[0][0], -c0 / k, 1e-9);
  // The run ends there: its last row is the event's.
  const nhdyn::CsvTable rows = nhdyn::load_csv(dir_ / "s.csv");
  EXPECT_EQ(rows.rows.back()[0], events.rows[0][0]);
  EXPECT_NE(run.out.find("stopped by event 'turned'"), std::string::npos) << run.out;
}

TEST_F(CliEvents, BicycleFallsAtTwoMetresPerSecondAndNotAtFive) {
  // examples/whipple_bicycle.toml with a roll rate of 0.5 rad/s at the start: below the stable
  // speed range (about 4.3 to 6 m/s) the bicycle falls over, inside it it recovers.
  const std::string model = example_copy("whipple_bicycle.toml", "", "velocity = { x = \"v\", ",
                                         "velocity = { x = \"v\", phi = \"0.5\", ");
  const EventsOutcome slow = nhdyn("simulate '" + model + "' --set v=2 --t-end 10 --stop-when 'abs(phi) > 1' -o slow.csv");
  ASSERT_EQ(slow.exit_code, 0) << slow.err;
  const EventsTable fallen = load_events(dir_ / "slow-events.csv");
  ASSERT_EQ(fallen.rows.size(), 1u);
  const int phi = fallen.column("phi");
  EXPECT_NEAR(std::abs(fallen.rows[0][static_cast<std::size_t>(phi)]), 1.0, 1e-12);
  EXPECT_GT(fallen.rows[0][0], 0.5);
  EXPECT_LT(fallen.rows[0][0], 10.0);
  EXPECT_NE(slow.out.find("stopped by event 'abs(phi) > 1'"), std::string::npos) << slow.out;

  const EventsOutcome fast = nhdyn("simulate '" + model + "' --set v=5 --t-end 10 --stop-when 'abs(phi) > 1' -o fast.csv");
  ASSERT_EQ(fast.exit_code, 0) << fast.err;
  EXPECT_EQ(load_events(dir_ / "fast-events.csv").rows.size(), 0u);
  const nhdyn::CsvTable rows = nhdyn::load_csv(dir_ / "fast.csv");
  EXPECT_EQ(rows.rows.back()[0], 10.0);
  double largest = 0.0;
  for (const std::vector<double>& r : rows.rows)
    largest = std::max(largest, std::abs(r[static_cast<std::size_t>(rows.column("phi"))]));
  EXPECT_LT(largest, 0.5);  // it never came near falling
}

TEST_F(CliEvents, TheStopWhenExampleOfTheDocs) {
  // docs/cli.md, "Events": the pendulum released at theta0 = 2 rad passes the bottom after P/4.
  const EventsOutcome run = nhdyn("simulate " + examples + "pendulum_cartesian.toml --stop-when \"x < 0\" -o pendulum.csv");
  ASSERT_EQ(run.exit_code, 0) << run.err;
  EXPECT_NE(run.out.find("stopped by event 'x < 0', 83 rows -> pendulum.csv"), std::string::npos) << run.out;
  EXPECT_NE(run.out.find("events: 1 located -> pendulum-events.csv\n    x < 0 at t = 0.81625294126\n"),
            std::string::npos)
      << run.out;
  const double quarter = std::sqrt(1.5 / 9.81) * std::comp_ellint_1(std::sin(1.0));
  EXPECT_NEAR(load_events(dir_ / "pendulum-events.csv").rows.at(0).at(0), quarter, 1e-9);
}

TEST_F(CliEvents, SameInputSameBytes) {
  const std::string args = "simulate " + examples + "pendulum_cartesian.toml --event bottom=x --t-end 4 -o ";
  ASSERT_EQ(nhdyn(args + "a.csv").exit_code, 0);
  ASSERT_EQ(nhdyn(args + "b.csv").exit_code, 0);
  EXPECT_EQ(read_text(dir_ / "a.csv"), read_text(dir_ / "b.csv"));
  EXPECT_EQ(read_text(dir_ / "a-events.csv"), read_text(dir_ / "b-events.csv"));
}

// A run whose steps no longer advance (here a spring of 1e12 N/m under dopri5 over 100 s; a
// solution running into a singularity it cannot pass does the same) ends at the first check, after
// 1e5 steps, saying what the pace would need, not after the whole step budget.
TEST_F(CliEvents, ARunThatStallsEndsWhenItsPaceCannotReachTheEnd) {
  std::ofstream(dir_ / "stiff.toml") << R"toml(name = "stiff-spring"
coordinates = ["x"]
kinetic_energy = "m/2 * x'^2"
potential_energy = "k/2 * x^2"
[parameters]
m = 1.0
k = 1e12
[initial]
position = { x = 1e-6 }
velocity = { x = 0 }
[simulation]
t_end = 100
output_step = 10
)toml";
  const EventsOutcome run = nhdyn("simulate stiff.toml --max-steps 1000000 -o s.csv");
  EXPECT_EQ(run.exit_code, 1) << run.err;
  EXPECT_NE(run.err.find("dopri5: the integration stalls at t = 0.00"), std::string::npos) << run.err;
  EXPECT_NE(run.err.find("its last 100000 steps advanced t by"), std::string::npos) << run.err;
  EXPECT_NE(run.err.find("try cvode-bdf"), std::string::npos) << run.err;
  EXPECT_TRUE(fs::exists(dir_ / "s.partial.csv"));
}

TEST_F(CliEvents, AFailedRunKeepsItsRowsInAPartialFile) {
  const EventsOutcome run = nhdyn("simulate " + examples + "pendulum_cartesian.toml --max-steps 40 -o p.csv");
  EXPECT_EQ(run.exit_code, 1) << run.err;
  EXPECT_FALSE(fs::exists(dir_ / "p.csv"));
  ASSERT_TRUE(fs::exists(dir_ / "p.partial.csv")) << run.err;
  const std::string text = read_text(dir_ / "p.partial.csv");
  const std::string first = text.substr(0, text.find('\n'));
  EXPECT_EQ(first.rfind("# nhdyn: simulation of 'pendulum-cartesian' failed at t = ", 0), 0u) << first;
  EXPECT_NE(first.find("budget of 40 steps"), std::string::npos) << first;
  // The rest is the CSV the run would have written, up to the failure.
  std::ofstream(dir_ / "rest.csv") << text.substr(text.find('\n') + 1);
  const nhdyn::CsvTable rows = nhdyn::load_csv(dir_ / "rest.csv");
  EXPECT_EQ(rows.header[0], "t");
  ASSERT_GT(rows.rows.size(), 2u);
  EXPECT_EQ(rows.rows[0][0], 0.0);
  EXPECT_NE(run.err.find("p.partial.csv"), std::string::npos) << run.err;
}

// Each refused with exit 2 before a row is computed, with a message that says what and where.
TEST_F(CliEvents, BadInputIsRefusedBeforeTheRun) {
  const std::string pendulum = examples + "pendulum_cartesian.toml";
  const std::string sleigh = examples + "chaplygin_sleigh.toml";
  struct Case {
    std::string args;
    std::vector<std::string> said;
  };
  const std::string unknown = example_copy("chaplygin_sleigh.toml",
                                           "\n[[events]]\nname = \"turned\"\nwhen = \"cos(phii)*x'\"\n");
  const std::vector<Case> cases = {
      {"simulate '" + unknown + "'", {"chaplygin_sleigh.toml:68:13: ", "unknown symbol 'phii'", "did you mean 'phi'?"}},
      {"simulate " + pendulum + " --stop-when 'abs(x) 1.2'", {"--stop-when \"abs(x) 1.2\"", "expected a condition"}},
      {"simulate " + pendulum + " --stop-when 'abs(x) = 1.2'", {"unexpected '='", "LHS > RHS"}},
      {"simulate " + pendulum + " --stop-when 'abs(xx) > 1.2'", {"unknown symbol 'xx'", "did you mean 'x'?", "column 5"}},
      {"simulate " + pendulum + " --event 'far=abs(xx)'", {"--event \"far=abs(xx)\"", "did you mean 'x'?"}},
      {"simulate " + pendulum + " --event 'abs(x)'", {"expected NAME=EXPR"}},
      {"simulate " + sleigh + " --event 'start=x'", {"--event \"start=x\": event 'start'", "already at zero at the start"}},
      {"simulate " + sleigh + " --stop-when 'phi > -1'", {"--stop-when \"phi > -1\": ", "already holds at the start"}},
      {"simulate " + sleigh + " --stop-when 'abs(phii) > 1'",
       {"--stop-when \"abs(phii) > 1\": unknown symbol 'phii'; did you mean 'phi'? (column 5 of \"abs(phii) > 1\")"}},
      {"simulate " + sleigh + " --stop-when 'phi > 1 > 2'", {"expected one comparison"}},
      {"simulate " + pendulum + " --max-steps 0", {"max_steps (--max-steps) = 0 must be at least 1", "(default 50000000)"}},
      {"simulate " + pendulum + " --max-steps=-5", {"max_steps (--max-steps) = -5 must be at least 1"}},
      {"simulate " + pendulum + " --event bottom=x --integrator rk4", {"rk4", "dopri5, dop853"}},
      {"simulate " + pendulum + " --event \"up=R_xx\"", {"unknown symbol 'R_xx'", "did you mean 'R_x'?"}},
  };
  for (const Case& c : cases) {
    const EventsOutcome run = nhdyn(c.args + " -o r.csv");
    EXPECT_EQ(run.exit_code, 2) << c.args << "\n" << run.err;
    for (const std::string& s : c.said) EXPECT_NE(run.err.find(s), std::string::npos) << c.args << "\n" << run.err;
    EXPECT_FALSE(fs::exists(dir_ / "r.csv")) << c.args;
    EXPECT_FALSE(fs::exists(dir_ / "r-events.csv")) << c.args;
    EXPECT_FALSE(fs::exists(dir_ / "r.partial.csv")) << c.args;
  }
}

TEST_F(CliEvents, ModelFileEventKeysAreChecked) {
  const std::string bad_direction = example_copy(
      "chaplygin_sleigh.toml", "\n[[events]]\nname = \"turned\"\nwhen = \"phi\"\ndirection = \"raising\"\n");
  EventsOutcome run = nhdyn("simulate '" + bad_direction + "' -o r.csv");
  EXPECT_EQ(run.exit_code, 2);
  EXPECT_NE(run.err.find("did you mean 'rising'?"), std::string::npos) << run.err;
  const std::string no_when =
      example_copy("chaplygin_sleigh.toml", "\n[[events]]\nname = \"turned\"\nwhen_ = \"phi\"\n");
  run = nhdyn("simulate '" + no_when + "' -o r.csv");
  EXPECT_EQ(run.exit_code, 2);
  EXPECT_NE(run.err.find("did you mean 'when'?"), std::string::npos) << run.err;
}

}  // namespace
