// NAME_Flong and NAME_Flat of a rolling body whose shape has an axle (a [[contacts]] disk,
// docs/derivations/rolling-bodies.md section 5): the same columns as a [[wheels]] entry on the
// same disk at random rolling states, and the components along
// e_long = (a x n)/|a x n|, e_lat = n x e_long computed here from the angles; the same disk on a
// quaternion frame (whose axle is taken from R's numerator) at the corresponding states; the
// column order with rubber rolling.
#include <gtest/gtest.h>

#include <Eigen/Geometry>

#include <algorithm>
#include <cmath>
#include <random>
#include <string>
#include <vector>

#include "multibody/multibody_support.hpp"
#include "nhdyn/frontend/load_model.hpp"
#include "nhdyn/model/contact_forces.hpp"
#include "support/models.hpp"

namespace nhdyn::multibody_test {
namespace {

constexpr double kR = 0.2;  // the disk's radius

// A thin disk whose centre is at (x, y, z), turned by z-x-y angles, rolling on z = 0: as a
// [[wheels]] entry (`helper` "wheel") or a [[contacts]] disk ("rolling" or "rubber").
std::string angle_disk_text(const std::string& helper) {
  if (helper == "wheel") {
    return test::free_disk_text("disk-angles", "", "\n[[wheels]]\nname = \"disk\"\nbody = \"disk\"\naxis = \"y\"\nradius = \"r\"\n");
  }
  return test::free_disk_text("disk-angles", "",
                              "\n[[contacts]]\nname = \"disk\"\nbody = \"disk\"\nshape = { disk = \"r\", axis = \"y\" }\n"
                              "rolling = \"" + helper + "\"\n");
}

// The same disk turned by the quaternion e.
constexpr const char* kQuaternionDisk = R"(
name = "disk-quaternion"
coordinates = ["x", "y", "z", "e0", "e1", "e2", "e3"]
gravity = [0, 0, "-g"]

[parameters]
m = 0.5
r = 0.2
g = 9.81

[[frames]]
name = "disk"
translation = ["x", "y", "z"]
rotations = "quaternion"
quaternion = ["e0", "e1", "e2", "e3"]

[[bodies]]
name = "disk"
frame = "disk"
mass = "m"
inertia = ["m*r^2/4", "m*r^2/2", "m*r^2/4"]

[[contacts]]
name = "disk"
body = "disk"
shape = { disk = "r", axis = "y" }

[initial]
position = { x = 0, y = 0, z = "r", e0 = 1, e1 = 0, e2 = 0, e3 = 0 }
)";

std::vector<double> forces_at(const Model& model, const std::vector<double>& q, const std::vector<double>& v) {
  Data data = dynamics_at(model, q, v);
  compute_contact_forces(model, data);
  EXPECT_LT(data.contact.residual, 1e-12);
  return {data.contact.values.data(), data.contact.values.data() + data.contact.values.size()};
}

// A state on the ground and rolling: z = r cos(theta), v_C = -omega x (P - C) with the rim point
// P - C = r (a (a . n) - n) / |a x n| (rolling-bodies.md section 2); also the axle a and omega.
struct RollingState {
  std::vector<double> q, v;
  Eigen::Vector3d axle, omega;
};

RollingState rolling_state(std::mt19937& rng) {
  RollingState s;
  const double psi = uniform(rng, -3, 3), theta = uniform(rng, -1.2, 1.2), phi = uniform(rng, -3, 3);
  const double dpsi = uniform(rng, -3, 3), dtheta = uniform(rng, -3, 3), dphi = uniform(rng, -8, 8);
  const Eigen::Matrix3d Rz = Eigen::AngleAxisd(psi, Eigen::Vector3d::UnitZ()).toRotationMatrix();
  const Eigen::Matrix3d Rzx = Rz * Eigen::AngleAxisd(theta, Eigen::Vector3d::UnitX()).toRotationMatrix();
  const Eigen::Vector3d n = Eigen::Vector3d::UnitZ();
  s.axle = Rzx.col(1);
  s.omega = dpsi * n + dtheta * Rz.col(0) + dphi * s.axle;
  const Eigen::Vector3d rim = kR * (s.axle * s.axle.dot(n) - n) / s.axle.cross(n).norm();
  const Eigen::Vector3d vC = -s.omega.cross(rim);
  s.q = {uniform(rng, -2, 2), uniform(rng, -2, 2), kR * std::cos(theta), psi, theta, phi};
  s.v = {vC(0), vC(1), vC(2), dpsi, dtheta, dphi};
  return s;
}

TEST(RollingAxleForces, DiskContactHasTheWheelsLongitudinalAndLateralForces) {
  const Model wheel = load_model_text(angle_disk_text("wheel"), "wheel.toml");
  const Model contact = load_model_text(angle_disk_text("rolling"), "contact.toml");
  const std::vector<std::string> columns = {"disk_Fx", "disk_Fy", "disk_Fz", "disk_N",
                                            "disk_Flong", "disk_Flat", "contact_residual"};
  ASSERT_EQ(contact_force_columns(contact), columns);
  ASSERT_EQ(contact_force_columns(wheel), columns);
  ASSERT_TRUE(contact.contact_forces->notes.empty()) << contact.contact_forces->notes.front();
  std::mt19937 rng(31);
  for (int trial = 0; trial < 10; ++trial) {
    const RollingState s = rolling_state(rng);
    const std::vector<double> w = forces_at(wheel, s.q, s.v), c = forces_at(contact, s.q, s.v);
    ASSERT_EQ(c.size(), 6u);
    const double scale = std::abs(w[3]) + std::abs(w[4]) + std::abs(w[5]);
    for (std::size_t k = 0; k < 6; ++k) EXPECT_NEAR(c[k], w[k], 1e-10 * scale) << columns[k] << " trial " << trial;
    // e_long = (a x n)/|a x n|, e_lat = n x e_long, the axle's projection onto the ground plane.
    const Eigen::Vector3d n = Eigen::Vector3d::UnitZ(), F(c[0], c[1], c[2]);
    const Eigen::Vector3d along = s.axle.cross(n).normalized(), across = n.cross(along);
    EXPECT_LT((across - (s.axle - s.axle.dot(n) * n).normalized()).norm(), 1e-14);
    EXPECT_NEAR(c[3], n.dot(F), 1e-12 * scale);
    EXPECT_NEAR(c[4], along.dot(F), 1e-12 * scale) << "trial " << trial;
    EXPECT_NEAR(c[5], across.dot(F), 1e-12 * scale) << "trial " << trial;
  }
}

// The angle state mapped to the quaternion model: e from the z-x-y angles (quaternion-frame.md
// (6.2)), e' = E(e)^T omega / 2 (6.1); the same centre and its velocity.
TEST(RollingAxleForces, DiskOnAQuaternionFrameHasTheSameForces) {
  const Model angles = load_model_text(angle_disk_text("rolling"), "contact.toml");
  const Model quaternion = load_model_text(kQuaternionDisk, "disk_quaternion.toml");
  ASSERT_EQ(contact_force_columns(quaternion), contact_force_columns(angles));
  ASSERT_TRUE(quaternion.contact_forces->notes.empty()) << quaternion.contact_forces->notes.front();
  std::mt19937 rng(37);
  for (int trial = 0; trial < 6; ++trial) {
    const RollingState s = rolling_state(rng);
    const Eigen::Quaterniond e = Eigen::AngleAxisd(s.q[3], Eigen::Vector3d::UnitZ()) *
                                 Eigen::AngleAxisd(s.q[4], Eigen::Vector3d::UnitX()) *
                                 Eigen::AngleAxisd(s.q[5], Eigen::Vector3d::UnitY());
    Eigen::Matrix<double, 3, 4> E;
    E << -e.x(), e.w(), -e.z(), e.y(),  //
        -e.y(), e.z(), e.w(), -e.x(),   //
        -e.z(), -e.y(), e.x(), e.w();
    const Eigen::Vector4d rate = 0.5 * E.transpose() * s.omega;
    const std::vector<double> qq = {s.q[0], s.q[1], s.q[2], e.w(), e.x(), e.y(), e.z()};
    const std::vector<double> vq = {s.v[0], s.v[1], s.v[2], rate(0), rate(1), rate(2), rate(3)};
    const std::vector<double> a = forces_at(angles, s.q, s.v), b = forces_at(quaternion, qq, vq);
    const double scale = std::abs(a[3]) + std::abs(a[4]) + std::abs(a[5]);
    for (std::size_t k = 0; k < 6; ++k) EXPECT_NEAR(b[k], a[k], 1e-10 * scale) << "column " << k << " trial " << trial;
  }
}

TEST(RollingAxleForces, RubberDiskReportsTheSpinMomentAfterTheAxleColumns) {
  const Model rubber = load_model_text(angle_disk_text("rubber"), "rubber.toml");
  const std::vector<std::string> columns = {"disk_Fx",   "disk_Fy",    "disk_Fz",         "disk_N",
                                            "disk_Flong", "disk_Flat", "disk_Mspin", "contact_residual"};
  EXPECT_EQ(contact_force_columns(rubber), columns);
}

}  // namespace
}  // namespace nhdyn::multibody_test

namespace nhdyn::multibody_test {
namespace {

// A wheel with a round tyre (a [[contacts]] torus: rim R, tube r) pushed along x at its centre by
// F, upright and from rest: it rolls on the tube's lowest point, at the distance rho = R + r below
// the axle, so x'' = F / (m + J/rho^2) with J its moment of inertia about the axle; the ground
// takes the rest of the push back, Flong = -(F - m x''), and holds its weight, N = m g, with no
// lateral force. A torus rolling on its rim's radius R (a thin disk's closed form) would give other
// numbers. Then at leaning, turning states: Flong and Flat are F's components along
// e_long = (a x n)/|a x n| and e_lat = n x e_long, as for the disk.
TEST(RollingAxleForces, TorusTyreHasTheClosedFormPushedUprightAndTheAxleComponentsLeaning) {
  const Model tyre = load_model_text(R"toml(
name = "torus-tyre"
coordinates = ["x", "y", "z", "psi", "theta", "phi"]
gravity = [0, 0, "-g"]

[parameters]
m = 2.0
R = 0.25
r = 0.06
g = 9.81
F = 3.0

[[frames]]
name = "wheel"
translation = ["x", "y", "z"]
rotations = [["z", "psi"], ["x", "theta"], ["y", "phi"]]

[[bodies]]
name = "wheel"
frame = "wheel"
mass = "m"
inertia = ["m*(R^2/2 + 5/8*r^2)", "m*(R^2 + 3/4*r^2)", "m*(R^2/2 + 5/8*r^2)"]

[[contacts]]
name = "tyre"
body = "wheel"
shape = { torus = ["R", "r"], axis = "y" }

[forces]
x = "F"

[initial]
position = { x = 0, y = 0, z = "R + r", psi = 0, theta = 0, phi = 0 }
)toml",
                                     "tyre.toml");
  const std::vector<std::string> columns = {"tyre_Fx", "tyre_Fy", "tyre_Fz", "tyre_N", "tyre_Flong", "tyre_Flat"};
  const std::vector<std::string> all = contact_force_columns(tyre);
  ASSERT_GE(all.size(), columns.size());
  for (std::size_t k = 0; k < columns.size(); ++k) ASSERT_EQ(all[k], columns[k]);
  const double m = 2.0, R = 0.25, r = 0.06, g = 9.81, F = 3.0, J = m * (R * R + 0.75 * r * r), rho = R + r;
  const double a = F / (m + J / (rho * rho));
  const Data data = dynamics_at(tyre, {0, 0, rho, 0, 0, 0}, {0, 0, 0, 0, 0, 0});
  EXPECT_NEAR(data.qdd(0), a, 1e-12);
  std::vector<double> c = forces_at(tyre, {0, 0, rho, 0, 0, 0}, {0, 0, 0, 0, 0, 0});
  EXPECT_NEAR(c[3], m * g, 1e-12);
  EXPECT_NEAR(c[4], -(F - m * a), 1e-12);
  EXPECT_NEAR(c[5], 0.0, 1e-12);
  // Leaning by theta and turning: the centre sits R cos(theta) + r above the ground, and the
  // contact point, the tube's lowest point, is R (a (a . n) - n)/|a x n| - r n from it.
  std::mt19937 rng(7);
  for (int trial = 0; trial < 5; ++trial) {
    const double psi = uniform(rng, -3, 3), theta = uniform(rng, -1.0, 1.0), phi = uniform(rng, -3, 3);
    const double dpsi = uniform(rng, -3, 3), dtheta = uniform(rng, -3, 3), dphi = uniform(rng, -8, 8);
    const Eigen::Matrix3d Rz = Eigen::AngleAxisd(psi, Eigen::Vector3d::UnitZ()).toRotationMatrix();
    const Eigen::Matrix3d Rzx = Rz * Eigen::AngleAxisd(theta, Eigen::Vector3d::UnitX()).toRotationMatrix();
    const Eigen::Vector3d n = Eigen::Vector3d::UnitZ(), axle = Rzx.col(1);
    const Eigen::Vector3d omega = dpsi * n + dtheta * Rz.col(0) + dphi * axle;
    const Eigen::Vector3d contact = R * (axle * axle.dot(n) - n) / axle.cross(n).norm() - r * n;
    const Eigen::Vector3d vC = -omega.cross(contact);
    c = forces_at(tyre, {0.3, -0.2, R * std::cos(theta) + r, psi, theta, phi}, {vC(0), vC(1), vC(2), dpsi, dtheta, dphi});
    const Eigen::Vector3d force(c[0], c[1], c[2]), along = axle.cross(n).normalized(), across = n.cross(along);
    const double scale = force.norm();
    ASSERT_GT(scale, 1.0);  // the weight at least: the identities below are not 0 = 0
    EXPECT_NEAR(c[3], n.dot(force), 1e-12 * scale);
    EXPECT_NEAR(c[4], along.dot(force), 1e-12 * scale) << "trial " << trial;
    EXPECT_NEAR(c[5], across.dot(force), 1e-12 * scale) << "trial " << trial;
  }
}

}  // namespace
}  // namespace nhdyn::multibody_test
