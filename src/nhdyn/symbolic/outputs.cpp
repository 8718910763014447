#include "nhdyn/symbolic/outputs.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cctype>
#include <sstream>

#include "nhdyn/core/error.hpp"
#include "nhdyn/symbolic/compile.hpp"
#include "nhdyn/symbolic/kinematics.hpp"

#include "nhdyn/symbolic/detail/occurrence.hpp"

namespace nhdyn::symbolic {

bool reads_dynamics(const Spec& spec, const GiNaC::ex& e) {
  // One walk for all the symbols, not a has() per symbol: the same leaves.
  const SymbolSet in = symbols_of(e);
  for (int i = 0; i < spec.symbols.coordinates(); ++i)
    if (in.count(spec.symbols.acceleration(i)) > 0 || in.count(spec.symbols.reaction(i)) > 0) return true;
  return false;
}

Tape compile_dynamics_tape(const Spec& spec, const std::vector<GiNaC::ex>& expressions,
                                 const std::vector<std::string>& what, const std::vector<ContactForceSymbol>& contact) {
  // A spec of 2n coordinates whose symbols stand for [q; q''] and, as their velocities, [q'; R]:
  // the compiler then maps them to the input registers of the dynamics layout.
  const int n = spec.n();
  Spec layout;
  layout.name = spec.name;
  GiNaC::exmap map;
  map[spec.symbols.time()] = layout.symbols.time();
  for (int i = 0; i < n; ++i) {
    const std::string& name = spec.coordinates[static_cast<std::size_t>(i)];
    layout.coordinates.push_back(name);
    const int j = layout.symbols.add_coordinate(name);
    map[spec.symbols.coordinate(i)] = layout.symbols.coordinate(j);
    map[spec.symbols.velocity(i)] = layout.symbols.velocity(j);
  }
  for (int i = 0; i < n; ++i) {
    const std::string name = spec.coordinates[static_cast<std::size_t>(i)] + "''";
    layout.coordinates.push_back(name);
    const int j = layout.symbols.add_coordinate(name);
    map[spec.symbols.acceleration(i)] = layout.symbols.coordinate(j);
    map[spec.symbols.reaction(i)] = layout.symbols.velocity(j);
  }
  // The contact layout: one more coordinate per contact-force column (its velocity slot unused).
  for (const ContactForceSymbol& c : contact) {
    layout.coordinates.push_back(c.name);
    const int j = layout.symbols.add_coordinate(c.name);
    map[c.symbol] = layout.symbols.coordinate(j);
  }
  layout.parameters = spec.parameters;
  for (const SpecParameter& p : spec.parameters) {
    layout.symbols.add_parameter(p.name);
    map[spec.symbols.parameter(p.name)] = layout.symbols.parameter(p.name);
  }
  std::vector<GiNaC::ex> mapped;
  mapped.reserve(expressions.size());
  // no_pattern: the keys are symbols, so a lookup per node finds them; GiNaC's default tries every
  // key as a pattern at every node.
  for (const GiNaC::ex& e : expressions) mapped.push_back(e.subs(map, GiNaC::subs_options::no_pattern));
  return compile_expressions(layout, mapped, what);
}

namespace {

// An expression as text the SpecBuilder reads back (GiNaC prints the constant pi as "Pi").
std::string readable(const GiNaC::ex& e) {
  std::ostringstream out;
  out << e;
  std::string text = out.str();
  const auto identifier = [](char c) { return std::isalnum(static_cast<unsigned char>(c)) || c == '_'; };
  for (std::size_t at = text.find("Pi"); at != std::string::npos; at = text.find("Pi", at + 2))
    if ((at == 0 || !identifier(text[at - 1])) && (at + 2 >= text.size() || !identifier(text[at + 2])))
      text.replace(at, 2, "pi");
  return text;
}

}  // namespace

void add_multibody_outputs(SpecBuilder& builder, const MultibodyBuilder& multibody, const std::vector<std::string>& frames,
                           const std::vector<std::string>& points) {
  struct Item {
    std::string name;
    Vector3 position;
    SourceLocation where;
  };
  std::vector<Item> items;
  for (const std::string& point : points) items.push_back({point, multibody.point_position(point), {}});
  for (const std::string& frame : frames) {
    const PlacedFrame& placed = multibody.placed_frame(frame);
    // A frame that only turns about its parent's origin (a lean, a spin) adds no new position.
    if (placed.parent >= 0) {
      bool same = true;
      const Vector3& parent = multibody.placed_frame_at(placed.parent).origin;
      for (std::size_t i = 0; i < 3; ++i) same = same && (placed.origin[i] - parent[i]).expand().is_zero();
      if (same) continue;
    }
    if (std::any_of(points.begin(), points.end(), [&](const std::string& p) { return p == frame; })) continue;
    items.push_back({frame, placed.origin, placed.where});
  }
  if (static_cast<int>(items.size()) > kMaxAutomaticOutputItems) return;
  static const char* const position_suffix[3] = {"_x", "_y", "_z"};
  static const char* const velocity_suffix[3] = {"_vx", "_vy", "_vz"};
  for (const Item& item : items) {
    const Vector3 velocity = time_derivative(item.position, builder.current().symbols);
    for (int pass = 0; pass < 2; ++pass)
      for (std::size_t i = 0; i < 3; ++i) {
        const GiNaC::ex& e = pass == 0 ? item.position[i] : velocity[i];
        const std::string name = item.name + (pass == 0 ? position_suffix[i] : velocity_suffix[i]);
        try {
          builder.output(name, e, readable(e), item.where, /*automatic=*/true);
        } catch (const ModelError&) {
          // The name is taken (a coordinate, a parameter, a reaction, an earlier output): left out.
        }
      }
  }
}

void compile_outputs(const Spec& spec, Model& model) {
  model.outputs = ModelOutputs{};
  if (spec.outputs.empty()) return;
  std::vector<GiNaC::ex> expressions;
  std::vector<std::string> what;
  for (const SpecOutput& o : spec.outputs) {
    const std::vector<int> contact = contact_force_columns_in(spec, o.expression);
    if (!contact.empty()) {
      const std::string at = o.where.describe();
      throw ModelError(fmt::format("{}output '{}' reads the contact force '{}': outputs cannot read the contact "
                                   "forces (their columns are in the results already); an event may name it "
                                   "(docs/model-format.md, [[events]])",
                                   at.empty() ? "" : at + ": ", o.name,
                                   spec.contact_forces->columns[static_cast<std::size_t>(contact.front())].name));
    }
    DerivedOutput out;
    out.name = o.name;
    out.expression = o.text;
    out.where = o.where.describe();
    out.automatic = o.automatic;
    out.dynamics = reads_dynamics(spec, o.expression);
    model.outputs.list.push_back(std::move(out));
    expressions.push_back(o.expression);
    what.push_back(fmt::format("{}output '{}'", o.where.describe().empty() ? "" : o.where.describe() + ": ", o.name));
  }
  model.outputs.tape = compile_dynamics_tape(spec, expressions, what);
}

}  // namespace nhdyn::symbolic
