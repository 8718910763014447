// Terrain as a user meets it (docs/multibody.md, "Rolling bodies"): examples/ball_over_bump.toml
// runs, and `nhdyn simulate` on a broken copy of it exits with code 2 and a message that names
// the file and line, the value at fault and what to do: a terrain that is not a function of X and
// Y, one that is not differentiable, an unknown contact coordinate, a start off the terrain, and
// a configuration where the contact point is not unique (a ball as curved as a hollow).
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include "support/cli_run.hpp"

namespace {

namespace fs = std::filesystem;

std::string bump_text() {
  std::ifstream in(std::string(NHDYN_SOURCE_DIR) + "/examples/ball_over_bump.toml");
  std::stringstream text;
  text << in.rdbuf();
  return text.str();
}

// `nhdyn simulate` on the example with each `from` replaced by its `to`, in a fresh directory.
nhdyn::test::CliOutcome simulate_bump(const std::string& test,
                                      const std::vector<std::pair<std::string, std::string>>& changes,
                                      const std::string& options = "--t-end 0.05") {
  std::string text = bump_text();
  for (const auto& [from, to] : changes) {
    const std::size_t at = text.find(from);
    EXPECT_NE(at, std::string::npos) << from;
    if (at != std::string::npos) text.replace(at, from.size(), to);
  }
  const fs::path dir = fs::temp_directory_path() / ("nhdyn_terrain_" + test);
  fs::create_directories(dir);
  std::ofstream(dir / "bump.toml") << text;
  return nhdyn::test::run_nhdyn("simulate bump.toml -o out.csv " + options, dir);
}

void expect_terrain_refused(const nhdyn::test::CliOutcome& outcome, const std::vector<std::string>& parts) {
  EXPECT_EQ(outcome.exit_code, 2) << outcome.out;
  for (const std::string& part : parts)
    EXPECT_NE(outcome.out.find(part), std::string::npos) << outcome.out << "\n  lacks: " << part;
}

constexpr const char* kBumpTerrain = "terrain = \"H*exp(-(X^2 + Y^2)/w^2)\"";

TEST(RollingTerrainCli, TheExampleRunsAndKeepsItsEnergy) {
  const nhdyn::test::CliOutcome outcome = simulate_bump("runs", {}, "--t-end 1.5");
  EXPECT_EQ(outcome.exit_code, 0) << outcome.out;
  EXPECT_NE(outcome.out.find("1.5 s, 151 rows"), std::string::npos) << outcome.out;
}

TEST(RollingTerrainCli, TerrainThatIsNotAFunctionOfXAndY) {
  expect_terrain_refused(simulate_bump("z", {{kBumpTerrain, "terrain = \"Z - H*exp(-(X^2 + Y^2)/w^2)\""}}),
                 {"bump.toml:46:10", "contact 'ball'", "contains Z", "Z = h(X, Y)", "surface"});
}

TEST(RollingTerrainCli, TerrainThatIsNotDifferentiable) {
  expect_terrain_refused(simulate_bump("abs", {{kBumpTerrain, "terrain = \"H*exp(-abs(X)/w)\""}}),
                 {"bump.toml:46:10", "is not differentiable", "abs", "sqrt(X^2 + eps^2)"});
}

TEST(RollingTerrainCli, UnknownContactCoordinate) {
  expect_terrain_refused(simulate_bump("coordinate", {{"coordinates = [\"u\", \"v\"]", "coordinates = [\"u\", \"vv\"]"}}),
                 {"bump.toml:46:10", "'vv' is not a coordinate", "did you mean 'v'?"});
  // Without `coordinates` nhdyn adds ball_u, ball_v: the model's own u, v then hold nothing, and
  // without inertia or a constraint on them [D A; b] is singular, which the start says.
  expect_terrain_refused(simulate_bump("missing", {{", coordinates = [\"u\", \"v\"]", ""}}),
                 {"a motion of u, v has no kinetic energy and no constraint holds it"});
}

TEST(RollingTerrainCli, StartOffTheTerrainGivesTheGap) {
  // The centre 1 cm above the top: the gap is 0.01 m. --fix-initial keeps the z written, so it
  // refuses, naming the gap; with z left out of [initial] it puts the ball back on the top.
  expect_terrain_refused(simulate_bump("gap", {{"z = \"H + r\"", "z = \"H + r + 0.01\""}}),
                 {"ball_contact (position level): residual 0.01 (bump.toml:42:1)",
                  "the gap between the body and the ground", "--fix-initial"});
  expect_terrain_refused(
      simulate_bump("gap_kept", {{"z = \"H + r\"", "z = \"H + r + 0.01\""}}, "--t-end 0.05 --fix-initial"),
      {"keeps every value [initial] writes", "'ball_contact' (position level, bump.toml:42:1)", "residual 0.01"});
  const nhdyn::test::CliOutcome fixed =
      simulate_bump("gap_fixed", {{" z = \"H + r\",", ""}}, "--t-end 0.05 --fix-initial");
  EXPECT_EQ(fixed.exit_code, 0) << fixed.out;
  EXPECT_NE(fixed.out.find("    z = 0.1 (changed by +0.1), was 0"), std::string::npos) << fixed.out;
}

TEST(RollingTerrainCli, BallAsCurvedAsAHollowIsRefused) {
  // In a hollow Z = -h, whose bottom has the radius of curvature w^2 / (2 H) = 0.9 m, a ball of
  // that radius touches along a whole cap: the contact point is not unique (the constraints would
  // leave u', v' free, with no inertia). The start's check names both curvatures, 1/r = 1.11111
  // and the ball's less the hollow's, 0; a ball of 1 m is flatter still (-0.111111).
  const auto hollow = [&](const std::string& name, const std::string& r) {
    return simulate_bump(name, {{kBumpTerrain, "terrain = \"-H*exp(-(X^2 + Y^2)/w^2)\""},
                                {"r = { value = 0.05", "r = { value = " + r},
                                {"z = \"H + r\"", "z = \"-H + r\""},
                                {"u = \"V*w^2/(w^2 + 2*H*r)\"", "u = 0"}});
  };
  expect_terrain_refused(hollow("hollow", "0.9"), {"bump.toml:", "contact 'ball'", "flatter than the hollow",
                                                   "1.11111 and 1.11111"});
  expect_terrain_refused(hollow("hollow_flatter", "1.0"),
                         {"contact 'ball'", "flatter than the hollow", "-0.111111 and -0.111111"});
}

}  // namespace
