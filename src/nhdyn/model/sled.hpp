// The sled (knife edge) on an inclined plane (Neimark-Fufaev; docs/notation.md section 6).
// q = (x, y, phi): contact point and heading; the centre of mass sits at distance a ahead of the
// contact point. Two variants:
//  - `sled`: centre-of-mass potential Pi = -m g sin(alpha) (x + a cos phi) and the constraint in
//    the regular form -sin(phi) x' + cos(phi) y' = 0 with D = [[cos phi, sin phi, 0], [0, 0, 1]]
//    (the paper's constraint and D times cos phi), valid at every heading;
//  - `sled-paper`: the paper's potential Pi = -m g sin(alpha) x, constraint y' - tan(phi) x' = 0
//    and D = [[1, tan phi, 0], [0, 0, 1]] exactly as printed (singular at phi = +-pi/2).
// Derivations: docs/derivations/sled.md.
#pragma once

#include "nhdyn/model/model.hpp"

namespace nhdyn {

struct SledParameters {
  double m = 1.0;                   // mass [kg]
  double a = 0.5;                   // contact point to centre of mass [m]
  double rho = 0.7;                 // radius of gyration about the contact point, rho > a [m]
  double alpha = 0.5235987755982988;  // plane inclination, pi/6 [rad]
  double g = 9.81;                  // gravity [m/s^2]
};

enum class SledVariant { centre_of_mass, paper };

Model make_sled_model(SledVariant variant = SledVariant::centre_of_mass, const SledParameters& p = {});

}  // namespace nhdyn
