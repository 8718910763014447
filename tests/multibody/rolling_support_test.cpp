// The support mapping of the closed-form shapes for a direction of any length
// (docs/derivations/rolling-bodies.md section 2.1): the contact point and reach that a quaternion
// frame's contact takes from m = R_2(e)^T n, of length e.e, against the closed forms of section 2
// written here from the unit normal nu = R(e)^T n, at random quaternions off the unit sphere.
#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <random>
#include <string>

#include "nhdyn/symbolic/contact_shapes.hpp"
#include "nhdyn/symbolic/kinematics.hpp"

namespace nhdyn::multibody_test {
namespace {

using Vec3 = std::array<double, 3>;

double number(const GiNaC::ex& e) { return GiNaC::ex_to<GiNaC::numeric>(e.evalf()).to_double(); }

Vec3 numbers(const symbolic::Vector3& v) { return {number(v[0]), number(v[1]), number(v[2])}; }

double dot3(const Vec3& a, const Vec3& b) { return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]; }

// The unit normal in body axes, nu = R^T n with R the rotation of e / |e| written out here, and the
// shape's lowest point along it by the closed forms of section 2.
struct Expected {
  Vec3 point;
  double reach;
};

Expected closed_form(const std::string& shape, const Vec3& nu, const std::array<double, 3>& size, int axis) {
  if (shape == "sphere") return {{-size[0] * nu[0], -size[0] * nu[1], -size[0] * nu[2]}, size[0]};
  if (shape == "ellipsoid") {
    const double rho = std::sqrt(size[0] * size[0] * nu[0] * nu[0] + size[1] * size[1] * nu[1] * nu[1] +
                                 size[2] * size[2] * nu[2] * nu[2]);
    return {{-size[0] * size[0] * nu[0] / rho, -size[1] * size[1] * nu[1] / rho, -size[2] * size[2] * nu[2] / rho}, rho};
  }
  // Disk and torus: the rim point along the part of -nu normal to the axle, at the rim's radius.
  Vec3 rim = {-nu[0], -nu[1], -nu[2]};
  rim[static_cast<std::size_t>(axis)] = 0.0;
  const double across = std::sqrt(dot3(rim, rim));
  Expected out{{size[0] * rim[0] / across, size[0] * rim[1] / across, size[0] * rim[2] / across}, size[0] * across};
  if (shape == "torus") {
    for (std::size_t i = 0; i < 3; ++i) out.point[i] -= size[1] * nu[i];
    out.reach += size[1];
  }
  return out;
}

TEST(RollingSupport, DirectionOfAnyLengthGivesTheSamePointAndReach) {
  std::mt19937 random(25);
  std::uniform_real_distribution<double> uniform(-1.0, 1.0);
  const struct {
    std::string key;
    std::array<double, 3> size;
    int axis;
  } shapes[] = {{"sphere", {0.3, 0, 0}, -1},
                {"ellipsoid", {0.2, 0.03, 0.02}, -1},
                {"disk", {0.4, 0, 0}, 1},
                {"torus", {0.5, 0.07, 0}, 0}};
  for (int trial = 0; trial < 20; ++trial) {
    // e off the unit sphere (|e| from about 0.3 to 2), a unit ground normal n.
    symbolic::Quaternion e;
    for (GiNaC::ex& c : e) c = GiNaC::numeric(uniform(random) * (trial % 2 == 0 ? 1.0 : 1.9));
    Vec3 n = {uniform(random), uniform(random), uniform(random)};
    const double size_n = std::sqrt(dot3(n, n));
    for (double& x : n) x /= size_n;
    const symbolic::Vector3 n_ex = {n[0], n[1], n[2]};
    const GiNaC::ex length = symbolic::quaternion_squared_norm(e);
    const symbolic::Vector3 m = symbolic::multiply_transposed(symbolic::quaternion_rotation_polynomial(e), n_ex);
    const Vec3 nu = numbers(symbolic::multiply_transposed(symbolic::quaternion_rotation(e), n_ex));
    ASSERT_NEAR(dot3(nu, nu), 1.0, 1e-12);
    for (const auto& shape : shapes) {
      symbolic::ShapeValues values;
      for (int i = 0; i < 3 && shape.size[static_cast<std::size_t>(i)] > 0; ++i)
        values.sizes.push_back(GiNaC::numeric(shape.size[static_cast<std::size_t>(i)]));
      values.axis = shape.axis;
      const symbolic::ShapeSupport s = symbolic::find_contact_shape(shape.key)->support(values, m, length);
      const Expected want = closed_form(shape.key, nu, shape.size, shape.axis);
      const Vec3 point = numbers(s.point);
      for (std::size_t i = 0; i < 3; ++i)
        EXPECT_NEAR(point[i], want.point[i], 1e-13) << shape.key << " trial " << trial << " component " << i;
      EXPECT_NEAR(number(s.reach), want.reach, 1e-13) << shape.key << " trial " << trial;
      // The reach is -nu . y*: the point is where the plane touches.
      EXPECT_NEAR(number(s.reach), -dot3(nu, point), 1e-13) << shape.key << " trial " << trial;
    }
  }
}

}  // namespace
}  // namespace nhdyn::multibody_test
