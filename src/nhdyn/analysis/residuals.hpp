// The constraint residuals along a solution at the three levels, the energy and its balance. In the Do Sanh
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

// Requires compute_terms. Writes data.energy when the model defines one (else leaves it 0), and
// data.energy_function (h, docs/derivations/energy-balance.md (E2)) when it has an energy balance.
void compute_energy(const Model& model, Data& data);

// Requires compute_acceleration (R must be current). Writes the three parts of the power (E3):
// data.power_forces = Q_nc . q' and data.power_time = -dL/dt|explicit from the model (0 where it
// has no energy balance), data.power_reactions = R . q'. Allocates nothing; O(n) beyond the
// model's power program, which a conservative model does not have.
void compute_power(const Model& model, Data& data);

// The energy balance of an output row, in the order of its CSV columns (io/results.hpp):
// h, P, W_forces, W_reactions, W_time, W, h - h(t0) - W. Reads what compute_energy,
// compute_power and simulate wrote into data.
inline constexpr int kEnergyBalanceColumns = 7;
void fill_energy_balance(const Data& data, double* out);

}  // namespace nhdyn
