// A [[wheels]] entry with the contact modes' keys end to end (docs/contact-modes.md, "Wheels"):
// examples/rolling_disk_hop_wheel.toml, the hopping disk of rolling_disk_hop.toml written as a
// wheel, gives the same CSV and the same FILE-events.csv, byte for byte after the provenance
// header (which names the file), and prints the same touchdowns; so does the disk released on the
// floor, which slips (disk_slip). A bad value on the wheel exits 2 naming file:line.
#include <gtest/gtest.h>
#include <unistd.h>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include "support/cli_run.hpp"
#include "support/text.hpp"

namespace {

namespace fs = std::filesystem;

using nhdyn::test::contains;
using nhdyn::test::csv_body;
using nhdyn::test::example;
using nhdyn::test::read_text;
using nhdyn::test::run_nhdyn;
using nhdyn::test::split;

class CliWheelModes : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() / ("nhdyn-wheel-modes-" + std::to_string(::getpid()) + "-" +
                                        ::testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::remove_all(dir_);
    fs::create_directories(dir_);
  }
  void TearDown() override { fs::remove_all(dir_); }
  fs::path dir_;
};

// The lines of the summary that name events ("    disk_touchdown at t = ...").
std::vector<std::string> event_lines(const std::string& out) {
  std::vector<std::string> lines;
  std::size_t at = 0;
  while (at < out.size()) {
    const std::size_t end = std::min(out.find('\n', at), out.size());
    const std::string line = out.substr(at, end - at);
    if (contains(line, " at t = ")) lines.push_back(line);
    at = end + 1;
  }
  return lines;
}

// Runs the wheel and the contact form with `options`; both succeed with the same rows and events.
void expect_same_runs(const fs::path& dir, const std::string& options, const std::vector<std::string>& events) {
  const auto run = [&](const std::string& file, const std::string& csv) {
    return run_nhdyn("simulate '" + example(file) + "' " + options + " -o " + csv, dir);
  };
  const auto wheel = run("rolling_disk_hop_wheel.toml", "w.csv");
  const auto contact = run("rolling_disk_hop.toml", "c.csv");
  ASSERT_EQ(wheel.exit_code, 0) << wheel.out;
  ASSERT_EQ(contact.exit_code, 0) << contact.out;
  EXPECT_EQ(event_lines(wheel.out), event_lines(contact.out));
  EXPECT_EQ(event_lines(wheel.out), events) << wheel.out;
  const std::string rows = csv_body(read_text(dir / "w.csv"));
  ASSERT_FALSE(rows.empty());
  EXPECT_EQ(rows, csv_body(read_text(dir / "c.csv")));
  EXPECT_EQ(csv_body(read_text(dir / "w-events.csv")), csv_body(read_text(dir / "c-events.csv")));
  // The contact's columns, under the wheel's name; not the rows of a wheel without the keys.
  const std::vector<std::string> header = split(rows.substr(0, rows.find('\n')));
  for (const char* column : {"residual_vel_disk_roll1", "disk_mode", "disk_slip_speed", "disk_gap", "disk_N",
                             "disk_X", "work_friction", "impact_loss"})
    EXPECT_NE(std::find(header.begin(), header.end(), column), header.end()) << column;
  EXPECT_EQ(std::find(header.begin(), header.end(), "residual_vel_disk_slip1"), header.end());
}

TEST_F(CliWheelModes, TheHopWrittenAsAWheelIsTheHop) {
  expect_same_runs(dir_, "",
                   {"    disk_touchdown at t = 0.100963755469", "    disk_touchdown at t = 0.208226928772",
                    "    disk_touchdown at t = 0.270034066402"});
}

TEST_F(CliWheelModes, TheWheelReleasedOnTheFloorSlipsAsTheContactDoes) {
  expect_same_runs(dir_, "--set h=0 --set theta0=0.1 --t-end 0.5", {"    disk_slip at t = 0.463063746922"});
}

TEST_F(CliWheelModes, ABadValueOnTheWheelExits2WithItsPlace) {
  std::string text = read_text(example("rolling_disk_hop_wheel.toml"));
  nhdyn::test::replace_once(text, "unilateral = true", "unilateral = \"yes\"");
  int line = 1;
  for (std::size_t i = 0; i < text.find("unilateral = \"yes\""); ++i) line += text[i] == '\n' ? 1 : 0;
  std::ofstream(dir_ / "bad.toml") << text;
  const auto run = run_nhdyn("simulate bad.toml -o bad.csv", dir_);
  EXPECT_EQ(run.exit_code, 2) << run.out;
  EXPECT_TRUE(contains(run.out, "bad.toml:" + std::to_string(line) + ":14: wheel 'disk': unilateral must be true or "
                                                                       "false"))
      << run.out;
  EXPECT_FALSE(fs::exists(dir_ / "bad.csv"));
}

// Another method than sanh is refused as for a [[contacts]] entry, and the message says where the
// keys to remove are: a wheel's are on its [[wheels]] entry.
TEST_F(CliWheelModes, AnotherMethodIsRefusedNamingTheWheelsEntries) {
  const auto run = run_nhdyn("simulate '" + example("rolling_disk_hop_wheel.toml") + "' --method lagrange -o l.csv", dir_);
  EXPECT_EQ(run.exit_code, 2) << run.out;
  EXPECT_TRUE(contains(run.out, "--method lagrange cannot solve them")) << run.out;
  EXPECT_TRUE(contains(run.out, "from the [[contacts]] and [[wheels]] entries to run --method lagrange")) << run.out;
  EXPECT_FALSE(fs::exists(dir_ / "l.csv"));
}

}  // namespace
