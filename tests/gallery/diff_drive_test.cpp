// Exam: the differential-drive robot of examples/diff_drive.toml (x, y, theta, phi_r, phi_l; three
// rolling constraints; motor torques and bearing friction as [forces]) against the closed forms
// derived in docs/gallery/diff_drive.md. With M_v = m + 2 Jw/rw^2 and M_w = J + 2 Jw d^2/rw^2, the
// speed v and turning rate w = theta' obey
//
//     M_v v' = (tau_r + tau_l)/rw - 2 c v / rw^2,     M_w w' = d (tau_r - tau_l)/rw - 2 c d^2 w / rw^2,
//
// so v = v_inf + (v0 - v_inf) e^{-k_v t}, w = w_inf + (w0 - w_inf) e^{-k_w t}, and theta, phi_r,
// phi_l are their integrals; equal torques drive straight, opposite ones turn in place. The power
// balance T(t) - T(0) = integral of (Q_r phi_r' + Q_l phi_l') dt holds on every motion.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <vector>

#include "gallery/gallery.hpp"

namespace nhdyn::gallery {
namespace {

struct Robot {
  double m, J, Jw, rw, d, c, tau_r, tau_l;
  double Mv() const { return m + 2 * Jw / (rw * rw); }
  double Mw() const { return J + 2 * Jw * d * d / (rw * rw); }
  double v_inf() const { return rw * (tau_r + tau_l) / (2 * c); }
  double w_inf() const { return rw * (tau_r - tau_l) / (2 * c * d); }
  double kv() const { return 2 * c / (rw * rw * Mv()); }
  double kw() const { return 2 * c * d * d / (rw * rw * Mw()); }
  // The kinetic energy of the test's own formula, and the power of the wheel torques.
  double T(const Vector& v) const {
    return 0.5 * m * (v(0) * v(0) + v(1) * v(1)) + 0.5 * J * v(2) * v(2) + 0.5 * Jw * (v(3) * v(3) + v(4) * v(4));
  }
  double power(const Vector& v) const { return (tau_r - c * v(3)) * v(3) + (tau_l - c * v(4)) * v(4); }
  double dpower(const Vector& v, const Vector& a) const {
    return (tau_r - 2 * c * v(3)) * a(3) + (tau_l - 2 * c * v(4)) * a(4);
  }
};

Robot robot_of(const Model& model) {
  return {parameter(model, "m"),  parameter(model, "J"), parameter(model, "Jw"),    parameter(model, "rw"),
          parameter(model, "d"),  parameter(model, "c"), parameter(model, "tau_r"), parameter(model, "tau_l")};
}

struct RobotErrors {
  double v = 0.0;      // max |v - v_exact| / max(|v_inf|, |v0|, 1e-3 m/s)
  double w = 0.0;      // max |w - w_exact| / max(|w_inf|, |w0|, 1e-3 rad/s)
  double theta = 0.0;  // max |theta - theta_exact| [rad]
  double wheels = 0.0; // max |phi - phi_exact| [rad]
  double power = 0.0;  // max |T(t) - T(0) - integral of the power| / max T
  double drift = 0.0;  // max |(-sin, cos) . (x', y')| and |x - x_exact|, |y - y_exact| where known
};

// The closed forms from the model's initial state (v0, w0 read from it); x, y only in the two
// special cases (straight: theta0 = 0 and w = 0 throughout; in place: v = 0 throughout).
RobotErrors measure_robot(const Model& model, double t_end) {
  const Robot p = robot_of(model);
  const double th0 = model.q0(2), v0 = std::cos(th0) * model.v0(0) + std::sin(th0) * model.v0(1), w0 = model.v0(2);
  const double vi = p.v_inf(), wi = p.w_inf(), kv = p.kv(), kw = p.kw();
  const double v_scale = std::max({std::abs(vi), std::abs(v0), 1e-3});
  const double w_scale = std::max({std::abs(wi), std::abs(w0), 1e-3});
  const bool straight = th0 == 0.0 && w0 == 0.0 && wi == 0.0, in_place = v0 == 0.0 && vi == 0.0;
  RobotErrors err;
  double work = 0.0, T_max = 0.0;
  const std::vector<Row> rows = run_rows(model, tight_options(t_end, 0.01));
  for (std::size_t i = 0; i < rows.size(); ++i) {
    const Row& r = rows[i];
    const double ev = std::exp(-kv * r.t), ew = std::exp(-kw * r.t);
    const double v_exact = vi + (v0 - vi) * ev, w_exact = wi + (w0 - wi) * ew;
    const double s_exact = vi * r.t + (v0 - vi) * (1 - ev) / kv;  // distance along the path
    const double th_exact = th0 + wi * r.t + (w0 - wi) * (1 - ew) / kw;
    const double v = std::cos(r.q(2)) * r.v(0) + std::sin(r.q(2)) * r.v(1);
    err.v = std::max(err.v, std::abs(v - v_exact) / v_scale);
    err.w = std::max(err.w, std::abs(r.v(2) - w_exact) / w_scale);
    err.theta = std::max(err.theta, std::abs(r.q(2) - th_exact));
    const double turned = th_exact - th0;
    err.wheels = std::max({err.wheels, std::abs(r.q(3) - model.q0(3) - (s_exact + p.d * turned) / p.rw),
                           std::abs(r.q(4) - model.q0(4) - (s_exact - p.d * turned) / p.rw)});
    err.drift = std::max(err.drift, std::abs(-std::sin(r.q(2)) * r.v(0) + std::cos(r.q(2)) * r.v(1)));
    if (straight) err.drift = std::max({err.drift, std::abs(r.q(0) - model.q0(0) - s_exact), std::abs(r.q(1) - model.q0(1))});
    if (in_place) err.drift = std::max({err.drift, std::abs(r.q(0) - model.q0(0)), std::abs(r.q(1) - model.q0(1))});
    // Power balance: the trapezoidal rule corrected with the end derivatives of the power
    // (error h^5 P''''/720 per interval).
    if (i > 0) {
      const Row& s = rows[i - 1];
      const double h = r.t - s.t;
      work += h / 2 * (p.power(s.v) + p.power(r.v)) + h * h / 12 * (p.dpower(s.v, s.qdd) - p.dpower(r.v, r.qdd));
    }
    T_max = std::max(T_max, p.T(r.v));
    err.power = std::max(err.power, std::abs(p.T(r.v) - p.T(rows.front().v) - work));
  }
  err.power /= T_max;
  return err;
}

TEST(DiffDrive, UnequalTorquesMatchTheClosedFormSpeedAndTurningRate) {
  const RobotErrors err = measure_robot(load_example("diff_drive.toml"), 20.0);
  EXPECT_LT(err.v, 1e-9);
  EXPECT_LT(err.w, 1e-9);
  EXPECT_LT(err.theta, 1e-9);
  EXPECT_LT(err.wheels, 1e-8);
  EXPECT_LT(err.power, 5e-9);
  EXPECT_LT(err.drift, 1e-9);
}

TEST(DiffDrive, EqualTorquesDriveStraight) {
  const RobotErrors err = measure_robot(load_example("diff_drive.toml", {{"tau_r", 0.02}, {"tau_l", 0.02}}), 10.0);
  EXPECT_LT(err.v, 1e-9);
  EXPECT_LT(err.w, 1e-9);
  EXPECT_LT(err.drift, 1e-9);  // x = the closed-form distance, y = 0
  EXPECT_LT(err.power, 5e-9);
}

TEST(DiffDrive, OppositeTorquesTurnInPlace) {
  const RobotErrors err = measure_robot(load_example("diff_drive.toml", {{"tau_r", 0.02}, {"tau_l", -0.02}}), 10.0);
  EXPECT_LT(err.w, 1e-9);
  EXPECT_LT(err.theta, 1e-9);
  EXPECT_LT(err.drift, 1e-9);  // x = y = 0
  EXPECT_LT(err.power, 5e-9);
}

// A moving start (not at rest, heading askew) decays to the same limit: the closed forms hold from
// any initial v0, w0 on the constraints.
TEST(DiffDrive, ClosedFormsHoldFromAMovingStart) {
  Model model = load_example("diff_drive.toml");
  const Robot p = robot_of(model);
  const double th0 = 0.7, v0 = -0.3, w0 = 2.0;
  model.q0 << 0.5, -0.2, th0, 0.0, 0.0;
  model.v0 << v0 * std::cos(th0), v0 * std::sin(th0), w0, (v0 + p.d * w0) / p.rw, (v0 - p.d * w0) / p.rw;
  const RobotErrors err = measure_robot(model, 10.0);
  EXPECT_LT(err.v, 1e-9);
  EXPECT_LT(err.w, 1e-9);
  EXPECT_LT(err.theta, 1e-9);
  EXPECT_LT(err.power, 5e-9);
}

// Negative controls: the wheels' inertia doubled in T, or the left wheel's rolling written with the
// wrong sense of turning, fail the exam by far.
TEST(DiffDrive, TheExamRejectsWrongModels) {
  const RobotErrors heavy = measure_robot(load_altered_example("diff_drive.toml", "Jw/2 * (", "Jw * ("), 20.0);
  EXPECT_GT(heavy.v, 1e-3);
  EXPECT_GT(heavy.power, 1e-3);
  const RobotErrors crossed = measure_robot(
      load_altered_example("diff_drive.toml", "sin(theta)*y' - d*theta' - rw*phi_l'", "sin(theta)*y' + d*theta' - rw*phi_l'"),
      20.0);
  EXPECT_GT(crossed.w, 1e-2);
}

}  // namespace
}  // namespace nhdyn::gallery
