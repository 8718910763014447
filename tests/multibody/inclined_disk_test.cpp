// Consistency: rotating the whole scene changes nothing. The rolling disk on a plane tilted by
// alpha about the y axis, with vertical gravity (the plane's normal (sin alpha, 0, cos alpha) is
// then opposite to no axis: the general normalization and tangent basis), against the disk on the
// horizontal plane z = 0 given explicitly (normal = [0, 0, 1]) with gravity tilted the other way.
// Same coordinates (in the plane), so q'' and R must agree at every state.
#include <gtest/gtest.h>

#include <cmath>
#include <random>
#include <string>
#include <vector>

#include "multibody/multibody_support.hpp"
#include "nhdyn/frontend/model_file.hpp"
#include "nhdyn/symbolic/compile.hpp"

namespace nhdyn::multibody_test {
namespace {

const std::string frames = R"TOML(
[parameters]
m = 0.5
r = 0.2
g = 9.81
alpha = 0.35

[[frames]]
name = "heading"
parent = "PARENT"
translation = ["x", "y", 0]
rotations = [["z", "psi"]]

[[frames]]
name = "lean"
parent = "heading"
rotations = [["x", "theta"]]

[[frames]]
name = "disk"
parent = "lean"
translation = [0, 0, "r"]
rotations = [["y", "phi"]]

[[bodies]]
name = "disk"
frame = "disk"
mass = "m"
inertia = ["m*r^2/4", "m*r^2/2", "m*r^2/4"]
)TOML";

std::string with_parent(const std::string& parent) {
  std::string text = frames;
  text.replace(text.find("PARENT"), 6, parent);
  return text;
}

TEST(InclinedDisk, TiltingThePlaneEqualsTiltingGravity) {
  // The plane frame, tilted by alpha about y, carries the disk's frames.
  std::string a = "name = \"tilted-plane\"\ncoordinates = [\"x\", \"y\", \"psi\", \"theta\", \"phi\"]\n"
                  "gravity = [0, 0, \"-g\"]\n" + with_parent("plane") +
                  "\n[[wheels]]\nname = \"disk\"\nbody = \"disk\"\naxis = \"y\"\nradius = \"r\"\n"
                  "normal = [\"sin(alpha)\", 0, \"cos(alpha)\"]\n";
  a.insert(a.find("[[frames]]"), "[[frames]]\nname = \"plane\"\nrotations = [[\"y\", \"alpha\"]]\n\n");
  const std::string tilted_gravity =
      "name = \"tilted-gravity\"\ncoordinates = [\"x\", \"y\", \"psi\", \"theta\", \"phi\"]\n"
      "gravity = [\"g*sin(alpha)\", 0, \"-g*cos(alpha)\"]\n" +
      with_parent("ground") + "\n[[wheels]]\nname = \"disk\"\nbody = \"disk\"\naxis = \"y\"\nradius = \"r\"\nnormal = [0, 0, 1]\n";
  const symbolic::Spec spec_a = load_model_string(a, "a.toml");
  const symbolic::Spec spec_b = load_model_string(tilted_gravity, "b.toml");
  ASSERT_EQ(spec_a.s(), 2);  // the contact holds identically in both
  ASSERT_EQ(spec_b.s(), 2);
  const Model model_a = symbolic::compile_model(spec_a), model_b = symbolic::compile_model(spec_b);
  std::mt19937 rng(23);
  for (int trial = 0; trial < 10; ++trial) {
    std::vector<double> q{uniform(rng, -2, 2), uniform(rng, -2, 2), uniform(rng, -3, 3), uniform(rng, -1, 1),
                          uniform(rng, -3, 3)};
    std::vector<double> v{0, 0, uniform(rng, -3, 3), uniform(rng, -3, 3), uniform(rng, -8, 8)};
    v[0] = 0.2 * v[4] * std::cos(q[2]);
    v[1] = 0.2 * v[4] * std::sin(q[2]);
    const Data da = dynamics_at(model_a, q, v), db = dynamics_at(model_b, q, v);
    EXPECT_LT((da.qdd - db.qdd).norm(), 1e-12 * db.qdd.norm()) << trial;
    EXPECT_LT((da.R - db.R).norm(), 1e-12 * db.R.norm()) << trial;
    // The heights differ by a constant only: T + V changes alike.
    EXPECT_NEAR(evaluate(spec_a, spec_a.kinetic_energy, q, v), evaluate(spec_b, spec_b.kinetic_energy, q, v), 1e-13);
  }
  // Negative control: the gravity tilted the wrong way is told apart.
  std::string wrong = tilted_gravity;
  wrong.replace(wrong.find("\"g*sin(alpha)\""), 14, "\"-g*sin(alpha)\"");
  const Model model_w = symbolic::compile_model(load_model_string(wrong, "w.toml"));
  const std::vector<double> q{0.1, 0.2, 0.7, 0.3, 0.1}, v{0.2 * 2 * std::cos(0.7), 0.2 * 2 * std::sin(0.7), 1, 0.5, 2};
  EXPECT_GT((dynamics_at(model_w, q, v).qdd - dynamics_at(model_a, q, v).qdd).norm(), 1e-3);
}

}  // namespace
}  // namespace nhdyn::multibody_test
