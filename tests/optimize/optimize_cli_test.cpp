// End-to-end runs of `nhdyn optimize` against independent results
// (docs/derivations/optimal-programs.md, section 10): the double integrator's closed-form optimum
// (Hermite-Simpson exact, the trapezoidal J_N in closed form), the Brockett integrator's circle
// (J = 2 pi a / T), the brachistochrone's cycloid, the motion `nhdyn simulate` computes under the
// same force (the double integrator, parallel parking), and each refusal of bad input with its exit code.
#include <dlfcn.h>
#include <gtest/gtest.h>
#include <unistd.h>

#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <algorithm>
#include <map>
#include <sstream>
#include <string>
#include <vector>

#include "support/cli_run.hpp"
#include "support/text.hpp"

namespace {

namespace fs = std::filesystem;
using nhdyn::test::example;
using nhdyn::test::run_nhdyn;
using Outcome = nhdyn::test::CliOutcome;

const double kPi = 3.14159265358979323846;

// The value after "label: " in the summary (NaN when absent).
double summary_value(const std::string& out, const std::string& label) {
  const std::size_t at = out.find("\n" + label + ": ");
  if (at == std::string::npos) return std::nan("");
  return std::stod(out.substr(at + label.size() + 3));
}

struct Table {
  std::vector<std::string> columns;
  std::vector<std::vector<double>> rows;
  std::vector<double> column(const std::string& name) const {
    std::vector<double> out;
    for (std::size_t c = 0; c < columns.size(); ++c)
      if (columns[c] == name)
        for (const auto& row : rows) out.push_back(row[c]);
    return out;
  }
};

Table read_csv(const fs::path& path) {
  std::ifstream in(path);
  Table table;
  std::string line;
  while (std::getline(in, line)) {
    if (line.empty() || line[0] == '#') continue;
    std::vector<std::string> cells;
    std::stringstream s(line);
    std::string cell;
    while (std::getline(s, cell, ',')) cells.push_back(cell);
    if (table.columns.empty()) {
      table.columns = cells;
      continue;
    }
    std::vector<double> row;
    for (const std::string& c : cells) row.push_back(std::stod(c));
    table.rows.push_back(row);
  }
  return table;
}

class OptimizeCli : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() / ("nhdyn_optcli_" + std::to_string(::getpid()) + "_" +
                                        ::testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::create_directories(dir_);
  }
  void TearDown() override { fs::remove_all(dir_); }
  void write(const std::string& file, const std::string& text) { std::ofstream(dir_ / file) << text; }
  std::string read_example(const std::string& name) {
    std::ifstream in(example(name));
    std::stringstream s;
    s << in.rdbuf();
    return s.str();
  }
  // The example with `from` replaced by `to` in it, written to `file`.
  void write_variant(const std::string& name, const std::string& file,
                     const std::vector<std::pair<std::string, std::string>>& changes) {
    std::string text = read_example(name);
    for (const auto& [from, to] : changes) {
      const std::size_t at = text.find(from);
      ASSERT_NE(at, std::string::npos) << from;
      text.replace(at, from.size(), to);
    }
    write(file, text);
  }
  Outcome optimize(const std::string& args) {
    Outcome run = run_nhdyn("optimize " + args, dir_);
    if (run.out.find("built without IPOPT") != std::string::npos) skipped_ = true;
    return run;
  }
  fs::path dir_;
  bool skipped_ = false;
};

#define SKIP_WITHOUT_IPOPT(run) \
  if (skipped_) GTEST_SKIP() << "nhdyn was built without IPOPT: " << (run).out

TEST_F(OptimizeCli, DoubleIntegratorHermiteSimpsonIsExact) {
  const Outcome run = optimize(example("double_integrator.toml") + " -o di.csv");
  SKIP_WITHOUT_IPOPT(run);
  ASSERT_EQ(run.exit_code, 0) << run.out;
  for (const char* label : {"status: solved", "iterations: ", "objective: ", "constraint violation: ", "replay difference: "})
    EXPECT_NE(run.out.find(label), std::string::npos) << label << "\n" << run.out;
  // F = 6 d/T^2 (1 - 2 t/T), x = d (3 s^2 - 2 s^3), J = 12 d^2/T^3 (d = 1, T = 2): Hermite-Simpson
  // reproduces the cubic and Simpson's rule integrates F^2 exactly, at any N.
  EXPECT_NEAR(summary_value(run.out, "objective"), 1.5, 1e-9);
  EXPECT_LT(summary_value(run.out, "replay difference"), 1e-9);
  const Table t = read_csv(dir_ / "di.csv");
  ASSERT_EQ(t.columns.back(), "u_F");
  const std::vector<double> time = t.column("t"), x = t.column("x"), u = t.column("u_F");
  ASSERT_EQ(time.size(), 33U);  // 17 nodes and 16 midpoints
  for (std::size_t i = 0; i < time.size(); ++i) {
    const double s = time[i] / 2;
    EXPECT_NEAR(u[i], 1.5 * (1 - 2 * s), 1e-6) << "t = " << time[i];
    EXPECT_NEAR(x[i], 3 * s * s - 2 * s * s * s, 1e-8) << "t = " << time[i];
  }
  // --set reaches the numbers of [optimize]: final x = d = 2, t_end = duration = 1: J = 12 * 4 / 1.
  const Outcome set = optimize(example("double_integrator.toml") + " --set d=2 --set duration=1");
  ASSERT_EQ(set.exit_code, 0) << set.out;
  EXPECT_NEAR(summary_value(set.out, "objective"), 48.0, 1e-7) << set.out;
}

// IPOPT reads an options file ipopt.opt from the working directory unless told not to: one that
// stops it after an iteration, or asks it to print, changes nothing (the options are nhdyn's).
TEST_F(OptimizeCli, AnIpoptOptionsFileInTheWorkingDirectoryIsNotRead) {
  write("ipopt.opt", "max_iter 1\nprint_level 5\n");
  const Outcome run = optimize(example("sled_heading_optimal.toml") + " -o sled.csv");
  SKIP_WITHOUT_IPOPT(run);
  ASSERT_EQ(run.exit_code, 0) << run.out;
  EXPECT_NE(run.out.find("status: solved"), std::string::npos) << run.out;
  EXPECT_EQ(run.out.find("This is Ipopt"), std::string::npos) << run.out;
  EXPECT_GT(summary_value(run.out, "iterations"), 1.0) << run.out;
}

TEST_F(OptimizeCli, DoubleIntegratorTrapezoidalMeetsItsDiscreteClosedForm) {
  // J_N = 12 d^2/T^3 N^3/((N - 1)(N^2 + N - 3)) (section 10.1): no other discretization meets it;
  // its error against 12 d^2/T^3 falls with order 2.
  std::vector<double> errors;
  for (int N : {4, 8, 16, 32}) {
    write_variant("double_integrator.toml", "di.toml",
                  {{"nodes = 17", "nodes = " + std::to_string(N + 1)}, {"\"hermite-simpson\"", "\"trapezoidal\""}});
    const Outcome run = optimize("di.toml");
    SKIP_WITHOUT_IPOPT(run);
    ASSERT_EQ(run.exit_code, 0) << run.out;
    const double J = summary_value(run.out, "objective");
    const double n = N;
    EXPECT_NEAR(J, 1.5 * n * n * n / ((n - 1) * (n * n + n - 3)), 1e-8 * J) << "N = " << N;
    errors.push_back(J - 1.5);
  }
  for (std::size_t i = 1; i < errors.size(); ++i) EXPECT_NEAR(std::log2(errors[i - 1] / errors[i]), 2.0, 0.15);
}

TEST_F(OptimizeCli, ReplayAgreesWithSimulateUnderTheSameForce) {
  // The optimal force of the double integrator as a [forces] entry: `nhdyn simulate` moves the mass
  // to the optimized positions.
  const Outcome run = optimize(example("double_integrator.toml") + " -o di.csv");
  SKIP_WITHOUT_IPOPT(run);
  ASSERT_EQ(run.exit_code, 0) << run.out;
  write_variant("double_integrator.toml", "forced.toml",
                {{"[optimize]", "[forces]\nx = \"6*d/duration^2*(1 - 2*t/duration)\"\n\n[optimize]"}});
  const Outcome sim = run_nhdyn("simulate forced.toml --t-end 2 --output-step 0.0625 --rtol 1e-12 --atol 1e-12 -o sim.csv", dir_);
  ASSERT_EQ(sim.exit_code, 0) << sim.out;
  const Table opt = read_csv(dir_ / "di.csv"), simulated = read_csv(dir_ / "sim.csv");
  const std::vector<double> x = opt.column("x"), xs = simulated.column("x");
  ASSERT_EQ(x.size(), xs.size());
  for (std::size_t i = 0; i < x.size(); ++i) EXPECT_NEAR(x[i], xs[i], 1e-9) << i;
}

// A circle near the optimal one (5 per cent off, as the derivation's check), as a guess CSV.
std::string circle_guess() {
  const double R = std::sqrt(1 / (2 * kPi)), w = 2 * kPi;
  std::string out = "t,x,y,z,x',y',z',x'',y'',z'',u_Fx,u_Fy\n";
  for (int i = 0; i <= 200; ++i) {
    const double t = i / 200.0, s = std::sin(w * t), c = std::cos(w * t), k = 1 + 0.05 * std::sin(3 * w * t);
    const double values[] = {t, k * R * s, k * R * (1 - c), k * R * R * (w * t - s), k * R * w * c, k * R * w * s,
                             k * R * R * w * (1 - c), -k * R * w * w * s, k * R * w * w * c, k * R * R * w * w * s,
                             -R * w * w * s, R * w * w * c};
    for (std::size_t j = 0; j < std::size(values); ++j) out += (j ? "," : "") + std::to_string(values[j]);
    out += "\n";
  }
  return out;
}

TEST_F(OptimizeCli, BrockettIntegratorReachesTheCircle) {
  // J* = 2 pi a / T (a = T = 1): the circle of radius sqrt(a/(2 pi)) run once (section 10.2), with
  // z(t) = a (t/T - sin(2 pi t/T)/(2 pi)) and x^2 + y^2 = 2 R^2 (1 - cos(2 pi t/T)).
  write("circle.csv", circle_guess());
  const Outcome straight = optimize(example("brockett.toml") + " -o b.csv");
  SKIP_WITHOUT_IPOPT(straight);
  // From the straight line (a stationary point of the violation) IPOPT stalls: said plainly, exit
  // 1, the last iterate kept.
  EXPECT_EQ(straight.exit_code, 1) << straight.out;
  EXPECT_NE(straight.out.find("--guess"), std::string::npos) << straight.out;
  EXPECT_TRUE(fs::exists(dir_ / "b.partial.csv"));
  EXPECT_FALSE(fs::exists(dir_ / "b.csv"));

  const Outcome hs = optimize(example("brockett.toml") + " --guess circle.csv --tolerance 1e-10 -o b9.csv");  // 9 nodes
  ASSERT_EQ(hs.exit_code, 0) << hs.out;
  // Hermite-Simpson, N = 8: J_N - J = 1.32e-3 (the derivation's table; order 4)
  EXPECT_NEAR(summary_value(hs.out, "objective") - 2 * kPi, 1.32e-3, 0.03e-3) << hs.out;
  const Table t = read_csv(dir_ / "b9.csv");
  const std::vector<double> time = t.column("t"), x = t.column("x"), y = t.column("y"), z = t.column("z");
  const double R2 = 1 / (2 * kPi);
  for (std::size_t i = 0; i < time.size(); ++i) {
    EXPECT_NEAR(z[i], time[i] - std::sin(2 * kPi * time[i]) / (2 * kPi), 3e-4) << time[i];
    EXPECT_NEAR(x[i] * x[i] + y[i] * y[i], 2 * R2 * (1 - std::cos(2 * kPi * time[i])), 1e-3) << time[i];
  }
  // Trapezoidal, N = 8: the discrete optimum J_N - J = 3.0794e-1 of the derivation's Newton solve.
  write_variant("brockett.toml", "t9.toml", {{"\"hermite-simpson\"", "\"trapezoidal\""}});
  const Outcome trap = optimize("t9.toml --guess circle.csv --tolerance 1e-10");
  ASSERT_EQ(trap.exit_code, 0) << trap.out;
  EXPECT_NEAR(summary_value(trap.out, "objective") - 2 * kPi, 3.0794e-1, 2e-4) << trap.out;
}

TEST_F(OptimizeCli, BrachistochroneFollowsTheCycloid) {
  // (x1, y1) = (2, 1), g = 9.81: phi1 = 3.508368768524, R = 0.517199921687, T* = 0.805563829516.
  const Outcome run = optimize(example("brachistochrone.toml") + " -o br.csv");
  SKIP_WITHOUT_IPOPT(run);
  ASSERT_EQ(run.exit_code, 0) << run.out;
  const double T = 0.805563829516, R = 0.517199921687, omega = std::sqrt(9.81 / R);
  EXPECT_NEAR(summary_value(run.out, "t_end"), T, 1e-6 * T) << run.out;
  EXPECT_LT(summary_value(run.out, "replay difference"), 1e-4) << run.out;
  const Table t = read_csv(dir_ / "br.csv");
  const std::vector<double> time = t.column("t"), x = t.column("x"), y = t.column("y");
  for (std::size_t i = 0; i < time.size(); ++i) {
    const double phi = omega * time[i] * T / time.back();
    EXPECT_NEAR(x[i], R * (phi - std::sin(phi)), 1e-4) << time[i];
    EXPECT_NEAR(y[i], R * (1 - std::cos(phi)), 1e-4) << time[i];
  }
}

// The sled turned from rest to a heading with the least integral of T^2 (examples/sled_heading_optimal.toml).
// With a = 0 it turns in place, m rho^2 phi'' = T: the cubic optimum, J = 12 (m rho^2)^2 heading^2 / T^3,
// which Hermite-Simpson meets exactly. With the file's a = 0.5 there is no closed form; the result must
// keep two identities of the exact dynamics that the transcription does not impose as such: the speed
// along the blade v' = a phi'^2, so v(T) = a int phi'^2 dt, and the work of the torque, int T phi' dt,
// equal to the final kinetic energy m v(T)^2 / 2 (phi'(T) = 0; the blade does no work).
TEST_F(OptimizeCli, SledTurnedToAHeadingMeetsItsClosedFormAndItsIdentities) {
  const Outcome turn = optimize(example("sled_heading_optimal.toml") + " --set a=0 -o turn.csv");
  SKIP_WITHOUT_IPOPT(turn);
  ASSERT_EQ(turn.exit_code, 0) << turn.out;
  const double I = 0.7 * 0.7, heading = kPi / 2, T = 2.0;
  EXPECT_NEAR(summary_value(turn.out, "objective"), 12 * I * I * heading * heading / (T * T * T), 1e-8) << turn.out;
  const Table in_place = read_csv(dir_ / "turn.csv");
  const std::vector<double> t0 = in_place.column("t"), u0 = in_place.column("u_T"), x0 = in_place.column("x");
  for (std::size_t i = 0; i < t0.size(); ++i) {
    EXPECT_NEAR(u0[i], I * 6 * heading / (T * T) * (1 - 2 * t0[i] / T), 1e-6) << "t = " << t0[i];
    EXPECT_NEAR(x0[i], 0.0, 1e-9) << "t = " << t0[i];
  }

  const Outcome run = optimize(example("sled_heading_optimal.toml") + " -o sled.csv");
  ASSERT_EQ(run.exit_code, 0) << run.out;
  EXPECT_LT(summary_value(run.out, "replay difference"), 1e-5) << run.out;
  const Table t = read_csv(dir_ / "sled.csv");
  const std::vector<double> time = t.column("t"), w = t.column("phi'"), u = t.column("u_T"), phi = t.column("phi");
  const std::vector<double> xd = t.column("x'"), yd = t.column("y'");
  ASSERT_EQ(time.size(), 41U);  // 21 nodes and 20 midpoints
  EXPECT_NEAR(phi.back(), heading, 1e-9);
  EXPECT_NEAR(w.back(), 0.0, 1e-9);
  // Simpson's rule over node, midpoint, node (the quadrature of the transcription itself).
  const auto integral = [&](const auto& f) {
    double sum = 0;
    for (std::size_t k = 0; k + 2 < time.size(); k += 2)
      sum += (time[k + 2] - time[k]) / 6 * (f(k) + 4 * f(k + 1) + f(k + 2));
    return sum;
  };
  const double v_end = std::hypot(xd.back(), yd.back());
  ASSERT_GT(v_end, 0.5);  // the sled has moved off: the identities below are not 0 = 0
  EXPECT_NEAR(v_end, 0.5 * integral([&](std::size_t k) { return w[k] * w[k]; }), 1e-5 * v_end);
  EXPECT_NEAR(0.5 * v_end * v_end, integral([&](std::size_t k) { return u[k] * w[k]; }), 1e-5 * v_end * v_end);
  // Turning costs less than in place: the term m a v phi' brakes the turn the torque must stop.
  EXPECT_LT(summary_value(run.out, "objective"), 12 * I * I * heading * heading / (T * T * T));
}

// The Whipple bicycle moved one lane over at 5 m/s by its steer torque (examples/bicycle_lane_change.toml),
// at 15 nodes to keep the test short. The ends are imposed; what is not imposed is how a bicycle must
// turn: it counter-steers (the steer first turns away from the lane, delta < 0, and the rear contact
// point first moves away from it, y < 0) before it turns towards it, and it leans into the turn.
TEST_F(OptimizeCli, BicycleChangesLaneByCounterSteering) {
  const Outcome run = optimize(example("bicycle_lane_change.toml") + " --set node_count=15 -o lane.csv");
  SKIP_WITHOUT_IPOPT(run);
  ASSERT_EQ(run.exit_code, 0) << run.out;
  EXPECT_NE(run.out.find("status: solved"), std::string::npos) << run.out;
  EXPECT_LT(summary_value(run.out, "replay difference"), 2e-3) << run.out;  // of a 1 m lane, order 4 in h
  const Table t = read_csv(dir_ / "lane.csv");
  const std::vector<double> time = t.column("t"), y = t.column("y"), delta = t.column("delta"), phi = t.column("phi");
  ASSERT_EQ(time.size(), 29U);
  EXPECT_NEAR(y.back(), 1.0, 1e-8);
  EXPECT_NEAR(phi.back(), 0.0, 1e-8);
  double first_delta = 0, first_y = 0, largest_lean = 0;
  for (std::size_t i = 0; i < time.size(); ++i) {
    if (time[i] < 0.75) first_delta = std::min(first_delta, delta[i]), first_y = std::min(first_y, y[i]);
    if (time[i] > 0.5 && time[i] < 1.5) largest_lean = std::max(largest_lean, phi[i]);
  }
  EXPECT_LT(first_delta, -0.01) << "no counter-steer";
  EXPECT_LT(first_y, -0.01) << "the rear contact did not first move away from the lane";
  EXPECT_GT(largest_lean, 0.05) << "no lean into the turn towards +y (phi > 0 leans right, z down)";
}

// The controls of a Hermite-Simpson result (quadratic through node, midpoint, node on each interval,
// continuous at the nodes) as one expression in t: the first interval's quadratic plus, at each
// later node t_k, the change of slope and curvature switched on by H(t - t_k), with
// H(s) s = (s + |s|)/2. `time` and `u` hold the points in order (2N + 1 of them).
std::string piecewise_quadratic(const std::vector<double>& time, const std::vector<double>& u) {
  const auto num = [](double v) {
    std::ostringstream s;
    s.precision(17);
    s << "(" << v << ")";
    return s.str();
  };
  std::vector<double> alpha, beta, start, length;
  for (std::size_t a = 0; a + 2 < time.size(); a += 2) {
    const double h = time[a + 2] - time[a];
    const double b = 2 * (u[a] - 2 * u[a + 1] + u[a + 2]) / (h * h);
    beta.push_back(b);
    alpha.push_back((u[a + 2] - u[a]) / h - b * h);
    start.push_back(time[a]);
    length.push_back(h);
  }
  const std::string s0 = "(t - " + num(start[0]) + ")";
  std::string out = num(u[0]) + " + " + num(alpha[0]) + "*" + s0 + " + " + num(beta[0]) + "*" + s0 + "^2";
  for (std::size_t k = 1; k < alpha.size(); ++k) {
    const double d_alpha = alpha[k] - (alpha[k - 1] + 2 * beta[k - 1] * length[k - 1]), d_beta = beta[k] - beta[k - 1];
    const std::string s = "(t - " + num(start[k]) + ")";
    out += " + (" + num(d_alpha) + " + " + num(d_beta) + "*" + s + ")*(" + s + " + abs" + s + ")/2";
  }
  return out;
}

TEST_F(OptimizeCli, ParallelParkingMeetsItsEndsKeepsClearAndReplaysInSimulate) {
  // examples/parking.toml at 31 nodes (the example has 61) from its guess: IPOPT converges, the
  // final state is the one asked for, the steer, force and torque bounds and the post's clearance
  // hold at every point, and `nhdyn simulate` under the optimal controls (as [forces], interpolated
  // as Hermite-Simpson defines them) ends where the optimized motion ends, to within the
  // collocation error that the replay difference measures.
  // The guess is the one the file names (guess = "parking_guess.csv", beside it), run from another
  // folder.
  const Outcome run = optimize(example("parking.toml") + " --set node_count=31 -o park.csv");
  SKIP_WITHOUT_IPOPT(run);
  ASSERT_EQ(run.exit_code, 0) << run.out;
  EXPECT_NE(run.out.find("first guess: " + example("parking_guess.csv")), std::string::npos) << run.out;
  EXPECT_NE(run.out.find("status: solved"), std::string::npos) << run.out;
  const double replay = summary_value(run.out, "replay difference");
  EXPECT_LT(replay, 0.1) << run.out;
  const Table t = read_csv(dir_ / "park.csv");
  const std::vector<double> time = t.column("t"), x = t.column("x"), y = t.column("y"), theta = t.column("theta"),
                            delta = t.column("delta"), F = t.column("u_F"), T = t.column("u_T");
  ASSERT_EQ(time.size(), 61U);
  const std::size_t last = time.size() - 1;
  EXPECT_NEAR(x[last], 0.0, 1e-8);
  EXPECT_NEAR(y[last], 2.0, 1e-8);
  EXPECT_NEAR(theta[last], 0.0, 1e-8);
  EXPECT_NEAR(delta[last], 0.0, 1e-8);
  EXPECT_NEAR(t.column("x'")[last], 0.0, 1e-8);
  EXPECT_NEAR(t.column("delta'")[last], 0.0, 1e-8);
  EXPECT_LT(std::abs(t.column("y'")[last]), 1e-2);  // released: the drift of the blade constraints
  EXPECT_LT(std::abs(t.column("theta'")[last]), 1e-2);
  double clearance = 1e9, front_clearance = 1e9, x_max = 0.0;
  for (std::size_t i = 0; i < time.size(); ++i) {
    clearance = std::min(clearance, std::hypot(x[i] - 5.5, y[i] - 2.0));
    front_clearance = std::min(front_clearance, std::hypot(x[i] + 1.5 * std::cos(theta[i]) - 5.5, y[i] + 1.5 * std::sin(theta[i]) - 2.0));
    x_max = std::max(x_max, x[i]);
    EXPECT_LE(std::abs(delta[i]), kPi / 4 + 1e-6) << time[i];
    EXPECT_LE(std::abs(F[i]), 300 + 1e-4) << time[i];
    EXPECT_LE(std::abs(T[i]), 50 + 1e-4) << time[i];
  }
  EXPECT_GE(clearance, 1.2 - 1e-6);
  EXPECT_GE(front_clearance, 1.2 - 1e-6);
  EXPECT_LT(front_clearance, 1.2 + 1e-4);  // the post is in the way: the constraint is active
  EXPECT_GT(x_max, 1.0);                   // the car cannot slide sideways: it drives out and back

  // The independent check: simulate's own integration of the model under F and T as forces.
  const std::string f = piecewise_quadratic(time, F), torque = piecewise_quadratic(time, T);
  write_variant("parking.toml", "forced.toml",
                {{"[optimize]", "[forces]\nx = \"(" + f + ")*cos(theta)\"\ny = \"(" + f + ")*sin(theta)\"\ndelta = \"" +
                                    torque + "\"\n\n[optimize]"}});
  const Outcome sim = run_nhdyn("simulate forced.toml --t-end 30 --output-step 0.5 --rtol 1e-11 --atol 1e-11 -o sim.csv", dir_);
  ASSERT_EQ(sim.exit_code, 0) << sim.out;
  const Table s = read_csv(dir_ / "sim.csv");
  ASSERT_EQ(s.column("t").size(), 61U);
  double worst = 0.0;
  for (const char* c : {"x", "y", "theta", "delta"}) {
    const std::vector<double> optimized = t.column(c), simulated = s.column(c);
    for (std::size_t i = 0; i < time.size(); i += 2) worst = std::max(worst, std::abs(optimized[i] - simulated[i]));
  }
  EXPECT_LT(worst, 1.5 * replay + 1e-6) << "replay difference " << replay;
  EXPECT_GT(worst, 0.5 * replay) << "replay difference " << replay;  // the same error, seen twice
}

// The values of the report's plotted series `name` ({"name":"R_x","v":[...]} in the page's data).
std::vector<double> report_series(const std::string& page, const std::string& name) {
  const std::string key = "{\"name\":\"" + name + "\",\"v\":[";
  const std::size_t at = page.find(key);
  std::vector<double> out;
  if (at == std::string::npos) return out;
  std::stringstream s(page.substr(at + key.size(), page.find(']', at) - at - key.size()));
  std::string cell;
  while (std::getline(s, cell, ',')) out.push_back(std::stod(cell));
  return out;
}

TEST_F(OptimizeCli, HtmlReportsTheOptimalMotionWithTheControlsTakenOutOfTheReactions) {
  // A knife edge pushed along its blade by F and turned by T: the blade's reaction
  // R = A q'' - Q - G - B u has no theta part (b has none), so R_theta = J theta'' - T = 0 to the
  // solver's tolerance, where J theta'' alone is not. The double integrator has no constraint:
  // R_x = m x'' - F = 0, and its energy balance error is the trapezoidal rule's error on the work
  // of F (the controls' work booked with the forces), small and back to 0 at t_end (F v is odd
  // about T/2).
  write("blade.toml", R"toml(name = "blade"
coordinates = ["x", "y", "theta"]
kinetic_energy = "m/2 * (x'^2 + y'^2) + J/2 * theta'^2"
[parameters]
m = 1.0
J = 1.0
[[constraints]]
name = "blade"
velocity = "-sin(theta)*x' + cos(theta)*y'"
[optimize]
controls = [{ name = "F", actuator = ["cos(theta)", "sin(theta)", 0] }, { name = "T", actuator = "theta" }]
objective = "F^2 + T^2"
t_end = 2
nodes = 11
initial = { position = { x = 0, y = 0, theta = 0 }, velocity = { x = 0, y = 0, theta = 0 } }
final = { position = { x = 1, y = 0.1, theta = 0.2 }, velocity = { x = 0, y = 0, theta = 0 } }
)toml");
  const Outcome run = optimize("blade.toml -o blade.csv --html blade.html");
  SKIP_WITHOUT_IPOPT(run);
  ASSERT_EQ(run.exit_code, 0) << run.out;
  EXPECT_NE(run.out.find("report -> blade.html"), std::string::npos) << run.out;
  std::ifstream in(dir_ / "blade.html");
  std::stringstream text;
  text << in.rdbuf();
  const std::string page = text.str();
  EXPECT_NE(page.find("blade: optimal program, 11 nodes, hermite-simpson"), std::string::npos);
  EXPECT_NE(page.find("replay difference"), std::string::npos);
  const std::vector<double> r_theta = report_series(page, "R_theta"), theta2 = read_csv(dir_ / "blade.csv").column("theta''");
  ASSERT_EQ(r_theta.size(), 21U);
  double largest_theta2 = 0.0;
  for (double v : theta2) largest_theta2 = std::max(largest_theta2, std::abs(v));
  EXPECT_GT(largest_theta2, 0.1);
  for (std::size_t i = 0; i < r_theta.size(); ++i) EXPECT_LT(std::abs(r_theta[i]), 1e-7) << i;
  // The controls in a panel of their own, the CSV's u_F and u_T to the page's 6 digits.
  EXPECT_NE(page.find("\"title\":\"controls u (the optimum's)\""), std::string::npos);
  for (const char* control : {"u_F", "u_T"}) {
    const std::vector<double> shown = report_series(page, control), written = read_csv(dir_ / "blade.csv").column(control);
    ASSERT_EQ(shown.size(), written.size()) << control;
    double largest = 0.0;
    for (std::size_t i = 0; i < shown.size(); ++i) {
      EXPECT_NEAR(shown[i], written[i], 1e-5 * std::abs(written[i]) + 1e-12) << control << " " << i;
      largest = std::max(largest, std::abs(written[i]));
    }
    EXPECT_GT(largest, 0.1) << control;  // a control that acts
  }

  const Outcome di = optimize(example("double_integrator.toml") + " -o di.csv --html di.html");
  ASSERT_EQ(di.exit_code, 0) << di.out;
  std::ifstream in2(dir_ / "di.html");
  std::stringstream text2;
  text2 << in2.rdbuf();
  const std::vector<double> rx = report_series(text2.str(), "R_x"), balance = report_series(text2.str(), "balance_error");
  ASSERT_EQ(rx.size(), 33U);
  for (double v : rx) EXPECT_LT(std::abs(v), 1e-9);
  ASSERT_EQ(balance.size(), 33U);
  for (double v : balance) EXPECT_LT(std::abs(v), 2e-3);
  EXPECT_LT(std::abs(balance.back()), 1e-9);

  const Outcome same = optimize(example("double_integrator.toml") + " -o di2.csv --html di2.csv");
  EXPECT_EQ(same.exit_code, 2) << same.out;
  EXPECT_NE(same.out.find("--html"), std::string::npos) << same.out;
  const Outcome no_csv = optimize(example("double_integrator.toml") + " --html x.html");
  EXPECT_EQ(no_csv.exit_code, 2) << no_csv.out;
  EXPECT_NE(no_csv.out.find("give -o FILE.csv too"), std::string::npos) << no_csv.out;
}

TEST_F(OptimizeCli, FinalValuesTheConstraintsDetermineAreReleased) {
  // A knife edge brought to rest: x' = y' = 0 at t_end fixes the sideways speed twice (the blade
  // constraint already does), which the discrete motion meets only up to its drift. The rank rule
  // releases y' and says so; the blade's residual there is the drift, small.
  write("blade.toml", R"toml(name = "blade"
coordinates = ["x", "y", "theta"]
kinetic_energy = "m/2 * (x'^2 + y'^2) + J/2 * theta'^2"
[parameters]
m = 1.0
J = 1.0
[[constraints]]
name = "blade"
velocity = "-sin(theta)*x' + cos(theta)*y'"
[optimize]
controls = [{ name = "F", actuator = ["cos(theta)", "sin(theta)", 0] }, { name = "T", actuator = "theta" }]
objective = "F^2 + T^2"
t_end = 2
nodes = 11
initial = { position = { x = 0, y = 0, theta = 0 }, velocity = { x = 0, y = 0, theta = 0 } }
final = { position = { x = 1, y = 0.1, theta = 0.2 }, velocity = { x = 0, y = 0, theta = 0 } }
)toml");
  const Outcome run = optimize("blade.toml -o blade.csv");
  SKIP_WITHOUT_IPOPT(run);
  ASSERT_EQ(run.exit_code, 0) << run.out;
  EXPECT_NE(run.out.find("note: the final y' is determined by the constraints (blade)"), std::string::npos) << run.out;
  EXPECT_LT(summary_value(run.out, "replay difference"), 1e-3) << run.out;
  const Table t = read_csv(dir_ / "blade.csv");
  EXPECT_DOUBLE_EQ(t.column("x'").back(), 0.0);
  EXPECT_LT(std::abs(t.column("y'").back()), 1e-3);
  EXPECT_GT(std::abs(t.column("y'").back()), 0.0);  // left free: the drift, not pinned
}

// A final value the constraints determine is released only when it agrees with them: x - y = 0
// with x = 1, y = 0 at t_end is a contradiction, refused before any work with the constraint and
// its residual (released, x met 0 with exit 0 and a note that said it met its value).
TEST_F(OptimizeCli, FinalValuesThatContradictTheConstraintsAreRefused) {
  const std::string model = R"toml(name = "pair"
coordinates = ["x", "y", "z"]
kinetic_energy = "m/2 * (x'^2 + y'^2 + z'^2)"
[parameters]
m = 1.0
[[constraints]]
name = "c1"
position = "x - y"
[optimize]
controls = [{ name = "Fx", actuator = "x" }, { name = "Fy", actuator = "y" }]
objective = "Fx^2 + Fy^2"
t_end = 1
nodes = 9
initial = { position = { x = 0, y = 0, z = 0 }, velocity = { x = 0, y = 0, z = 0 } }
)toml";
  write("contradict.toml", model + "final = { position = { x = 1, y = 0 } }\n");
  const Outcome run = run_nhdyn("optimize contradict.toml -o c.csv", dir_);
  EXPECT_EQ(run.exit_code, 2) << run.out;
  EXPECT_NE(run.out.find("contradict.toml:15:28: the final values of [optimize] violate the constraint c1 (position): "
                         "with x = 1, y = 0 its "
                         "residual at t_end is 1.000e+00, and no free final value can change it"),
            std::string::npos)
      << run.out;
  EXPECT_EQ(run.out.find("status:"), std::string::npos) << run.out;
  EXPECT_FALSE(fs::exists(dir_ / "c.csv"));
  // A constraint not defined at the final values (sqrt(y - 0.5) at the straight line's y = 0) is
  // named so, not said to be violated by values that leave y free (it read "the constraint :" and
  // "-nan").
  write("undefined.toml", R"toml(name = "undefined"
coordinates = ["x", "y"]
kinetic_energy = "1/2 * x'^2 + 1/2*y'^2"
[[constraints]]
name = "c1"
velocity = "x' - sqrt(y - 0.5)*y'"
[optimize]
controls = [{ name = "F", actuator = "x" }]
objective = "F^2"
t_end = 1
nodes = 5
initial = { position = { x = 0, y = 0 }, velocity = { x = 0, y = 0 } }
final = { position = { x = 1 }, velocity = { x = 0 } }
)toml");
  const Outcome undefined = run_nhdyn("optimize undefined.toml -o u.csv", dir_);
  EXPECT_EQ(undefined.exit_code, 2) << undefined.out;
  EXPECT_NE(undefined.out.find("the constraint c1 (velocity) is not defined at the final values of [optimize]"),
            std::string::npos)
      << undefined.out;
  EXPECT_NE(undefined.out.find("(its residual at t_end is NaN)"), std::string::npos) << undefined.out;
  EXPECT_FALSE(fs::exists(dir_ / "c.partial.csv"));
  // Values on the constraint: one of them released, both met.
  write("agree.toml", model + "final = { position = { x = 1, y = 1 } }\n");
  const Outcome agree = optimize("agree.toml -o a.csv");
  SKIP_WITHOUT_IPOPT(agree);
  ASSERT_EQ(agree.exit_code, 0) << agree.out;
  EXPECT_NE(agree.out.find("is determined by the constraints (c1)"), std::string::npos) << agree.out;
  const Table t = read_csv(dir_ / "a.csv");
  EXPECT_NEAR(t.column("x").back(), 1.0, 1e-8);
  EXPECT_NEAR(t.column("y").back(), 1.0, 1e-8);
}

TEST_F(OptimizeCli, InfeasibleProblemIsSaidPlainlyAndItsLastIterateKept) {
  // |F| <= 0.1 moves the mass at most 0.1 T^2/4 = 0.1 from rest to rest in T = 2, not d = 1.
  write_variant("double_integrator.toml", "weak.toml", {{"final =", "bounds = { F = [-0.1, 0.1] }\nfinal ="}});
  const Outcome run = optimize("weak.toml -o weak.csv");
  SKIP_WITHOUT_IPOPT(run);
  EXPECT_EQ(run.exit_code, 1) << run.out;
  EXPECT_NE(run.out.find("status: infeasible"), std::string::npos) << run.out;
  EXPECT_NE(run.out.find("IPOPT did not converge"), std::string::npos) << run.out;
  const Table partial = read_csv(dir_ / "weak.partial.csv");
  EXPECT_EQ(partial.rows.size(), 33U);
  EXPECT_FALSE(fs::exists(dir_ / "weak.csv"));
}

TEST_F(OptimizeCli, BadInputExitsTwoNamingWhere) {
  write_variant("double_integrator.toml", "unknown.toml", {{"objective = \"F^2\"", "objective = \"F^2 + vel\""}});
  const Outcome unknown = run_nhdyn("optimize unknown.toml", dir_);
  EXPECT_EQ(unknown.exit_code, 2) << unknown.out;
  EXPECT_NE(unknown.out.find("unknown.toml:13:20: unknown symbol 'vel'"), std::string::npos) << unknown.out;

  write_variant("double_integrator.toml", "bounds.toml", {{"final =", "bounds = { F = [2, 1] }\nfinal ="}});
  const Outcome bounds = run_nhdyn("optimize bounds.toml", dir_);
  EXPECT_EQ(bounds.exit_code, 2) << bounds.out;
  EXPECT_NE(bounds.out.find("bounds.toml:18:16"), std::string::npos) << bounds.out;
  EXPECT_NE(bounds.out.find("lower 2 > upper 1"), std::string::npos) << bounds.out;

  write_variant("double_integrator.toml", "nothing.toml", {{"actuator = \"x\"", "actuator = [\"0*m\"]"}});
  const Outcome nothing = run_nhdyn("optimize nothing.toml", dir_);
  EXPECT_EQ(nothing.exit_code, 2) << nothing.out;
  EXPECT_NE(nothing.out.find("control 'F' acts on nothing"), std::string::npos) << nothing.out;

  // guess = "..." names a CSV relative to the model file's folder: a missing one, or a value that is
  // not a path, is refused before the solve, at its line.
  write_variant("double_integrator.toml", "guess.toml", {{"final =", "guess = \"missing.csv\"\nfinal ="}});
  const Outcome guess = run_nhdyn("optimize guess.toml", dir_);
  EXPECT_EQ(guess.exit_code, 2) << guess.out;
  EXPECT_NE(guess.out.find("guess.toml:18:9: the guess file missing.csv does not exist"), std::string::npos)
      << guess.out;
  write_variant("double_integrator.toml", "guess_number.toml", {{"final =", "guess = 3\nfinal ="}});
  const Outcome number = run_nhdyn("optimize guess_number.toml", dir_);
  EXPECT_EQ(number.exit_code, 2) << number.out;
  EXPECT_NE(number.out.find("guess_number.toml:18:9: guess must be the path of a CSV"), std::string::npos)
      << number.out;

  const Outcome no_section = run_nhdyn("optimize " + example("sled.toml"), dir_);
  EXPECT_EQ(no_section.exit_code, 2) << no_section.out;
  EXPECT_NE(no_section.out.find("has no [optimize] section"), std::string::npos) << no_section.out;

  // The solver's options, before any work: IPOPT dropped tol 0 and max_iter -5 for its defaults
  // with a note of its own, and took --tolerance 1e300 to call the straight-line start solved.
  for (const std::string tolerance : {"0", "-1e-8", "nan", "inf", "1e300", "0.02"}) {
    const Outcome loose = run_nhdyn("optimize " + example("double_integrator.toml") + " -o t.csv --tolerance " + tolerance,
                                    dir_);
    EXPECT_EQ(loose.exit_code, 2) << tolerance << ": " << loose.out;
    EXPECT_NE(loose.out.find("the optimizer's tolerance"), std::string::npos) << loose.out;
    EXPECT_NE(loose.out.find("must be a number above 0 and at most 0.01"), std::string::npos) << loose.out;
    EXPECT_FALSE(fs::exists(dir_ / "t.csv")) << tolerance;
  }
  for (const std::string budget : {"0", "-5"}) {
    const Outcome none = run_nhdyn("optimize " + example("double_integrator.toml") + " -o i.csv --max-iterations " + budget,
                                   dir_);
    EXPECT_EQ(none.exit_code, 2) << budget << ": " << none.out;
    EXPECT_NE(none.out.find("the optimizer's iteration budget " + budget + " must be at least 1"), std::string::npos)
        << none.out;
    EXPECT_FALSE(fs::exists(dir_ / "i.csv")) << budget;
  }
}

// optimize imposes a contact's constraints at every point, rolling and bilateral: a contact that
// may slide or lift off is refused before any work, at its [[contacts]] entry, rather than
// optimized under another law than the model's (a ball "rolled" by 21 N where mu m g is 0.01 N).
TEST_F(OptimizeCli, ContactsThatMaySlideOrLiftOffAreRefusedBeforeAnyWork) {
  const std::string section = R"toml(
[optimize]
controls = [{ name = "F", actuator = "x" }]
objective = "F^2"
t_end = 0.2
nodes = 5
initial = { position = { x = 0, y = 0, z = "r", a = 0, b = 0, c = 0 }, velocity = { x = 0, y = 0, z = 0, a = 0, b = 0, c = 0 } }
final = { position = { x = 1 }, velocity = { x = 0 } }
)toml";
  const std::string base = read_example("ball_thrown_sliding.toml") + section;
  const auto variant = [&](const std::string& file, const std::string& keys) {
    std::string text = base;
    const std::string from = "friction = \"mu\"\nmode = \"sliding\"\n";
    const std::size_t at = text.find(from);
    EXPECT_NE(at, std::string::npos);
    text.replace(at, from.size(), keys);
    write(file, text);
  };
  variant("unilateral.toml", "friction = \"mu\"\nunilateral = true\n");
  variant("sliding.toml", "friction = \"mu\"\nmode = \"sliding\"\n");
  variant("rolling.toml", "");
  for (const auto& [file, keys] : {std::pair<std::string, std::string>{"unilateral", "friction and unilateral"},
                                   {"sliding", "friction and mode"}}) {
    const Outcome run = run_nhdyn("optimize " + file + ".toml --set mu=0.01 -o out.csv --html out.html", dir_);
    EXPECT_EQ(run.exit_code, 2) << run.out;
    EXPECT_NE(run.out.find(file + ".toml:37"), std::string::npos) << run.out;
    EXPECT_NE(run.out.find("contact 'ball' has " + keys + ": optimize takes contacts as rolling, bilateral "
                           "constraints"),
              std::string::npos)
        << run.out;
    EXPECT_NE(run.out.find("remove friction, unilateral, restitution and mode from the contact"), std::string::npos)
        << run.out;
    EXPECT_EQ(run.out.find("status:"), std::string::npos) << run.out;  // no solve
    EXPECT_FALSE(fs::exists(dir_ / "out.csv"));
    EXPECT_FALSE(fs::exists(dir_ / "out.partial.csv"));
    EXPECT_FALSE(fs::exists(dir_ / "out.html"));
  }
  // The same ball without the keys rolls, and is optimized as such.
  const Outcome rolling = optimize("rolling.toml -o rolling.csv");
  SKIP_WITHOUT_IPOPT(rolling);
  EXPECT_EQ(rolling.exit_code, 0) << rolling.out;
  EXPECT_NE(rolling.out.find("status: solved"), std::string::npos) << rolling.out;
}

// --html takes models without contacts: the refusal comes before the solve and writes nothing
// (it came after the whole solve, and left -o's CSV behind with exit 2).
TEST_F(OptimizeCli, HtmlOnAContactModelIsRefusedBeforeAnyWork) {
  std::string text = read_example("ball_thrown_sliding.toml");
  const std::string from = "friction = \"mu\"\nmode = \"sliding\"\n";
  const std::size_t at = text.find(from);
  ASSERT_NE(at, std::string::npos);
  text.replace(at, from.size(), "");  // a rolling, bilateral contact: optimize takes it
  write("rolling.toml", text + R"toml(
[optimize]
controls = [{ name = "F", actuator = "x" }]
objective = "F^2"
t_end = 0.2
nodes = 5
initial = { position = { x = 0, y = 0, z = "r", a = 0, b = 0, c = 0 }, velocity = { x = 0, y = 0, z = 0, a = 0, b = 0, c = 0 } }
final = { position = { x = 1 }, velocity = { x = 0 } }
)toml");
  const Outcome run = run_nhdyn("optimize rolling.toml -o out/x.csv --plot out/x.png --html out/x.html", dir_);
  EXPECT_EQ(run.exit_code, 2) << run.out;
  EXPECT_NE(run.out.find("--html: the report of an optimum is for models without contacts and [[programs]], and "
                         "ball-thrown-sliding has contacts; leave --html out"),
            std::string::npos)
      << run.out;
  EXPECT_EQ(run.out.find("status:"), std::string::npos) << run.out;  // no solve
  EXPECT_FALSE(fs::exists(dir_ / "out")) << run.out;                   // nothing written, no folder made
}

// A first guess is an input of the run (docs/cli.md, "One rule for the files of a command"):
// neither -o, --plot, --html nor a failed solve's FILE.partial.csv may replace it, whether it
// comes from --guess or from guess = in [optimize]; refused before any work, naming both.
TEST_F(OptimizeCli, TheFirstGuessIsAnInputThatNoOutputReplaces) {
  const std::string guess = "t,x,x'\n0,0,0\n2,1,0\n";
  write("g.csv", guess);
  write("h.partial.csv", guess);
  const auto unchanged = [&](const std::string& file) {
    std::ifstream in(dir_ / file);
    std::stringstream s;
    s << in.rdbuf();
    EXPECT_EQ(s.str(), guess) << file;
  };
  const std::string di = example("double_integrator.toml");
  for (const auto& [args, role] :
       {std::pair<std::string, std::string>{"--guess g.csv -o g.csv", "-o 'g.csv'"},
        {"--guess h.partial.csv -o h.csv", "the partial-results file 'h.partial.csv'"},
        {"--guess g.csv -o x.csv --html g.csv", "--html 'g.csv'"}}) {
    const Outcome run = run_nhdyn("optimize " + di + " " + args, dir_);
    EXPECT_EQ(run.exit_code, 2) << args << "\n" << run.out;
    EXPECT_NE(run.out.find("refusing to write " + role + ": it is --guess"), std::string::npos) << run.out;
    EXPECT_EQ(run.out.find("status:"), std::string::npos) << run.out;
    unchanged("g.csv");
    unchanged("h.partial.csv");
    EXPECT_FALSE(fs::exists(dir_ / "x.csv"));
    EXPECT_FALSE(fs::exists(dir_ / "h.csv"));
  }
  // guess = in the file, given back as the partial-results file of -o.
  write_variant("double_integrator.toml", "di.toml", {{"final =", "guess = \"h.partial.csv\"\nfinal ="}});
  const Outcome named = run_nhdyn("optimize di.toml -o h.csv", dir_);
  EXPECT_EQ(named.exit_code, 2) << named.out;
  EXPECT_NE(named.out.find("refusing to write the partial-results file 'h.partial.csv': it is the first guess "
                           "(guess = in [optimize])"),
            std::string::npos)
      << named.out;
  unchanged("h.partial.csv");
  // Outputs that are not the guess are taken.
  const Outcome other = optimize(di + " --guess h.partial.csv -o other.csv");
  SKIP_WITHOUT_IPOPT(other);
  EXPECT_EQ(other.exit_code, 0) << other.out;
  unchanged("h.partial.csv");
}

// The replay rule (docs/optimize.md): a result IPOPT calls solved one of whose intervals, replayed
// from the optimum's own state at its start, ends further than a tenth of a coordinate's range from
// it is no motion of the model: exit 1, the discrete optimum in FILE.partial.csv, no FILE.csv, and
// the reason with what to do.
TEST_F(OptimizeCli, AnOptimumTheReplayDoesNotConfirmIsNotCalledSolved) {
  const auto rejected = [&](const Outcome& run, const std::string& stem) {
    EXPECT_EQ(run.exit_code, 1) << run.out;
    EXPECT_NE(run.out.find("status: not a motion of the model (IPOPT: "), std::string::npos) << run.out;
    EXPECT_NE(run.out.find("IPOPT solved the discrete problem, but its optimum is not a motion of the model"),
              std::string::npos)
        << run.out;
    EXPECT_NE(run.out.find("give more nodes, a tighter --tolerance or a first guess"), std::string::npos) << run.out;
    EXPECT_NE(run.out.find("discrete optimum -> " + stem + ".partial.csv"), std::string::npos) << run.out;
    EXPECT_FALSE(fs::exists(dir_ / (stem + ".csv")));
    std::ifstream in(dir_ / (stem + ".partial.csv"));
    std::string first;
    std::getline(in, first);
    EXPECT_EQ(first.rfind("# nhdyn optimize: not a motion of the model (interval replay ", 0), 0U) << first;
    EXPECT_GT(summary_value(run.out, "interval replay"), 0.03);
  };
  // x'' = x F / m from rest at x = 0: x stays 0 whatever F, so x = 1 is out of reach; the discrete
  // problem "reached" it by a jump in the last interval (replay difference 1 for a range of 1).
  write_variant("double_integrator.toml", "stuck.toml", {{"actuator = \"x\"", "actuator = [\"x\"]"}});
  const Outcome stuck = optimize("stuck.toml -o stuck.csv");
  SKIP_WITHOUT_IPOPT(stuck);
  rejected(stuck, "stuck");
  EXPECT_NE(stuck.out.find("the problem may have no solution (an actuator that cannot move the system"),
            std::string::npos)
      << stuck.out;
  // Parking at 3 nodes: an interval ends 0.5 rad off in a heading that turns 0.33 rad (from t0,
  // 3.6 m off for a 2 m manoeuvre).
  rejected(optimize(example("parking.toml") + " --set node_count=3 -o park.csv"), "park");
  // A free final time over [1e-9, 1e9]: IPOPT's "acceptable" at t_end = 5e8 s for the bead that
  // reaches its end point in 0.806 s.
  write_variant("brachistochrone.toml", "wide.toml", {{"t_end = { free = [0.1, 5] }", "t_end = { free = [1e-9, 1e9] }"}});
  rejected(optimize("wide.toml -o wide.csv"), "wide");
  // The shipped examples stay far inside the limit (the double integrator, exact, and the
  // brachistochrone here; the others in their own tests).
  for (const char* name : {"double_integrator.toml", "brachistochrone.toml"}) {
    const Outcome run = optimize(example(name) + " -o ok.csv");
    EXPECT_EQ(run.exit_code, 0) << run.out;
    const std::size_t at = run.out.find("; limit ");
    ASSERT_NE(at, std::string::npos) << run.out;
    EXPECT_LT(summary_value(run.out, "interval replay"), 1e-3 * std::stod(run.out.substr(at + 8))) << run.out;
  }
  // Each coordinate against its own range and size: a height standing still at 1e9 (whose floor
  // is 10) or a flywheel turning through 5000 rad (whose range is 5000) left the impossible x of
  // a mass that x F cannot move, and an x that the controls take 1 m off within an interval,
  // inside a limit set by the other coordinate.
  write("tall.toml", R"toml(name = "tall"
coordinates = ["x", "z"]
kinetic_energy = "1/2 * x'^2 + 1/2*z'^2"
[optimize]
controls = [{ name = "F", actuator = ["x", "0"] }]
objective = "F^2"
t_end = 1
nodes = 11
initial = { position = { x = 0, z = 1e9 }, velocity = { x = 0, z = 0 } }
final = { position = { x = 1 }, velocity = { x = 0 } }
)toml");
  rejected(optimize("tall.toml -o tall.csv"), "tall");
  write("flywheel.toml", R"toml(name = "flywheel"
coordinates = ["x", "phi"]
kinetic_energy = "1/2 * x'^2 + 1/2*phi'^2"
potential_energy = "-c*sin(5000*t)*x"
[parameters]
c = 1e3
[optimize]
controls = [{ name = "F", actuator = "x" }]
objective = "1e-6*F^2 + 1e6*x^2"
t_end = 1
nodes = 21
method = "trapezoidal"
initial = { position = { x = 0, phi = 0 }, velocity = { x = 0, phi = 5000 } }
final = { position = { x = 0 }, velocity = { x = 0 } }
)toml");
  const Outcome flywheel = optimize("flywheel.toml -o flywheel.csv");
  rejected(flywheel, "flywheel");
  EXPECT_NE(flywheel.out.find("interval replay: 1.0"), std::string::npos) << flywheel.out;
  EXPECT_NE(flywheel.out.find(" in x ("), std::string::npos) << flywheel.out;
  // An unstable motion: a pendulum on a cart swung up from hanging, whose replay from t0 drifts
  // with the instability (0.42 at 41 nodes, 0.10 at 81: as h^2) while each interval's error is
  // small (1.3e-3): accepted, the replay from t0 reported.
  write("cartpole.toml", R"toml(name = "cartpole"
coordinates = ["x", "theta"]
kinetic_energy = "(mc + mb)/2 * x'^2 + mb*l*cos(theta)*x'*theta' + mb*l^2/2 * theta'^2"
potential_energy = "-mb*g*l*cos(theta)"
[parameters]
mc = 1.0
mb = 0.3
l = 0.5
g = 9.81
[optimize]
controls = [{ name = "F", actuator = "x" }]
objective = "F^2"
t_end = 2
nodes = 41
method = "trapezoidal"
initial = { position = { x = 0, theta = 0 }, velocity = { x = 0, theta = 0 } }
final = { position = { x = 1, theta = 3.141592653589793 }, velocity = { x = 0, theta = 0 } }
bounds = { F = [-20, 20] }
)toml");
  const Outcome swing = optimize("cartpole.toml -o swing.csv");
  EXPECT_EQ(swing.exit_code, 0) << swing.out;
  EXPECT_GT(summary_value(swing.out, "replay difference"), 0.1) << swing.out;
  EXPECT_LT(summary_value(swing.out, "interval replay"), 0.01) << swing.out;
}

// A guess is read as a table of finite numbers over [t0, t_end], times never decreasing, each
// column once: anything else is refused before any work by file, row and column (NaN reached IPOPT
// as "Invalid number", unsorted or outside times were interpolated as they fell); columns that
// name nothing in the problem, and a guess covering part of [t0, t_end], are named in a note.
TEST_F(OptimizeCli, AGuessThatIsNotATableOfTheMotionIsRefusedByRowAndColumn) {
  const std::string di = example("double_integrator.toml");
  const auto refused = [&](const std::string& csv, const std::string& message) {
    write("g.csv", csv);
    const Outcome run = run_nhdyn("optimize " + di + " --guess g.csv -o o.csv", dir_);
    EXPECT_EQ(run.exit_code, 2) << csv << "\n" << run.out;
    EXPECT_NE(run.out.find("g.csv" + message), std::string::npos) << csv << "\n" << run.out;
    EXPECT_EQ(run.out.find("status:"), std::string::npos) << run.out;
    EXPECT_FALSE(fs::exists(dir_ / "o.csv"));
    EXPECT_FALSE(fs::exists(dir_ / "o.partial.csv"));
  };
  refused("t,x,x'\n0,0,0\n1,nan,0\n2,1,0\n", ":3: x = nan is not finite");
  refused("t,x,x'\n0,0,0\n1,0.5,inf\n2,1,0\n", ":3: x' = inf is not finite");
  refused("t,x,x'\n0,0,0\n2,1,0\n1,0.5,0\n", ":4: t = 1 is before the row above (t = 2)");
  // The file's line, after a partial file's comment line.
  refused("# nhdyn optimize: IPOPT stopped\nt,x,x'\n0,0,0\n1,nan,0\n", ":4: x = nan is not finite");
  refused("t,x,x'\n5,0,0\n7,1,0\n", ": the guess covers t = 5 to 7, outside the problem's [0, 2]");
  refused("t,x,x'\n1,0,0\n1,1,0\n", ": the guess's times span nothing (every row at t = 1)");
  refused("t,x,x',x\n0,0,0,0\n2,1,0,1\n", ": the guess names the column 'x' twice (columns 2 and 4)");
  // Taken, with what it does not use and what it does not cover named.
  write("g.csv", "t,x,x',u_G,speed\n0,0,0,1,0\n1.5,1,0,1,0\n");
  const Outcome taken = optimize(di + " --guess g.csv -o o.csv");
  SKIP_WITHOUT_IPOPT(taken);
  EXPECT_EQ(taken.exit_code, 0) << taken.out;
  EXPECT_NE(taken.out.find("note: the guess g.csv has columns that name nothing in the problem, ignored: u_G, speed"),
            std::string::npos)
      << taken.out;
  EXPECT_NE(taken.out.find("note: the guess g.csv covers t = 0 to 1.5 of [0, 2]: its last row is held beyond"),
            std::string::npos)
      << taken.out;
  // A previous result, which covers [t0, t_end] with the problem's columns, gets neither note.
  const Outcome again = optimize(di + " --guess o.csv -o o2.csv");
  EXPECT_EQ(again.exit_code, 0) << again.out;
  EXPECT_EQ(again.out.find("note: the guess"), std::string::npos) << again.out;
}

// What can be decided before IPOPT is, with the expression's file:line:column: an objective, path
// constraint or actuator that is not finite on the first guess (IPOPT stopped on "Invalid number"
// and the note blamed the straight line), and a path constraint that the fixed initial or final
// values, or nothing at all, make fail (IPOPT ran 38 iterations to "infeasible").
TEST_F(OptimizeCli, WhatFailsOnTheFirstGuessOrAtTheFixedEndsIsNamedBeforeTheSolve) {
  const auto refused = [&](const std::string& file, const std::vector<std::pair<std::string, std::string>>& changes,
                           const std::string& message) {
    write_variant("double_integrator.toml", file, changes);
    const Outcome run = run_nhdyn("optimize " + file + " -o o.csv", dir_);
    EXPECT_EQ(run.exit_code, 2) << run.out;
    EXPECT_NE(run.out.find(message), std::string::npos) << run.out;
    EXPECT_EQ(run.out.find("status:"), std::string::npos) << run.out;
    EXPECT_EQ(run.out.find("IPOPT did not converge"), std::string::npos) << run.out;
    EXPECT_FALSE(fs::exists(dir_ / "o.csv"));
    EXPECT_FALSE(fs::exists(dir_ / "o.partial.csv"));
    return run.out;
  };
  const std::string sqrt = refused("sqrt.toml", {{"objective = \"F^2\"", "objective = \"F^2 + sqrt(x - 0.5)\""}},
                                   "sqrt.toml:13:13: the objective \"F^2 + sqrt(x - 0.5)\" is not finite (");
  EXPECT_NE(sqrt.find("at the first guess's point t = 0, x = 0, x' = 0, F = 0: give a first guess where it is defined"),
            std::string::npos)
      << sqrt;
  refused("inverse.toml", {{"final =", "path = [\"1/x <= 100\"]\nfinal ="}},
          "inverse.toml:18:9: the path constraint \"1/x <= 100\" is not finite (inf) at the first guess's point t = 0, "
          "x = 0, x' = 0, F = 0");
  // The straight line from 0 to 1 passes x = 0.5 at its middle point, t = 1.
  refused("pole.toml", {{"actuator = \"x\"", "actuator = [\"1/(x - 0.5)\"]"}},
          "pole.toml:12:38: the actuator [1/(x - 0.5)] of control 'F' (its entry on x) is not finite (inf) at the first "
          "guess's point t = 1, x = 0.5, x' = 0, F = 0");
  // The model's own terms: Q = -dV/dx of V = sqrt(x - 0.5) at x = 0, named by its entry.
  refused("terms.toml", {{"kinetic_energy = \"m/2 * x'^2\"", "kinetic_energy = \"m/2 * x'^2\"\npotential_energy = \"sqrt(x - 0.5)\""}},
          "the model's term Q_x (from its kinetic and potential energy, forces and constraints) is not finite (NaN) at "
          "the first guess's point t = 0, x = 0, x' = 0, F = 0");
  // A mass of 0 or below: x moved from 0 to 1 under F = 0, exit 0 (simulate refuses the inertia).
  for (const char* mass : {"0", "-1"}) {
    const Outcome run = run_nhdyn("optimize " + example("double_integrator.toml") + " --set m=" + mass + " -o o.csv", dir_);
    EXPECT_EQ(run.exit_code, 2) << run.out;
    EXPECT_NE(run.out.find("the inertia matrix A of model 'double_integrator' is not positive definite on the motions "
                           "its constraints allow at the first guess's point t = 0"),
              std::string::npos)
        << run.out;
    EXPECT_FALSE(fs::exists(dir_ / "o.csv"));
  }
  refused("start.toml", {{"final =", "path = [\"x >= 2\"]\nfinal ="}},
          "start.toml:18:9: the path constraint \"x >= 2\" cannot hold at t = 0: with the fixed initial values x = 0, "
          "its left side less its right side is -2, which must be >= 0");
  refused("end.toml", {{"final =", "path = [\"x + x' <= 0.5\"]\nfinal ="}},
          "end.toml:18:9: the path constraint \"x + x' <= 0.5\" cannot hold at t = 2: with the fixed final values x = "
          "1, x' = 0, its left side less its right side is 0.5, which must be <= 0; change the final values");
  refused("never.toml", {{"final =", "path = [\"1 >= 2\"]\nfinal ="}},
          "never.toml:18:9: the path constraint \"1 >= 2\" cannot hold at t = 0: it reads no coordinate, velocity or "
          "control");
  // A path constraint the free values can meet is left to IPOPT: x <= 1.2 along the way.
  write_variant("double_integrator.toml", "fine.toml", {{"final =", "path = [\"x <= 1.2\", \"2 >= 1\"]\nfinal ="}});
  const Outcome fine = optimize("fine.toml -o fine.csv");
  SKIP_WITHOUT_IPOPT(fine);
  EXPECT_EQ(fine.exit_code, 0) << fine.out;
}

// Messages about boundary values, bounds, control names and the guess file say where and what:
// file:line:column for a value outside its bounds (and the bounds' own place), no IPOPT infinity
// shown as if the user had given bounds, "control" for a control, a directory called one.
TEST_F(OptimizeCli, BoundsControlNamesAndTheGuessFileAreNamedWhereTheyAreWritten) {
  const auto refused = [&](const std::string& args, const std::string& message) {
    const Outcome run = run_nhdyn("optimize " + args + " -o o.csv", dir_);
    EXPECT_EQ(run.exit_code, 2) << args << "\n" << run.out;
    EXPECT_NE(run.out.find(message), std::string::npos) << args << "\n" << run.out;
    EXPECT_FALSE(fs::exists(dir_ / "o.csv"));
  };
  write_variant("double_integrator.toml", "final.toml", {{"final =", "bounds = { x = [0, 0.5] }\nfinal ="}});
  refused("final.toml", "final.toml:19:28: the final value x = 1 lies outside its bounds [0, 0.5] (given at "
                        "final.toml:18:16): change one of them");
  write_variant("double_integrator.toml", "initial.toml",
                {{"final =", "bounds = { \"x'\" = [1, 2] }\nfinal ="}});
  refused("initial.toml", "initial.toml:17:52: the initial value x' = 0 lies outside its bounds [1, 2] (given at "
                          "initial.toml:18:19)");
  // No bounds given: IPOPT's infinity is not shown as bounds.
  const std::string huge = example("double_integrator.toml") + " --set d=1e150";
  const Outcome run = run_nhdyn("optimize " + huge + " -o o.csv", dir_);
  EXPECT_EQ(run.exit_code, 2) << run.out;
  EXPECT_NE(run.out.find("double_integrator.toml:18:28: the final value x = 1e+150 is too large for the optimizer"),
            std::string::npos)
      << run.out;
  EXPECT_EQ(run.out.find("1e+20"), std::string::npos) << run.out;
  // A control's name refused as a control's, at its name.
  for (const auto& [name, why] : {std::pair<std::string, std::string>{"t", "'t' is the time"},
                                  {"F G", "not a valid name"},
                                  {"sin", "'sin' is the name of a function"}}) {
    write_variant("double_integrator.toml", "name.toml", {{"name = \"F\"", "name = \"" + name + "\""}, {"F^2", "x^2"}});
    refused("name.toml", "name.toml:12:22: control '");
    refused("name.toml", why);
  }
  // A one-sided bound: what to write instead of inf.
  write_variant("double_integrator.toml", "inf.toml", {{"final =", "bounds = { F = [-inf, 10] }\nfinal ="}});
  refused("inf.toml", "inf.toml:18:17: the bounds of F are finite numbers: for a bound on one side only, give the "
                      "other a value far beyond the motion, e.g. F = [-1e6, 10]");
  // --html and --plot go into a folder that exists (or the one made for -o): optimize makes only
  // the folders of its tables.
  refused(example("double_integrator.toml") + " --html nodir/x.html", "the directory 'nodir' does not exist");
  EXPECT_FALSE(fs::exists(dir_ / "nodir"));
  // guess = a directory says so.
  write_variant("double_integrator.toml", "dir.toml", {{"final =", "guess = \".\"\nfinal ="}});
  refused("dir.toml", "dir.toml:18:9: the guess file . is a directory");
}

// IPOPT is a module loaded when a program is first solved (src/nhdyn/optimize/ipopt/solver_module.cpp):
// the dynamic loader's own account (LD_DEBUG=files lists every object it opens) shows that a
// simulation opens none of IPOPT's libraries and that `optimize` does.
TEST_F(OptimizeCli, IpoptIsLoadedByOptimizeAlone) {
  // The loader's account of the processes of one run (the shell's and nhdyn's), written to files
  // `prefix`.PID (LD_DEBUG_OUTPUT), read back together.
  const auto opened = [&](const std::string& prefix) {
    std::string text;
    for (const auto& entry : fs::directory_iterator(dir_)) {
      if (entry.path().filename().string().rfind(prefix + ".", 0) != 0) continue;
      std::ifstream in(entry.path());
      std::stringstream s;
      s << in.rdbuf();
      text += s.str();
    }
    return text;
  };
  ::setenv("LD_DEBUG", "files", 1);
  ::setenv("LD_DEBUG_OUTPUT", (dir_ / "simulate").c_str(), 1);
  const Outcome simulate = run_nhdyn("simulate " + example("sled.toml") + " --t-end 1 -o sled.csv", dir_);
  ::setenv("LD_DEBUG_OUTPUT", (dir_ / "optimize").c_str(), 1);
  const Outcome solve = optimize(example("double_integrator.toml") + " -o di.csv");
  ::unsetenv("LD_DEBUG");
  ::unsetenv("LD_DEBUG_OUTPUT");
  SKIP_WITHOUT_IPOPT(solve);
  ASSERT_EQ(simulate.exit_code, 0) << simulate.out;
  ASSERT_EQ(solve.exit_code, 0) << solve.out;
  const std::string by_simulate = opened("simulate"), by_optimize = opened("optimize");
  // The loader lists what it opens (the C library at least): the check below can see a library.
  ASSERT_NE(by_simulate.find("file=libc.so"), std::string::npos) << by_simulate;
  EXPECT_EQ(by_simulate.find("ipopt"), std::string::npos) << by_simulate;
  EXPECT_EQ(by_simulate.find("libdmumps"), std::string::npos) << by_simulate;
  EXPECT_NE(by_optimize.find("libnhdyn_ipopt.so"), std::string::npos) << by_optimize;
  EXPECT_NE(by_optimize.find("file=libipopt.so"), std::string::npos) << by_optimize;
}

// NHDYN_IPOPT_MODULE names the module to load: a path that does not exist, a file that is not a
// shared object and a shared object that is not nhdyn's module are each refused by name, exit 2.
TEST_F(OptimizeCli, ASolverModuleThatCannotBeUsedIsNamed) {
  Dl_info libm{};
  ASSERT_NE(::dladdr(reinterpret_cast<void*>(static_cast<double (*)(double)>(&::cos)), &libm), 0);
  write("not_elf.so", "not a shared object\n");
  const std::string missing = (dir_ / "missing.so").string(), not_elf = (dir_ / "not_elf.so").string();
  const auto run_with = [&](const std::string& module) {
    ::setenv("NHDYN_IPOPT_MODULE", module.c_str(), 1);
    const Outcome run = optimize(example("double_integrator.toml") + " -o di.csv");
    ::unsetenv("NHDYN_IPOPT_MODULE");
    return run;
  };
  const Outcome none = run_with(missing);
  SKIP_WITHOUT_IPOPT(none);
  EXPECT_EQ(none.exit_code, 2) << none.out;
  EXPECT_NE(none.out.find("NHDYN_IPOPT_MODULE names " + missing + ", which does not exist"), std::string::npos)
      << none.out;
  const Outcome garbage = run_with(not_elf);
  EXPECT_EQ(garbage.exit_code, 2) << garbage.out;
  EXPECT_NE(garbage.out.find("nhdyn's IPOPT module " + not_elf + " could not be loaded: "), std::string::npos)
      << garbage.out;
  EXPECT_NE(garbage.out.find("NHDYN_IPOPT_MODULE names it"), std::string::npos) << garbage.out;
  const Outcome foreign = run_with(libm.dli_fname);
  EXPECT_EQ(foreign.exit_code, 2) << foreign.out;
  EXPECT_NE(foreign.out.find(std::string(libm.dli_fname) + " is not the IPOPT module of this nhdyn"), std::string::npos)
      << foreign.out;
  EXPECT_FALSE(fs::exists(dir_ / "di.csv"));
}

}  // namespace
