// The tippe top of examples/tippe_top.toml (docs/derivations/contact-modes.md section 10.4) end to
// end: spun nearly upright on a plane with Coulomb friction it turns over (its symmetry axis from
// k_z = cos(0.1) to near -1), through stick-slip, sliding, a phase of hops with plastic landings,
// and a final stick; Jellett's quantity J = L_G . (R e_z - a k), computed here from the CSV's
// quaternion and its rates, stays constant through every mode, switch and impact while L_G . e_z
// changes by orders of magnitude more; h - h0 - W stays at the integration error.
#include <gtest/gtest.h>
#include <unistd.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include "nhdyn/io/csv.hpp"
#include "support/cli_run.hpp"
#include "support/text.hpp"

namespace {

namespace fs = std::filesystem;

// The example's parameters.
constexpr double kTopM = 0.02, kTopR = 0.02, kTopA = 0.3 * kTopR;
constexpr double kTopI1 = 0.45 * kTopM * kTopR * kTopR, kTopI3 = 0.4 * kTopM * kTopR * kTopR;

struct TopBody {
  double R, a, I1, I3;
};
constexpr TopBody kExampleTop{kTopR, kTopA, kTopI1, kTopI3};

struct TopState {
  double kz;       // the symmetry axis' vertical component
  double jellett;  // L_G . (R e_z - a k)
  double lz;       // L_G . e_z
};

// From the unit quaternion e (normalized here: the integrator lets its norm drift at rtol) and its
// rate: the body's angular velocity w_b = 2 conj(e) e' (vector part), L_G = diag(I1, I1, I3) w_b in
// body axes, and e_z in body axes, the third row of the rotation matrix.
TopState top_state(const std::array<double, 4>& q, const std::array<double, 4>& qd, const TopBody& b = kExampleTop) {
  const double n = std::sqrt(q[0] * q[0] + q[1] * q[1] + q[2] * q[2] + q[3] * q[3]);
  const double w = q[0] / n, x = q[1] / n, y = q[2] / n, z = q[3] / n;
  const double dw = qd[0] / n, dx = qd[1] / n, dy = qd[2] / n, dz = qd[3] / n;
  // conj(e) * e' = (w dw + x dx + y dy + z dz, w d - dw v - v x d)
  const std::array<double, 3> wb = {2 * (w * dx - dw * x - (y * dz - z * dy)), 2 * (w * dy - dw * y - (z * dx - x * dz)),
                                    2 * (w * dz - dw * z - (x * dy - y * dx))};
  const std::array<double, 3> ez = {2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)};
  const std::array<double, 3> L = {b.I1 * wb[0], b.I1 * wb[1], b.I3 * wb[2]};
  const double lz = L[0] * ez[0] + L[1] * ez[1] + L[2] * ez[2];
  return {ez[2], b.R * lz - b.a * L[2], lz};
}

class CliTippeTop : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() / ("nhdyn-tippe-top-" + std::to_string(::getpid()));
    fs::remove_all(dir_);
    fs::create_directories(dir_);
  }
  void TearDown() override { fs::remove_all(dir_); }
  fs::path dir_;
};

TEST_F(CliTippeTop, TurnsOverWithJellettsQuantityConstantThroughEverySwitch) {
  const std::string example = std::string(NHDYN_SOURCE_DIR) + "/examples/tippe_top.toml";
  const nhdyn::test::CliOutcome run = nhdyn::test::run_nhdyn("simulate '" + example + "' -o top.csv", dir_);
  ASSERT_EQ(run.exit_code, 0) << run.out;
  const nhdyn::CsvTable csv = nhdyn::load_csv(dir_ / "top.csv");
  const auto col = [&](const std::string& name) {
    const int c = csv.column(name);
    EXPECT_GE(c, 0) << name;
    return static_cast<std::size_t>(std::max(c, 0));
  };
  const std::size_t t = col("t"), mode = col("ball_mode"), N = col("ball_N"), gap = col("ball_gap");
  const std::array<std::size_t, 4> e = {col("e0"), col("e1"), col("e2"), col("e3")};
  const std::array<std::size_t, 4> ed = {col("e0'"), col("e1'"), col("e2'"), col("e3'")};
  ASSERT_GT(csv.rows.size(), 800u);

  const auto state = [&](const std::vector<double>& row) {
    return top_state({row[e[0]], row[e[1]], row[e[2]], row[e[3]]}, {row[ed[0]], row[ed[1]], row[ed[2]], row[ed[3]]});
  };
  const TopState first = state(csv.rows.front());
  EXPECT_NEAR(first.kz, std::cos(0.1), 1e-12);
  // J0 = (R cos(0.1) - a) I3 spin, the spin about k with G at rest.
  EXPECT_NEAR(first.jellett, (kTopR * std::cos(0.1) - kTopA) * kTopI3 * 180.0, 1e-12);
  double j_change = 0.0, lz_min = first.lz, lz_max = first.lz, kz_min = 1.0;
  double balance = 0.0;
  std::array<int, 3> rows_in_mode{0, 0, 0};
  for (const std::vector<double>& row : csv.rows) {
    const TopState s = state(row);
    j_change = std::max(j_change, std::abs(s.jellett - first.jellett));
    lz_min = std::min(lz_min, s.lz);
    lz_max = std::max(lz_max, s.lz);
    kz_min = std::min(kz_min, s.kz);
    balance = std::max(balance, std::abs(row[col("balance_error")]));
    const int m = static_cast<int>(row[mode]);
    ASSERT_TRUE(m >= 0 && m <= 2) << row[t];
    ++rows_in_mode[static_cast<std::size_t>(m)];
    if (m == 1) {
      EXPECT_GT(row[N], 0.0) << row[t];  // sliding: the plane pushes
    } else if (m == 2) {
      EXPECT_GT(row[gap], -1e-9) << row[t];  // free: above the plane
    } else {
      // Rolling only in the two early sticks and after the final one, when it is inverted.
      EXPECT_TRUE(row[t] < 0.32 || s.kz < -0.95) << row[t];
    }
  }
  // Jellett's quantity: constant to the integration error (rtol 1e-9: 2e-9 relative), while
  // L_G . e_z, no integral, falls from 5.7e-4 to 3.1e-4 kg m^2/s.
  EXPECT_LT(j_change, 2e-8 * std::abs(first.jellett)) << j_change / first.jellett;
  EXPECT_GT(lz_max - lz_min, 1e6 * j_change);
  // Inverted: the symmetry axis near straight down at the end.
  const TopState last = state(csv.rows.back());
  EXPECT_LT(last.kz, -0.98);
  EXPECT_LT(kz_min, -0.98);
  EXPECT_LT(balance, 1e-9);  // E0 = 0.0546 J; the friction takes 0.0314 J, the landings 0.0032 J
  EXPECT_LT(csv.rows.back()[col("work_friction")], -0.03);
  EXPECT_GT(csv.rows.back()[col("impact_loss")], 1e-3);
  EXPECT_GT(rows_in_mode[1], 600);
  EXPECT_GT(rows_in_mode[2], 20);

  // The switches: stick-slip twice early, then lift-offs each followed by a touchdown (it hops),
  // and one last stick when it is inverted.
  std::ifstream in(dir_ / "top-events.csv");
  std::string line;
  std::vector<std::string> names;
  std::vector<double> times;
  while (std::getline(in, line))
    if (!line.starts_with('#') && !line.starts_with("event,")) {
      const std::vector<std::string> cells = nhdyn::test::split(line);
      names.push_back(cells.at(0));
      times.push_back(std::stod(cells.at(1)));
    }
  ASSERT_GT(names.size(), 7u);
  const std::vector<std::string> early = {"ball_stick", "ball_slip", "ball_stick", "ball_slip"};
  for (std::size_t i = 0; i < 4; ++i) {
    EXPECT_EQ(names[i], early[i]);
    EXPECT_LT(times[i], 0.32);
  }
  EXPECT_EQ(names.back(), "ball_stick");
  EXPECT_GT(times.back(), 8.0);
  const std::size_t hops = names.size() - 5;
  EXPECT_EQ(hops % 2, 0u);
  for (std::size_t i = 4; i + 1 < names.size(); ++i) {
    EXPECT_EQ(names[i], (i - 4) % 2 == 0 ? "ball_liftoff" : "ball_touchdown") << i;
    EXPECT_GT(times[i], 4.0);
    EXPECT_LT(times[i], 7.0);
  }
}

TEST_F(CliTippeTop, LeineAndGlockersTopSticksAndRollsUprightUnderPointCoulombFriction) {
  // docs/derivations/contact-modes.md 10.4, "A published top": m = 6 g, R = 15 mm, a = 3 mm,
  // I1 = 8e-7, I3 = 7e-7 kg m^2, mu = 0.3. Rolling keeps E and J, and the upright spin is stable.
  const std::string example = std::string(NHDYN_SOURCE_DIR) + "/examples/tippe_top.toml";
  const nhdyn::test::CliOutcome run = nhdyn::test::run_nhdyn(
      "simulate '" + example +
          "' --set m=0.006 --set R=0.015 --set alpha=0.2 --set k1=0.5925925925925926 --set k3=0.5185185185185185 "
          "--set mu=0.3 --t-end 2 -o lg.csv",
      dir_);
  ASSERT_EQ(run.exit_code, 0) << run.out;
  EXPECT_TRUE(nhdyn::test::contains(run.out, "events: 1 located")) << run.out;
  EXPECT_TRUE(nhdyn::test::contains(run.out, "ball_stick at t = 0.0361")) << run.out;
  const TopBody body{0.015, 0.003, 8e-7, 7e-7};
  const nhdyn::CsvTable csv = nhdyn::load_csv(dir_ / "lg.csv");
  const auto col = [&](const char* name) { return static_cast<std::size_t>(csv.column(name)); };
  const auto state = [&](const std::vector<double>& row) {
    return top_state({row[col("e0")], row[col("e1")], row[col("e2")], row[col("e3")]},
                     {row[col("e0'")], row[col("e1'")], row[col("e2'")], row[col("e3'")]}, body);
  };
  const TopState first = state(csv.rows.front());
  EXPECT_NEAR(first.jellett, (0.015 * std::cos(0.1) - 0.003) * 7e-7 * 180.0, 1e-14);
  for (const std::vector<double>& row : csv.rows) {
    const TopState s = state(row);
    EXPECT_NEAR(s.jellett, first.jellett, 1e-7 * std::abs(first.jellett)) << row[0];
    EXPECT_GT(s.kz, 0.99) << row[0];  // upright: it does not turn over
    EXPECT_EQ(row[col("ball_mode")], row[0] < 0.0361 ? 1.0 : 0.0) << row[0];
    EXPECT_LT(std::abs(row[col("balance_error")]), 1e-10);
  }
}

}  // namespace
