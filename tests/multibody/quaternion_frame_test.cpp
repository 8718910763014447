// Frames turned by a unit quaternion (rotations = "quaternion", docs/derivations/quaternion-frame.md):
// the rotation and angular velocity against their definitions at random states, the singular A
// with its null direction e, a torque-free body's integrals, the same motion as three angles where
// those are regular, the motion through the orientation where the angles lock (the angle model
// fails there), the tumbling Chaplygin ball's integrals and contact force, and the initial-state
// rules (unit norm, e.e' = 0, --fix-initial).
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <fstream>
#include <random>
#include <sstream>
#include <string>
#include <vector>

#include "multibody/multibody_support.hpp"
#include "nhdyn/analysis/simulation.hpp"
#include "nhdyn/core/error.hpp"
#include "nhdyn/frontend/load_model.hpp"
#include "nhdyn/io/results.hpp"
#include "nhdyn/symbolic/compile.hpp"
#include "nhdyn/symbolic/multibody.hpp"
#include "nhdyn/symbolic/spec_builder.hpp"
#include "support/text.hpp"

namespace nhdyn::multibody_test {
namespace {

using nhdyn::test::example;
using Matrix3 = std::array<std::array<double, 3>, 3>;
using Vec3 = std::array<double, 3>;

// The rotation of e / |e| (quaternion-frame.md (2.3)), written here independently.
Matrix3 rotation_of(const std::array<double, 4>& q) {
  const double s = q[0] * q[0] + q[1] * q[1] + q[2] * q[2] + q[3] * q[3];
  const double a = q[0], b = q[1], c = q[2], d = q[3];
  return {{{(a * a + b * b - c * c - d * d) / s, 2 * (b * c - a * d) / s, 2 * (b * d + a * c) / s},
           {2 * (b * c + a * d) / s, (a * a - b * b + c * c - d * d) / s, 2 * (c * d - a * b) / s},
           {2 * (b * d - a * c) / s, 2 * (c * d + a * b) / s, (a * a - b * b - c * c + d * d) / s}}};
}

// omega_F = 2 G(e) e' / (e.e), the angular velocity in the frame's axes (quaternion-frame.md (3.3)).
Vec3 body_rate(const std::array<double, 4>& e, const std::array<double, 4>& d) {
  const double s = 2.0 / (e[0] * e[0] + e[1] * e[1] + e[2] * e[2] + e[3] * e[3]);
  return {s * (-e[1] * d[0] + e[0] * d[1] + e[3] * d[2] - e[2] * d[3]),
          s * (-e[2] * d[0] - e[3] * d[1] + e[0] * d[2] + e[1] * d[3]),
          s * (-e[3] * d[0] + e[2] * d[1] - e[1] * d[2] + e[0] * d[3])};
}

Matrix3 rotation_zxy(double psi, double theta, double phi) {
  const auto product = [](const Matrix3& A, const Matrix3& B) {
    Matrix3 C{};
    for (int i = 0; i < 3; ++i)
      for (int j = 0; j < 3; ++j)
        for (int k = 0; k < 3; ++k) C[i][j] += A[i][k] * B[k][j];
    return C;
  };
  const double cz = std::cos(psi), sz = std::sin(psi), cx = std::cos(theta), sx = std::sin(theta);
  const double cy = std::cos(phi), sy = std::sin(phi);
  const Matrix3 Rz = {{{cz, -sz, 0}, {sz, cz, 0}, {0, 0, 1}}};
  const Matrix3 Rx = {{{1, 0, 0}, {0, cx, -sx}, {0, sx, cx}}};
  const Matrix3 Ry = {{{cy, 0, sy}, {0, 1, 0}, {-sy, 0, cy}}};
  return product(product(Rz, Rx), Ry);
}

// A run's rows as name -> value lookups.
struct Rows {
  std::vector<std::string> names;
  std::vector<std::vector<double>> rows;
  double at(std::size_t row, const std::string& name) const {
    const auto it = std::find(names.begin(), names.end(), name);
    EXPECT_NE(it, names.end()) << "no column " << name;
    return it == names.end() ? 0.0 : rows[row][static_cast<std::size_t>(it - names.begin())];
  }
  std::array<double, 4> quaternion(std::size_t row) const {
    return {at(row, "e0"), at(row, "e1"), at(row, "e2"), at(row, "e3")};
  }
  std::array<double, 4> quaternion_rate(std::size_t row) const {
    return {at(row, "e0'"), at(row, "e1'"), at(row, "e2'"), at(row, "e3'")};
  }
};

Rows run(const Model& model, SimulationOptions options, SimulationSummary* summary = nullptr) {
  Rows out;
  out.names = make_result_columns(model).all;
  std::vector<double> row;
  const SimulationSummary s = simulate(model, options, [&](const Data& data) {
    fill_result_row(model, data, row);
    out.rows.push_back(row);
  });
  if (summary != nullptr) *summary = s;
  else EXPECT_EQ(s.status, Status::ok) << s.message;
  return out;
}

SimulationOptions options(double t_end, double step) {
  SimulationOptions o;
  o.t_end = t_end;
  o.output_step = step;
  o.integrator.rtol = 1e-12;
  o.integrator.atol = 1e-14;
  return o;
}

// (2.3), (3.3): R is a rotation and skew(omega) = R' R^T, R omega_F = omega at random states, also
// off the unit sphere and with e.e' != 0; under a parent turned by an angle.
TEST(QuaternionFrame, RotationAndAngularVelocityAreExactForAnyQuaternion) {
  symbolic::SpecBuilder b("spin");
  for (const char* c : {"a", "e0", "e1", "e2", "e3"}) b.coordinate(c);
  symbolic::MultibodyBuilder mb(b);
  mb.frame("arm", "ground", {"0", "0", "0"}, {{"z", "a", {}}})
      .quaternion_frame("body", "arm", {"1", "a", "0"}, {"e0", "e1", "e2", "e3"});
  const symbolic::PlacedFrame& f = mb.placed_frame("body");
  const symbolic::Spec& spec = b.current();
  std::mt19937 rng(7);
  for (int trial = 0; trial < 6; ++trial) {
    std::vector<double> q(5), v(5);
    for (double& x : q) x = uniform(rng, -1.5, 1.5);
    for (double& x : v) x = uniform(rng, -2, 2);
    double R[3][3], Rdot[3][3], w[3], wl[3];
    for (unsigned i = 0; i < 3; ++i) {
      w[i] = evaluate(spec, f.omega[i], q, v);
      wl[i] = evaluate(spec, f.omega_local[i], q, v);
      for (unsigned j = 0; j < 3; ++j) {
        R[i][j] = evaluate(spec, f.rotation(i, j), q, v);
        Rdot[i][j] = evaluate(spec, symbolic::time_derivative(f.rotation(i, j), spec.symbols), q, v);
      }
    }
    for (int i = 0; i < 3; ++i)
      for (int j = 0; j < 3; ++j) {
        const double RRt = R[i][0] * R[j][0] + R[i][1] * R[j][1] + R[i][2] * R[j][2];
        EXPECT_NEAR(RRt, i == j ? 1.0 : 0.0, 1e-13);
      }
    const double det = R[0][0] * (R[1][1] * R[2][2] - R[1][2] * R[2][1]) - R[0][1] * (R[1][0] * R[2][2] - R[1][2] * R[2][0]) +
                       R[0][2] * (R[1][0] * R[2][1] - R[1][1] * R[2][0]);
    EXPECT_NEAR(det, 1.0, 1e-13);
    double S[3][3];
    for (int i = 0; i < 3; ++i)
      for (int j = 0; j < 3; ++j) S[i][j] = Rdot[i][0] * R[j][0] + Rdot[i][1] * R[j][1] + Rdot[i][2] * R[j][2];
    EXPECT_NEAR(S[2][1], w[0], 1e-12);
    EXPECT_NEAR(S[0][2], w[1], 1e-12);
    EXPECT_NEAR(S[1][0], w[2], 1e-12);
    for (int i = 0; i < 3; ++i) EXPECT_NEAR(S[i][i], 0.0, 1e-12);
    for (int i = 0; i < 3; ++i) EXPECT_NEAR(R[i][0] * wl[0] + R[i][1] * wl[1] + R[i][2] * wl[2], w[i], 1e-12);
  }
}

// (5.1): A e = 0 in the quaternion's columns — for a body whose centre of mass is off the frame's
// origin too — while the stacked matrix is regular and q'' solves it.
TEST(QuaternionFrame, InertiaMatrixIsSingularAlongTheQuaternionAndTheStackedMatrixRegular) {
  symbolic::SpecBuilder b("offset");
  for (const char* c : {"x", "y", "z", "e0", "e1", "e2", "e3"}) b.coordinate(c);
  b.parameter("m", 1.5).parameter("g", 9.81);
  symbolic::MultibodyBuilder mb(b);
  mb.quaternion_frame("body", "ground", {"x", "y", "z"}, {"e0", "e1", "e2", "e3"})
      .body("body", "body", "m", {"0.1", "-0.2", "0.3"}, {{{"1", "0.1", "0"}, {"0.1", "2", "0.2"}, {"0", "0.2", "2.5"}}})
      .gravity({"0", "0", "-g"});
  mb.apply();
  const Model model = symbolic::compile_model(b.build());
  ASSERT_EQ(model.s(), 1);
  EXPECT_EQ(model.constraints[0].name, "body_unit");
  std::mt19937 rng(11);
  for (int trial = 0; trial < 5; ++trial) {
    std::vector<double> q(7), v(7);
    for (double& x : q) x = uniform(rng, -1, 1);
    for (double& x : v) x = uniform(rng, -2, 2);
    double norm = 0.0, along = 0.0;
    for (int k = 3; k < 7; ++k) norm += q[static_cast<std::size_t>(k)] * q[static_cast<std::size_t>(k)];
    for (int k = 3; k < 7; ++k) q[static_cast<std::size_t>(k)] /= std::sqrt(norm);
    for (int k = 3; k < 7; ++k) along += q[static_cast<std::size_t>(k)] * v[static_cast<std::size_t>(k)];
    for (int k = 3; k < 7; ++k) v[static_cast<std::size_t>(k)] -= along * q[static_cast<std::size_t>(k)];
    const Data d = dynamics_at(model, q, v);
    double largest = 0.0;
    for (int i = 0; i < 7; ++i)
      for (int j = 0; j < 7; ++j) largest = std::max(largest, std::abs(d.A(i, j)));
    for (int i = 0; i < 7; ++i) {
      double Ae = 0.0;
      for (int k = 3; k < 7; ++k) Ae += d.A(i, k) * q[static_cast<std::size_t>(k)];
      EXPECT_LT(std::abs(Ae), 1e-13 * largest) << "row " << i;
    }
    EXPECT_TRUE(d.qdd.allFinite());
    double e_dd = 0.0, rate2 = 0.0;
    for (int k = 3; k < 7; ++k) {
      e_dd += q[static_cast<std::size_t>(k)] * d.qdd(k);
      rate2 += v[static_cast<std::size_t>(k)] * v[static_cast<std::size_t>(k)];
    }
    EXPECT_NEAR(e_dd, -rate2, 1e-11);  // (4.3): e.e'' + e'.e' = 0
  }
}


// The free body of examples/tumbling_body.toml spun about its intermediate axis flips over and back:
// energy 1/2 w.I w and world angular momentum R I w are kept, and so is |e| = 1.
TEST(QuaternionFrame, TumblingFreeBodyKeepsItsIntegralsAndUnitNorm) {
  const Model model = load_model(example("tumbling_body.toml"));
  const double I[3] = {1.0, 2.0, 3.0};
  const Rows r = run(model, options(30.0, 0.01));
  ASSERT_EQ(r.rows.size(), 3001u);
  Vec3 L0{};
  double E0 = 0.0, drift_L = 0.0, drift_E = 0.0, drift_norm = 0.0, lowest_yy = 1.0;
  for (std::size_t k = 0; k < r.rows.size(); ++k) {
    const std::array<double, 4> e = r.quaternion(k);
    const Matrix3 R = rotation_of(e);
    const Vec3 w = body_rate(e, r.quaternion_rate(k));
    Vec3 L{};
    for (int i = 0; i < 3; ++i)
      for (int j = 0; j < 3; ++j) L[i] += R[i][j] * I[j] * w[j];
    const double E = 0.5 * (I[0] * w[0] * w[0] + I[1] * w[1] * w[1] + I[2] * w[2] * w[2]);
    if (k == 0) {
      L0 = L;
      E0 = E;
    }
    for (int i = 0; i < 3; ++i) drift_L = std::max(drift_L, std::abs(L[i] - L0[i]));
    drift_E = std::max(drift_E, std::abs(E - E0));
    drift_norm = std::max(drift_norm, std::abs(e[0] * e[0] + e[1] * e[1] + e[2] * e[2] + e[3] * e[3] - 1.0));
    lowest_yy = std::min(lowest_yy, R[1][1]);
  }
  EXPECT_LT(lowest_yy, -0.99);  // the body's y axis has turned over: a flip happened
  EXPECT_LT(drift_L, 1e-10 * 2.0);
  EXPECT_LT(drift_E, 1e-10 * E0);
  EXPECT_LT(drift_norm, 1e-10);
}

// The same free body with three z-x-y angles, over the first seconds (the angles regular there):
// the two models' rotation matrices agree.
constexpr const char* kAnglesModel = R"(
name = "free-angles"
coordinates = ["x", "y", "z", "psi", "theta", "phi"]
[parameters]
m = 1.0
I1 = 1.0
I2 = 2.0
I3 = 3.0
wx = 0.01
wy = 1.0
wz = 0.0
[[frames]]
name = "body"
translation = ["x", "y", "z"]
rotations = [["z", "psi"], ["x", "theta"], ["y", "phi"]]
[[bodies]]
name = "body"
frame = "body"
mass = "m"
inertia = ["I1", "I2", "I3"]
# At zero angles omega = (theta', phi', psi').
[initial]
position = { x = 0, y = 0, z = 0, psi = 0, theta = 0, phi = 0 }
velocity = { x = 0, y = 0, z = 0, psi = "wz", theta = "wx", phi = "wy" }
)";

TEST(QuaternionFrame, FollowsTheAngleFrameWhereTheAnglesAreRegular) {
  const Rows quaternion = run(load_model(example("tumbling_body.toml")), options(6.0, 1.0));
  const Rows angles = run(load_model_text(kAnglesModel, "angles.toml"), options(6.0, 1.0));
  ASSERT_EQ(quaternion.rows.size(), 7u);
  ASSERT_EQ(angles.rows.size(), 7u);
  double turned = 0.0;
  for (std::size_t k = 0; k < 7; ++k) {
    const Matrix3 Rq = rotation_of(quaternion.quaternion(k));
    const Matrix3 Ra = rotation_zxy(angles.at(k, "psi"), angles.at(k, "theta"), angles.at(k, "phi"));
    EXPECT_GT(std::cos(angles.at(k, "theta")), 0.5);  // regular
    for (int i = 0; i < 3; ++i)
      for (int j = 0; j < 3; ++j) EXPECT_NEAR(Rq[i][j], Ra[i][j], 1e-9) << "t = " << k << " R" << i << j;
    turned = std::max(turned, 1.0 - Rq[0][0]);
  }
  EXPECT_GT(turned, 1.0);  // the body has turned by more than 90 degrees about y
}

// Spun about its x axis with a small rate about the vertical, the body's y axis passes within
// 1e-7 rad of the vertical at t = pi/2: theta = pi/2, where z-x-y angles lock (their A loses rank,
// psi' and phi' grow without bound). The angle model stops there with its step size gone to
// zero; the quaternion model goes through with its integrals kept and, without the small rate,
// follows R = Rx(w t) exactly.
TEST(QuaternionFrame, PassesThroughTheOrientationWhereTheAnglesLock) {
  SimulationSummary failed;
  run(load_model_text(kAnglesModel, "angles.toml", {{"wx", 1.0}, {"wy", 0.0}, {"wz", 1e-7}}), options(4.0, 0.1),
      &failed);
  EXPECT_NE(failed.status, Status::ok);
  EXPECT_NEAR(failed.t_reached, M_PI / 2, 1e-3) << failed.message;

  const Model tumbling = load_model(example("tumbling_body.toml"), {{"kick", 1.0}, {"spin", 0.0}});
  // e' = (0, w, 0, d) / 2 (quaternion-frame.md (6.1)), the rates of the angle model's start.
  EXPECT_DOUBLE_EQ(tumbling.v0(4), 0.5);
  Model nudged = tumbling;
  nudged.v0(6) = 0.5e-7;
  const double I[3] = {1.0, 2.0, 3.0};
  const Rows r = run(nudged, options(2 * M_PI, M_PI / 200));  // a row at t = pi/2
  ASSERT_EQ(r.rows.size(), 401u);
  double closest = 0.0, drift_E = 0.0, E0 = 0.0;
  for (std::size_t k = 0; k < r.rows.size(); ++k) {
    const std::array<double, 4> e = r.quaternion(k);
    const Vec3 w = body_rate(e, r.quaternion_rate(k));
    const double E = 0.5 * (I[0] * w[0] * w[0] + I[1] * w[1] * w[1] + I[2] * w[2] * w[2]);
    if (k == 0) E0 = E;
    drift_E = std::max(drift_E, std::abs(E - E0));
    closest = std::max(closest, rotation_of(e)[2][1]);  // sin(theta) of z-x-y
  }
  EXPECT_GT(closest, 1.0 - 1e-12);
  EXPECT_LT(drift_E, 1e-12);

  const Rows exact = run(tumbling, options(2 * M_PI, M_PI / 8));
  ASSERT_EQ(exact.rows.size(), 17u);
  for (std::size_t k = 0; k < exact.rows.size(); ++k) {
    const double a = exact.at(k, "t");
    const Matrix3 R = rotation_of(exact.quaternion(k));
    const Matrix3 Rx = rotation_zxy(0, a, 0);
    for (int i = 0; i < 3; ++i)
      for (int j = 0; j < 3; ++j) EXPECT_NEAR(R[i][j], Rx[i][j], 1e-9) << "t = " << a;
  }
}

std::string read_example(const std::string& name) {
  std::ifstream in(example(name));
  std::stringstream text;
  text << in.rdbuf();
  return text.str();
}

// The text with `from` replaced by `to` (once; `from` must occur).
std::string edited(std::string text, const std::string& from, const std::string& to) {
  const std::size_t at = text.find(from);
  EXPECT_NE(at, std::string::npos) << from;
  if (at != std::string::npos) text.replace(at, from.size(), to);
  return text;
}

int line_of(const std::string& text, const std::string& what) {
  const std::size_t at = text.find(what);
  EXPECT_NE(at, std::string::npos) << what;
  return 1 + static_cast<int>(std::count(text.begin(), text.begin() + static_cast<std::ptrdiff_t>(at), '\n'));
}

// The Chaplygin ball with a quaternion frame turns over again and again over 20 s; its energy and
// its angular momentum about the contact point K = I_G w + m r^2 (w - (w.n) n) (rolling-bodies.md
// section 6.6) are kept, the contact force carries exactly the weight (the centre stays at
// height r), and the momentum balance is used for it (no note).
TEST(QuaternionFrame, TumblingChaplyginBallKeepsItsIntegrals) {
  const Model model = load_model(example("chaplygin_ball_quaternion.toml"));
  ASSERT_TRUE(model.contact_forces);
  EXPECT_TRUE(model.contact_forces->notes.empty());
  const double m = 1.0, r = 0.1, g = 9.81;
  const double I[3] = {0.3 * m * r * r, 0.4 * m * r * r, 0.5 * m * r * r};
  SimulationSummary summary;
  SimulationOptions o = options(20.0, 0.01);
  o.integrator.rtol = 1e-11;
  o.integrator.atol = 1e-13;
  const Rows rows = run(model, o, &summary);
  ASSERT_EQ(summary.status, Status::ok) << summary.message;
  Vec3 K0{};
  double drift = 0.0, lowest_zz = 1.0, highest_lock = 0.0, force = 0.0, norm = 0.0;
  for (std::size_t k = 0; k < rows.rows.size(); ++k) {
    const std::array<double, 4> e = rows.quaternion(k);
    const Matrix3 R = rotation_of(e);
    const Vec3 wb = body_rate(e, rows.quaternion_rate(k));
    Vec3 w{}, K{};
    for (int i = 0; i < 3; ++i)
      for (int j = 0; j < 3; ++j) {
        w[i] += R[i][j] * wb[j];
        K[i] += R[i][j] * I[j] * wb[j];
      }
    for (int i = 0; i < 2; ++i) K[i] += m * r * r * w[i];
    if (k == 0) K0 = K;
    for (int i = 0; i < 3; ++i) drift = std::max(drift, std::abs(K[i] - K0[i]));
    lowest_zz = std::min(lowest_zz, R[2][2]);
    highest_lock = std::max(highest_lock, std::abs(R[2][1]));
    force = std::max(force, std::abs(rows.at(k, "ball_N") - m * g));
    norm = std::max(norm, std::abs(e[0] * e[0] + e[1] * e[1] + e[2] * e[2] + e[3] * e[3] - 1.0));
  }
  EXPECT_LT(lowest_zz, -0.9);       // the ball has turned over
  EXPECT_GT(highest_lock, 0.99);    // and come near the z-x-y angles' lock (|sin theta| = 1)
  EXPECT_LT(drift, 1e-10 * std::sqrt(K0[0] * K0[0] + K0[1] * K0[1] + K0[2] * K0[2]));
  EXPECT_LT(summary.energy.drift, 1e-10);
  EXPECT_LT(force, 1e-9 * m * g);
  EXPECT_LT(norm, 1e-9);
}

// The initial state: a quaternion not of unit norm and rates with e.e' != 0 are refused with the
// residuals of FRAME_unit, where the frame was written and what they mean; --fix-initial moves e
// to e / |e| (the change along e costs nothing, A e = 0) and removes the rate along e.
TEST(QuaternionFrame, InitialStateMustBeUnitWithRatesNormalToIt) {
  const std::string text = read_example("chaplygin_ball_quaternion.toml");
  const int frame_line = line_of(text, "quaternion = [");
  const std::string where = "ball.toml:" + std::to_string(frame_line) + ":";
  const auto refused = [&](const std::string& changed, const std::vector<std::string>& parts) {
    const Model model = load_model_text(changed, "ball.toml");
    try {
      run(model, options(0.1, 0.1));
      ADD_FAILURE() << "not refused";
    } catch (const ModelError& e) {
      for (const std::string& part : parts) EXPECT_NE(std::string(e.what()).find(part), std::string::npos) << e.what();
    }
  };
  refused(edited(text, "e0 = 1, e1 = 0", "e0 = 1.1, e1 = 0"),
          {"ball_unit (position level): residual 0.21", where, "|e| = sqrt(1 + residual)", "--fix-initial"});
  refused(edited(text, "e0 = 0, e1 = \"w1/2\"", "e0 = 0.25, e1 = \"w1/2\""),
          {"ball_unit (velocity level): residual 0.5", where, "2 e.e'"});

  const Model tumbling = load_model_text(edited(read_example("tumbling_body.toml"), "e0 = 1, e1 = 0", "e0 = 2, e1 = 0.5"));
  SimulationOptions o = options(0.1, 0.1);
  o.fix_initial = true;
  SimulationSummary summary;
  run(tumbling, o, &summary);
  ASSERT_EQ(summary.status, Status::ok) << summary.message;
  ASSERT_TRUE(summary.initial_fix);
  const Vector& q = summary.initial_fix->q;
  const Vector& v = summary.initial_fix->v;
  const double n = std::sqrt(2.0 * 2.0 + 0.5 * 0.5);
  const double e[4] = {2.0 / n, 0.5 / n, 0.0, 0.0};
  const double rate[4] = {0.0, 0.005, 0.5, 0.0};  // (0, kick, spin, 0) / 2
  const double along = e[0] * rate[0] + e[1] * rate[1];
  for (int k = 0; k < 4; ++k) {
    EXPECT_NEAR(q(3 + k), e[k], 1e-13) << k;
    EXPECT_NEAR(v(3 + k), rate[k] - along * e[k], 1e-13) << k;
  }
  for (int k = 0; k < 3; ++k) EXPECT_EQ(q(k), 0.0);
}

// Bad [[frames]] input: each refused with file:line and what to do.
TEST(QuaternionFrame, BadFrameInputIsRefusedWithWhereAndWhat) {
  const std::string text = read_example("chaplygin_ball_quaternion.toml");
  const int names = line_of(text, "quaternion = [");
  const int rotations = line_of(text, "\nrotations = \"quaternion\"") + 1;
  const auto refused = [&](const std::string& changed, int line, const std::vector<std::string>& parts) {
    try {
      load_model_text(changed, "ball.toml");
      ADD_FAILURE() << "not refused";
    } catch (const ModelError& e) {
      const std::string message = e.what();
      EXPECT_NE(message.find("ball.toml:" + std::to_string(line) + ":"), std::string::npos) << message;
      for (const std::string& part : parts) EXPECT_NE(message.find(part), std::string::npos) << message;
    }
  };
  const std::string four = "quaternion = [\"e0\", \"e1\", \"e2\", \"e3\"]";
  refused(edited(text, four, "quaternion = [\"e0\", \"e1\", \"e2\"]"), names, {"4 components", "3 are given"});
  refused(edited(text, four, "quaternion = [\"e0\", \"e1\", \"e2\", \"q3\"]"), names,
          {"'q3' is not a coordinate", "did you mean 'e3'", "`coordinates`"});
  refused(edited(text, four, "quaternion = [\"e0\", \"e1\", \"e1\", \"e3\"]"), names, {"'e1' is named twice"});
  refused(edited(text, "\nrotations = \"quaternion\"", "\nrotations = \"quaternions\""), rotations,
          {"rotations = \"quaternions\" is not known", "rotations = \"quaternion\""});
  refused(edited(text, four, ""), rotations, {"needs the four coordinates"});
  refused(edited(text, "\nrotations = \"quaternion\"", "\n"), names, {"add rotations = \"quaternion\""});
}

// Kane and Levinson's rattleback with a quaternion frame (an ellipsoid contact, the centre of mass
// off the frame's origin) from the start of examples/rattleback.toml converted by (6.1), (6.2):
// the same motion as the z-x-y angle model through its spin reversal, to the integration's accuracy.
TEST(QuaternionFrame, RattlebackFollowsTheAngleModelThroughItsReversal) {
  const Model angles = load_model(example("rattleback.toml"));
  const Model quaternion = load_model(example("rattleback_quaternion.toml"));
  SimulationOptions o = options(3.0, 0.5);
  o.integrator.rtol = 1e-11;
  o.integrator.atol = 1e-13;
  const Rows a = run(angles, o), q = run(quaternion, o);
  ASSERT_EQ(a.rows.size(), 7u);
  ASSERT_EQ(q.rows.size(), 7u);
  double reversed = 0.0;
  for (std::size_t k = 0; k < 7; ++k) {
    const Matrix3 Ra = rotation_zxy(a.at(k, "psi"), a.at(k, "theta"), a.at(k, "phi"));
    const Matrix3 Rq = rotation_of(q.quaternion(k));
    for (int i = 0; i < 3; ++i)
      for (int j = 0; j < 3; ++j) EXPECT_NEAR(Rq[i][j], Ra[i][j], 1e-8) << "t = " << a.at(k, "t");
    for (const char* c : {"x", "y", "z", "x'", "y'", "z'"}) EXPECT_NEAR(q.at(k, c), a.at(k, c), 1e-9) << c;
    // The spin about the vertical, from the quaternion: omega_z = (R omega_F)_z.
    const Vec3 wb = body_rate(q.quaternion(k), q.quaternion_rate(k));
    const double wz = Rq[2][0] * wb[0] + Rq[2][1] * wb[1] + Rq[2][2] * wb[2];
    const double wz_angles = a.at(k, "psi'") + a.at(k, "phi'") * std::sin(a.at(k, "theta"));
    EXPECT_NEAR(wz, wz_angles, 1e-8) << "t = " << a.at(k, "t");
    reversed = std::max(reversed, wz);
  }
  EXPECT_GT(reversed, 0.1);  // spun at -5 rad/s, it turns the other way from t = 2.35 s
}

}  // namespace
}  // namespace nhdyn::multibody_test
