// Exams of program motion (docs/derivations/program-motion.md) on the examples that carry
// [[programs]]: the sled turning at a prescribed rate (torque, speed and path against the closed
// forms of section 6), the two-link arm whose hand follows a circle (joint torques against the
// arm's inverse dynamics written independently, to 1e-9), and the cart whose pendulum angle is
// prescribed (the force in closed form where it exists, the refusal where S = 0). Consistency:
// the kernel's solve through the factorization of [D A; b] equals the direct solve of the stacked
// system (P2), whatever the choice of D, and the physical reactions satisfy D R = 0.
#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <string>
#include <vector>

#include "gallery/gallery.hpp"
#include "nhdyn/core/error.hpp"
#include "nhdyn/formulation/program_motion.hpp"
#include "nhdyn/model/terms.hpp"

namespace nhdyn::gallery {
namespace {

struct ProgramRow {
  double t = 0.0;
  Vector q, v;
  Vector u;
  Vector phi, f, e;  // program residuals
};

std::vector<ProgramRow> run_program_rows(const Model& model, const SimulationOptions& options,
                                         SimulationSummary* summary = nullptr) {
  std::vector<ProgramRow> rows;
  const SimulationSummary s = simulate(model, options, [&](const Data& d) {
    rows.push_back({d.t, d.q, d.v, d.motion.u, d.motion.phi, d.motion.f, d.motion.e});
  });
  EXPECT_EQ(s.status, Status::ok) << model.name << ": " << s.message;
  if (summary) *summary = s;
  return rows;
}

// Solves (P2) directly: the (n + m) x (n + m) stacked matrix with the D held in data.
void solve_stacked(const Model& model, const Data& data, Vector& qdd, Vector& u) {
  const int n = model.n(), s = model.s(), k = model.k(), m = model.m();
  const ProgramMotionData& w = data.motion;
  Matrix K = Matrix::Zero(n + m, n + m);
  Vector rhs(n + m);
  K.topLeftCorner(k, n) = data.D * data.A;
  K.topRightCorner(k, m) = -data.D * w.B;
  K.block(k, 0, s, n) = data.b;
  K.bottomLeftCorner(m, n) = w.b_p;
  rhs.head(k) = data.D * (data.Q + data.G);
  rhs.segment(k, s) = -data.b0;
  rhs.tail(m) = -w.b_p0;
  const Vector x = K.fullPivLu().solve(rhs);
  qdd = x.head(n);
  u = x.tail(m);
}

// --- the sled with its heading prescribed ----------------------------------------------------

struct Sled {
  double m, a, rho, alpha, g, omega, v0;
  explicit Sled(const Model& model)
      : m(parameter(model, "m")), a(parameter(model, "a")), rho(parameter(model, "rho")),
        alpha(parameter(model, "alpha")), g(parameter(model, "g")), omega(parameter(model, "omega")),
        v0(parameter(model, "v0")) {}
  double k() const { return g * std::sin(alpha); }
  double v(double t) const { return v0 + k() / omega * std::sin(omega * t) + a * omega * omega * t; }
  double u(double t) const { return m * a * omega * v(t) + m * g * a * std::sin(alpha) * std::sin(omega * t); }
  double x(double t) const {
    const double w = omega, s = std::sin(w * t), c = std::cos(w * t);
    return v0 / w * s + k() / (w * w) * s * s / 2 + a * (c - 1) + a * w * t * s;
  }
  double y(double t) const {
    const double w = omega, s = std::sin(w * t), c = std::cos(w * t);
    return v0 / w * (1 - c) + k() / (w * w) * (w * t - s * c) / 2 + a * (s - w * t * c);
  }
};

TEST(ProgramMotion, SledTurningAtAPrescribedRateFollowsTheClosedForm) {
  const Model model = load_example("sled_heading_program.toml");
  ASSERT_EQ(model.m(), 1);
  const Sled sled(model);
  SimulationSummary summary;
  const std::vector<ProgramRow> rows = run_program_rows(model, tight_options(10.0, 0.05), &summary);
  ASSERT_EQ(rows.size(), 201u);
  double worst_path = 0.0, worst_u = 0.0;
  for (const ProgramRow& r : rows) {
    const double scale = 1.0 + std::abs(sled.x(r.t)) + std::abs(sled.y(r.t));
    worst_path = std::max({worst_path, std::abs(r.q(0) - sled.x(r.t)) / scale, std::abs(r.q(1) - sled.y(r.t)) / scale,
                           std::abs(r.q(2) - sled.omega * r.t)});
    worst_u = std::max(worst_u, std::abs(r.u(0) - sled.u(r.t)) / (1.0 + std::abs(sled.u(r.t))));
    // The speed along the blade.
    const double speed = std::cos(r.q(2)) * r.v(0) + std::sin(r.q(2)) * r.v(1);
    EXPECT_NEAR(speed, sled.v(r.t), 1e-7 * (1.0 + std::abs(sled.v(r.t)))) << "t = " << r.t;
  }
  EXPECT_LT(worst_path, 1e-7);
  EXPECT_LT(worst_u, 1e-7);
  // Both terms of u(t) matter along the run: a wrong sign of either would miss by more than 1 N m.
  double speed_term = 0.0, slope_term = 0.0;
  for (const ProgramRow& r : rows) {
    speed_term = std::max(speed_term, std::abs(sled.m * sled.a * sled.omega * sled.v(r.t)));
    slope_term = std::max(slope_term, std::abs(sled.m * sled.g * sled.a * std::sin(sled.alpha) * std::sin(sled.omega * r.t)));
  }
  EXPECT_GT(speed_term, 1.0);
  EXPECT_GT(slope_term, 1.0);
  // The program holds at acceleration level to round-off, and at velocity and position level to
  // the integration error (phi'' = 0 exactly, so the heading is integrated without error growth).
  EXPECT_LT(summary.program.acceleration, 1e-12);
  EXPECT_LT(summary.program.velocity, 1e-9);
  EXPECT_LT(summary.program.position, 1e-8);
}

TEST(ProgramMotion, SledSolveEqualsTheStackedSystemForEveryComplement) {
  const Model model = load_example("sled_heading_program.toml");
  const Sled sled(model);
  // A state off the program (the solve does not need one on it), with the blade constraint met.
  const double t = 0.7, phi = 0.4, v = 1.3;
  const Vector q = (Vector(3) << 0.2, -0.1, phi).finished();
  const Vector qd = (Vector(3) << v * std::cos(phi), v * std::sin(phi), 0.6).finished();
  Vector u_first;
  for (Complement complement : {Complement::qr, Complement::partition}) {
    Data data = make_data(model);
    ASSERT_EQ(compute_terms(model, data, t, q.data(), qd.data()), Status::ok);
    ASSERT_EQ(compute_program_motion(model, data, complement, {}), Status::ok);
    Vector qdd, u;
    solve_stacked(model, data, qdd, u);
    EXPECT_LT((data.qdd - qdd).norm(), 1e-12 * (1.0 + qdd.norm())) << complement_name(complement);
    EXPECT_LT((data.motion.u - u).norm(), 1e-12 * (1.0 + u.norm())) << complement_name(complement);
    // S = b_p P B = 1 / (m rho^2) whatever D is.
    EXPECT_NEAR(data.motion.S(0, 0), 1.0 / (sled.m * sled.rho * sled.rho), 1e-14);
    // The physical reaction is ideal: it does no work along the blade (D R = 0), and the torque
    // is not part of it.
    EXPECT_LT((data.D * data.R).norm(), 1e-12);
    // The program holds at acceleration level: phi'' = 0.
    EXPECT_NEAR(data.qdd(2), 0.0, 1e-13);
    if (u_first.size() == 0) u_first = data.motion.u;
    else EXPECT_NEAR(data.motion.u(0), u_first(0), 1e-12);
  }
}

// --- the two-link arm whose hand follows a circle ---------------------------------------------

struct Arm {
  double m1, m2, l1, l2, g, cx, cy, r, omega;
  explicit Arm(const Model& model)
      : m1(parameter(model, "m1")), m2(parameter(model, "m2")), l1(parameter(model, "l1")),
        l2(parameter(model, "l2")), g(parameter(model, "g")), cx(parameter(model, "cx")), cy(parameter(model, "cy")),
        r(parameter(model, "r")), omega(parameter(model, "omega")) {}

  // The exact joint motion at t: inverse kinematics of the hand on the circle (elbow up), the rates
  // from the Jacobian, the accelerations from h'' = J q'' + J' q'.
  void state(double t, Eigen::Vector2d& q, Eigen::Vector2d& qd, Eigen::Vector2d& qdd) const {
    const double w = omega;
    const Eigen::Vector2d h(cx + r * std::cos(w * t), cy + r * std::sin(w * t));
    const Eigen::Vector2d hd(-r * w * std::sin(w * t), r * w * std::cos(w * t));
    const Eigen::Vector2d hdd = -w * w * (h - Eigen::Vector2d(cx, cy));
    q(1) = std::acos((h.squaredNorm() - l1 * l1 - l2 * l2) / (2 * l1 * l2));
    q(0) = std::atan2(h(1), h(0)) - std::atan2(l2 * std::sin(q(1)), l1 + l2 * std::cos(q(1)));
    const double s1 = std::sin(q(0)), c1 = std::cos(q(0)), s12 = std::sin(q(0) + q(1)), c12 = std::cos(q(0) + q(1));
    Eigen::Matrix2d J;
    J << -l1 * s1 - l2 * s12, -l2 * s12, l1 * c1 + l2 * c12, l2 * c12;
    qd = J.lu().solve(hd);
    const double w12 = qd(0) + qd(1);
    const Eigen::Vector2d Jdot_qd = -l1 * qd(0) * qd(0) * Eigen::Vector2d(c1, s1) - l2 * w12 * w12 * Eigen::Vector2d(c12, s12);
    qdd = J.lu().solve(hdd - Jdot_qd);
  }

  // The textbook inverse dynamics of the two-link arm with point masses (gravity along -y).
  Eigen::Vector2d torques(const Eigen::Vector2d& q, const Eigen::Vector2d& qd, const Eigen::Vector2d& qdd) const {
    const double c2 = std::cos(q(1)), s2 = std::sin(q(1));
    const double c1 = std::cos(q(0)), c12 = std::cos(q(0) + q(1));
    const double a11 = m1 * l1 * l1 + m2 * (l1 * l1 + l2 * l2 + 2 * l1 * l2 * c2);
    const double a12 = m2 * (l2 * l2 + l1 * l2 * c2);
    const double a22 = m2 * l2 * l2;
    const double h = m2 * l1 * l2 * s2;
    const double g1 = (m1 + m2) * g * l1 * c1 + m2 * g * l2 * c12;
    const double g2 = m2 * g * l2 * c12;
    return {a11 * qdd(0) + a12 * qdd(1) - h * (2 * qd(0) * qd(1) + qd(1) * qd(1)) + g1,
            a12 * qdd(0) + a22 * qdd(1) + h * qd(0) * qd(0) + g2};
  }
};

TEST(ProgramMotion, ArmJointTorquesAreTheInverseDynamicsOnTheCircle) {
  const Model model = load_example("arm_circle_program.toml");
  ASSERT_EQ(model.m(), 2);
  const Arm arm(model);
  Data data = make_data(model);
  for (double t : {0.0, 0.3, 1.1, 2.0, 2.9, 4.4}) {
    Eigen::Vector2d q, qd, qdd;
    arm.state(t, q, qd, qdd);
    ASSERT_EQ(compute_terms(model, data, t, q.data(), qd.data()), Status::ok);
    ASSERT_EQ(compute_program_motion(model, data, Complement::qr, {}), Status::ok);
    const Eigen::Vector2d tau = arm.torques(q, qd, qdd);
    EXPECT_LT((data.motion.u - tau).norm(), 1e-9 * (1.0 + tau.norm())) << "t = " << t << ": u = "
                                                                        << data.motion.u.transpose()
                                                                        << ", inverse dynamics " << tau.transpose();
    EXPECT_LT((data.qdd - qdd).norm(), 1e-9 * (1.0 + qdd.norm())) << "t = " << t;
    // With no physical constraints there is no reaction: every force is the actuators'.
    EXPECT_LT(data.R.norm(), 1e-10 * (1.0 + tau.norm()));
  }
}

TEST(ProgramMotion, ArmFollowsTheCircleAlongARun) {
  const Model model = load_example("arm_circle_program.toml");
  const Arm arm(model);
  // The initial state (derived parameters of the file) is the exact one.
  Eigen::Vector2d q, qd, qdd;
  arm.state(model.t0, q, qd, qdd);
  EXPECT_LT((model.q0 - Vector(q)).norm(), 1e-13);
  EXPECT_LT((model.v0 - Vector(qd)).norm(), 1e-13);
  SimulationSummary summary;
  const std::vector<ProgramRow> rows = run_program_rows(model, tight_options(6.0, 0.05), &summary);
  double worst = 0.0;
  for (const ProgramRow& r : rows) {
    arm.state(r.t, q, qd, qdd);
    worst = std::max(worst, (r.q - Vector(q)).norm());
    // The torques at the state reached are the inverse dynamics of that state's acceleration,
    // which the programs fix: compare with the exact motion's (both follow the circle).
    const Eigen::Vector2d tau = arm.torques(q, qd, qdd);
    EXPECT_LT((r.u - Vector(tau)).norm(), 1e-6 * (1.0 + tau.norm())) << "t = " << r.t;
  }
  EXPECT_LT(worst, 1e-8);
  EXPECT_LT(summary.program.acceleration, 1e-11);
  EXPECT_LT(summary.program.position, 1e-8);
}

// --- the cart whose pendulum angle is prescribed ---------------------------------------------

TEST(ProgramMotion, CartForceIsTheClosedFormAwayFromTheSingularState) {
  const Model model = load_example("cart_pendulum_program.toml");
  const double mc = parameter(model, "mc"), mb = parameter(model, "mb"), l = parameter(model, "l"),
               g = parameter(model, "g"), omega = parameter(model, "omega");
  Data data = make_data(model);
  for (double theta : {0.3, -1.0, 1.4, 2.5}) {
    const Vector q = (Vector(2) << 0.1, theta).finished();
    const Vector qd = (Vector(2) << -0.2, omega).finished();
    ASSERT_EQ(compute_terms(model, data, 0.0, q.data(), qd.data()), Status::ok);
    ASSERT_EQ(compute_program_motion(model, data, Complement::qr, {}), Status::ok);
    const double expected = -(mc + mb) * g * std::tan(theta) - mb * l * omega * omega * std::sin(theta);
    EXPECT_NEAR(data.motion.u(0), expected, 1e-11 * (1.0 + std::abs(expected))) << "theta = " << theta;
    // S = -cos(theta) / (l (mc + mb sin^2(theta))).
    EXPECT_NEAR(data.motion.S(0, 0), -std::cos(theta) / (l * (mc + mb * std::sin(theta) * std::sin(theta))), 1e-14);
  }
}

TEST(ProgramMotion, CartWithThePendulumHorizontalIsRefusedNamingTheProgram) {
  const Model model = load_example("cart_pendulum_program.toml", {{"theta0", std::numbers::pi / 2}});
  try {
    simulate(model, tight_options(1.0, 0.1), [](const Data&) {});
    FAIL() << "a singular program was not refused";
  } catch (const ModelError& e) {
    const std::string message = e.what();
    EXPECT_NE(message.find("'swing'"), std::string::npos) << message;
    EXPECT_NE(message.find("singular"), std::string::npos) << message;
    EXPECT_NE(message.find("initial state"), std::string::npos) << message;
  }
}

TEST(ProgramMotion, ProgramsOffAtTheInitialStateAreListedWithTheirResiduals) {
  const Model model = load_altered_example("sled_heading_program.toml", "velocity = { x = \"v0\", y = 0, phi = \"omega\" }",
                                           "velocity = { x = \"v0\", y = 0, phi = \"2*omega\" }");
  try {
    simulate(model, tight_options(1.0, 0.1), [](const Data&) {});
    FAIL() << "an initial state off its program was not refused";
  } catch (const ModelError& e) {
    const std::string message = e.what();
    EXPECT_NE(message.find("heading (velocity level): residual 1"), std::string::npos) << message;
  }
}

TEST(ProgramMotion, FeedbackKeepsTheProgramAndChangesNothingOnIt) {
  // On the exact motion the residuals are zero, so the feedback changes nothing but round-off: the
  // torque stays the closed form.
  const Model model = load_example("sled_heading_program.toml");
  const Sled sled(model);
  SimulationOptions options = tight_options(5.0, 0.05);
  options.formulation.program_feedback = {true, 5.0, 5.0};
  SimulationSummary summary;
  const std::vector<ProgramRow> rows = run_program_rows(model, options, &summary);
  for (const ProgramRow& r : rows) EXPECT_NEAR(r.u(0), sled.u(r.t), 1e-7 * (1.0 + std::abs(sled.u(r.t))));
  EXPECT_LT(summary.program.position, 1e-9);
}

TEST(ProgramMotion, FeedbackMakesTheProgramResidualADampedOscillator) {
  // Off the program, (P6): phi'' = -2 alpha (phi' - omega) - beta^2 (phi - omega t).
  const Model model = load_example("sled_heading_program.toml");
  const double omega = parameter(model, "omega");
  const double t = 0.5, phi = 0.62, phid = 1.3;
  const Vector q = (Vector(3) << 0.2, -0.1, phi).finished();
  const Vector qd = (Vector(3) << std::cos(phi), std::sin(phi), phid).finished();
  Data data = make_data(model);
  const ProgramFeedback feedback{true, 3.0, 4.0};
  ASSERT_EQ(compute_terms(model, data, t, q.data(), qd.data()), Status::ok);
  ASSERT_EQ(compute_program_motion(model, data, Complement::qr, feedback), Status::ok);
  EXPECT_NEAR(data.qdd(2), -2 * 3.0 * (phid - omega) - 16.0 * (phi - omega * t), 1e-12);
  data.stage = Stage::acceleration;
  compute_program_residuals(model, data);
  EXPECT_NEAR(data.motion.phi(0), phi - omega * t, 1e-15);
  EXPECT_NEAR(data.motion.f(0), phid - omega, 1e-15);
  // The acceleration-level residual is the model's, without the feedback terms.
  EXPECT_NEAR(data.motion.e(0), data.qdd(2), 1e-15);
}

}  // namespace
}  // namespace nhdyn::gallery
