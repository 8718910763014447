// Derived outputs from their expressions (model/output.hpp): a model file's [outputs] and a
// multibody model's automatic point and frame positions and velocities (SpecBuilder::output) are
// compiled into one tape of Model::outputs, in the "dynamics layout": a tape
// of 2n coordinates whose coordinate inputs are [q; q''] and velocity inputs [q'; R], so that an
// expression may read the accelerations and the generalized reactions R_x of a solved state. The
// parameters stay parameters (--set changes them without recompiling). Events whose expressions
// read q'' or R (through an output) are compiled the same way (symbolic/events.cpp), and those that
// read the contact forces in a layout with their columns too. Outputs may not read the contact
// forces (their tape's layout has no slots for them, and their columns are in the results
// already): compile_outputs refuses them.
#pragma once

#include <string>
#include <vector>

#include "nhdyn/model/model.hpp"
#include "nhdyn/symbolic/contact_forces.hpp"
#include "nhdyn/symbolic/multibody.hpp"
#include "nhdyn/symbolic/spec.hpp"
#include "nhdyn/symbolic/spec_builder.hpp"

namespace nhdyn::symbolic {

// Whether `e` contains an acceleration or a reaction of `spec`.
bool reads_dynamics(const Spec& spec, const GiNaC::ex& e);

// The expressions (in t, q, q', q'', R and the parameters of `spec`) as one tape in the
// dynamics layout, one output each; `what` names each in errors (ModelError). With `contact`
// (the symbols of the contact-force columns, SpecContactForces::columns) the tape is in the
// contact layout (model/event.hpp): 2n + contact.size() coordinates, the values of those columns
// after [q; q''] (and zeros after [q'; R]), so that an event may read NAME_N.
Tape compile_dynamics_tape(const Spec& spec, const std::vector<GiNaC::ex>& expressions,
                                 const std::vector<std::string>& what,
                                 const std::vector<ContactForceSymbol>& contact = {});

// A multibody model's automatic outputs (docs/multibody.md, "Positions and velocities"): for each
// named point, then each frame whose origin is not identically its parent's, the world position
// and velocity of it, columns NAME_x, NAME_y, NAME_z, NAME_vx, NAME_vy, NAME_vz. None when there
// are more than kMaxAutomaticOutputItems such points and frames (a wide model: write [outputs]
// for the ones wanted). A name that would clash with a coordinate, parameter, reaction or an
// earlier output is left out. `frames` and `points` in the order they were declared.
inline constexpr int kMaxAutomaticOutputItems = 32;
void add_multibody_outputs(SpecBuilder& builder, const MultibodyBuilder& multibody, const std::vector<std::string>& frames,
                           const std::vector<std::string>& points);

// Fills model.outputs from spec.outputs (an empty list and tape when there are none).
void compile_outputs(const Spec& spec, Model& model);

}  // namespace nhdyn::symbolic
