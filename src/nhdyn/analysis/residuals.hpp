// The constraint residuals along a solution at the three levels, and the energy. In the Do Sanh
// form the acceleration-level residual e = b q'' + b0 is round-off by construction; what the
// solution violates at velocity and position level comes from the integration error alone and
// measures it (docs/notation.md §4, (2.14)).
#pragma once

#include "nhdyn/model/data.hpp"
#include "nhdyn/model/model.hpp"

namespace nhdyn {

// Requires compute_acceleration for the current state (Stage::acceleration). Writes data.phi
// (position-level constraints), data.f (position- and velocity-level constraints) and data.e
// (all constraints). Allocates nothing.
void compute_residuals(const Model& model, Data& data);

// Requires compute_terms. Writes data.energy when the model defines one (else leaves it 0).
void compute_energy(const Model& model, Data& data);

}  // namespace nhdyn
