// Convex bodies rolling on a plane, a turntable and in a bowl ([[contacts]]): the examples against
// the closed forms of docs/derivations/rolling-bodies.md section 6, the contact point against the
// shape, and the contact forces against the momentum balance.
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <complex>
#include <string>
#include <vector>

#include "nhdyn/analysis/linearization.hpp"
#include "nhdyn/analysis/simulation.hpp"
#include "nhdyn/frontend/load_model.hpp"
#include "nhdyn/io/results.hpp"
#include "support/text.hpp"

namespace nhdyn {
namespace {

using nhdyn::test::example;

double parameter(const Model& model, const std::string& name) {
  for (const Parameter& p : model.parameters)
    if (p.name == name) return p.value;
  ADD_FAILURE() << "no parameter " << name;
  return 0.0;
}

int column(const ResultColumns& columns, const std::string& name) {
  for (std::size_t i = 0; i < columns.all.size(); ++i)
    if (columns.all[i] == name) return static_cast<int>(i);
  ADD_FAILURE() << "no column " << name;
  return 0;
}

// R = Rz(psi) Rx(theta) Ry(phi), the body-fixed z-x-y sequence of the examples' frames.
using Matrix3 = std::array<std::array<double, 3>, 3>;
Matrix3 rotation_zxy(double psi, double theta, double phi) {
  const double cps = std::cos(psi), sps = std::sin(psi), cth = std::cos(theta), sth = std::sin(theta);
  const double cph = std::cos(phi), sph = std::sin(phi);
  const Matrix3 Rz = {{{cps, -sps, 0}, {sps, cps, 0}, {0, 0, 1}}};
  const Matrix3 Rx = {{{1, 0, 0}, {0, cth, -sth}, {0, sth, cth}}};
  const Matrix3 Ry = {{{cph, 0, sph}, {0, 1, 0}, {-sph, 0, cph}}};
  Matrix3 T{}, R{};
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j)
      for (int k = 0; k < 3; ++k) T[i][j] += Rz[i][k] * Rx[k][j];
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j)
      for (int k = 0; k < 3; ++k) R[i][j] += T[i][k] * Ry[k][j];
  return R;
}

// The eigenvalues' imaginary parts above `floor`, ascending (their conjugates below -floor are
// left out); every other eigenvalue must be zero, and every real part (an undamped rolling body
// at rest).
std::vector<double> frequencies(const Linearization& l, double floor) {
  std::vector<double> out;
  for (const std::complex<double>& e : l.eigenvalues) {
    EXPECT_LT(std::abs(e.real()), 1e-9) << e;
    if (e.imag() > floor) {
      out.push_back(e.imag());
    } else if (e.imag() >= -floor) {
      EXPECT_LT(std::abs(e.imag()), 1e-6) << e;
    }
  }
  std::sort(out.begin(), out.end());
  return out;
}

// Rolling-bodies.md (6.1): omega^2 = g / ((1 + k)(Rb - r)), k = 2/5, a double pair. Sliding would
// give g / (Rb - r) (18 % higher), rolling on the outside g / ((1 + k)(Rb + r)).
TEST(RollingBodies, BallInBowlOscillatesAtTheClosedFormFrequency) {
  const Model model = load_model(example("ball_in_bowl.toml"), {{"x0", 0.0}});
  const double g = parameter(model, "g"), r = parameter(model, "r"), Rb = parameter(model, "Rb");
  const double omega = std::sqrt(g / (1.4 * (Rb - r)));
  EXPECT_NEAR(omega, 3.946065, 1e-6);  // the derivation's figure
  const std::vector<double> w = frequencies(calc_linearization(model), 1e-3);
  ASSERT_EQ(w.size(), 2u);
  for (double x : w) EXPECT_NEAR(x, omega, 1e-12 * omega);
}

// The released ball (x0 = 1 cm, an angle of 0.022 rad) crosses the bottom after the quarter period
// of the exact planar motion; its contact force is m (a_C - g) at every row.
TEST(RollingBodies, BallInBowlSimulatedQuarterPeriod) {
  const Model model = load_model(example("ball_in_bowl.toml"));
  const double g = parameter(model, "g"), r = parameter(model, "r"), Rb = parameter(model, "Rb");
  const double omega = std::sqrt(g / (1.4 * (Rb - r)));
  const ResultColumns columns = make_result_columns(model);
  const int x = column(columns, "x"), Fx = column(columns, "ball_Fx"), Fz = column(columns, "ball_Fz");
  const int ax = column(columns, "x''"), az = column(columns, "z''"), check = column(columns, "contact_residual");
  const double m = parameter(model, "m");
  SimulationOptions options;
  options.t_end = 0.5;
  options.output_step = 1e-3;
  options.integrator.rtol = 1e-12;
  options.integrator.atol = 1e-14;
  std::vector<double> row, previous;
  double crossing = -1.0;
  simulate(model, options, [&](const Data& data) {
    fill_result_row(model, data, row);
    const auto at = [&](int i) { return row[static_cast<std::size_t>(i)]; };
    // The ball alone: F = m (a_C - g), row by row.
    EXPECT_NEAR(at(Fx), m * at(ax), 1e-12 * m * g);
    EXPECT_NEAR(at(Fz), m * (at(az) + g), 1e-12 * m * g);
    EXPECT_LT(at(check), 1e-13);
    if (!previous.empty() && previous[static_cast<std::size_t>(x)] > 0 && at(x) <= 0) {
      const double t0 = previous[0], x0 = previous[static_cast<std::size_t>(x)];
      crossing = t0 + (data.t - t0) * x0 / (x0 - at(x));
    }
    previous = row;
  });
  // Planar rolling makes T = 1/2 m (1 + k) l^2 theta'^2 exactly: a pendulum of g / (1 + k), whose
  // quarter period from theta0 is pi / (2 omega AGM(1, cos(theta0 / 2))).
  const double theta0 = std::asin(0.01 / (Rb - r));
  double p = 1.0, s = std::cos(theta0 / 2);
  for (int i = 0; i < 8; ++i) {
    const double mean = (p + s) / 2;
    s = std::sqrt(p * s);
    p = mean;
  }
  ASSERT_GT(crossing, 0.0);
  EXPECT_NEAR(crossing, M_PI / (2 * omega * p), 1e-8);
  EXPECT_GT(crossing - M_PI / (2 * omega), 1e-6);  // the amplitude's correction is seen
}

// Rolling-bodies.md (6.2): the centre circles at w = k Omega / (1 + k) = 2 Omega / 7 about
// C0 = C(0) + n x v_C(0) / w, for every row; N = m g; F = m a_C horizontally.
TEST(RollingBodies, BallOnTurntableCirclesAtTwoSeventhsOfTheRate) {
  const Model model = load_model(example("ball_on_turntable.toml"));
  const double Omega = parameter(model, "Omega"), x0 = parameter(model, "x0"), u0 = parameter(model, "u0");
  const double m = parameter(model, "m"), g = parameter(model, "g");
  const double w = 2.0 * Omega / 7.0, radius = u0 / w;
  const ResultColumns columns = make_result_columns(model);
  const int x = column(columns, "x"), y = column(columns, "y"), N = column(columns, "ball_N");
  const int Fx = column(columns, "ball_Fx"), Fy = column(columns, "ball_Fy");
  const int X = column(columns, "ball_X"), Z = column(columns, "ball_Z");
  SimulationOptions options;
  options.t_end = 10.0;
  options.output_step = 0.05;
  options.integrator.rtol = 1e-11;
  options.integrator.atol = 1e-13;
  std::vector<double> row;
  int rows = 0;
  simulate(model, options, [&](const Data& data) {
    fill_result_row(model, data, row);
    const auto at = [&](int i) { return row[static_cast<std::size_t>(i)]; };
    const double t = data.t;
    EXPECT_NEAR(at(x), x0 - radius + radius * std::cos(w * t), 1e-9);
    EXPECT_NEAR(at(y), radius * std::sin(w * t), 1e-9);
    EXPECT_NEAR(at(N), m * g, 1e-12 * m * g);
    // a_C = -w^2 (C - C0)
    EXPECT_NEAR(at(Fx), -m * w * w * radius * std::cos(w * t), 1e-9 * m * g);
    EXPECT_NEAR(at(Fy), -m * w * w * radius * std::sin(w * t), 1e-9 * m * g);
    EXPECT_NEAR(at(X), at(x), 1e-15);
    EXPECT_NEAR(at(Z), 0.0, 1e-15);
    ++rows;
  });
  EXPECT_EQ(rows, 201);
}

// Rolling-bodies.md (6.4): the two rocking frequencies of a uniform ellipsoid on its short axis.
TEST(RollingBodies, EllipsoidRocksAtTheClosedFormFrequencies) {
  const Model model = load_model(example("ellipsoid_rocking.toml"), {{"tilt", 0.0}});
  const double g = parameter(model, "g"), a = parameter(model, "a"), b = parameter(model, "b"),
               c = parameter(model, "c");
  const double wy = std::sqrt(5 * g * (a * a - c * c) / (c * (a * a + 6 * c * c)));
  const double wx = std::sqrt(5 * g * (b * b - c * c) / (c * (b * b + 6 * c * c)));
  EXPECT_NEAR(wy, 12.130540, 1e-6);
  EXPECT_NEAR(wx, 8.620799, 1e-6);
  const std::vector<double> w = frequencies(calc_linearization(model), 1e-3);
  ASSERT_EQ(w.size(), 2u);
  EXPECT_NEAR(w[0], wx, 1e-12 * wx);
  EXPECT_NEAR(w[1], wy, 1e-12 * wy);
}

// Along a rocking motion the contact point is on the plane and on the ellipsoid, where the
// ellipsoid's normal is -n; energy is conserved.
TEST(RollingBodies, EllipsoidContactPointIsOnBothSurfaces) {
  const Model model = load_model(example("ellipsoid_rocking.toml"), {{"tilt", 0.3}});
  const double a = parameter(model, "a"), b = parameter(model, "b"), c = parameter(model, "c");
  const ResultColumns columns = make_result_columns(model);
  const int X = column(columns, "foot_X"), Z = column(columns, "foot_Z"), q = column(columns, "x");
  SimulationOptions options;
  options.t_end = 1.0;
  options.output_step = 0.01;
  options.integrator.rtol = 1e-11;
  options.integrator.atol = 1e-13;
  std::vector<double> row;
  // Start with a turn about every axis, so that the motion is not planar.
  Model turned = model;
  turned.v0(3) = 2.0;  // psi'
  turned.v0(4) = 1.0;  // theta'
  // The rolling condition then needs x', y', z': let the initial fix find them.
  options.fix_initial = true;
  const SimulationSummary summary = simulate(turned, options, [&](const Data& data) {
    fill_result_row(turned, data, row);
    const auto at = [&](int i) { return row[static_cast<std::size_t>(i)]; };
    // The contact point in body axes is R^T (P - C).
    const Matrix3 R = rotation_zxy(at(q + 3), at(q + 4), at(q + 5));
    const double d[3] = {at(X) - at(q), at(X + 1) - at(q + 1), at(Z) - at(q + 2)};
    double y[3] = {};
    for (int i = 0; i < 3; ++i)
      for (int k = 0; k < 3; ++k) y[i] += R[k][i] * d[k];
    EXPECT_NEAR(y[0] * y[0] / (a * a) + y[1] * y[1] / (b * b) + y[2] * y[2] / (c * c), 1.0, 1e-10);
    EXPECT_NEAR(at(Z), 0.0, 1e-10);
    // The ellipsoid's normal at y, M y in body axes, turned to world, is along -z.
    double nw[3] = {};
    const double My[3] = {y[0] / (a * a), y[1] / (b * b), y[2] / (c * c)};
    for (int i = 0; i < 3; ++i)
      for (int k = 0; k < 3; ++k) nw[i] += R[i][k] * My[k];
    const double length = std::sqrt(nw[0] * nw[0] + nw[1] * nw[1] + nw[2] * nw[2]);
    EXPECT_NEAR(nw[2] / length, -1.0, 1e-12);
  });
  EXPECT_LT(summary.energy.drift, 1e-10);
}

// Rolling-bodies.md (6.5): the solid hemisphere, rubber rolling: omega^2 = 15 g / (26 r), twice;
// rubber rolling removes the spin about the vertical (no zero eigenvalue for it).
TEST(RollingBodies, HemisphereRocksAtTheClosedFormFrequency) {
  const Model model = load_model(example("hemisphere_rocking.toml"), {{"tilt", 0.0}});
  const double g = parameter(model, "g"), r = parameter(model, "r");
  const double omega = std::sqrt(15 * g / (26 * r));
  EXPECT_NEAR(omega, 7.523042, 1e-6);
  const Linearization l = calc_linearization(model);
  const std::vector<double> w = frequencies(l, 1e-3);
  ASSERT_EQ(w.size(), 2u);
  for (double x : w) EXPECT_NEAR(x, omega, 1e-12 * omega);
  bool spin = false;
  for (const Constraint& c : model.constraints) spin = spin || c.name == "hemisphere_spin";
  EXPECT_TRUE(spin);
  const ResultColumns columns = make_result_columns(model);
  EXPECT_NE(std::find(columns.all.begin(), columns.all.end(), "hemisphere_Mspin"), columns.all.end());
}

// Rolling-bodies.md section 6.6: the Chaplygin ball keeps its energy and its angular momentum about
// the contact point, K = I_G omega + m r^2 (omega - (omega.n) n), every component in the world.
TEST(RollingBodies, ChaplyginBallKeepsItsIntegrals) {
  const Model model = load_model(example("chaplygin_ball.toml"));
  const double m = parameter(model, "m"), r = parameter(model, "r");
  const double I[3] = {0.3 * m * r * r, 0.4 * m * r * r, 0.5 * m * r * r};
  const ResultColumns columns = make_result_columns(model);
  const int q = column(columns, "psi"), v = column(columns, "psi'");
  SimulationOptions options;
  options.t_end = 2.0;
  options.output_step = 0.01;
  options.integrator.rtol = 1e-11;
  options.integrator.atol = 1e-13;
  std::vector<double> row;
  std::array<double, 3> K0{};
  bool first = true;
  double largest_angle = 0.0, drift = 0.0;
  const SimulationSummary summary = simulate(model, options, [&](const Data& data) {
    fill_result_row(model, data, row);
    const auto at = [&](int i) { return row[static_cast<std::size_t>(i)]; };
    const Matrix3 R = rotation_zxy(at(q), at(q + 1), at(q + 2));
    const Matrix3 Rz = rotation_zxy(at(q), 0, 0), Rzx = rotation_zxy(at(q), at(q + 1), 0);
    // omega = psi' e_z + theta' Rz e_x + phi' Rz Rx e_y.
    std::array<double, 3> w{};
    for (int i = 0; i < 3; ++i) w[i] = (i == 2 ? at(v) : 0.0) + at(v + 1) * Rz[i][0] + at(v + 2) * Rzx[i][1];
    // I_G omega = R I R^T omega.
    std::array<double, 3> body{}, K{};
    for (int i = 0; i < 3; ++i)
      for (int k = 0; k < 3; ++k) body[i] += R[k][i] * w[k];
    for (int i = 0; i < 3; ++i) {
      for (int k = 0; k < 3; ++k) K[i] += R[i][k] * I[k] * body[k];
      K[i] += m * r * r * (i == 2 ? 0.0 : w[i]);
    }
    if (first) K0 = K;
    first = false;
    for (int i = 0; i < 3; ++i) drift = std::max(drift, std::abs(K[i] - K0[i]));
    largest_angle = std::max({largest_angle, std::abs(at(q + 1)), std::abs(at(q + 2))});
  });
  EXPECT_GT(largest_angle, 0.3);  // the ball has turned: the test is not about a ball at rest
  EXPECT_LT(drift, 1e-10 * std::sqrt(K0[0] * K0[0] + K0[1] * K0[1] + K0[2] * K0[2]));
  EXPECT_LT(summary.energy.drift, 1e-10);
}

// Kane and Levinson's rattleback, spun at -5 rad/s: it rocks, stops turning and turns the other way;
// the contact does no work, so the energy stays (the constraints are held by projection, the
// integration's drift of the position level being what would otherwise do work). The reference
// is the independent Newton-Euler model of docs/derivations/checks/rolling_rattleback.py from the
// example's start (rolling_bodies_review.md note 4): psi' first changes sign at 2.351541 s, is
// +4.320337 rad/s at 5 s and stays within [-5.3153, +5.3969] over 10 s.
TEST(RollingBodies, RattlebackReversesItsSpinAndKeepsItsEnergy) {
  const Model model = load_model(example("rattleback.toml"));
  const ResultColumns columns = make_result_columns(model);
  const int spin = column(columns, "psi'"), spin_rate = column(columns, "psi''");
  SimulationOptions options;
  options.t_end = 10.0;
  options.output_step = 1e-3;
  options.integrator.rtol = 1e-10;
  options.integrator.atol = 1e-12;
  options.stabilization = Stabilization::projection;
  std::vector<double> row;
  double lowest = 0.0, highest = 0.0, reversal = -1.0, at_5 = 0.0;
  double t0 = 0.0, w0 = 0.0, dw0 = 0.0;
  const SimulationSummary summary = simulate(model, options, [&](const Data& data) {
    fill_result_row(model, data, row);
    const double w = row[static_cast<std::size_t>(spin)], dw = row[static_cast<std::size_t>(spin_rate)];
    lowest = std::min(lowest, w);
    highest = std::max(highest, w);
    // The crossing on the cubic Hermite interpolant of psi' and psi'' over the 1 ms step (the
    // rocking at ~110 rad/s makes a linear one err by ~1e-5 s), by bisection.
    if (reversal < 0 && w0 < 0 && w >= 0) {
      const double h = data.t - t0;
      const auto cubic = [&](double s) {
        const double s2 = s * s, s3 = s2 * s;
        return (2 * s3 - 3 * s2 + 1) * w0 + (s3 - 2 * s2 + s) * h * dw0 + (-2 * s3 + 3 * s2) * w + (s3 - s2) * h * dw;
      };
      double lo = 0.0, hi = 1.0;
      for (int i = 0; i < 60; ++i) (cubic((lo + hi) / 2) < 0 ? lo : hi) = (lo + hi) / 2;
      reversal = t0 + h * (lo + hi) / 2;
    }
    if (std::abs(data.t - 5.0) < 1e-9) at_5 = w;
    t0 = data.t;
    w0 = w;
    dw0 = dw;
  });
  EXPECT_NEAR(reversal, 2.351541, 2e-6);
  EXPECT_NEAR(at_5, 4.320337, 2e-6);
  // The review's range was read on a coarser grid: the 1 ms grid reaches at least as far.
  EXPECT_LT(lowest, -5.3153);
  EXPECT_GT(lowest, -5.33);
  EXPECT_GT(highest, 5.3969);
  EXPECT_LT(highest, 5.41);
  EXPECT_LT(summary.energy.drift, 1e-9 * summary.energy.initial);
}

// The rattleback's linearization about upright spin psi' = s against the closed-form quartic of
// rolling_bodies_review.md note 4 (derived from the exact contact: rho1 = a^2/c, rho2 = b^2/c,
// ell = c - h). Its roots at s = +5 are -2.120692 +- 109.392323 i and +0.202521 +- 34.143692 i
// (the slow pair grows: this sense is unstable, the reversal's seed); at s = -5 their negatives.
// Every other eigenvalue is zero (the symmetry and the family of upright spins).
TEST(RollingBodies, RattlebackEigenvaluesAboutUprightSpinSolveTheClosedFormQuartic) {
  for (const double s : {5.0, -5.0}) {
    const Model model = load_model(example("rattleback.toml"), {{"tilt", 0.0}, {"spin", s}});
    const double m = parameter(model, "m"), g = parameter(model, "g"), a = parameter(model, "a"),
                 b = parameter(model, "b"), c = parameter(model, "c"), h = parameter(model, "h");
    const double A = m * parameter(model, "A"), B = m * parameter(model, "B"), C = m * parameter(model, "C"),
                 D = m * parameter(model, "D");
    const double rho1 = a * a / c, rho2 = b * b / c, ell = c - h;
    const double A1 = A + m * ell * ell, B1 = B + m * ell * ell;
    const double P1 = m * g * (rho1 - ell), P2 = m * g * (rho2 - ell);
    const double Ap = A1 - C - m * ell * rho1, Bp = B1 - C - m * ell * rho2;
    const double Delta = A1 * B1 - D * D, Deltap = Ap * Bp - D * D;
    const std::array<double, 5> coefficient = {P1 * P2 - s * s * (P1 * Bp + P2 * Ap) + Deltap * s * s * s * s,
                                               -D * m * ell * (rho1 - rho2) * s * s * s,
                                               A1 * P1 + B1 * P2 + (Delta + Deltap) * s * s,
                                               -D * m * ell * (rho1 - rho2) * s, Delta};
    // The heading enters the rolling rows (world tangents) but, by symmetry, not the reduced
    // dynamics: it is cyclic with x and y.
    LinearizationOptions lin;
    lin.cyclic = {"psi"};
    const Linearization l = calc_linearization(model, lin);
    std::vector<std::complex<double>> nontrivial;
    for (const std::complex<double>& e : l.eigenvalues) {
      if (std::abs(e) > 1.0) nontrivial.push_back(e);
      else EXPECT_LT(std::abs(e), 1e-6) << e;
    }
    ASSERT_EQ(nontrivial.size(), 4u);
    for (const std::complex<double>& e : nontrivial) {
      std::complex<double> value = 0.0, power = 1.0;
      double scale = 0.0;
      for (const double k : coefficient) {
        value += k * power;
        scale += std::abs(k) * std::abs(power);
        power *= e;
      }
      EXPECT_LT(std::abs(value), 1e-10 * scale) << "eigenvalue " << e << " at spin " << s;
    }
    // The figures of the review, for the sense s: the fast pair and the slow pair.
    const double sign = s > 0 ? 1.0 : -1.0;
    bool fast = false, slow = false;
    for (const std::complex<double>& e : nontrivial) {
      fast = fast || (std::abs(e.real() - sign * -2.120692) < 1e-6 && std::abs(std::abs(e.imag()) - 109.392323) < 1e-6);
      slow = slow || (std::abs(e.real() - sign * 0.202521) < 1e-6 && std::abs(std::abs(e.imag()) - 34.143692) < 1e-6);
    }
    EXPECT_TRUE(fast && slow) << "spin " << s;
  }
}

}  // namespace
}  // namespace nhdyn
