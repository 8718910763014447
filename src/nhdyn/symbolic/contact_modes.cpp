#include "nhdyn/symbolic/contact_modes.hpp"

#include <fmt/format.h>

#include <cmath>
#include <exception>
#include <memory>

#include "nhdyn/model/contact_modes.hpp"
#include "nhdyn/symbolic/compile.hpp"
#include "nhdyn/symbolic/contact_forces.hpp"
#include "nhdyn/symbolic/detail/contact_geometry.hpp"
#include "nhdyn/symbolic/rolling_contact.hpp"

namespace nhdyn::symbolic {
namespace {

std::string value_text(const std::optional<double>& v) { return v ? fmt::format("{:.6g}", *v) : "not a number"; }

}  // namespace

std::optional<SpecContactMode> parse_contact_mode(const ContactText& text, const ContactParsers& p) {
  if (text.modes.empty()) return std::nullopt;
  const std::string context = fmt::format("contact '{}'", text.name);
  SpecContactMode out;
  out.name = text.name;
  out.where = text.where;
  std::string mode;
  bool two = false;
  for (const auto& [key, value] : text.modes) {
    if (key == "friction" || key == "mu_s" || key == "mu_k") {
      const std::string what = key == "friction" ? "friction" : key == "mu_s" ? "friction[1] (mu_s)" : "friction[2] (mu_k)";
      const GiNaC::ex mu = p.constant(value, text.where, context + ": " + what);
      const std::optional<double> v = contact_number_of(mu, *p.spec);
      if (!v || *v < 0.0)
        throw_model_error(text.where, context,
                          fmt::format("{} = \"{}\" is {}; a Coulomb friction coefficient is a number >= 0 (e.g. "
                                      "friction = 0.3; leave the key out for a contact that never slips)",
                                      what, value, value_text(v)));
      out.friction = true;
      if (key != "mu_k") out.mu_s = mu;
      if (key != "mu_s") out.mu_k = mu;
      two = two || key != "friction";
    } else if (key == "unilateral") {
      out.unilateral = value == "true";
    } else if (key == "restitution") {
      out.restitution = p.constant(value, text.where, context + ": restitution");
      const std::optional<double> v = contact_number_of(out.restitution, *p.spec);
      if (!v || *v < 0.0 || *v > 1.0)
        throw_model_error(text.where, context,
                          fmt::format("restitution = \"{}\" is {}; Newton's coefficient of restitution is between 0 "
                                      "(a plastic impact) and 1 (an elastic one)",
                                      value, value_text(v)));
    } else if (key == "mode") {
      mode = value;
    }
  }
  if (two) {
    const std::optional<double> s = contact_number_of(out.mu_s, *p.spec), k = contact_number_of(out.mu_k, *p.spec);
    if (s && k && *s < *k)
      throw_model_error(text.where, context,
                        fmt::format("friction = [mu_s, mu_k] has mu_s = {:.6g} below mu_k = {:.6g}; the static "
                                    "coefficient must be at least the kinetic one (else a contact that sticks slips "
                                    "again at once)",
                                    *s, *k));
  }
  if (!mode.empty()) {
    if (mode == "rolling") out.initial = static_cast<int>(ContactMode::rolling);
    else if (mode == "sliding") out.initial = static_cast<int>(ContactMode::sliding);
    else if (mode == "free") out.initial = static_cast<int>(ContactMode::free);
    else
      throw_model_error(text.where, context,
                        fmt::format("unknown mode '{}'; the mode at t0 is \"rolling\", \"sliding\" or \"free\"", mode));
    if (out.initial == static_cast<int>(ContactMode::sliding) && !out.friction)
      throw_model_error(text.where, context,
                        "mode = \"sliding\" needs a friction coefficient (friction = 0.3): without one the contact "
                        "never slips");
    if (out.initial == static_cast<int>(ContactMode::free) && !out.unilateral)
      throw_model_error(text.where, context,
                        "mode = \"free\" needs unilateral = true: a bilateral contact never leaves the ground");
  }
  return out;
}

int constraints_always_held(const Spec& spec) {
  int held = spec.s();
  if (!spec.contact_forces) return held;
  for (const SpecContactMode& m : spec.contact_forces->modes)
    for (const SpecConstraint& c : spec.constraints) {
      const bool sliding_drops = c.name == m.name + "_roll1" || c.name == m.name + "_roll2" || c.name == m.name + "_spin";
      const bool free_drops = sliding_drops || c.name == m.name + "_contact";
      if ((m.friction && sliding_drops) || (m.unilateral && free_drops)) --held;
    }
  return held;
}

void compile_contact_modes(const Spec& spec, Model& model) {
  if (!spec.contact_forces || spec.contact_forces->modes.empty()) return;
  auto out = std::make_shared<ContactModeModel>();
  std::vector<GiNaC::ex> outputs;
  std::vector<std::string> what;
  for (const SpecContactMode& m : spec.contact_forces->modes) {
    ContactModeContact c;
    c.name = m.name;
    c.where = m.where.describe();
    c.friction = m.friction;
    c.unilateral = m.unilateral;
    c.initial = m.initial;
    int positions = 0, velocities = 0;
    for (int row = 0; row < model.s(); ++row) {
      const Constraint& con = model.constraints[static_cast<std::size_t>(row)];
      const std::string& name = con.name;
      if (name == m.name + "_contact") {
        c.gap = row;
        c.gap_position = positions;
        c.gap_velocity = velocities;
      } else if (name == m.name + "_roll1" || name == m.name + "_roll2") {
        const std::size_t a = name.back() == '1' ? 0 : 1;
        c.roll[a] = row;
        c.roll_velocity[a] = velocities;
      } else if (name == m.name + "_spin") {
        c.spin = row;
        c.spin_velocity = velocities;
      }
      if (con.level == ConstraintLevel::position) ++positions;
      if (con.level != ConstraintLevel::acceleration) ++velocities;
    }
    if (c.gap < 0)
      throw_model_error(m.where, fmt::format("contact '{}'", m.name),
                        "friction and unilateral need the contact's gap as a constraint, but the coordinates hold the "
                        "body on the ground (its gap is zero for every position); give the body a coordinate along "
                        "the ground's normal (its height), so that the contact adds NAME_contact "
                        "(docs/contact-modes.md)");
    if (c.roll[0] < 0 || c.roll[1] < 0)
      throw_model_error(m.where, fmt::format("contact '{}'", m.name),
                        "the contact has no pair of no-slip constraints NAME_roll1, NAME_roll2 (a bug)");
    out->contacts.push_back(c);
    for (const GiNaC::ex& e : {m.mu_s, m.mu_k, m.restitution}) outputs.push_back(e);
    for (const Vector3* v : {&m.normal, &m.tangent1, &m.tangent2})
      for (const GiNaC::ex& e : *v) outputs.push_back(e);
    for (int i = 0; i < ContactModeModel::kOutputs; ++i)
      what.push_back(fmt::format("contact '{}': mode output {}", m.name, i));
  }
  out->tape = compile_expressions(spec, outputs, what);
  model.contact_modes = std::move(out);
}

}  // namespace nhdyn::symbolic
