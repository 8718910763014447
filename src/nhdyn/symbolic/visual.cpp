#include "nhdyn/symbolic/visual.hpp"

#include "nhdyn/symbolic/compile.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <map>
#include <optional>
#include <sstream>

#include "nhdyn/core/error.hpp"
#include "nhdyn/symbolic/detail/plain_words.hpp"
#include "nhdyn/symbolic/simplify.hpp"
#include "nhdyn/symbolic/spec.hpp"

namespace nhdyn::symbolic {
namespace {

std::string text_of(const GiNaC::ex& e) {
  std::ostringstream out;
  out << e;
  return out.str();
}

const char* kind_name(VisualKind kind) { return visual_kind_name(kind); }

// Expressions of one spec into one Tape whose `parameter` instructions read the parameters in
// the order of spec.parameters, so that the tape follows the values of the run it draws. The
// scene's expressions are short (a few positions and rotations), so this translation aims at being
// plain rather than at the smallest tape: a subexpression met twice is computed once. With
// `parameters_only` (the sizes) t, the coordinates and the velocities are refused.
class Emitter {
 public:
  Emitter(const Spec& spec, bool parameters_only)
      : tape_(parameters_only ? 0 : spec.n(), static_cast<int>(spec.parameters.size())),
        parameters_only_(parameters_only), spec_(parameters_only ? nullptr : &spec) {
    for (std::size_t i = 0; i < spec.parameters.size(); ++i)
      parameters_.emplace(spec.symbols.parameter(spec.parameters[i].name), static_cast<int>(i));
    variables_.emplace(spec.symbols.time(), parameters_only ? -1 : Tape::time_register());
    for (int i = 0; i < spec.n(); ++i) {
      variables_.emplace(spec.symbols.coordinate(i), parameters_only ? -1 : tape_.coordinate_register(i));
      variables_.emplace(spec.symbols.velocity(i), parameters_only ? -1 : tape_.velocity_register(i));
    }
  }

  // A field: a function of `variables` (in the places of the coordinates) and the parameters. A
  // variable may be a coordinate of the spec (an implicit shape's point): it is read as the
  // variable, and every other coordinate, t and the velocities are refused.
  Emitter(const Spec& spec, const std::vector<GiNaC::ex>& variables)
      : tape_(static_cast<int>(variables.size()), static_cast<int>(spec.parameters.size())),
        parameters_only_(true) {
    for (std::size_t i = 0; i < spec.parameters.size(); ++i)
      parameters_.emplace(spec.symbols.parameter(spec.parameters[i].name), static_cast<int>(i));
    for (std::size_t i = 0; i < variables.size(); ++i)
      variables_.emplace(variables[i], tape_.coordinate_register(static_cast<int>(i)));
    variables_.emplace(spec.symbols.time(), -1);
    for (int i = 0; i < spec.n(); ++i) {
      variables_.emplace(spec.symbols.coordinate(i), -1);
      variables_.emplace(spec.symbols.velocity(i), -1);
    }
  }

  // Compiles `e` into the next output; `what` names it in errors ("radius", "position").
  void output(const GiNaC::ex& e, const VisualItem& item, const char* what) {
    item_ = &item;
    what_ = what;
    const GiNaC::ex value = numeric_form(e);
    if (spec_) {
      checked_.push_back(e);
      whats_.emplace_back(what);
    }
    if (GiNaC::is_exactly_a<GiNaC::numeric>(value)) {
      tape_.add_constant_output(number(value, e));
      return;
    }
    tape_.add_output(emit(value, e));
  }

  // The positions' tape comes from the model's own compiler (compile.hpp), whose canonical form
  // orders every sum and product by a key of our own: emitted in GiNaC's order, which follows
  // where libginac is loaded, the scene's numbers differed in the last bits from run to run (a
  // report of the rattleback was not the same file twice). The walk above still checks every
  // expression, with the scene's messages. The sizes and fields keep this emitter's tape: numbers
  // of the parameters and of the field's variables, which no run-to-run test has caught differing.
  Tape take() { return spec_ ? compile_expressions(*spec_, checked_, whats_) : std::move(tape_); }

 private:
  // Numbers, pi and exact fractions as doubles; the parameters stay symbols.
  GiNaC::ex numeric_form(const GiNaC::ex& e) const {
    try {
      return e.evalf();
    } catch (const std::exception& error) {
      fail(e, fmt::format("cannot be evaluated: {}", plain_words(error.what())));
    }
  }

  double number(const GiNaC::ex& value, const GiNaC::ex& original) const {
    const GiNaC::numeric& x = GiNaC::ex_to<GiNaC::numeric>(value);
    if (!x.is_real()) fail(original, "is not a real number");
    const double d = x.to_double();
    if (!std::isfinite(d)) fail(original, "is not finite");
    return d;
  }

  [[noreturn]] void fail(const GiNaC::ex& e, const std::string& why) const {
    throw ModelError(fmt::format("{}{}[visual] {} '{}': {} '{}' {}", item_->where, item_->where.empty() ? "" : ": ",
                                 kind_name(item_->kind), item_->name, what_, text_of(e), why));
  }

  int emit(const GiNaC::ex& e, const GiNaC::ex& original) {
    const auto found = memo_.find(e);
    if (found != memo_.end()) return found->second;
    const int r = emit_new(e, original);
    memo_.emplace(e, r);
    return r;
  }

  int emit_new(const GiNaC::ex& e, const GiNaC::ex& original) {
    if (GiNaC::is_exactly_a<GiNaC::numeric>(e)) return tape_.push_constant(number(e, original));
    if (GiNaC::is_a<GiNaC::symbol>(e)) {
      const auto parameter = parameters_.find(e);
      if (parameter != parameters_.end()) return tape_.push_parameter(parameter->second);
      const auto variable = variables_.find(e);
      if (variable == variables_.end())
        fail(original, fmt::format("uses '{}', which is not t, a coordinate, a velocity or a parameter", text_of(e)));
      if (parameters_only_ && variable->second < 0)
        fail(original, fmt::format("uses '{}': a {} must depend on the parameters only", text_of(e), what_));
      return variable->second;
    }
    if (GiNaC::is_exactly_a<GiNaC::add>(e)) {
      int sum = emit(e.op(0), original);
      for (std::size_t i = 1; i < e.nops(); ++i) sum = tape_.push(Op::add, sum, emit(e.op(i), original));
      return sum;
    }
    if (GiNaC::is_exactly_a<GiNaC::mul>(e)) {
      int product = emit(e.op(0), original);
      for (std::size_t i = 1; i < e.nops(); ++i) product = tape_.push(Op::mul, product, emit(e.op(i), original));
      return product;
    }
    if (GiNaC::is_exactly_a<GiNaC::power>(e)) {
      const int base = emit(e.op(0), original);
      const GiNaC::ex exponent = e.op(1);
      if (GiNaC::is_exactly_a<GiNaC::numeric>(exponent)) {
        const double k = number(exponent, original);
        if (k == 0.5) return tape_.push(Op::sqrt, base);
        if (k == std::round(k) && k != 0.0 && std::abs(k) <= 64.0) return tape_.push(Op::powi, base, 0, 0, k);
        return tape_.push(Op::pow_k, base, 0, 0, k);
      }
      return tape_.push(Op::pow, base, emit(exponent, original));
    }
    if (GiNaC::is_a<GiNaC::function>(e)) {
      const std::string name = GiNaC::ex_to<GiNaC::function>(e).get_name();
      static const std::map<std::string, Op> unary = {
          {"sin", Op::sin},   {"cos", Op::cos},   {"tan", Op::tan},   {"exp", Op::exp},   {"log", Op::log},
          {"abs", Op::abs},   {"sqrt", Op::sqrt}, {"asin", Op::asin}, {"acos", Op::acos}, {"atan", Op::atan},
          {"sinh", Op::sinh}, {"cosh", Op::cosh}, {"tanh", Op::tanh}};
      const auto op = unary.find(name);
      if (op != unary.end() && e.nops() == 1) return tape_.push(op->second, emit(e.op(0), original));
      if (name == "atan2" && e.nops() == 2)
        return tape_.push(Op::atan2, emit(e.op(0), original), emit(e.op(1), original));
      fail(original, fmt::format("calls {}(), which the scene cannot evaluate", name));
    }
    fail(original, fmt::format("contains '{}', which is not a scalar expression", text_of(e)));
  }

  Tape tape_;
  bool parameters_only_ = false;
  const Spec* spec_ = nullptr;
  std::vector<GiNaC::ex> checked_;
  std::vector<std::string> whats_;
  const VisualItem* item_ = nullptr;
  const char* what_ = "";
  std::map<GiNaC::ex, int, GiNaC::ex_is_less> parameters_;  // parameter symbol -> its index
  std::map<GiNaC::ex, int, GiNaC::ex_is_less> variables_;   // t, q, q' -> input register (-1 for sizes)
  std::map<GiNaC::ex, int, GiNaC::ex_is_less> memo_;
};

// Marks the coordinates that appear inside sin, cos or tan of `e`.
void mark_angles(const Spec& spec, const GiNaC::ex& e, std::vector<bool>& angles) {
  if (GiNaC::is_a<GiNaC::function>(e)) {
    const std::string name = GiNaC::ex_to<GiNaC::function>(e).get_name();
    if (name == "sin" || name == "cos" || name == "tan") {
      for (int i = 0; i < spec.n(); ++i)
        if (e.has(spec.symbols.coordinate(i))) angles[static_cast<std::size_t>(i)] = true;
      return;
    }
  }
  for (std::size_t i = 0; i < e.nops(); ++i) mark_angles(spec, e.op(i), angles);
}

}  // namespace

int visual_outputs(VisualKind kind) {
  switch (kind) {
    case VisualKind::sphere:
    case VisualKind::track:
    case VisualKind::terrain:
    case VisualKind::surface: return 3;
    case VisualKind::segment: return 6;
    default: return 12;
  }
}

int visual_sizes(VisualKind kind) {
  switch (kind) {
    case VisualKind::sphere:
    case VisualKind::wheel:
    case VisualKind::terrain: return 1;
    case VisualKind::body: return 10;
    case VisualKind::ellipsoid: return 3;
    case VisualKind::torus: return 2;
    case VisualKind::surface: return 5;
    default: return 0;
  }
}

const char* visual_kind_name(VisualKind kind) {
  switch (kind) {
    case VisualKind::sphere: return "sphere";
    case VisualKind::segment: return "segment";
    case VisualKind::wheel: return "wheel";
    case VisualKind::body: return "body";
    case VisualKind::frame: return "frame";
    case VisualKind::ellipsoid: return "ellipsoid";
    case VisualKind::torus: return "torus";
    case VisualKind::solid: return "solid";
    case VisualKind::track: return "track";
    case VisualKind::terrain: return "terrain";
    case VisualKind::surface: return "surface";
    case VisualKind::plane: return "plane";
  }
  return "?";
}

namespace {

// The expressions of the spec's automatic outputs `item.at_outputs` (a contact point's NAME_X,
// NAME_Y, NAME_Z), or nothing when one is not there: the multibody builder leaves out an output
// whose name the user took, and the path is then not drawn rather than another quantity's.
std::optional<std::vector<GiNaC::ex>> output_expressions(const Spec& spec, const VisualItem& item) {
  std::vector<GiNaC::ex> out;
  for (const std::string& name : item.at_outputs) {
    const auto found = std::find_if(spec.outputs.begin(), spec.outputs.end(),
                                    [&](const SpecOutput& o) { return o.name == name && o.automatic; });
    if (found == spec.outputs.end()) return std::nullopt;
    out.push_back(found->expression);
  }
  return out;
}

// A plane item whose normal (R's third column) is +-z and that does not turn: the plane z = 0,
// which the scene's grid draws.
bool level_and_fixed(const VisualItem& plane) {
  return plane.other.size() == 9 && symbolic::is_zero(plane.other[2]) && symbolic::is_zero(plane.other[5]) &&
         symbolic::is_zero(plane.other[8] * plane.other[8] - 1) && symbolic::is_zero(plane.field);
}

bool same_plane(const VisualItem& a, const VisualItem& b) {
  if (a.other.size() != b.other.size()) return false;
  for (std::size_t i = 0; i < a.other.size(); ++i)
    if (!symbolic::is_zero(a.other[i] - b.other[i])) return false;
  return symbolic::is_zero(a.field - b.field);
}

// The items drawn, in their order: each distinct plane once, and no plane at all when every one is
// level and fixed (the grid in z = 0 shows it, as in a scene without plane items).
std::vector<const VisualItem*> drawn_items(const SpecVisual& visual) {
  const bool planes = std::any_of(visual.items.begin(), visual.items.end(), [](const VisualItem& item) {
    return item.kind == VisualKind::plane && !level_and_fixed(item);
  });
  std::vector<const VisualItem*> out;
  for (const VisualItem& item : visual.items) {
    if (item.kind == VisualKind::plane &&
        (!planes || std::any_of(out.begin(), out.end(), [&](const VisualItem* drawn) {
          return drawn->kind == VisualKind::plane && same_plane(*drawn, item);
        })))
      continue;
    out.push_back(&item);
  }
  return out;
}

}  // namespace

VisualScene compile_visual(const Spec& spec) {
  VisualScene scene;
  scene.planar = spec.visual.planar;
  scene.ground = spec.visual.ground;
  for (const SpecParameter& p : spec.parameters) scene.parameters.push_back(p.name);
  scene.angles.assign(static_cast<std::size_t>(spec.n()), false);
  mark_angles(spec, spec.kinetic_energy, scene.angles);
  mark_angles(spec, spec.potential_energy, scene.angles);
  for (const GiNaC::ex& f : spec.forces) mark_angles(spec, f, scene.angles);
  for (const SpecConstraint& c : spec.constraints) mark_angles(spec, c.expression, scene.angles);

  Emitter positions(spec, false), sizes(spec, true);
  int offset = 0, size_offset = 0;
  for (const VisualItem* drawn : drawn_items(spec.visual)) {
    const VisualItem& written = *drawn;
    VisualItem resolved;
    if (!written.at_outputs.empty()) {
      std::optional<std::vector<GiNaC::ex>> at = output_expressions(spec, written);
      if (!at) continue;
      resolved = written;
      resolved.at = std::move(*at);
    }
    const VisualItem& item = written.at_outputs.empty() ? written : resolved;
    for (const GiNaC::ex& e : item.at) mark_angles(spec, e, scene.angles);
    for (const GiNaC::ex& e : item.other) mark_angles(spec, e, scene.angles);
    VisualShape shape;
    shape.kind = item.kind;
    shape.name = item.name;
    shape.offset = offset;
    shape.size_offset = size_offset;
    shape.axis = item.axis;
    shape.where = item.where;
    shape.body = item.body;
    const std::size_t expected = static_cast<std::size_t>(visual_outputs(item.kind));
    if (item.at.size() + item.other.size() != expected ||
        (item.kind == VisualKind::body && item.inertia.size() != 9) ||
        (item.kind != VisualKind::body && item.kind != VisualKind::sphere && item.kind != VisualKind::wheel &&
         item.sizes.size() != static_cast<std::size_t>(visual_sizes(item.kind))))
      throw ModelError(fmt::format("{}{}[visual] {} '{}': {} values given, {} expected", item.where,
                                   item.where.empty() ? "" : ": ", kind_name(item.kind), item.name,
                                   item.at.size() + item.other.size(), expected));
    for (const GiNaC::ex& e : item.at) shape.expressions.push_back(text_of(e));
    for (const GiNaC::ex& e : item.other) shape.expressions.push_back(text_of(e));
    for (const GiNaC::ex& e : item.at) positions.output(e, item, "position");
    for (const GiNaC::ex& e : item.other) positions.output(e, item, item.kind == VisualKind::segment ? "position" : "rotation");
    if (item.kind == VisualKind::sphere || item.kind == VisualKind::wheel) {
      sizes.output(item.size, item, "radius");
      size_offset += 1;
    }
    if (item.kind == VisualKind::body) {
      sizes.output(item.size, item, "mass");
      for (const GiNaC::ex& e : item.inertia) sizes.output(e, item, "inertia");
      size_offset += 10;
    }
    if (item.kind != VisualKind::body && item.kind != VisualKind::sphere && item.kind != VisualKind::wheel) {
      for (const GiNaC::ex& e : item.sizes) sizes.output(e, item, "size");
      size_offset += visual_sizes(item.kind);
    }
    if (item.kind == VisualKind::solid || item.kind == VisualKind::terrain || item.kind == VisualKind::surface) {
      Emitter field(spec, item.field_variables);
      field.output(item.field, item, "surface");
      shape.field = field.take();
    }
    if (item.kind == VisualKind::plane && !symbolic::is_zero(item.field)) {
      Emitter rate(spec, item.field_variables);
      rate.output(item.field, item, "rate");
      shape.field = rate.take();
    }
    offset += visual_outputs(item.kind);
    scene.shapes.push_back(shape);
  }
  scene.tape = positions.take();
  scene.sizes = sizes.take();
  return scene;
}

}  // namespace nhdyn::symbolic
