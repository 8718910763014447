// The contact-force columns end to end (docs/multibody.md "Contact forces"): `nhdyn simulate` on the
// rolling disk built from its body writes disk_Fx ... disk_Flat and contact_residual, and every row's
// force is the one (D1) of docs/derivations/contact-forces.md gives from that row's own q, q', q''
// (m times the acceleration of the centre plus the weight); a sled held flat by its frames writes
// nan for its normal force and says why on stderr before the run.
#include <gtest/gtest.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>
#include "support/models.hpp"
#include "support/text.hpp"

namespace {

namespace fs = std::filesystem;

using nhdyn::test::split;

using nhdyn::test::read_text;

struct ContactCsv {
  std::vector<std::string> header;
  std::vector<std::vector<double>> rows;
  std::size_t column(const std::string& name) const {
    const auto at = std::find(header.begin(), header.end(), name);
    EXPECT_NE(at, header.end()) << "no column " << name;
    return static_cast<std::size_t>(at - header.begin());
  }
};

ContactCsv read_contact_csv(const fs::path& path) {
  ContactCsv csv;
  std::ifstream in(path);
  std::string line;
  while (std::getline(in, line) && line.starts_with('#')) {
  }  // the provenance header (io/provenance.hpp)
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

int run(const fs::path& dir, const std::string& arguments) {
  const std::string command = "cd '" + dir.string() + "' && '" NHDYN_CLI_PATH "' " + arguments + " > out.txt 2> err.txt";
  const int status = std::system(command.c_str());
  return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
}

TEST(CliContactForces, RollingDiskColumnsAreTheCentreOfMassBalanceOfEachRow) {
  const fs::path dir = fresh_directory("nhdyn-contact-cli");
  const std::string model = std::string(NHDYN_SOURCE_DIR) + "/examples/rolling_disk_bodies.toml";
  ASSERT_EQ(run(dir, "simulate '" + model + "' --t-end 1 -o disk.csv"), 0) << read_text(dir / "err.txt");
  EXPECT_EQ(read_text(dir / "err.txt").find("contact forces"), std::string::npos);
  const ContactCsv csv = read_contact_csv(dir / "disk.csv");
  // The contact columns, then the derived outputs (the multibody points' positions).
  const std::size_t Fx = csv.column("disk_Fx"), N = csv.column("disk_N"), Flat = csv.column("disk_Flat");
  const std::size_t check = csv.column("contact_residual");
  ASSERT_EQ(check, Fx + 6);
  ASSERT_EQ(csv.column("disk_Fy"), Fx + 1);
  ASSERT_EQ(csv.column("disk_Fz"), Fx + 2);
  ASSERT_EQ(csv.column("disk_Flong"), Fx + 4);
  const std::size_t q = csv.column("x"), v = csv.column("x'"), a = csv.column("x''");
  const double m = 0.5, r = 0.2, g = 9.81;  // the example's parameters
  ASSERT_EQ(csv.rows.size(), 101u);
  for (const std::vector<double>& row : csv.rows) {
    const double psi = row[q + 2], th = row[q + 3], dpsi = row[v + 2], dth = row[v + 3];
    const double At = std::sin(th) * row[a + 2] + 2 * std::cos(th) * dth * dpsi;
    const double An = std::sin(th) * (dth * dth + dpsi * dpsi) - std::cos(th) * row[a + 3];
    EXPECT_NEAR(row[Fx], m * row[a] + m * r * (std::cos(psi) * At - std::sin(psi) * An), 1e-12);
    EXPECT_NEAR(row[Fx + 1], m * row[a + 1] + m * r * (std::sin(psi) * At + std::cos(psi) * An), 1e-12);
    EXPECT_NEAR(row[Fx + 2], m * (g - r * std::cos(th) * dth * dth - r * std::sin(th) * row[a + 3]), 1e-12);
    EXPECT_NEAR(row[N], m * g, 1e-8);         // the steady circle: N = m g
    EXPECT_NEAR(row[Flat], -0.991828, 1e-6);  // and F_lat of docs/derivations/contact-forces.md 6.3
    EXPECT_LT(row[check], 1e-13);
  }
  fs::remove_all(dir);
}

TEST(CliContactForces, UndeterminedNormalForceIsNanWithANote) {
  const fs::path dir = fresh_directory("nhdyn-contact-cli-sled");
  std::ofstream(dir / "sled.toml") << nhdyn::test::kFlatSledBodies;
  ASSERT_EQ(run(dir, "simulate sled.toml --t-end 0.5 -o sled.csv"), 0) << read_text(dir / "err.txt");
  const std::string err = read_text(dir / "err.txt");
  EXPECT_NE(err.find("note: contact forces: "), std::string::npos) << err;
  EXPECT_NE(err.find("blade_N"), std::string::npos) << err;
  const ContactCsv csv = read_contact_csv(dir / "sled.csv");
  ASSERT_FALSE(csv.rows.empty());
  for (const std::vector<double>& row : csv.rows) {
    EXPECT_TRUE(std::isnan(row[csv.column("blade_N")]));
    EXPECT_TRUE(std::isnan(row[csv.column("blade_Fz")]));
    EXPECT_TRUE(std::isfinite(row[csv.column("blade_Flat")]));
    // The horizontal force is R's: R_x, R_y are its world components (the blade point is (x, y)).
    EXPECT_NEAR(row[csv.column("blade_Fx")], row[csv.column("R_x")], 1e-12);
    EXPECT_NEAR(row[csv.column("blade_Fy")], row[csv.column("R_y")], 1e-12);
  }
  fs::remove_all(dir);
}

}  // namespace
