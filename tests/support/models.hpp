// Small model files several test files load or write out, kept once: each is the smallest model
// that shows one behaviour, described where it is defined.
#pragma once

#include <string>

namespace nhdyn::test {

// A Chaplygin sleigh built from frames (x, y, theta keep it flat on the plane): its blade's normal
// force is not determined by the model (NaN with a note; the frames carry the part of the weight
// the one blade cannot, its centre of mass being ahead of the blade), its lateral force is.
inline constexpr const char* kFlatSledBodies = R"(name = "sled-bodies"
coordinates = ["x", "y", "theta"]
gravity = [0, 0, "-g"]

[parameters]
m = 2.0
a = 0.3
g = 9.81

[[frames]]
name = "sled"
translation = ["x", "y", 0]
rotations = [["z", "theta"]]

[[points]]
name = "blade"
frame = "sled"

[[bodies]]
name = "sled"
frame = "sled"
mass = "m"
com = ["a", 0, 0]
inertia = [0.05, 0.1, 0.1]

[[knife_edges]]
name = "blade"
point = "blade"
axis = "x"

[initial]
position = { x = 0, y = 0, theta = 0 }
velocity = { x = 1, theta = 0.5 }
)";

// A blade written as y' - tan(phi) x' = 0 on a body turning at the constant rate phi' = 1 (no
// force, centre of mass at the blade), so phi = t: the row of b grows as 1/|cos t| and is singular
// where phi crosses pi/2.
inline constexpr const char* kTanBlade = R"(name = "turning-blade"
coordinates = ["x", "y", "phi"]
kinetic_energy = "m/2 * (x'^2 + y'^2) + m*rho^2/2 * phi'^2"
[parameters]
m = 1.0
rho = 0.5
[[constraints]]
name = "blade"
velocity = "y' - tan(phi)*x'"
[initial]
position = { x = 0, y = 0, phi = 0 }
velocity = { x = 1, y = 0, phi = 1 }
)";

// A thin disk (m = 0.5, r = 0.2, g = 9.81, the moments of a uniform disk) whose centre (x, y, z)
// is free, turned by z-x-y angles (psi, theta, phi) with its axle along its frame's y axis, named
// `name`; `parameters` adds lines to [parameters], `entries` follows the body (the [[wheels]] or
// [[contacts]] entry that puts it on the ground), and [initial] starts it upright at the origin,
// its centre at height r, with `initial` added (a velocity = { ... } line).
inline std::string free_disk_text(const std::string& name, const std::string& parameters, const std::string& entries,
                                  const std::string& initial = "") {
  return "name = \"" + name + R"toml("
coordinates = ["x", "y", "z", "psi", "theta", "phi"]
gravity = [0, 0, "-g"]

[parameters]
m = 0.5
r = 0.2
g = 9.81
)toml" + parameters + R"toml(
[[frames]]
name = "disk"
translation = ["x", "y", "z"]
rotations = [["z", "psi"], ["x", "theta"], ["y", "phi"]]

[[bodies]]
name = "disk"
frame = "disk"
mass = "m"
inertia = ["m*r^2/4", "m*r^2/2", "m*r^2/4"]
)toml" + entries + R"toml(
[initial]
position = { x = 0, y = 0, z = "r", psi = 0, theta = 0, phi = 0 }
)toml" + initial;
}

// A solid ball (radius r, centre (x, y, z)) whose contact point on the terrain is (u, v, h(u, v)).
inline std::string ball_on_terrain(const std::string& terrain, const std::string& initial) {
  return R"toml(name = "ball-on-terrain"
coordinates = ["x", "y", "z", "u", "v", "psi", "theta", "phi"]
gravity = [0, 0, "-g"]

[parameters]
m = 1.5
r = 0.1
g = 9.81
alpha = 0.3
H = 0.05
w = 0.3

[[frames]]
name = "ball"
translation = ["x", "y", "z"]
rotations = [["z", "psi"], ["x", "theta"], ["y", "phi"]]

[[bodies]]
name = "ball"
frame = "ball"
mass = "m"
inertia = ["2/5*m*r^2", "2/5*m*r^2", "2/5*m*r^2"]

[[contacts]]
name = "ball"
body = "ball"
shape = { sphere = "r" }
ground = { terrain = ")toml" +
         terrain + R"toml(", coordinates = ["u", "v"] }

)toml" + initial;
}

}  // namespace nhdyn::test
