#include "nhdyn/symbolic/contact_forces.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <memory>
#include <string>
#include <utility>
#include <vector>

#include "nhdyn/core/error.hpp"
#include "nhdyn/symbolic/compile.hpp"
#include "nhdyn/symbolic/detail/derivative.hpp"
#include "nhdyn/symbolic/detail/occurrence.hpp"

namespace nhdyn::symbolic {
namespace {

void append(std::vector<GiNaC::ex>& out, const Vector3& v) { out.insert(out.end(), v.begin(), v.end()); }

Vector3 times(const GiNaC::matrix& I, const Vector3& w) {
  Vector3 out;
  for (unsigned i = 0; i < 3; ++i) out[i] = I(i, 0) * w[0] + I(i, 1) * w[1] + I(i, 2) * w[2];
  return out;
}

// By detail::derivative: GiNaC's derivative, 0 at once where a symbol does not occur.
Vector3 diff(const Vector3& v, const GiNaC::symbol& x) {
  return {detail::derivative(v[0], x), detail::derivative(v[1], x), detail::derivative(v[2], x)};
}

// d/dt of v(t, q, q') along the motion with q'' = 0: dv/dt + sum_i dv/dq_i q_i' (the part of the
// acceleration that does not multiply q''; the rest is (dv/dq') q'').
Vector3 drift(const Vector3& v, const SymbolTable& symbols) {
  Vector3 out = diff(v, symbols.time());
  for (int i = 0; i < symbols.coordinates(); ++i) out = add(out, scale(symbols.velocity(i), diff(v, symbols.coordinate(i))));
  return out;
}

// The row of b of a constraint (hand-written: an unknown multiplier along it in (C1)).
std::vector<GiNaC::ex> b_row(const Spec& spec, const SpecConstraint& c) {
  std::vector<GiNaC::ex> row;
  for (int j = 0; j < spec.n(); ++j) {
    switch (c.level) {
      case ConstraintLevel::position: row.push_back(detail::derivative(c.expression, spec.symbols.coordinate(j))); break;
      case ConstraintLevel::velocity: row.push_back(detail::derivative(c.expression, spec.symbols.velocity(j))); break;
      case ConstraintLevel::acceleration: row.push_back(detail::derivative(c.expression, spec.symbols.acceleration(j))); break;
    }
  }
  return row;
}

// The constraints that no contact helper wrote (hand-written rows of b, each an unknown of (C1)).
std::vector<const SpecConstraint*> hand_constraints(const Spec& spec, const SpecContactForces& in) {
  std::vector<const SpecConstraint*> hand;
  for (const SpecConstraint& con : spec.constraints)
    if (std::find(in.generated.begin(), in.generated.end(), con.name) == in.generated.end()) hand.push_back(&con);
  return hand;
}

// Whether the momentum balance (C3) describes every force on the bodies: not when T or V has
// hand-written parts, there are generalized forces or programs (actuator forces), or constraints
// that no contact helper wrote (forces at points nhdyn does not know). Empty when it does, else why not.
std::string why_balance_is_incomplete(const Spec& spec, const SpecContactForces& in,
                                      const std::vector<const SpecConstraint*>& hand) {
  bool forces = false;
  for (const GiNaC::ex& f : spec.forces) forces = forces || !f.is_zero();
  std::string why;
  if (in.other_energy) why = "the kinetic or potential energy has hand-written parts";
  else if (forces) why = "the model has generalized forces ([forces])";
  else if (spec.m() > 0) why = "the model has programs, whose actuator forces act on the bodies";
  else
    for (const SpecConstraint* con : hand)
      if (why.empty() && std::find(in.internal.begin(), in.internal.end(), con->name) == in.internal.end())
        why = fmt::format("the constraint '{}' is written by hand", con->name);
  return why;
}

// Per contact and unknown: J^T d (n), E d (6), d (3); fills the contacts' layout in c.
void append_contact_unknowns(const SpecContactForces& in, const SymbolTable& symbols, const GiNaC::ex& per_length,
                             ContactForceModel& c, std::vector<GiNaC::ex>& outputs) {
  const int n = c.n;
  int values = 0;  // result columns so far
  for (const ContactPoint& p : in.contacts) {
    ContactForceContact contact;
    contact.name = p.name;
    contact.kind = p.kind;
    contact.reported = p.kind == ContactKind::knife_edge || p.kind == ContactKind::rolling;
    contact.first_unknown = c.unknowns;
    contact.unknowns = static_cast<int>(p.directions.size()) + (p.spin ? 1 : 0);
    contact.system = std::max(p.system, 0);
    if (contact.reported) {
      contact.components = contact_components(p.kind, p.spin, p.axle);
      contact.first_value = values;
      values += static_cast<int>(contact.components.size());
    }
    const Vector3 arm =
        p.system >= 0 ? subtract(p.point, in.origins[static_cast<std::size_t>(p.system)]) : Vector3{0, 0, 0};
    for (const Vector3& d : p.directions) {
      const GiNaC::ex along = dot(p.velocity, d);
      for (int j = 0; j < n; ++j) outputs.push_back(detail::derivative(along, symbols.velocity(j)));
      if (p.system >= 0) {
        append(outputs, d);
        append(outputs, scale(per_length, cross(arm, d)));
      } else {
        for (int r = 0; r < 6; ++r) outputs.push_back(0);
      }
      append(outputs, d);
      c.unknown_system.push_back(contact.system);
      ++c.unknowns;
    }
    if (p.spin) {
      // A pure moment M n: its column (d omega/d q')^T n in (C1), [0; n / L] in (C3), no force.
      const GiNaC::ex about = dot(p.omega, p.normal);
      for (int j = 0; j < n; ++j) outputs.push_back(detail::derivative(about, symbols.velocity(j)));
      for (int r = 0; r < 3; ++r) outputs.push_back(0);
      if (p.system >= 0) append(outputs, scale(per_length, p.normal));
      else append(outputs, Vector3{0, 0, 0});
      append(outputs, Vector3{0, 0, 0});
      contact.spin_unknown = c.unknowns;
      c.unknown_system.push_back(contact.system);
      ++c.unknowns;
    }
    c.contacts.push_back(std::move(contact));
  }
}

// Per system s: K (6 x n, column-major) and k, the balance K q'' + k of the bodies of s about its origin.
void append_system_balance(const SpecContactForces& in, const SymbolTable& symbols, const GiNaC::ex& per_length,
                           int n, int s, std::vector<GiNaC::ex>& outputs) {
  const Vector3 O = s < static_cast<int>(in.origins.size()) ? in.origins[static_cast<std::size_t>(s)] : Vector3{0, 0, 0};
  std::vector<GiNaC::ex> K(static_cast<std::size_t>(6 * n), 0);
  Vector3 force{0, 0, 0}, moment{0, 0, 0};
  for (const ContactBody& b : in.bodies) {
    if (b.system != s) continue;
    const Vector3 arm = subtract(b.centre, O);
    const Vector3 velocity = time_derivative(b.centre, symbols);
    for (int j = 0; j < n; ++j) {
      // m_B dv_B/dq_j' = m_B dr_B/dq_j: the column of q_j'' in m_B a_B.
      const Vector3 Jv = scale(b.mass, diff(b.centre, symbols.coordinate(j)));
      const Vector3 Jw = diff(b.omega, symbols.velocity(j));
      const Vector3 m = add(cross(arm, Jv), times(b.inertia, Jw));
      for (int r = 0; r < 3; ++r) {
        K[static_cast<std::size_t>(6 * j + r)] += Jv[static_cast<std::size_t>(r)];
        K[static_cast<std::size_t>(6 * j + 3 + r)] += per_length * m[static_cast<std::size_t>(r)];
      }
    }
    const Vector3 a0 = subtract(drift(velocity, symbols), in.gravity);  // a_B - g without q''
    const Vector3 ma = scale(b.mass, a0);
    force = add(force, ma);
    const Vector3 Iw = times(b.inertia, b.omega);
    moment = add(moment, add(add(cross(arm, ma), times(b.inertia, drift(b.omega, symbols))), cross(b.omega, Iw)));
  }
  outputs.insert(outputs.end(), K.begin(), K.end());
  append(outputs, force);
  append(outputs, scale(per_length, moment));
}

}  // namespace

void compile_contact_forces(const Spec& spec, Model& model) {
  if (!spec.contact_forces || spec.contact_forces->contacts.empty()) return;
  const SpecContactForces& in = *spec.contact_forces;
  const SymbolTable& symbols = spec.symbols;
  const int n = spec.n();
  auto out = std::make_shared<ContactForceModel>();
  ContactForceModel& c = *out;
  c.n = n;
  c.systems = static_cast<int>(in.origins.size());
  c.system_names = in.system_names;
  c.length = in.length;
  const GiNaC::ex per_length = GiNaC::numeric(1.0 / in.length);

  const std::vector<const SpecConstraint*> hand = hand_constraints(spec, in);
  const std::string why = why_balance_is_incomplete(spec, in, hand);
  c.balance_rows.assign(static_cast<std::size_t>(c.systems), why.empty() ? 1 : 0);
  if (!why.empty())
    c.notes.push_back(fmt::format("the bodies' momentum balance is not used for the contact forces since {}: only "
                                  "what the reactions R determine is reported",
                                  why));
  c.hand_constraints = static_cast<int>(hand.size());

  std::vector<GiNaC::ex> outputs;
  append_contact_unknowns(in, symbols, per_length, c, outputs);
  if (c.systems == 0) {
    c.systems = 1;  // contacts on bodies fixed to the ground: one empty system keeps the layout
    c.system_names.push_back("ground");
    c.balance_rows.assign(1, 0);
  }
  for (int s = 0; s < c.systems; ++s) append_system_balance(in, symbols, per_length, n, s, outputs);
  // Per reported contact: n, e_long, e_lat.
  for (const ContactPoint& p : in.contacts) {
    if (p.kind != ContactKind::knife_edge && p.kind != ContactKind::rolling) continue;
    append(outputs, p.normal);
    append(outputs, p.longitudinal);
    append(outputs, p.lateral);
  }
  for (const SpecConstraint* con : hand) {
    const std::vector<GiNaC::ex> row = b_row(spec, *con);
    outputs.insert(outputs.end(), row.begin(), row.end());
  }
  // The shortcut needs the force's three world components as the only unknowns: a rolling
  // contact (a wheel is one) without a spin moment (rubber).
  c.single_contact = c.systems == 1 && c.contacts.size() == 1 && c.contacts.front().kind == ContactKind::rolling &&
                     c.contacts.front().unknowns == 3 && c.hand_constraints == 0 && c.balance_rows.front() &&
                     in.contacts.front().system == 0;
  std::vector<std::string> what(outputs.size());
  for (std::size_t i = 0; i < what.size(); ++i) what[i] = fmt::format("contact forces: output {}", i);
  c.tape = compile_expressions(spec, outputs, what);
  if (c.tape.outputs() != c.outputs())
    throw ModelError(fmt::format("model '{}': the contact-force tape has {} outputs, expected {} (a bug)",
                                 spec.name, c.tape.outputs(), c.outputs()));
  analyse_contact_forces(model, c);
  model.contact_forces = std::move(out);
}

std::vector<ContactForceSymbol> make_contact_force_symbols(const std::vector<ReportedContact>& reported) {
  std::vector<ContactForceSymbol> columns;
  for (const auto& [name, components] : reported)
    for (ContactComponent k : components) {
      const std::string column = name + "_" + contact_component_name(k);
      columns.push_back({column, static_cast<int>(columns.size()), GiNaC::symbol(column)});
    }
  return columns;
}

std::vector<int> contact_force_columns_in(const Spec& spec, const GiNaC::ex& e) {
  std::vector<int> found;
  if (!spec.contact_forces) return found;
  // One walk for all the columns, not a has() per column: the same leaves.
  const SymbolSet in = symbols_of(e);
  for (const ContactForceSymbol& c : spec.contact_forces->columns)
    if (in.count(c.symbol) > 0) found.push_back(c.column);
  return found;
}

void require_determined_contact_forces(const Spec& spec, const Model& model, const GiNaC::ex& e,
                                       const std::string& where, const std::string& what) {
  const std::vector<int> columns = contact_force_columns_in(spec, e);
  if (columns.empty()) return;
  const std::string at = where.empty() ? "" : where + ": ";
  const ContactForceModel* c = model.contact_forces.get();
  if (c == nullptr || static_cast<int>(c->determined.size()) != c->values() ||
      static_cast<int>(spec.contact_forces->columns.size()) != c->values())
    throw ModelError(fmt::format("{}{} reads the contact force '{}', but model '{}' has no such contact forces",
                                 at, what, spec.contact_forces->columns[static_cast<std::size_t>(columns.front())].name,
                                 model.name));
  for (int column : columns) {
    if (c->determined[static_cast<std::size_t>(column)]) continue;
    const std::string& name = spec.contact_forces->columns[static_cast<std::size_t>(column)].name;
    // The load's note on this contact says why (docs/multibody.md "When a column is NaN").
    std::string why;
    for (const std::string& note : c->notes)
      if (note.find(name) != std::string::npos) why = note;
    throw ModelError(fmt::format("{}{} reads the contact force '{}', which model '{}' does not determine: its column is "
                                 "NaN in every row{}, so the event could never cross zero; name a determined "
                                 "component (docs/multibody.md, \"When a column is NaN\")",
                                 at, what, name, model.name, why.empty() ? "" : " (" + why + ")"));
  }
}

}  // namespace nhdyn::symbolic
