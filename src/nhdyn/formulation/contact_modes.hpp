// The equations of motion of a model whose contacts may slide or be free (model/contact_modes.hpp):
// the Do Sanh form with the rows each contact's mode keeps, and for a sliding contact the
// modified complement of docs/derivations/contact-modes.md section 3,
//
//     [ D A ] q'' = [ D (Q + G) ],   D B~^T = 0,   b = the kept rows,                       (S4)
//     [  b  ]       [   -b0     ]
//
// where B~ is b with each sliding contact's gap row w_n replaced by w_n - mu_k w_s (w_s = e_s^T J,
// the no-slip rows along the slip direction): D annihilates the direction of the sliding contact's
// force N (n - mu_k e_s), b keeps its normal constraint. compute_acceleration (formulation.hpp)
// calls it for every Data whose model has contact modes, whatever the modes are (all rolling is
// the ordinary sanh form with D from a QR factorization of b^T).
#pragma once

#include "nhdyn/core/status.hpp"
#include "nhdyn/model/data.hpp"
#include "nhdyn/model/model.hpp"

namespace nhdyn {

// Requires compute_terms for the current state (dense path). Writes data.qdd, data.R, and in
// data.modes each contact's mu, N, friction F_t, slip s (tangent basis and world), the direction
// e_s used while sliding and the friction's power; data.power_friction. Cost: one QR of the n x r
// matrix B~^T (r kept rows) and one LU of n x n. Allocates only when the number of kept rows
// changed since the last call (a switch). A singular system (Painleve's paradox, section 3.3 of
// the derivation) returns Status::singular_system with data.failed_quantity naming the contact.
// With data.modes.defer_forces set and every contact rolling, writes q'' and R only (the
// ordinary sanh solve) and leaves the contact values to compute_mode_forces.
Status compute_mode_acceleration(const Model& model, Data& data);

// The contact values of the last compute_mode_acceleration when it deferred them (nothing when
// they are current): one QR of b^T for the multipliers. Requires that solve's state in data.
Status compute_mode_forces(const Model& model, Data& data);

}  // namespace nhdyn
