// The N-trailer chain (issue 5): N Chaplygin sleighs on a horizontal plane joined by pins, built
// in C++ for any N — as a Spec through SpecBuilder, or as the text of a model file that loads back
// into the same model (`nhdyn example chain --bodies N`). The derivation, the choice of coordinates
// and the exact checks are in docs/gallery/chain.md.
//
//     q = (x1, y1, theta1, ..., xN, yN, thetaN)      n = 3N
//     body i: blade contact point P_i = (x_i, y_i), heading theta_i, e1_i = (cos, sin)(theta_i);
//             centre of mass at P_i + a e1_i, front hitch at P_i + f e1_i, rear at P_i - r e1_i.
//     T = sum_i m/2 (x_i'^2 + y_i'^2) + m a theta_i' (cos(theta_i) y_i' - sin(theta_i) x_i')
//                + (J + m a^2)/2 theta_i'^2
//     blade_i:    -sin(theta_i) x_i' + cos(theta_i) y_i' = 0                       (N, velocity)
//     pin_i_x:    x_{i+1} + f cos(theta_{i+1}) - x_i + r cos(theta_i) = 0         (N-1, position)
//     pin_i_y:    y_{i+1} + f sin(theta_{i+1}) - y_i + r sin(theta_i) = 0         (N-1, position)
//     s = 3N - 2, k = 2: the lead's speed along its blade and its turning rate.
//
// Each constraint touches one body or two neighbours, and they are ordered body by body
// (blade1, pin1_x, pin1_y, blade2, ...), so b is block banded.
#pragma once

#include <string>

namespace nhdyn::symbolic {

struct Spec;  // spec.hpp: declared only, so that `nhdyn example chain` (write_chain_toml) sees no GiNaC

// Parameters shared by all bodies; the file's parameter names in brackets.
struct ChainParameters {
  int bodies = 3;              // N >= 1, at most kMaxChainBodies
  double mass = 1.0;           // [m] kg, each body
  double inertia = 0.1;        // [J] kg m^2, about the body's centre of mass (vertical axis)
  double com_offset = 0.2;     // [a] m, blade contact point to centre of mass, along the blade
  double front_hitch = 0.6;    // [f] m, blade contact point to the front hitch, ahead of it
  double rear_hitch = 0.3;     // [r] m, blade contact point to the rear hitch, behind it
  double speed = 1.0;          // [v0] m/s, initial speed of every body along its blade
  double turn_rate = 0.5;      // [w0] rad/s, initial turning rate of the lead (body 1)
  double t_end = 10.0;         // s, default end time of a simulation
};

// The largest chain the generator builds. The model file grows by about 0.5 kB a body (5 MB at
// the limit) and the derivation about linearly (docs/performance.md, "The figures"). A
// simulation with the dense solvers holds n x n matrices (n = 3N): make_data refuses a model whose
// dense matrices exceed the machine's memory (check_dense_memory), which on a machine of 24 GB is
// from about N = 4000 on; the sparse path (model/data.hpp) needs megabytes at the limit.
inline constexpr int kMaxChainBodies = 10000;

// Throws InputError naming the first bad value, its limit and what to do: bodies outside
// [1, kMaxChainBodies]; a mass, inertia, hitch distance or end time that is not positive and
// finite; an offset a that is negative or not finite; speeds that are not finite; the turning
// rates w0 (-r/f)^(i-1) down the chain overflowing (r much larger than f on a long chain).
void check_chain_parameters(const ChainParameters& p);

// The chain as a Spec: coordinates x1, y1, theta1, ...; parameters m, J, a, f, r, v0, w0; the
// initial state has every body on the x axis heading along +x (body i's blade at
// x = -(i-1)(f + r)), all moving at v0, the lead turning at w0 and body i at w0 (-r/f)^(i-1), as
// the pins require (docs/gallery/chain.md). The initial values are expressions in the parameters,
// so --set keeps them on the constraints. Checks the parameters first (check_chain_parameters).
Spec make_chain_spec(const ChainParameters& p);

// The same model as the text of a model file (docs/model-format.md), with a header comment saying
// how it was made; load_model_string of it gives a Spec equal to make_chain_spec(p).
std::string write_chain_toml(const ChainParameters& p);

}  // namespace nhdyn::symbolic
