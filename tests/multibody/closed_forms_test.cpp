// Exams of the multibody front end (symbolic/multibody.hpp) built through the C++ API, against
// closed forms: a compound pendulum, a heavy symmetric top (Lagrange's theta equation, steady
// precession), a free rigid body in gravity (its centre falls with g, its
// rotation obeys Euler's torque-free equations), a particle held on a sphere by point_on_surface
// (the spherical pendulum: q'' = g_tangential - |v|^2/l u), a knife edge on the ground (the
// classical constraint -sin(phi) x' + cos(phi) y' = 0), and the angular velocity of a rotation
// chain (R w_local = w, skew(w) = R' R^T).
#include <gtest/gtest.h>

#include <cmath>
#include <random>
#include <vector>

#include "multibody/multibody_support.hpp"
#include "nhdyn/symbolic/compile.hpp"
#include "nhdyn/symbolic/multibody.hpp"
#include "nhdyn/symbolic/simplify.hpp"
#include "nhdyn/symbolic/spec_builder.hpp"

namespace nhdyn::multibody_test {
namespace {

using symbolic::MultibodyBuilder;
using symbolic::SpecBuilder;

TEST(MultibodyClosedForms, CompoundPendulum) {
  // A rod swinging about the world y axis: theta'' = -m g l sin(theta) / (Iyy + m l^2).
  SpecBuilder b("pendulum");
  b.coordinate("theta").parameter("m", 1.3).parameter("l", 0.7).parameter("g", 9.81).parameter("J", 0.05);
  MultibodyBuilder mb(b);
  mb.frame("arm", "ground", {"0", "0", "0"}, {{"y", "theta", {}}})
      .body("rod", "arm", "m", {"0", "0", "-l"}, {{{"2*J", "0", "0"}, {"0", "J", "0"}, {"0", "0", "3*J"}}})
      .gravity({"0", "0", "-g"});
  mb.apply();
  const symbolic::Spec spec = b.build();
  const Model model = symbolic::compile_model(spec);
  std::mt19937 rng(3);
  for (int trial = 0; trial < 10; ++trial) {
    const std::vector<double> q{uniform(rng, -3, 3)}, v{uniform(rng, -5, 5)};
    const Data d = dynamics_at(model, q, v);
    const double exact = -1.3 * 9.81 * 0.7 * std::sin(q[0]) / (0.05 + 1.3 * 0.7 * 0.7);
    EXPECT_NEAR(d.qdd(0), exact, 1e-13 * (1 + std::abs(exact)));
    // T = 1/2 (J + m l^2) theta'^2, V = -m g l cos(theta).
    EXPECT_NEAR(evaluate(spec, spec.kinetic_energy, q, v), 0.5 * (0.05 + 1.3 * 0.49) * v[0] * v[0], 1e-13);
    EXPECT_NEAR(evaluate(spec, spec.potential_energy, q, v), -1.3 * 9.81 * 0.7 * std::cos(q[0]), 1e-13);
  }
}

TEST(MultibodyClosedForms, HeavySymmetricTop) {
  // Euler angles z(psi), x(theta), z(phi) about the fixed tip; centre of mass l up the symmetry
  // axis. Lagrange's equation for theta, with I1 = I1c + m l^2 and w3 = phi' + psi' cos(theta):
  //   I1 theta'' = I1 psi'^2 sin(theta) cos(theta) - I3 w3 psi' sin(theta) + m g l sin(theta),
  // and steady precession (theta' = 0, all q'' = 0) when w3 = (I1 Omega^2 cos(theta) + m g l) / (I3 Omega).
  const double m = 0.4, g = 9.81, l = 0.05, I1c = 2e-4, I3 = 3e-4, I1 = I1c + m * l * l;
  SpecBuilder b("top");
  b.coordinate("psi").coordinate("theta").coordinate("phi");
  b.parameter("m", m).parameter("g", g).parameter("l", l).parameter("I1c", I1c).parameter("I3", I3);
  MultibodyBuilder mb(b);
  mb.frame("top", "ground", {"0", "0", "0"}, {{"z", "psi", {}}, {"x", "theta", {}}, {"z", "phi", {}}})
      .body("top", "top", "m", {"0", "0", "l"}, {{{"I1c", "0", "0"}, {"0", "I1c", "0"}, {"0", "0", "I3"}}})
      .gravity({"0", "0", "-g"});
  mb.apply();
  const Model model = symbolic::compile_model(b.build());
  std::mt19937 rng(21);
  for (int trial = 0; trial < 10; ++trial) {
    const std::vector<double> q{uniform(rng, -3, 3), uniform(rng, 0.2, 1.4), uniform(rng, -3, 3)};
    const std::vector<double> v{uniform(rng, -10, 10), uniform(rng, -5, 5), uniform(rng, -100, 100)};
    const double w3 = v[2] + v[0] * std::cos(q[1]);
    const double exact = (I1 * v[0] * v[0] * std::sin(q[1]) * std::cos(q[1]) - I3 * w3 * v[0] * std::sin(q[1]) +
                          m * g * l * std::sin(q[1])) / I1;
    const Data d = dynamics_at(model, q, v);
    EXPECT_NEAR(d.qdd(1), exact, 1e-11 * (1 + std::abs(exact))) << trial;
  }
  // Steady precession at Omega = 2 rad/s, theta = 0.6.
  const double theta = 0.6, Omega = 2.0;
  const double w3 = (I1 * Omega * Omega * std::cos(theta) + m * g * l) / (I3 * Omega);
  const Data steady = dynamics_at(model, {0.3, theta, 0.0}, {Omega, 0.0, w3 - Omega * std::cos(theta)});
  EXPECT_LT(steady.qdd.norm(), 1e-10 * w3 * Omega);
  // Negative control: 10 % more spin and it nods.
  const Data off = dynamics_at(model, {0.3, theta, 0.0}, {Omega, 0.0, 1.1 * w3 - Omega * std::cos(theta)});
  EXPECT_GT(std::abs(off.qdd(1)), 1e-2);
}

TEST(MultibodyClosedForms, FreeRigidBodyFallsWithGAndObeysEulersEquations) {
  SpecBuilder b("free-body");
  for (const char* c : {"x", "y", "z", "yaw", "pitch", "roll"}) b.coordinate(c);
  b.parameter("m", 2.0).parameter("g", 9.81);
  MultibodyBuilder mb(b);
  mb.frame("body", "ground", {"x", "y", "z"}, {{"z", "yaw", {}}, {"y", "pitch", {}}, {"x", "roll", {}}})
      .body("brick", "body", "m", {"0", "0", "0"}, {{{"0.3", "0.01", "0"}, {"0.01", "0.5", "0.02"}, {"0", "0.02", "0.7"}}})
      .gravity({"0", "0", "-g"});
  mb.apply();
  const symbolic::Spec spec = b.build();
  const Model model = symbolic::compile_model(spec);
  const symbolic::Vector3& w = mb.placed_frame("body").omega_local;
  // dw/dt along the motion including the accelerations.
  symbolic::Vector3 wdot;
  for (std::size_t i = 0; i < 3; ++i) {
    wdot[i] = symbolic::time_derivative(w[i], spec.symbols);
    for (int j = 0; j < spec.n(); ++j) wdot[i] += w[i].diff(spec.symbols.velocity(j)) * spec.symbols.acceleration(j);
  }
  const double I[3][3] = {{0.3, 0.01, 0}, {0.01, 0.5, 0.02}, {0, 0.02, 0.7}};
  std::mt19937 rng(5);
  for (int trial = 0; trial < 10; ++trial) {
    std::vector<double> q(6), v(6);
    for (double& c : q) c = uniform(rng, -1.2, 1.2);
    for (double& c : v) c = uniform(rng, -4, 4);
    const Data d = dynamics_at(model, q, v);
    EXPECT_NEAR(d.qdd(0), 0.0, 1e-12);
    EXPECT_NEAR(d.qdd(1), 0.0, 1e-12);
    EXPECT_NEAR(d.qdd(2), -9.81, 1e-12);
    const std::vector<double> qdd(d.qdd.data(), d.qdd.data() + 6);
    double wv[3], a[3];
    for (std::size_t i = 0; i < 3; ++i) {
      wv[i] = evaluate(spec, w[i], q, v);
      a[i] = evaluate(spec, wdot[i], q, v, qdd);
    }
    // I w' + w x (I w) = 0.
    double Iw[3], Ia[3];
    for (int i = 0; i < 3; ++i) {
      Iw[i] = I[i][0] * wv[0] + I[i][1] * wv[1] + I[i][2] * wv[2];
      Ia[i] = I[i][0] * a[0] + I[i][1] * a[1] + I[i][2] * a[2];
    }
    const double gyro[3] = {wv[1] * Iw[2] - wv[2] * Iw[1], wv[2] * Iw[0] - wv[0] * Iw[2], wv[0] * Iw[1] - wv[1] * Iw[0]};
    const double scale = std::abs(gyro[0]) + std::abs(gyro[1]) + std::abs(gyro[2]);
    for (int i = 0; i < 3; ++i) EXPECT_LT(std::abs(Ia[i] + gyro[i]), 1e-11 * (1 + scale)) << trial;
    // Negative control: without the gyroscopic term the equation fails.
    EXPECT_GT(std::abs(Ia[0]) + std::abs(Ia[1]) + std::abs(Ia[2]), 1e-3 * scale);
  }
}

TEST(MultibodyClosedForms, ParticleOnASphereIsTheSphericalPendulum) {
  SpecBuilder b("spherical-pendulum");
  for (const char* c : {"X1", "Y1", "Z1"}) b.coordinate(c);
  b.parameter("m", 0.8).parameter("g", 9.81).parameter("l", 1.5);
  MultibodyBuilder mb(b);
  // A translating frame: no rotation, so the inertia plays no part.
  mb.frame("bob", "ground", {"X1", "Y1", "Z1"}, {})
      .body("bob", "bob", "m", {"0", "0", "0"}, {{{"1", "0", "0"}, {"0", "1", "0"}, {"0", "0", "1"}}})
      .point("centre", "bob", {"0", "0", "0"})
      .point_on_surface("rod", "centre", "X^2 + Y^2 + Z^2 - l^2")
      .gravity({"0", "0", "-g"});
  mb.apply();
  const Model model = symbolic::compile_model(b.build());
  std::mt19937 rng(9);
  for (int trial = 0; trial < 10; ++trial) {
    // A point on the sphere and a tangent velocity.
    double u[3] = {uniform(rng, -1, 1), uniform(rng, -1, 1), uniform(rng, -1, 1)};
    const double nu = std::sqrt(u[0] * u[0] + u[1] * u[1] + u[2] * u[2]);
    for (double& c : u) c /= nu;
    double w[3] = {uniform(rng, -2, 2), uniform(rng, -2, 2), uniform(rng, -2, 2)};
    const double wu = w[0] * u[0] + w[1] * u[1] + w[2] * u[2];
    for (int i = 0; i < 3; ++i) w[i] -= wu * u[i];
    const std::vector<double> q{1.5 * u[0], 1.5 * u[1], 1.5 * u[2]}, v{w[0], w[1], w[2]};
    const Data d = dynamics_at(model, q, v);
    const double speed2 = w[0] * w[0] + w[1] * w[1] + w[2] * w[2];
    const double g[3] = {0, 0, -9.81};
    const double gu = g[2] * u[2];
    for (int i = 0; i < 3; ++i) {
      const double exact = g[i] - gu * u[i] - speed2 / 1.5 * u[i];
      EXPECT_NEAR(d.qdd(i), exact, 1e-12 * (10 + speed2)) << trial;
    }
  }
}

TEST(MultibodyClosedForms, KnifeEdgeOnTheGroundIsTheClassicalConstraint) {
  SpecBuilder b("skate");
  for (const char* c : {"x", "y", "phi"}) b.coordinate(c);
  b.parameter("m", 1.0).parameter("g", 9.81);
  MultibodyBuilder mb(b);
  mb.frame("skate", "ground", {"x", "y", "0"}, {{"z", "phi", {}}})
      .point("contact", "skate", {"0", "0", "0"})
      .body("skate", "skate", "m", {"0.1", "0", "0"}, {{{"0.01", "0", "0"}, {"0", "0.02", "0"}, {"0", "0", "0.03"}}})
      .knife_edge("blade", "contact", "x")
      .gravity({"0", "0", "-g"});
  mb.apply();
  const symbolic::Spec spec = b.build();
  ASSERT_EQ(spec.s(), 1);
  const GiNaC::ex expected = -GiNaC::sin(spec.symbols.coordinate(2)) * spec.symbols.velocity(0) +
                             GiNaC::cos(spec.symbols.coordinate(2)) * spec.symbols.velocity(1);
  EXPECT_TRUE(symbolic::is_zero(spec.constraints[0].expression - expected)) << spec.constraints[0].expression;
  // Negative control: the blade along y gives the other constraint.
  EXPECT_FALSE(symbolic::is_zero(spec.constraints[0].expression + GiNaC::cos(spec.symbols.coordinate(2)) *
                                                                     spec.symbols.velocity(0)));
}

TEST(MultibodyClosedForms, AngularVelocityOfARotationChain) {
  SpecBuilder b("chain");
  for (const char* c : {"a", "bb", "c"}) b.coordinate(c);
  b.parameter("k", 0.3);
  MultibodyBuilder mb(b);
  mb.frame("one", "ground", {"a", "0", "0"}, {{"z", "a", {}}, {"x", "bb^2", {}}})
      .frame("two", "one", {"0", "1", "c"}, {{"y", "c + k*t", {}}, {"z", "a*bb", {}}});
  const symbolic::PlacedFrame& f = mb.placed_frame("two");
  const symbolic::Spec& spec = b.current();
  std::mt19937 rng(13);
  for (int trial = 0; trial < 5; ++trial) {
    std::vector<double> q{uniform(rng, -2, 2), uniform(rng, -2, 2), uniform(rng, -2, 2)};
    std::vector<double> v{uniform(rng, -2, 2), uniform(rng, -2, 2), uniform(rng, -2, 2)};
    const double t = uniform(rng, 0, 1);
    double R[3][3], Rdot[3][3], w[3], wl[3];
    for (unsigned i = 0; i < 3; ++i) {
      w[i] = evaluate(spec, f.omega[i], q, v, {}, t);
      wl[i] = evaluate(spec, f.omega_local[i], q, v, {}, t);
      for (unsigned j = 0; j < 3; ++j) {
        R[i][j] = evaluate(spec, f.rotation(i, j), q, v, {}, t);
        Rdot[i][j] = evaluate(spec, symbolic::time_derivative(f.rotation(i, j), spec.symbols), q, v, {}, t);
      }
    }
    // R' R^T = skew(w).
    double S[3][3];
    for (int i = 0; i < 3; ++i)
      for (int j = 0; j < 3; ++j) S[i][j] = Rdot[i][0] * R[j][0] + Rdot[i][1] * R[j][1] + Rdot[i][2] * R[j][2];
    EXPECT_NEAR(S[2][1], w[0], 1e-12);
    EXPECT_NEAR(S[0][2], w[1], 1e-12);
    EXPECT_NEAR(S[1][0], w[2], 1e-12);
    EXPECT_NEAR(S[1][2], -w[0], 1e-12);
    for (int i = 0; i < 3; ++i) {
      EXPECT_NEAR(R[i][0] * wl[0] + R[i][1] * wl[1] + R[i][2] * wl[2], w[i], 1e-12);
      EXPECT_NEAR(S[i][i], 0.0, 1e-12);
    }
  }
}

}  // namespace
}  // namespace nhdyn::multibody_test
