// Exam of program motion on the Whipple bicycle (examples/bicycle_roll_program.toml): at 5 m/s the
// roll angle is made to follow phi(t) = A sin(omega t) by a steer torque. The torque and the steer
// angle are compared with those of the benchmark's linearized equations (Meijaard, Papadopoulos,
// Ruina and Schwab, Proc. R. Soc. A 463 (2007), eq. (A 1), with their published matrices)
//
//     M q'' + v C1 q' + (g K0 + v^2 K2) q = [T_phi; T_delta],   q = (phi, delta),
//
// with T_phi = 0 and phi prescribed: the first row is a linear ODE for delta driven by phi, the
// second gives T_delta (docs/derivations/program-motion.md, section 6, where the solution below is
// derived). The nonlinear motion differs from the linear one by the terms the linearization drops;
// by the bicycle's mirror symmetry (phi, delta, the torque and the lateral coordinates change sign
// with A) the torque is odd in A, so the difference is O(A^3) and, relative to the torque, O(A^2):
// halving A divides the relative difference by 4. The program itself holds at acceleration level
// to round-off and at velocity and position level to the integration error.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <complex>
#include <cstdio>
#include <vector>

#include "gallery/gallery.hpp"
#include "nhdyn/model/parameters.hpp"

namespace nhdyn::gallery {
namespace {

// Coordinates of the model: x y psi phi theta delta thetaR thetaF.
constexpr int kPhi = 3, kDelta = 5;

// The benchmark's linear equations (Meijaard et al. 2007, section 4, for the benchmark bicycle of
// their Table 1, which the example's parameters are) with phi = A sin(omega t) prescribed and the
// steer starting straight and still, delta(0) = delta'(0) = 0.
struct LinearRollProgram {
  double M[2][2] = {{80.81722, 2.31941332208709}, {2.31941332208709, 0.29784188199686}};
  double C1[2][2] = {{0.0, 33.86641391492494}, {-0.85035641456978, 1.68540397397560}};
  double K0[2][2] = {{-80.95, -2.59951685249872}, {-2.59951685249872, -0.80329488458618}};
  double K2[2][2] = {{0.0, 76.59734589573222}, {0.0, 2.65431523794604}};
  double g, v, A, omega;
  std::complex<double> H;  // delta's periodic part: A Im(H e^{i omega t})
  double s1, s2;           // the roots of the steer's homogeneous equation (real, negative)
  double c1, c2;           // the transient c1 e^{s1 t} + c2 e^{s2 t} that starts delta at rest

  double K(int i, int j) const { return g * K0[i][j] + v * v * K2[i][j]; }
  // The row-i, column-j entry of M s^2 + v C1 s + K at s = i omega.
  std::complex<double> Z(int i, int j) const {
    const std::complex<double> s(0.0, omega);
    return M[i][j] * s * s + v * C1[i][j] * s + K(i, j);
  }

  LinearRollProgram(double g_, double v_, double A_, double omega_) : g(g_), v(v_), A(A_), omega(omega_) {
    // Row 1 with phi = A Im(e^{i omega t}): Z_pp + Z_pd H = 0.
    H = -Z(0, 0) / Z(0, 1);
    // The homogeneous steer equation M_pd s^2 + v C1_pd s + K_pd = 0 (the zero dynamics of the
    // program): two real negative roots at 5 m/s (-13.7 and -59.3 1/s).
    const double a = M[0][1], b = v * C1[0][1], c = K(0, 1);
    const double disc = b * b - 4 * a * c;
    EXPECT_GT(disc, 0.0);
    s1 = (-b + std::sqrt(disc)) / (2 * a);
    s2 = (-b - std::sqrt(disc)) / (2 * a);
    // delta(0) = 0, delta'(0) = 0: c1 + c2 = -A Im(H), s1 c1 + s2 c2 = -A omega Re(H).
    const double d0 = A * H.imag(), dd0 = A * omega * H.real();
    c2 = (dd0 - s1 * d0) / (s1 - s2);
    c1 = -d0 - c2;
  }
  std::complex<double> e(double t) const { return std::exp(std::complex<double>(0.0, omega * t)); }
  double phi(double t) const { return A * std::sin(omega * t); }
  double phid(double t) const { return A * omega * std::cos(omega * t); }
  double phidd(double t) const { return -A * omega * omega * std::sin(omega * t); }
  double delta(double t) const { return A * (H * e(t)).imag() + c1 * std::exp(s1 * t) + c2 * std::exp(s2 * t); }
  double deltad(double t) const {
    return A * omega * (H * e(t)).real() + c1 * s1 * std::exp(s1 * t) + c2 * s2 * std::exp(s2 * t);
  }
  double deltadd(double t) const {
    return -A * omega * omega * (H * e(t)).imag() + c1 * s1 * s1 * std::exp(s1 * t) + c2 * s2 * s2 * std::exp(s2 * t);
  }
  // Row i of M q'' + v C1 q' + K q.
  double row(int i, double t) const {
    return M[i][0] * phidd(t) + M[i][1] * deltadd(t) + v * (C1[i][0] * phid(t) + C1[i][1] * deltad(t)) +
           K(i, 0) * phi(t) + K(i, 1) * delta(t);
  }
  double torque(double t) const { return row(1, t); }
};

struct RollRun {
  double torque_scale = 0.0, steer_scale = 0.0;  // max |T_delta|, max |delta| of the linear solution
  double torque_difference = 0.0, steer_difference = 0.0;  // max |nonlinear - linear|
  double speed_change = 0.0;                      // max |x' - v| (the forward speed is free)
  SimulationSummary summary;
};

RollRun run_roll_program(const Model& model, double t_end) {
  const double A = parameter(model, "A");
  const LinearRollProgram linear(parameter(model, "g"), parameter(model, "v"), A, parameter(model, "omega"));
  // The closed form solves the benchmark's equations (a check of the algebra above).
  for (const double t : {0.0, 0.3, 2.0, 7.0}) EXPECT_NEAR(linear.row(0, t), 0.0, 1e-12);
  EXPECT_NEAR(linear.delta(0.0), 0.0, 1e-15);
  EXPECT_NEAR(linear.deltad(0.0), 0.0, 1e-14);

  RollRun run;
  run.summary = simulate(model, tight_options(t_end, 0.01), [&](const Data& d) {
    const double t = d.t;
    run.torque_scale = std::max(run.torque_scale, std::abs(linear.torque(t)));
    run.steer_scale = std::max(run.steer_scale, std::abs(linear.delta(t)));
    run.torque_difference = std::max(run.torque_difference, std::abs(d.motion.u(0) - linear.torque(t)));
    run.steer_difference = std::max(run.steer_difference, std::abs(d.q(kDelta) - linear.delta(t)));
    run.speed_change = std::max(run.speed_change, std::abs(d.v(0) - linear.v));
    // The roll angle is the program's.
    EXPECT_NEAR(d.q(kPhi), linear.phi(t), 1e-8) << "t = " << t;
  });
  EXPECT_EQ(run.summary.status, Status::ok) << run.summary.message;
  return run;
}

// Loaded and compiled once: the multibody derivation is the slow part.
const Model& bicycle() {
  static const Model model = load_example("bicycle_roll_program.toml");
  return model;
}

TEST(BicycleRollProgram, SteerTorqueIsTheBenchmarksToSecondOrderInTheAmplitude) {
  const Model& model = bicycle();
  ASSERT_EQ(model.m(), 1);
  ASSERT_DOUBLE_EQ(parameter(model, "A"), 0.05);
  ASSERT_DOUBLE_EQ(parameter(model, "v"), 5.0);
  const double t_end = 10.0;
  const RollRun large = run_roll_program(model, t_end);
  Model half = model;
  set_parameter(half, "A", 0.025);
  ASSERT_NEAR(half.v0(kPhi), 0.025, 1e-15);  // the initial roll rate follows A
  const RollRun small = run_roll_program(half, t_end);

  const double rel_large = large.torque_difference / large.torque_scale;
  const double rel_small = small.torque_difference / small.torque_scale;
  const double steer_large = large.steer_difference / large.steer_scale;
  const double steer_small = small.steer_difference / small.steer_scale;
  std::printf("A = 0.05: max |T| %.6g N m, torque rel. difference %.3e, steer rel. difference %.3e, speed change %.3e\n",
              large.torque_scale, rel_large, steer_large, large.speed_change);
  std::printf("A = 0.025: max |T| %.6g N m, torque rel. difference %.3e, steer rel. difference %.3e, speed change %.3e\n",
              small.torque_scale, rel_small, steer_small, small.speed_change);
  // The linear torque is the right one to first order: the relative difference is small (measured
  // 5.7e-3 for the torque, 2.2e-3 for the steer angle at A = 0.05) ...
  EXPECT_LT(rel_large, 1e-2);
  EXPECT_LT(steer_large, 1e-2);
  // ... and falls as A^2 (ratio 4 for half the amplitude; measured 3.99 for both): second order in
  // the amplitude. A wrong linear reference (a sign of C1, K2 or of the transient) leaves a
  // difference of first order, whose relative size does not fall with A.
  EXPECT_NEAR(rel_large / rel_small, 4.0, 0.4);
  EXPECT_NEAR(steer_large / steer_small, 4.0, 0.4);
  // The forward speed, free in the nonlinear model, changes at second order (0.116 m/s at A = 0.05).
  EXPECT_NEAR(large.speed_change / small.speed_change, 4.0, 0.4);
}

TEST(BicycleRollProgram, TheProgramHoldsAlongTheRun) {
  const RollRun run = run_roll_program(bicycle(), 10.0);
  ASSERT_EQ(run.summary.status, Status::ok);
  std::printf("program residuals: acc %.3e, vel %.3e, pos %.3e\n", run.summary.program.acceleration,
              run.summary.program.velocity, run.summary.program.position);
  // Measured 7e-18, 4e-16 and 1.4e-15: the roll's acceleration is the program's to round-off at
  // every evaluation, and phi'' = -A sin(t) depends on t alone, which dopri5 integrates almost
  // exactly at rtol 1e-10.
  EXPECT_LT(run.summary.program.acceleration, 1e-14);
  EXPECT_LT(run.summary.program.velocity, 1e-12);
  EXPECT_LT(run.summary.program.position, 1e-12);
}

}  // namespace
}  // namespace nhdyn::gallery
