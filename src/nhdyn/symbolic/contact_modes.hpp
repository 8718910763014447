// The symbolic half of contacts that may slide or lift off (docs/contact-modes.md): the keys
// `friction`, `unilateral`, `restitution` and `mode` of a [[contacts]] entry parsed into a
// SpecContactMode (kept in the Spec beside the contact forces), and its compilation at load into
// model/contact_modes.hpp's ContactModeModel: the rows of b the contact's modes keep or drop,
// found by the names the contact's constraints have (NAME_contact, NAME_roll1, NAME_roll2,
// NAME_spin), and one program giving mu_s, mu_k, e, the normal and the two tangent directions.
//
//     ContactText::modes -> parse_contact_mode (MultibodyBuilder::contact) -> SpecContactMode
//         -> (add_contact: its directions) -> SpecContactForces::modes -> compile_contact_modes
#pragma once

#include <ginac/ginac.h>

#include <optional>
#include <string>

#include "nhdyn/model/model.hpp"
#include "nhdyn/symbolic/kinematics.hpp"
#include "nhdyn/symbolic/spec.hpp"

namespace nhdyn::symbolic {

struct ContactText;
struct ContactParsers;

struct SpecContactMode {
  std::string name;
  SourceLocation where;
  bool friction = false;         // a friction limit is given
  GiNaC::ex mu_s = 0, mu_k = 0;  // Coulomb's static and kinetic coefficients (parameters only)
  bool unilateral = false;
  GiNaC::ex restitution = 0;
  int initial = -1;              // ContactMode given by `mode`, or -1
  // The contact's directions (world; set by the multibody builder from the contact's geometry):
  // the ground's normal and the tangents of its no-slip rows.
  Vector3 normal = {0, 0, 0}, tangent1 = {0, 0, 0}, tangent2 = {0, 0, 0};
};

// The mode keys of `text` (ContactText::modes), checked: friction >= 0 (mu_s >= mu_k),
// 0 <= restitution <= 1, a known mode consistent with the other keys. nullopt when the entry has
// none of them (the contact rolls for ever, as before). Throws ModelError naming file:line.
std::optional<SpecContactMode> parse_contact_mode(const ContactText& text, const ContactParsers& parsers);

// The constraints that hold in every mode of the model's contacts: s less the rows some mode can
// drop (a unilateral contact's gap, no-slip and spin rows; a contact with friction alone its
// no-slip and spin rows). A model may declare n or more constraints when fewer than n always hold
// (a ball that rolls off a sphere onto a floor: two contacts never held at once); its modes then
// keep fewer than n rows at a time, or the run stops and says which contacts held together.
int constraints_always_held(const Spec& spec);

// Builds Model::contact_modes from spec.contact_forces->modes (nothing when there are none).
// Throws ModelError naming the contact when its gap is not a constraint row (a body held on the
// ground by its coordinates cannot lift off or carry its normal force in the equations). Called
// by compile_model once the evaluator exists.
void compile_contact_modes(const Spec& spec, Model& model);

}  // namespace nhdyn::symbolic
