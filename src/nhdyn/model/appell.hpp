// Appell's particle (docs/notation.md section 6): a particle whose speed of fall is tied to its
// horizontal speed by the nonlinear nonholonomic constraint z'^2 = a^2 (x'^2 + y'^2); z points
// down. Hand-written from the paper, with the paper's acceleration-level constraint and analytic D.
// The closed-form solution it is tested against is derived in docs/derivations/appell.md.
#pragma once

#include "nhdyn/model/model.hpp"

namespace nhdyn {

struct AppellParameters {
  double m = 1.0;   // mass [kg]
  double g = 9.81;  // gravity [m/s^2]
  double a = 0.5;   // ratio of vertical to horizontal speed [-]
};

// Initial state: at the origin with horizontal velocity (1, 0.5) m/s and z' = a |(x', y')| > 0.
// The model carries its exact motion from that state (Evaluator::solution).
Model make_appell_model(const AppellParameters& p = {});

}  // namespace nhdyn
