// Bad [[contacts]] input as a user meets it (docs/multibody.md, "Rolling bodies"): `nhdyn simulate`
// on a broken copy of examples/ball_in_bowl.toml exits with code 2 and a message that names the
// file and line, the name or value at fault, and what to do.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>

#include "support/cli_run.hpp"

namespace {

namespace fs = std::filesystem;

std::string bowl_text() {
  std::ifstream in(std::string(NHDYN_SOURCE_DIR) + "/examples/ball_in_bowl.toml");
  std::stringstream text;
  text << in.rdbuf();
  return text.str();
}

// `nhdyn simulate` on the example with `from` replaced by `to`, in a fresh directory.
nhdyn::test::CliOutcome simulate_altered(const std::string& test, const std::string& from, const std::string& to) {
  std::string text = bowl_text();
  const std::size_t at = text.find(from);
  EXPECT_NE(at, std::string::npos) << from;
  if (at != std::string::npos) text.replace(at, from.size(), to);
  const fs::path dir = fs::temp_directory_path() / ("nhdyn_rolling_" + test);
  fs::create_directories(dir);
  std::ofstream(dir / "bowl.toml") << text;
  return nhdyn::test::run_nhdyn("simulate bowl.toml -o out.csv --t-end 0.01", dir);
}

void expect_refused(const nhdyn::test::CliOutcome& outcome, const std::vector<std::string>& parts) {
  EXPECT_EQ(outcome.exit_code, 2) << outcome.out;
  for (const std::string& part : parts)
    EXPECT_NE(outcome.out.find(part), std::string::npos) << outcome.out << "\n  lacks: " << part;
}

TEST(RollingContactsCli, TheExampleRuns) {
  const nhdyn::test::CliOutcome outcome = simulate_altered("runs", "rolling = \"rolling\"", "rolling = \"rolling\"");
  EXPECT_EQ(outcome.exit_code, 0) << outcome.out;
}

TEST(RollingContactsCli, UnknownBody) {
  expect_refused(simulate_altered("body", "body = \"ball\"", "body = \"bal\""),
                 {"bowl.toml:35:1", "contact 'ball'", "'bal' is not a body", "did you mean 'ball'?"});
}

TEST(RollingContactsCli, UnknownShapeKey) {
  expect_refused(simulate_altered("shape", "shape = { sphere = \"r\" }", "shape = { sphre = \"r\" }"),
                 {"bowl.toml:38:9", "unknown shape 'sphre'", "did you mean 'sphere'?", "ellipsoid"});
  expect_refused(simulate_altered("option", "shape = { sphere = \"r\" }", "shape = { sphere = \"r\", axis = \"y\" }"),
                 {"bowl.toml:38:9", "a sphere has no key 'axis'"});
}

TEST(RollingContactsCli, BallLargerThanTheBowl) {
  expect_refused(simulate_altered("large", "r = { value = 0.05", "r = { value = 0.6"),
                 {"bowl.toml:35:1", "the ball (radius 0.6) is not smaller than the bowl (radius 0.5)"});
}

TEST(RollingContactsCli, NotTouchingAtTheStartGivesTheGap) {
  // The centre 1 cm below where the wall holds it (into the wall): the gap (Rb - r) - |C - K| is
  // -0.00999758 m.
  const nhdyn::test::CliOutcome outcome =
      simulate_altered("gap", "z = \"Rb - sqrt((Rb - r)^2 - x0^2)\"", "z = \"Rb - sqrt((Rb - r)^2 - x0^2) - 0.01\"");
  expect_refused(outcome, {"ball_contact (position level): residual -0.00999758 (bowl.toml:35:1)",
                           "the gap between the body and the ground", "--fix-initial"});
  // --fix-initial keeps the z written, so it cannot close the gap: refused, naming it.
  const fs::path dir = fs::temp_directory_path() / "nhdyn_rolling_gap";
  const nhdyn::test::CliOutcome kept = nhdyn::test::run_nhdyn("simulate bowl.toml -o out.csv --t-end 0.01 --fix-initial", dir);
  expect_refused(kept, {"keeps every value [initial] writes", "'ball_contact' (position level, bowl.toml:35:1)",
                        "residual -0.00999758"});
  // With z left out of [initial], --fix-initial moves it onto the wall and says so.
  simulate_altered("gap_free", ", z = \"Rb - sqrt((Rb - r)^2 - x0^2)\"", "");
  const nhdyn::test::CliOutcome fixed = nhdyn::test::run_nhdyn(
      "simulate bowl.toml -o out.csv --t-end 0.01 --fix-initial", fs::temp_directory_path() / "nhdyn_rolling_gap_free");
  EXPECT_EQ(fixed.exit_code, 0) << fixed.out;
  EXPECT_NE(fixed.out.find("    z = 0.0501111248"), std::string::npos) << fixed.out;  // Rb - sqrt((Rb - r)^2 - x0^2)
  EXPECT_NE(fixed.out.find(", was 0\n"), std::string::npos) << fixed.out;
}

}  // namespace
