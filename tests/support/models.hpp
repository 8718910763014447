// Small model files several test files load or write out, kept once: each is the smallest model
// that shows one behaviour, described where it is defined.
#pragma once

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

}  // namespace nhdyn::test
