// Events on contact forces end to end (docs/multibody.md "Contact forces", docs/cli.md "Events"):
// `nhdyn simulate examples/rolling_disk_liftoff.toml` stops the falling disk where its normal
// force disk_N crosses zero, at the theta of the closed form of docs/derivations/contact-forces.md
// section 6.4; the event is a row of the CSV (with disk_N zero to round-off) and of
// FILE-events.csv; --stop-when and --event name the columns too; and an event on a contact force
// that the model lacks or does not determine (NaN by design) is refused with exit 2 before the run.
// The same disk as a [[contacts]] entry that may slide, lift off and land
// (examples/rolling_disk_hop.toml, docs/contact-modes.md): dropped at a lean it lands where its rim
// meets the floor, flies between its bounces as a free body, and the impacts' energy is booked in
// impact_loss; released on the floor it slips at the closed-form angle and does not hop; without a
// friction limit it reaches N = 0 at the same closed form and the run ends there (no mode is
// consistent).
#include <gtest/gtest.h>
#include <unistd.h>

#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <functional>
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

const std::string kHopExample = std::string(NHDYN_SOURCE_DIR) + "/examples/rolling_disk_hop.toml";

// The hop example's parameters (m, r, g) and its drop (theta0, h).
constexpr double kM = 0.5, kR = 0.2, kG = 9.81, kTheta0 = 0.3, kH = 0.05;

// The planar state of the disk (it leans about x; x, psi and phi stay 0) from a CSV or events row.
struct DiskState {
  double t, y, z, theta, vy, vz, w;
  double kinetic() const { return 0.5 * kM * (vy * vy + vz * vz) + 0.5 * (kM * kR * kR / 4) * w * w; }
  // Free flight: the centre on a parabola, the lean rate constant (no moment about the centre, and
  // the diameter it turns about is a principal axis).
  DiskState fly(double tau) const {
    return {t + tau, y + vy * tau, z + vz * tau - kG * tau * tau / 2, theta + w * tau, vy, vz - kG * tau, w};
  }
  double gap() const { return z - kR * std::cos(theta); }  // the rim's lowest point above the floor
};

DiskState disk_state(const std::vector<double>& row, const std::function<std::size_t(const std::string&)>& col) {
  for (const char* zero : {"x", "psi", "phi", "x'", "psi'", "phi'"}) EXPECT_EQ(row[col(zero)], 0.0) << zero;
  return {row[col("t")], row[col("y")], row[col("z")], row[col("theta")], row[col("y'")], row[col("z'")],
          row[col("theta'")]};
}

// The first time after `from` (gap 0, rising) at which the free flight's gap falls through 0.
double next_touchdown(const DiskState& from) {
  double lo = 1e-9, hi = lo;
  while (from.fly(hi).gap() > 0.0) {
    lo = hi;
    hi += 1e-3;
    if (hi > 1.0) return NAN;
  }
  for (int i = 0; i < 200 && hi - lo > 1e-15; ++i) {
    const double mid = (lo + hi) / 2;
    (from.fly(mid).gap() > 0.0 ? lo : hi) = mid;
  }
  return from.t + (lo + hi) / 2;
}

TEST_F(CliContactEvents, TheDroppedDiskLandsWhereItsRimMeetsTheFloorAndFliesAsAFreeBodyBetweenBounces) {
  const nhdyn::test::CliOutcome run = run_nhdyn("simulate '" + kHopExample + "' -o hop.csv", dir_);
  ASSERT_EQ(run.exit_code, 0) << run.out;
  const ContactEventsTable events = load_contact_events(dir_ / "hop-events.csv");
  ASSERT_EQ(events.names.size(), 3u) << run.out;
  const nhdyn::CsvTable csv = nhdyn::load_csv(dir_ / "hop.csv");
  const auto col = [&](const std::string& name) { return csv_column(csv, name); };
  const auto event_col = [&](const std::string& name) { return events.column(name); };

  // The first fall: the rim drops h at rest, theta stays theta0.
  const double t1 = std::sqrt(2 * kH / kG);
  double loss_before = 0.0, kinetic_before = 0.5 * kM * (kG * t1) * (kG * t1);
  double t_landing = t1;
  for (std::size_t k = 0; k < events.names.size(); ++k) {
    EXPECT_EQ(events.names[k], "disk_touchdown");
    const std::vector<double>& e = events.rows[k];
    // Located where the rim meets the floor, on the flight before it (closed form).
    EXPECT_NEAR(e[event_col("t")], t_landing, 1e-9) << k;
    if (k == 0) {
      EXPECT_NEAR(e[event_col("theta")], kTheta0, 1e-12);
    }
    // The touchdown's row carries the velocities after the impact; h jumps by T+ - T-, booked in
    // impact_loss (V is continuous), so h - h0 - W does not jump.
    std::size_t at = 0;
    while (at < csv.rows.size() && csv.rows[at][col("t")] != e[event_col("t")]) ++at;
    ASSERT_LT(at, csv.rows.size()) << "no row at touchdown " << k;
    const DiskState after = disk_state(csv.rows[at], col);
    EXPECT_EQ(csv.rows[at][col("disk_mode")], 2.0);  // it bounces: free
    EXPECT_GT(after.vz + kR * std::sin(after.theta) * after.w, 0.0);  // the rim's lowest point rises
    const double loss = csv.rows[at][col("impact_loss")];
    EXPECT_GT(loss - loss_before, 0.0);
    EXPECT_NEAR(loss - loss_before, kinetic_before - after.kinetic(), 1e-9) << k;
    loss_before = loss;

    // The flight to the next touchdown (or t_end): every row on the closed-form free flight.
    const double t_next = next_touchdown(after);
    const double t_until = k + 1 < events.names.size() ? events.rows[k + 1][event_col("t")] : 0.3;
    int rows = 0;
    for (std::size_t i = at + 1; i < csv.rows.size() && csv.rows[i][col("t")] < t_until; ++i, ++rows) {
      const DiskState s = disk_state(csv.rows[i], col);
      const DiskState f = after.fly(s.t - after.t);
      EXPECT_NEAR(s.y, f.y, 1e-10);
      EXPECT_NEAR(s.z, f.z, 1e-10);
      EXPECT_NEAR(s.theta, f.theta, 1e-10);
      EXPECT_NEAR(s.vy, f.vy, 1e-10);
      EXPECT_NEAR(s.vz, f.vz, 1e-10);
      EXPECT_NEAR(s.w, f.w, 1e-10);  // the angular momentum about the centre, I w, is constant
      EXPECT_EQ(csv.rows[i][col("disk_mode")], 2.0);
      EXPECT_GT(csv.rows[i][col("disk_gap")], 0.0);
      EXPECT_EQ(csv.rows[i][col("impact_loss")], loss);
    }
    EXPECT_GT(rows, 1) << k;
    t_landing = t_next;
    kinetic_before = after.fly(t_next - after.t).kinetic();
  }
  EXPECT_GT(t_landing, 0.3);  // the fourth landing is after t_end
  for (const std::vector<double>& row : csv.rows) EXPECT_LT(std::abs(row[col("balance_error")]), 1e-12);
}

TEST_F(CliContactEvents, TheDiskReleasedOnTheFloorSlipsAtTheClosedFormAndDoesNotHop) {
  // Released at rest at theta0 = 0.1 it rolls about its contact point (N and F_lat of
  // docs/derivations/contact-forces.md 6.4) until |F_lat| = mu N, then slides with N > 0.
  const double mu = 0.5, c0 = std::cos(0.1);
  const auto excess = [&](double theta) {
    const double c = std::cos(theta);
    return 0.8 * std::sin(theta) * std::abs(2 * c0 - 3 * c) - mu * (1 - 8 * c0 * c + 12 * c * c) / 5;
  };
  double lo = 0.1, hi = liftoff_theta(0.0);
  for (int i = 0; i < 200 && hi - lo > 1e-15; ++i) {
    const double mid = (lo + hi) / 2;
    (excess(mid) < 0.0 ? lo : hi) = mid;
  }
  const nhdyn::test::CliOutcome run =
      run_nhdyn("simulate '" + kHopExample + "' --set h=0 --set theta0=0.1 --t-end 0.54 -o slide.csv", dir_);
  ASSERT_EQ(run.exit_code, 0) << run.out;
  const ContactEventsTable events = load_contact_events(dir_ / "slide-events.csv");
  ASSERT_EQ(events.names.size(), 1u) << run.out;
  EXPECT_EQ(events.names[0], "disk_slip");
  EXPECT_NEAR(events.rows[0][events.column("theta")], (lo + hi) / 2, 1e-9);
  const nhdyn::CsvTable csv = nhdyn::load_csv(dir_ / "slide.csv");
  const std::size_t mode = csv_column(csv, "disk_mode");
  for (const std::vector<double>& row : csv.rows) {
    EXPECT_GT(row[csv_column(csv, "disk_N")], 0.5) << row[0];  // m g = 4.905 N: far from lifting off
    EXPECT_LT(std::abs(row[csv_column(csv, "balance_error")]), 1e-9);
    EXPECT_EQ(row[mode], row[0] < events.rows[0][events.column("t")] ? 0.0 : 1.0) << row[0];
  }
  EXPECT_LT(csv.rows.back()[csv_column(csv, "work_friction")], -1e-3);
}

TEST_F(CliContactEvents, TheSlidingDiskThatFallsFlatEndsTheRunSayingSoWithTheRowsBefore) {
  // Sliding on, the disk lies flat near t = 0.562 s, where its contact point is not defined: the
  // run ends with that reason (not the solver's symptom) and every output row before it.
  const nhdyn::test::CliOutcome run =
      run_nhdyn("simulate '" + kHopExample + "' --set h=0 --set theta0=0.1 --t-end 0.8 -o flat.csv", dir_);
  EXPECT_EQ(run.exit_code, 1) << run.out;
  EXPECT_TRUE(contains(run.out, "contact 'disk': the disk lies flat")) << run.out;
  const nhdyn::CsvTable csv = nhdyn::load_csv(dir_ / "flat.partial.csv");
  ASSERT_GT(csv.rows.size(), 2u);
  EXPECT_NEAR(csv.rows.back()[csv_column(csv, "t")], 0.56, 1e-12);  // the last output time before it
}

TEST_F(CliContactEvents, WithoutAFrictionLimitTheDiskReachesNZeroAtTheClosedFormWhereNoModeIsConsistent) {
  std::string text = read_text(kHopExample);
  nhdyn::test::replace_once(text, "friction = \"mu\"\n", "");
  std::ofstream(dir_ / "rolling.toml") << text;
  const nhdyn::test::CliOutcome run = run_nhdyn("simulate rolling.toml --set h=0 --set theta0=0.1 --t-end 0.55 -o r.csv", dir_);
  EXPECT_EQ(run.exit_code, 1) << run.out;
  for (const char* said : {"contact 'disk': its normal force falls to 0 at t = 0.4901525", "|F_t| = 1.72209 N",
                           "gap acceleration -5.925", "no mode is consistent", "Give the contact a friction coefficient"})
    EXPECT_TRUE(contains(run.out, said)) << said << "\n" << run.out;
  // The lift-off row ends the partial results: at the closed-form theta, the mode free.
  const nhdyn::CsvTable csv = nhdyn::load_csv(dir_ / "r.partial.csv");
  ASSERT_GT(csv.rows.size(), 2u);
  const std::vector<double>& last = csv.rows.back();
  EXPECT_NEAR(last[csv_column(csv, "theta")], liftoff_theta(0.0), kLiftoffCliTolerance);
  EXPECT_EQ(last[csv_column(csv, "disk_mode")], 2.0);
  for (std::size_t i = 0; i + 1 < csv.rows.size(); ++i) EXPECT_GT(csv.rows[i][csv_column(csv, "disk_N")], 0.0);
  // F_lat = (4/5) m g sin(theta)(2 c0 - 3 c) there, which the message gives.
  const double c = std::cos(liftoff_theta(0.0));
  EXPECT_NEAR(0.8 * kM * kG * std::sin(liftoff_theta(0.0)) * (2 * std::cos(0.1) - 3 * c), 1.72209, 1e-5);
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
