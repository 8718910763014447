// A closed-form contact point that turns singular along the run (docs/multibody.md, "Rolling
// bodies"): a thin disk released leaning far falls flat, where its contact point (the lowest point
// of the rim) is not defined. The run stops there with exit code 1 and a message naming the
// contact, the time and the reason; the rows before are in the partial file, with no NaN. The same
// disk as a [[wheels]] entry likewise, located at every step (before, the wheel rolled on through
// the plane, exit 0).
#include <gtest/gtest.h>
#include <unistd.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <string>

#include "nhdyn/io/csv.hpp"
#include "support/cli_run.hpp"
#include "support/text.hpp"

namespace {

namespace fs = std::filesystem;

constexpr const char* kFallingDisk = R"toml(name = "disk-falling-flat"
coordinates = ["x", "y", "z", "psi", "theta", "phi"]
gravity = [0, 0, "-g"]

[parameters]
m = 0.5
r = 0.2
g = 9.81
theta0 = 1.2

[[frames]]
name = "disk"
translation = ["x", "y", "z"]
rotations = [["z", "psi"], ["x", "theta"], ["y", "phi"]]

[[bodies]]
name = "disk"
frame = "disk"
mass = "m"
inertia = ["m*r^2/4", "m*r^2/2", "m*r^2/4"]

[[contacts]]
name = "wheel"
body = "disk"
shape = { disk = "r", axis = "y" }

[initial]
position = { x = 0, y = 0, z = "r*cos(theta0)", psi = 0, theta = "theta0", phi = 0 }

[simulation]
t_end = 1
output_step = 0.01
)toml";

// The run of `text` as flat.toml stops with exit 1 where the disk lies flat, naming the entry and
// the reason (`stop` says the measure and the time), with the rows before in the partial file:
// finite, the lean theta growing toward pi/2 (flat), the centre above the plane.
void expect_stops_flat(const std::string& text, const std::string& folder, const std::string& reason,
                       const std::string& stop) {
  const fs::path dir = fs::temp_directory_path() / folder;
  fs::create_directories(dir);
  fs::remove(dir / "o.csv");
  fs::remove(dir / "o.partial.csv");
  std::ofstream(dir / "flat.toml") << text;
  const nhdyn::test::CliOutcome outcome = nhdyn::test::run_nhdyn("simulate flat.toml -o o.csv", dir);
  EXPECT_EQ(outcome.exit_code, 1) << outcome.out;
  EXPECT_NE(outcome.out.find("flat.toml:22:1: " + reason), std::string::npos) << outcome.out;
  EXPECT_NE(outcome.out.find(stop), std::string::npos) << outcome.out;
  EXPECT_EQ(outcome.out.find("not a complement"), std::string::npos) << outcome.out;  // not the equations' symptom
  EXPECT_FALSE(fs::exists(dir / "o.csv"));
  const nhdyn::CsvTable partial = nhdyn::load_csv(dir / "o.partial.csv");
  ASSERT_GE(partial.rows.size(), 10u);
  const int theta = partial.column("theta");
  const int z = partial.column("z");
  for (const auto& row : partial.rows) {
    for (const double value : row) EXPECT_TRUE(std::isfinite(value));
    EXPECT_LT(row[static_cast<std::size_t>(theta)], 2.0 * std::atan(1.0) + 1e-9);
    EXPECT_GT(row[static_cast<std::size_t>(z)], 0.0);
  }
  EXPECT_GT(partial.rows.back()[static_cast<std::size_t>(theta)], 1.5);
}

// The contact's rim keeps its root |axle x normal| = sqrt(cos(theta)^2): the run stops where a step
// fails there, 1 - (axle . normal)^2 at round-off.
TEST(RollingSingularCli, DiskFallingFlatStopsNamingTheContact) {
  expect_stops_flat(kFallingDisk, "nhdyn_rolling_flat",
                    "contact 'wheel': the disk lies flat: its axle is along the ground's normal, where every point of "
                    "its rim is lowest",
                    "(1 - (axle . normal)^2 = ");
}

// The same disk as a [[wheels]] entry.
std::string falling_wheel() {
  std::string text = kFallingDisk;
  const std::string contact = "[[contacts]]\nname = \"wheel\"\nbody = \"disk\"\nshape = { disk = \"r\", axis = \"y\" }\n";
  const std::size_t at = text.find(contact);
  EXPECT_NE(at, std::string::npos);
  if (at != std::string::npos)
    text.replace(at, contact.size(), "[[wheels]]\nname = \"wheel\"\nbody = \"disk\"\naxis = \"y\"\nradius = \"r\"\n");
  return text;
}

// The wheel's rim is written with |axle x normal| = cos(theta), no root that could fail: the run
// stops where that falls through 0.01, located at every step (theta = acos(0.01) = 1.5608).
TEST(RollingSingularCli, WheelFallingFlatStopsWhereItsAxleMeetsTheNormal) {
  expect_stops_flat(falling_wheel(), "nhdyn_rolling_flat_wheel",
                    "wheel 'wheel': the disk lies flat: its axle is along the ground's normal, where every point of "
                    "its rim is lowest",
                    "(|axle x normal| = 0.01) at t = 0.139164, where x = 0, y = -0.0135822, z = 0.002, psi = 0, "
                    "theta = 1.5608,");
}

// Started flat (theta0 = pi/2 on rolling_disk_hop.toml): a bad start, exit 2 before any row (the
// run failed with exit 1 "at t = 0.01" after its first step, the message saying t = 0).
TEST(RollingSingularCli, ADiskStartedFlatIsABadStart) {
  const fs::path dir = fs::temp_directory_path() / ("nhdyn_rolling_started_flat_" + std::to_string(::getpid()));
  fs::create_directories(dir);
  const nhdyn::test::CliOutcome outcome = nhdyn::test::run_nhdyn(
      "simulate " + nhdyn::test::example("rolling_disk_hop.toml") + " --set theta0=pi/2 -q -o o.csv", dir);
  EXPECT_EQ(outcome.exit_code, 2) << outcome.out;
  EXPECT_NE(outcome.out.find("at the initial state: "), std::string::npos) << outcome.out;
  EXPECT_NE(outcome.out.find("contact 'disk': the disk lies flat"), std::string::npos) << outcome.out;
  EXPECT_NE(outcome.out.find("start it where the contact point is defined"), std::string::npos) << outcome.out;
  EXPECT_FALSE(fs::exists(dir / "o.csv"));
  EXPECT_FALSE(fs::exists(dir / "o.partial.csv"));
  fs::remove_all(dir);
}

}  // namespace
