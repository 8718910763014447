// Bad multibody descriptions in model files: each is refused with a ModelError that names the
// file and line, the name or value at fault, and what to do.
#include <gtest/gtest.h>

#include <string>

#include "nhdyn/core/error.hpp"
#include "nhdyn/frontend/model_file.hpp"

namespace nhdyn {
namespace {

// The rolling disk of examples/rolling_disk_bodies.toml in brief; tests replace one piece.
const std::string disk = R"(name = "disk"
coordinates = ["x", "y", "psi", "theta", "phi"]
gravity = [0, 0, "-g"]

[parameters]
m = 0.5
r = 0.2
g = 9.81

[[frames]]
name = "heading"
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

[[wheels]]
name = "disk"
body = "disk"
axis = "y"
radius = "r"
)";

std::string replaced(const std::string& from, const std::string& to) {
  std::string text = disk;
  const std::size_t at = text.find(from);
  EXPECT_NE(at, std::string::npos) << from;
  text.replace(at, from.size(), to);
  return text;
}

// The message of the ModelError that loading `text` throws ("" if none).
std::string error_of(const std::string& text) {
  try {
    load_model_string(text, "disk.toml");
  } catch (const ModelError& e) {
    return e.what();
  }
  return "";
}

void expect_error(const std::string& text, const std::vector<std::string>& parts) {
  const std::string message = error_of(text);
  ASSERT_FALSE(message.empty()) << "no error for:\n" << text;
  for (const std::string& part : parts) EXPECT_NE(message.find(part), std::string::npos) << message << "\n  lacks: " << part;
}

TEST(MultibodyBadInput, TheBriefDiskLoads) {
  EXPECT_EQ(error_of(disk), "");
  EXPECT_EQ(load_model_string(disk, "disk.toml").s(), 2);
}

TEST(MultibodyBadInput, InertiaNotPositiveDefinite) {
  expect_error(replaced("inertia = [\"m*r^2/4\", \"m*r^2/2\", \"m*r^2/4\"]", "inertia = [1, -1, 3]"),
               {"disk.toml:26:", "body 'disk'", "not positive definite", "[[1, 0, 0], [0, -1, 0], [0, 0, 3]]"});
  // Positive definite, but 1 + 1 < 3 breaks the triangle inequality of a rigid body's moments,
  // also when the axes are not principal.
  expect_error(replaced("inertia = [\"m*r^2/4\", \"m*r^2/2\", \"m*r^2/4\"]", "inertia = [1, 1, 3]"),
               {"disk.toml:26:", "body 'disk'", "triangle inequality"});
  expect_error(replaced("inertia = [\"m*r^2/4\", \"m*r^2/2\", \"m*r^2/4\"]",
                        "inertia = [[2, 0, 1], [0, 1, 0], [1, 0, 2]]"),  // moments 1, 1, 3
               {"disk.toml:26:", "triangle inequality"});
  // The thin disk is on the boundary (Iyy = Ixx + Izz) and is accepted: see TheBriefDiskLoads.
  expect_error(replaced("inertia = [\"m*r^2/4\", \"m*r^2/2\", \"m*r^2/4\"]", "inertia = [0, 1, 1]"),
               {"disk.toml:26:", "not positive definite"});
  expect_error(replaced("inertia = [\"m*r^2/4\", \"m*r^2/2\", \"m*r^2/4\"]", "inertia = [\"-m\", 1, 1]"),
               {"disk.toml:26:", "not positive definite"});
}

TEST(MultibodyBadInput, InertiaNotSymmetric) {
  expect_error(replaced("inertia = [\"m*r^2/4\", \"m*r^2/2\", \"m*r^2/4\"]",
                        "inertia = [[1, 0.1, 0], [0, 1, 0], [0, 0, 1]]"),
               {"disk.toml:26:", "not symmetric", "entry (1, 2)", "(2, 1)"});
}

TEST(MultibodyBadInput, MassNotPositive) {
  expect_error(replaced("mass = \"m\"", "mass = \"-m\""), {"disk.toml:26:", "body 'disk'", "positive"});
}

TEST(MultibodyBadInput, WheelWithoutContactPlane) {
  // No gravity and no normal.
  expect_error(replaced("gravity = [0, 0, \"-g\"]\n", ""), {"disk.toml:31:1:", "wheel 'disk'", "no ground plane", "normal = [0, 0, 1]"});
  // A zero normal.
  expect_error(replaced("radius = \"r\"", "radius = \"r\"\nnormal = [0, 0, 0]"),
               {"disk.toml:37:10:", "wheel 'disk'", "zero vector"});  // at the key
  // Zero gravity and no normal.
  expect_error(replaced("gravity = [0, 0, \"-g\"]", "gravity = [0, 0, 0]"),
               {"disk.toml:32:", "wheel 'disk'", "gravity vector is zero", "normal = [0, 0, 1]"});
}

TEST(MultibodyBadInput, RotationAboutAnUnknownAxis) {
  expect_error(replaced("rotations = [[\"x\", \"theta\"]]", "rotations = [[\"w\", \"theta\"]]"),
               {"disk.toml:18:", "frame 'lean'", "rotation 1", "unknown axis 'w'", "\"x\", \"y\" or \"z\""});
  expect_error(replaced("axis = \"y\"", "axis = \"q\""), {"disk.toml:32:", "wheel 'disk'", "unknown axis 'q'", "the axle is the \"x\", \"y\" or \"z\" axis"});
}

TEST(MultibodyBadInput, UnknownNamesSuggestTheNearest) {
  expect_error(replaced("parent = \"heading\"", "parent = \"heding\""),
               {"disk.toml:15:", "frame 'lean'", "'heding' is not a frame", "did you mean 'heading'?"});
  expect_error(replaced("frame = \"disk\"", "frame = \"dsk\""),
               {"disk.toml:26:", "body 'disk'", "'dsk' is not a frame", "did you mean 'disk'?"});
  expect_error(replaced("body = \"disk\"", "body = \"disc\""),
               {"disk.toml:32:", "wheel 'disk'", "'disc' is not a body", "did you mean 'disk'?"});
  expect_error(disk + "\n[[knife_edges]]\nname = \"blade\"\npoint = \"tip\"\naxis = \"x\"\n",
               {"disk.toml:38:", "knife edge 'blade'", "'tip' is not a point"});
  // An unknown symbol in an angle: the parser's own suggestion.
  expect_error(replaced("[\"x\", \"theta\"]", "[\"x\", \"thta\"]"), {"disk.toml:18:", "thta", "theta"});
}

TEST(MultibodyBadInput, DuplicateNames) {
  expect_error(replaced("name = \"lean\"", "name = \"heading\""),
               {"disk.toml:15:", "frame 'heading'", "already defined", "disk.toml:10:"});
  expect_error(disk + "\n[[bodies]]\nname = \"disk\"\nframe = \"lean\"\nmass = 1\ninertia = [1, 1, 1]\n",
               {"disk.toml:38:", "body 'disk'", "already defined"});
  expect_error(replaced("name = \"heading\"", "name = \"ground\""), {"disk.toml:10:", "frame 'ground'", "already defined"});
}

TEST(MultibodyBadInput, WrongTomlTypes) {
  expect_error(replaced("mass = \"m\"", "mass = true"), {"disk.toml:29:", "mass", "must be a number or an expression", "a boolean"});
  expect_error(replaced("translation = [0, 0, \"r\"]", "translation = [0, \"r\"]"),
               {"disk.toml:23:", "translation", "3 components"});
  expect_error(replaced("rotations = [[\"z\", \"psi\"]]", "rotations = [\"z\", \"psi\"]"),
               {"disk.toml:13:", "rotation 1", "must be an array"});
  expect_error(replaced("rotations = [[\"z\", \"psi\"]]", "rotations = [[\"z\", \"psi\", 1]]"),
               {"disk.toml:13:", "pair [axis, angle]"});
  expect_error(replaced("[[wheels]]", "[wheels]"), {"disk.toml:", "'wheels' must be an array"});
  expect_error(replaced("radius = \"r\"", "radius = \"r\"\nrdius = 1"), {"disk.toml:37:", "unknown key 'rdius'", "radius"});
  expect_error(replaced("name = \"disk\"\nframe", "frame"), {"disk.toml:26:", "[[bodies]]", "no 'name'"});
  expect_error(replaced("gravity = [0, 0, \"-g\"]", "gravity = 9.81"), {"disk.toml:3:", "'gravity' must be an array", "a floating-point number"});
  expect_error(replaced("inertia = [\"m*r^2/4\", \"m*r^2/2\", \"m*r^2/4\"]", "inertia = [1, 2]"),
               {"disk.toml:30:", "inertia", "3 principal moments or a 3 x 3 array"});
  expect_error(replaced("inertia = [\"m*r^2/4\", \"m*r^2/2\", \"m*r^2/4\"]", "inertia = [[1, 0, 0], [0, 1, 0], [0, 0]]"),
               {"disk.toml:30:", "row 3", "3 entries"});
  expect_error(replaced("axis = \"y\"", "axis = 2"), {"disk.toml:35:", "axis", "must be a string", "an integer"});
  expect_error(disk + "\n[[surfaces]]\nname = \"s\"\npoint = \"p\"\nsurface = 3\n", {"disk.toml:41:", "surface", "expression written as a string"});
}

TEST(MultibodyBadInput, VelocitiesInPlacementsAndCoordinatesInConstants) {
  expect_error(replaced("[\"z\", \"psi\"]", "[\"z\", \"psi'\"]"), {"disk.toml:13:", "frame 'heading'", "psi'"});
  expect_error(replaced("radius = \"r\"", "radius = \"r*theta\""), {"disk.toml:32:", "radius", "coordinate 'theta'"});
}

// A coordinate in a wheel's normal: named at the key, in the wheel's words (a wheel has no ground key).
TEST(MultibodyBadInput, ACoordinateInAWheelsNormal) {
  expect_error(replaced("radius = \"r\"", "radius = \"r\"\nnormal = [0, \"theta\", 1]"),
               {"disk.toml:37:10:", "wheel 'disk': plane normal:", "depends on the coordinate 'theta'"});
}

TEST(MultibodyBadInput, AWheelThatCannotTouchThePlane) {
  // The heading frame floats 1 m above the ground: n.P = 1 whatever the coordinates.
  expect_error(replaced("translation = [\"x\", \"y\", 0]", "translation = [\"x\", \"y\", 1]"),
               {"disk.toml:32:", "wheel 'disk'", "can never touch the ground", "the constant 1"});
}

}  // namespace
}  // namespace nhdyn
