// The model-file tables of the multibody front end that the rolling disk does not use —
// [[points]], [[knife_edges]], [[surfaces]], [[curves]], a full inertia tensor, a hand-written
// kinetic energy added to the bodies' — each against a closed form.
#include <gtest/gtest.h>

#include <cmath>
#include <random>
#include <string>
#include <vector>

#include "multibody/multibody_support.hpp"
#include "nhdyn/frontend/model_file.hpp"
#include "nhdyn/symbolic/compile.hpp"
#include "nhdyn/symbolic/simplify.hpp"

namespace nhdyn::multibody_test {
namespace {

TEST(MultibodyModelFile, KnifeEdgeAndAddedKineticEnergy) {
  // A skate whose blade runs along the frame's x axis, plus a flywheel written by hand (J phi'^2/2).
  const std::string text = R"TOML(name = "skate"
coordinates = ["x", "y", "phi"]
gravity = [0, 0, "-g"]
kinetic_energy = "J/2*phi'^2"
[parameters]
m = 2.0
g = 9.81
J = 0.5
[[frames]]
name = "skate"
translation = ["x", "y", 0]
rotations = [["z", "phi"]]
[[points]]
name = "contact"
frame = "skate"
[[bodies]]
name = "skate"
frame = "skate"
mass = "m"
inertia = [[0.01, 0, 0], [0, 0.02, 0], [0, 0, 0.03]]
[[knife_edges]]
name = "blade"
point = "contact"
axis = "x"
)TOML";
  const symbolic::Spec spec = load_model_string(text, "skate.toml");
  ASSERT_EQ(spec.s(), 1);
  EXPECT_EQ(spec.constraints[0].name, "blade");
  const GiNaC::ex& x = spec.symbols.velocity(0);
  const GiNaC::ex& y = spec.symbols.velocity(1);
  const GiNaC::ex& phi = spec.symbols.coordinate(2);
  EXPECT_TRUE(symbolic::is_zero(spec.constraints[0].expression - (-GiNaC::sin(phi) * x + GiNaC::cos(phi) * y)));
  // T = m/2 (x'^2 + y'^2) + (0.03 + J)/2 phi'^2.
  const GiNaC::ex expected =
      GiNaC::ex(1) * x * x + y * y + (GiNaC::numeric(3, 100) + GiNaC::numeric(1, 2)) / 2 * GiNaC::pow(spec.symbols.velocity(2), 2);
  const std::vector<double> q{0.3, -0.2, 0.7}, v{1.1, -0.4, 2.3};
  EXPECT_NEAR(evaluate(spec, spec.kinetic_energy, q, v), evaluate(spec, expected, q, v), 1e-14);
}

TEST(MultibodyModelFile, PointOnACurveIsUniformCircularMotion) {
  // A bead on the horizontal circle X^2 + Y^2 = R^2, Z = 0: q'' = -|v|^2/R^2 (X, Y, 0).
  const std::string text = R"TOML(name = "bead"
coordinates = ["X1", "Y1", "Z1"]
gravity = [0, 0, "-g"]
[parameters]
m = 0.3
g = 9.81
R = 0.8
[[frames]]
name = "bead"
translation = ["X1", "Y1", "Z1"]
[[bodies]]
name = "bead"
frame = "bead"
mass = "m"
inertia = [1, 1, 1]
[[points]]
name = "bead"
frame = "bead"
[[curves]]
name = "hoop"
point = "bead"
surfaces = ["X^2 + Y^2 - R^2", "Z"]
)TOML";
  const symbolic::Spec spec = load_model_string(text, "bead.toml");
  ASSERT_EQ(spec.s(), 2);
  EXPECT_EQ(spec.constraints[0].name, "hoop_1");
  EXPECT_EQ(spec.constraints[1].name, "hoop_2");
  const Model model = symbolic::compile_model(spec);
  std::mt19937 rng(17);
  for (int trial = 0; trial < 5; ++trial) {
    const double a = uniform(rng, -3, 3), w = uniform(rng, -4, 4);
    const std::vector<double> q{0.8 * std::cos(a), 0.8 * std::sin(a), 0.0};
    const std::vector<double> v{-0.8 * w * std::sin(a), 0.8 * w * std::cos(a), 0.0};
    const Data d = dynamics_at(model, q, v);
    EXPECT_NEAR(d.qdd(0), -w * w * q[0], 1e-12 * (1 + w * w));
    EXPECT_NEAR(d.qdd(1), -w * w * q[1], 1e-12 * (1 + w * w));
    EXPECT_NEAR(d.qdd(2), 0.0, 1e-12);
    // The hoop carries the weight: R = A q'' - Q - G has z component m g.
    EXPECT_NEAR(d.R(2), 0.3 * 9.81, 1e-12);
  }
}

TEST(MultibodyModelFile, PointOnASurface) {
  // A bead on the inclined plane Z = X tan(alpha), no friction: it accelerates down the slope at
  // g sin(alpha), i.e. X'' = -g sin(alpha) cos(alpha).
  const std::string text = R"TOML(name = "incline"
coordinates = ["X1", "Y1", "Z1"]
gravity = [0, 0, "-g"]
[parameters]
m = 0.3
g = 9.81
alpha = 0.4
[[frames]]
name = "bead"
translation = ["X1", "Y1", "Z1"]
[[bodies]]
name = "bead"
frame = "bead"
mass = "m"
inertia = [1, 1, 1]
[[points]]
name = "bead"
frame = "bead"
[[surfaces]]
name = "plane"
point = "bead"
surface = "Z - X*tan(alpha)"
)TOML";
  const Model model = symbolic::compile_model(load_model_string(text, "incline.toml"));
  const double t = std::tan(0.4);
  const Data d = dynamics_at(model, {1.0, 0.5, t}, {0.3, -0.2, 0.3 * t});
  EXPECT_NEAR(d.qdd(0), -9.81 * std::sin(0.4) * std::cos(0.4), 1e-12);
  EXPECT_NEAR(d.qdd(1), 0.0, 1e-12);
  EXPECT_NEAR(d.qdd(2), -9.81 * std::sin(0.4) * std::sin(0.4), 1e-12);
}

}  // namespace
}  // namespace nhdyn::multibody_test
