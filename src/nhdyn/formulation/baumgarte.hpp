// Baumgarte stabilization (docs/stabilization.md §2): the acceleration-level constraint that the
// formulations solve, b q'' + b0 = 0, is replaced by
//     b q'' + b0 + 2 alpha f + beta^2 phi = 0    for a position constraint (f = phi'),
//     b q'' + b0 + 2 alpha f              = 0    for a velocity constraint,
//     b q'' + b0                          = 0    for an acceleration constraint,
// so that a residual left by the integrator decays like exp(-alpha t) instead of drifting.
// The gains are rates [1/s]; alpha = beta damps the position residual critically.
#pragma once

#include <string>

#include "nhdyn/core/status.hpp"
#include "nhdyn/model/data.hpp"
#include "nhdyn/model/model.hpp"

namespace nhdyn {

struct BaumgarteGains {
  bool enabled = false;
  double alpha = 10.0;  // [1/s], damping of the velocity residual
  double beta = 10.0;   // [1/s], stiffness of the position residual
};

// Throws InputError unless both gains are finite and non-negative, naming the gain and value.
void check_baumgarte_gains(const BaumgarteGains& gains);

// Requires compute_terms. Writes data.phi, data.f (at the current state) and
// data.stabilization = 2 alpha f + beta^2 phi per constraint (s). Allocates nothing.
void compute_baumgarte_terms(const Model& model, Data& data, const BaumgarteGains& gains);

}  // namespace nhdyn
