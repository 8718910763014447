// The symbolic half of the contact forces (docs/derivations/contact-forces.md section 4, method
// (b)): what the multibody front end (multibody.hpp) knows about its bodies and contacts, kept in
// the Spec, and its compilation at load into the tape of model/contact_forces.hpp — the columns
// J^T d and E d of every unknown, the momentum balance of every connected system as K q'' + k, and
// the directions n, e_long, e_lat of every wheel and knife edge — followed by the numeric check of
// step 5 (analyse_contact_forces), which marks what the model does not determine.
#pragma once

#include <ginac/ginac.h>

#include <string>
#include <utility>
#include <vector>

#include "nhdyn/model/contact_forces.hpp"
#include "nhdyn/model/model.hpp"
#include "nhdyn/symbolic/contact_modes.hpp"
#include "nhdyn/symbolic/kinematics.hpp"
#include "nhdyn/symbolic/spec.hpp"

namespace nhdyn::symbolic {

// A rigid body: mass, centre of mass r_B(t, q) and angular velocity omega_B (linear in q') in world
// components, inertia about the centre of mass in world components (R I R^T).
struct ContactBody {
  GiNaC::ex mass;
  Vector3 centre;
  Vector3 omega;
  GiNaC::matrix inertia = GiNaC::matrix(3, 3);
  int system = -1;  // -1: fixed to the ground (not in any balance)
};

// A contact: the material point P (world) with its velocity v_P (linear in q'), the world
// directions of its unknowns, and (wheels, knife edges, rolling bodies with an axle) the ground's
// normal n and e_long, e_lat.
struct ContactPoint {
  std::string name;
  ContactKind kind = ContactKind::rolling;
  Vector3 point;
  Vector3 velocity;
  std::vector<Vector3> directions;
  Vector3 normal, longitudinal, lateral;
  int system = -1;
  // Rubber rolling (docs/derivations/rolling-bodies.md section 5): one more unknown, the moment of
  // the ground about n, whose column in (C1) is (d omega / d q')^T n with omega the body's angular
  // velocity (world).
  bool spin = false;
  Vector3 omega = {0, 0, 0};
  // A rolling body whose shape has an axle (disk, torus): longitudinal and lateral are set and
  // reported as NAME_Flong, NAME_Flat (rolling-bodies.md section 5).
  bool axle = false;
};

// A contact-force column (NAME_Fx ... NAME_Flat of a wheel or knife edge, NAME_Fx ... NAME_Mspin of
// a rolling body) as a symbol, so that the expressions of events may name it (symbolic/events.hpp):
// `column` indexes ContactForceData::values (in the order of the CSV columns).
struct ContactForceSymbol {
  std::string name;
  int column = 0;
  GiNaC::symbol symbol;
};

struct SpecContactForces {
  std::vector<ContactBody> bodies;
  std::vector<ContactPoint> contacts;
  std::vector<Vector3> origins;           // per system: the origin of its first frame (the point O)
  std::vector<std::string> system_names;  // per system: that frame's name
  Vector3 gravity = {0, 0, 0};
  std::vector<std::string> generated;     // the constraints the contact helpers wrote
  // Constraints of the coordinates themselves (a quaternion frame's unit norm): their multipliers are
  // unknowns like a hand-written constraint's, but they act on no body, so the momentum balance stays.
  std::vector<std::string> internal;
  bool other_energy = false;              // T or V written by hand besides the bodies'
  double length = 1.0;                    // L [m], the largest contact's size (a wheel's radius; or 1)
  // The columns of the reported contacts as symbols (make_contact_force_symbols), for the
  // expressions of events; outputs may not read them (they are computed before the forces).
  std::vector<ContactForceSymbol> columns;
  // The contacts that may slide or lift off (contact_modes.hpp), in the order of [[contacts]].
  std::vector<SpecContactMode> modes;
};

// One symbol per column of each reported contact (its name and components, in order).
// MultibodyBuilder::apply() fills SpecContactForces::columns with it; the command line's events
// make them from a loaded Model's contacts (symbolic/events.cpp).
using ReportedContact = std::pair<std::string, std::vector<ContactComponent>>;
std::vector<ContactForceSymbol> make_contact_force_symbols(const std::vector<ReportedContact>& reported);

// The columns (ContactForceSymbol::column) of the contact-force symbols that `e` contains, in
// increasing order; empty when `spec` has no contact forces or `e` reads none.
std::vector<int> contact_force_columns_in(const Spec& spec, const GiNaC::ex& e);

// Throws ModelError (prefixed by `where` and naming `what`) when `e` reads a contact-force column
// that `model` does not determine (NaN in every row, ContactForceModel::determined), naming the
// column and why (the load's note).
void require_determined_contact_forces(const Spec& spec, const Model& model, const GiNaC::ex& e,
                                       const std::string& where, const std::string& what);

// Builds Model::contact_forces from spec.contact_forces (nothing when it is null or has no
// contact): compiles the tape, then checks it at a generic state (analyse_contact_forces).
// Called by compile_model once the evaluator exists.
void compile_contact_forces(const Spec& spec, Model& model);

}  // namespace nhdyn::symbolic
