// The load-time note of the contact forces (docs/derivations/contact-forces.md step 5) is printed
// only where it is true. A contact whose point is held by coordinates of its own (an ellipsoid
// written as an implicit surface, a ball on terrain) balances only on the constraints; the check
// once looked off them and said the body was "held by the coordinates in a direction no contact
// supports". Now: no note, and the forces are each row's momentum balance (the implicit
// ellipsoid's equal the closed-form ellipsoid's). A sled held flat by its frames still gets it.
#include <gtest/gtest.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include "support/models.hpp"
#include "support/text.hpp"

namespace nhdyn::contact_force_note_test {
namespace {

namespace fs = std::filesystem;

using nhdyn::test::read_text;
using nhdyn::test::replace_once;
using nhdyn::test::split;

struct Csv {
  std::vector<std::string> header;
  std::vector<std::vector<double>> rows;
  std::size_t column(const std::string& name) const {
    const auto at = std::find(header.begin(), header.end(), name);
    EXPECT_NE(at, header.end()) << "no column " << name;
    return static_cast<std::size_t>(at - header.begin());
  }
};

Csv read_csv(const fs::path& path) {
  Csv csv;
  std::ifstream in(path);
  std::string line;
  while (std::getline(in, line) && line.starts_with('#')) {
  }  // the provenance header
  if (line.empty()) return csv;
  csv.header = split(line);
  while (std::getline(in, line)) {
    std::vector<double> row;
    for (const std::string& field : split(line)) row.push_back(std::strtod(field.c_str(), nullptr));
    csv.rows.push_back(std::move(row));
  }
  return csv;
}

fs::path fresh_directory(const std::string& name) {
  const fs::path dir = fs::temp_directory_path() / (name + "-" + std::to_string(::getpid()));
  fs::remove_all(dir);
  fs::create_directories(dir);
  return dir;
}

int run(const fs::path& dir, const std::string& arguments, const std::string& err) {
  const std::string command =
      "cd '" + dir.string() + "' && '" NHDYN_CLI_PATH "' " + arguments + " > out.txt 2> '" + err + "'";
  const int status = std::system(command.c_str());
  return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
}

std::string example(const std::string& name) { return std::string(NHDYN_SOURCE_DIR) + "/examples/" + name; }

TEST(CliContactForceNote, ImplicitShapeHasNoFalseNoteAndTheClosedFormsForces) {
  const fs::path dir = fresh_directory("nhdyn-contact-note-implicit");
  std::string text = read_text(example("ellipsoid_rocking.toml"));
  replace_once(text, R"(shape = { ellipsoid = ["a", "b", "c"] })", R"(shape = { surface = "X^2/a^2 + Y^2/b^2 + Z^2/c^2 - 1" })");
  std::ofstream(dir / "implicit.toml") << text;
  ASSERT_EQ(run(dir, "simulate implicit.toml --t-end 0.3 -o implicit.csv", "implicit.err"), 0)
      << read_text(dir / "implicit.err");
  ASSERT_EQ(run(dir, "simulate '" + example("ellipsoid_rocking.toml") + "' --t-end 0.3 -o closed.csv", "closed.err"), 0)
      << read_text(dir / "closed.err");
  EXPECT_EQ(read_text(dir / "implicit.err").find("note: contact forces"), std::string::npos)
      << read_text(dir / "implicit.err");
  const Csv implicit = read_csv(dir / "implicit.csv"), closed = read_csv(dir / "closed.csv");
  ASSERT_EQ(implicit.rows.size(), 61u);
  ASSERT_EQ(closed.rows.size(), implicit.rows.size());
  for (std::size_t k = 0; k < implicit.rows.size(); ++k)
    for (const char* name : {"foot_Fx", "foot_Fy", "foot_Fz", "foot_N"})
      EXPECT_NEAR(implicit.rows[k][implicit.column(name)], closed.rows[k][closed.column(name)], 1e-9)
          << name << " row " << k;
  fs::remove_all(dir);
}

// examples/ball_over_bump.toml: the contact point (u, v) on the terrain is held by coordinates.
TEST(CliContactForceNote, BallOnTerrainHasNoFalseNoteAndItsForceIsItsMomentumBalance) {
  const fs::path dir = fresh_directory("nhdyn-contact-note-terrain");
  ASSERT_EQ(run(dir, "simulate '" + example("ball_over_bump.toml") + "' --t-end 0.5 -o bump.csv", "bump.err"), 0)
      << read_text(dir / "bump.err");
  EXPECT_EQ(read_text(dir / "bump.err").find("note: contact forces"), std::string::npos) << read_text(dir / "bump.err");
  const Csv csv = read_csv(dir / "bump.csv");
  ASSERT_FALSE(csv.rows.empty());
  const double m = 0.2, g = 9.81;  // the example's parameters; the ball's centre of mass is (x, y, z)
  for (const std::vector<double>& row : csv.rows) {
    EXPECT_NEAR(row[csv.column("ball_Fx")], m * row[csv.column("x''")], 1e-12);
    EXPECT_NEAR(row[csv.column("ball_Fy")], m * row[csv.column("y''")], 1e-12);
    EXPECT_NEAR(row[csv.column("ball_Fz")], m * (row[csv.column("z''")] + g), 1e-12);
    EXPECT_GT(row[csv.column("ball_N")], 1.5);
  }
  fs::remove_all(dir);
}

// The verdict does not depend on the units: the Chaplygin ball 1e8 m across (its balance of moments
// 1e8 times its balance of forces) had its normal force called undetermined, written as NaN under a
// note blaming a statically indeterminate support; 1e5 to 1e7 m across, the check's own solve for
// q'' dropped the constraints (its matrix spread over 14 decades) and every force was written as 0
// under a note that the coordinates held the ball. On a horizontal plane the centre stays at height
// r, so the contact force is m (x'', y'', g) at every row, whatever the radius.
TEST(CliContactForceNote, TheVerdictDoesNotDependOnTheBodysSize) {
  const fs::path dir = fresh_directory("nhdyn-contact-note-size");
  for (const char* r : {"1e-6", "0.1", "1e5", "1e6", "1e8"}) {
    const std::string csv_name = std::string("ball-") + r + ".csv", err_name = std::string("ball-") + r + ".err";
    ASSERT_EQ(run(dir, "simulate '" + example("chaplygin_ball.toml") + "' --set r=" + r + " --t-end 1 -o " + csv_name,
                  err_name),
              0)
        << read_text(dir / err_name);
    EXPECT_EQ(read_text(dir / err_name).find("note: contact forces"), std::string::npos) << read_text(dir / err_name);
    const Csv csv = read_csv(dir / csv_name);
    ASSERT_EQ(csv.rows.size(), 101u) << r;
    const double m = 1.0, g = 9.81;  // the example's parameters
    for (const std::vector<double>& row : csv.rows) {
      const double scale = 1e-12 * std::max(1.0, std::abs(row[csv.column("x''")]) + std::abs(row[csv.column("y''")]));
      EXPECT_NEAR(row[csv.column("ball_Fx")], m * row[csv.column("x''")], scale) << r;
      EXPECT_NEAR(row[csv.column("ball_Fy")], m * row[csv.column("y''")], scale) << r;
      EXPECT_NEAR(row[csv.column("ball_Fz")], m * g, 1e-9) << r;
      EXPECT_NEAR(row[csv.column("ball_N")], m * g, 1e-9) << r;
    }
  }
  fs::remove_all(dir);
}

// And where the forces are not determined it still says so: the bicycle steered by a program, whose
// rear wheel's normal force its coordinates share (examples/bicycle_roll_program.toml). A column
// of the system at round-off once scaled to unit norm made it look determined, written as 0.
TEST(CliContactForceNote, AnUndeterminedNormalForceStaysNaNWithItsNote) {
  const fs::path dir = fresh_directory("nhdyn-contact-note-program");
  ASSERT_EQ(run(dir, "simulate '" + example("bicycle_roll_program.toml") + "' --t-end 0.1 -o b.csv", "b.err"), 0)
      << read_text(dir / "b.err");
  EXPECT_NE(read_text(dir / "b.err").find("contact 'rear': rear_Fz, rear_N not determined by the model, written as NaN"),
            std::string::npos)
      << read_text(dir / "b.err");
  const Csv csv = read_csv(dir / "b.csv");
  ASSERT_FALSE(csv.rows.empty());
  for (const std::vector<double>& row : csv.rows) {
    EXPECT_TRUE(std::isnan(row[csv.column("rear_N")]));
    EXPECT_GT(row[csv.column("front_N")], 100.0);
  }
  fs::remove_all(dir);
}

// Where the note is true it stays: a sled held flat by its frames (test::kFlatSledBodies).
TEST(CliContactForceNote, SledHeldByItsFramesKeepsItsNote) {
  const fs::path dir = fresh_directory("nhdyn-contact-note-sled");
  std::ofstream(dir / "sled.toml") << nhdyn::test::kFlatSledBodies;
  ASSERT_EQ(run(dir, "simulate sled.toml --t-end 0.1 -o sled.csv", "sled.err"), 0) << read_text(dir / "sled.err");
  const std::string err = read_text(dir / "sled.err");
  EXPECT_NE(err.find("note: contact forces: the bodies hanging from frame 'sled' are held by the coordinates"),
            std::string::npos)
      << err;
  fs::remove_all(dir);
}

}  // namespace
}  // namespace nhdyn::contact_force_note_test
