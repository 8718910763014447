// Events on contact forces end to end (docs/multibody.md "Contact forces", docs/cli.md "Events"):
// `nhdyn simulate examples/rolling_disk_liftoff.toml` stops the falling disk where its normal
// force disk_N crosses zero, at the theta of the closed form of docs/derivations/contact-forces.md
// section 6.4; the event is a row of the CSV (with disk_N zero to round-off) and of
// FILE-events.csv; --stop-when and --event name the columns too; and an event on a contact force
// that the model lacks or does not determine (NaN by design) is refused with exit 2 before the run.
#include <gtest/gtest.h>
#include <unistd.h>

#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include "nhdyn/io/csv.hpp"
#include "support/cli_run.hpp"
#include "support/models.hpp"
#include "support/text.hpp"

namespace {

namespace fs = std::filesystem;

using nhdyn::test::contains;
using nhdyn::test::read_text;
using nhdyn::test::run_nhdyn;
using nhdyn::test::split;

class CliContactEvents : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() / ("nhdyn-contact-events-" + std::to_string(::getpid()) + "-" +
                                        ::testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::remove_all(dir_);
    fs::create_directories(dir_);
  }
  void TearDown() override { fs::remove_all(dir_); }
  fs::path dir_;
};

const std::string kLiftoffExample = std::string(NHDYN_SOURCE_DIR) + "/examples/rolling_disk_liftoff.toml";

// theta where the disk's N = fraction * m g on the way down (docs/derivations/contact-forces.md 6.4,
// theta0 = 0.1 at rest): the larger root c of 12 c^2 - 8 k c + 1 - 5 fraction = 0, k = cos(theta0).
double liftoff_theta(double fraction) {
  const double k = std::cos(0.1);
  return std::acos((8 * k + std::sqrt(64 * k * k - 48 * (1 - 5 * fraction))) / 24);
}

// The example's rtol is 1e-11: the located state is as accurate as the solution, a modest multiple
// of it (tests/multibody/contact_events_test.cpp); 100 rtol.
constexpr double kLiftoffCliTolerance = 1e-9;

// FILE-events.csv: the header and, per event, its name and numbers.
struct ContactEventsTable {
  std::vector<std::string> header, names;
  std::vector<std::vector<double>> rows;
  std::size_t column(const std::string& name) const {
    for (std::size_t i = 1; i < header.size(); ++i)
      if (header[i] == name) return i - 1;
    ADD_FAILURE() << "no column " << name;
    return 0;
  }
};

ContactEventsTable load_contact_events(const fs::path& path) {
  ContactEventsTable table;
  std::ifstream in(path);
  std::string line;
  while (std::getline(in, line) && line.starts_with('#')) {
  }  // the provenance header (io/provenance.hpp)
  if (line.empty()) return table;
  table.header = split(line);
  while (std::getline(in, line)) {
    const std::vector<std::string> cells = split(line);
    table.names.push_back(cells.at(0));
    std::vector<double> values;
    for (std::size_t i = 1; i < cells.size(); ++i) values.push_back(std::stod(cells[i]));
    table.rows.push_back(values);
  }
  return table;
}

std::size_t csv_column(const nhdyn::CsvTable& csv, const std::string& name) {
  for (std::size_t i = 0; i < csv.header.size(); ++i)
    if (csv.header[i] == name) return i;
  ADD_FAILURE() << "no column " << name;
  return 0;
}

TEST_F(CliContactEvents, TheLiftoffExampleStopsWhereTheNormalForceVanishes) {
  // docs/multibody.md, "Events on contact forces".
  const nhdyn::test::CliOutcome run = run_nhdyn("simulate '" + kLiftoffExample + "' -o liftoff.csv", dir_);
  ASSERT_EQ(run.exit_code, 0) << run.out;
  EXPECT_TRUE(contains(run.out, "stopped by event 'liftoff'")) << run.out;
  EXPECT_TRUE(contains(run.out, "events: 1 located -> liftoff-events.csv")) << run.out;

  const ContactEventsTable events = load_contact_events(dir_ / "liftoff-events.csv");
  ASSERT_EQ(events.names.size(), 1u);
  EXPECT_EQ(events.names[0], "liftoff");
  const std::vector<double>& e = events.rows[0];
  EXPECT_NEAR(e[events.column("theta")], liftoff_theta(0.0), kLiftoffCliTolerance);
  EXPECT_NEAR(e[events.column("t")], 0.49015, 2e-5);

  // The event's state is the CSV's last row (the run stops there), with disk_N zero to round-off.
  const nhdyn::CsvTable csv = nhdyn::load_csv(dir_ / "liftoff.csv");
  ASSERT_GT(csv.rows.size(), 2u);
  const std::vector<double>& last = csv.rows.back();
  EXPECT_EQ(last[csv_column(csv, "t")], e[events.column("t")]);
  EXPECT_EQ(last[csv_column(csv, "theta")], e[events.column("theta")]);
  EXPECT_LT(std::abs(last[csv_column(csv, "disk_N")]), 1e-11);  // m g = 4.905 N
  for (std::size_t i = 0; i + 1 < csv.rows.size(); ++i) EXPECT_GT(csv.rows[i][csv_column(csv, "disk_N")], 0.0);
}

TEST_F(CliContactEvents, StopWhenAndEventNameTheColumns) {
  // A threshold of the column in the parameters: N = m g / 10 is reached before the liftoff.
  nhdyn::test::CliOutcome run =
      run_nhdyn("simulate '" + kLiftoffExample + "' --stop-when 'disk_N < m*g/10' -o tenth.csv", dir_);
  ASSERT_EQ(run.exit_code, 0) << run.out;
  EXPECT_TRUE(contains(run.out, "stopped by event 'disk_N < m*g/10'")) << run.out;
  ContactEventsTable events = load_contact_events(dir_ / "tenth-events.csv");
  ASSERT_EQ(events.names.size(), 1u);
  EXPECT_NEAR(events.rows[0][events.column("theta")], liftoff_theta(0.1), kLiftoffCliTolerance);

  // --event on the lateral force: F_lat = (4/5) m g sin(theta)(2 k - 3 c) changes sign at c = 2k/3,
  // before the liftoff, which then stops the run.
  run = run_nhdyn("simulate '" + kLiftoffExample + "' --event slide=disk_Flat -o lat.csv", dir_);
  ASSERT_EQ(run.exit_code, 0) << run.out;
  events = load_contact_events(dir_ / "lat-events.csv");
  ASSERT_EQ(events.names.size(), 2u);
  EXPECT_EQ(events.names[0], "slide");
  EXPECT_NEAR(events.rows[0][events.column("theta")], std::acos(2 * std::cos(0.1) / 3), kLiftoffCliTolerance);
  EXPECT_EQ(events.names[1], "liftoff");
}

TEST_F(CliContactEvents, MissingOrUndeterminedContactForcesAreRefusedBeforeTheRun) {
  // The sled held flat by its frames: blade_N is NaN by design (docs/multibody.md).
  const std::string sled = nhdyn::test::kFlatSledBodies;
  std::ofstream(dir_ / "sled.toml") << sled;
  std::ofstream(dir_ / "sled_event.toml") << sled << "\n[[events]]\nname = \"lift\"\nwhen = \"blade_N\"\n";
  const std::string pendulum = std::string(NHDYN_SOURCE_DIR) + "/examples/pendulum_cartesian.toml";
  struct Case {
    std::string args;
    std::vector<std::string> said;
  };
  const std::vector<Case> cases = {
      {"simulate sled.toml --stop-when 'blade_N < 0'",
       {"--stop-when \"blade_N < 0\"", "'blade_N', which model 'sled-bodies' does not determine", "NaN"}},
      {"simulate sled.toml --event 'up=blade_Fz'", {"'blade_Fz', which model 'sled-bodies' does not determine"}},
      {"simulate sled_event.toml", {"sled_event.toml:37:9: event 'lift' reads the contact force 'blade_N'"}},
      {"simulate '" + pendulum + "' --stop-when 'disk_N < 0'",
       {"unknown symbol 'disk_N'", "model 'pendulum-cartesian' has no contact forces"}},
  };
  for (const Case& c : cases) {
    const nhdyn::test::CliOutcome run = run_nhdyn(c.args + " -o r.csv", dir_);
    EXPECT_EQ(run.exit_code, 2) << c.args << "\n" << run.out;
    for (const std::string& s : c.said) EXPECT_TRUE(contains(run.out, s)) << c.args << "\n" << run.out;
    EXPECT_FALSE(fs::exists(dir_ / "r.csv")) << c.args;
    EXPECT_FALSE(fs::exists(dir_ / "r-events.csv")) << c.args;
    EXPECT_FALSE(fs::exists(dir_ / "r.partial.csv")) << c.args;
  }
  // The determined lateral force is accepted.
  const nhdyn::test::CliOutcome run = run_nhdyn("simulate sled.toml --t-end 0.5 --event 'side=blade_Flat' -o r.csv", dir_);
  EXPECT_EQ(run.exit_code, 0) << run.out;
}

}  // namespace
