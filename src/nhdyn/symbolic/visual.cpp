#include "nhdyn/symbolic/visual.hpp"

#include <fmt/format.h>

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>
#include <map>
#include <sstream>

#include "nhdyn/core/error.hpp"
#include "nhdyn/symbolic/spec.hpp"

namespace nhdyn::symbolic {
namespace {

std::string text_of(const GiNaC::ex& e) {
  std::ostringstream out;
  out << e;
  return out.str();
}

const char* kind_name(VisualKind kind) {
  switch (kind) {
    case VisualKind::sphere: return "sphere";
    case VisualKind::segment: return "segment";
    case VisualKind::wheel: return "wheel";
    case VisualKind::body: return "body";
    case VisualKind::frame: return "frame";
  }
  return "?";
}

// Expressions of one spec, parameters already replaced by their values, into one Program. The
// scene's expressions are short (a few positions and rotations), so this translation aims at being
// plain rather than at the smallest program: a subexpression met twice is computed once.
class Emitter {
 public:
  explicit Emitter(const Spec& spec) : spec_(spec), program_(spec.n()) {
    registers_.emplace(spec.symbols.time(), Program::time_register());
    for (int i = 0; i < spec.n(); ++i) {
      registers_.emplace(spec.symbols.coordinate(i), program_.coordinate_register(i));
      registers_.emplace(spec.symbols.velocity(i), program_.velocity_register(i));
    }
  }

  void output(const GiNaC::ex& e, const VisualItem& item) {
    item_ = &item;
    const GiNaC::ex value = numeric_form(e);
    if (GiNaC::is_exactly_a<GiNaC::numeric>(value)) {
      program_.add_constant_output(number(value, e));
      return;
    }
    program_.add_output(emit(value, e));
  }

  // The value of a size: parameters only.
  double constant(const GiNaC::ex& e, const VisualItem& item, const char* what) {
    item_ = &item;
    const GiNaC::ex value = numeric_form(e);
    if (!GiNaC::is_exactly_a<GiNaC::numeric>(value))
      fail(e, fmt::format("its {} must depend on the parameters only", what));
    return number(value, e);
  }

  Program take() { return std::move(program_); }

 private:
  GiNaC::ex numeric_form(const GiNaC::ex& e) const {
    try {
      return e.subs(spec_.parameter_values()).evalf();
    } catch (const std::exception& error) {
      fail(e, fmt::format("cannot be evaluated ({})", error.what()));
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
    throw ModelError(fmt::format("{}{}[visual] {} '{}': '{}' {}", item_->where, item_->where.empty() ? "" : ": ",
                                 kind_name(item_->kind), item_->name, text_of(e), why));
  }

  int emit(const GiNaC::ex& e, const GiNaC::ex& original) {
    const auto found = memo_.find(e);
    if (found != memo_.end()) return found->second;
    const int r = emit_new(e, original);
    memo_.emplace(e, r);
    return r;
  }

  int emit_new(const GiNaC::ex& e, const GiNaC::ex& original) {
    if (GiNaC::is_exactly_a<GiNaC::numeric>(e)) return program_.push_constant(number(e, original));
    if (GiNaC::is_a<GiNaC::symbol>(e)) {
      const auto found = registers_.find(e);
      if (found == registers_.end())
        fail(original, fmt::format("uses '{}', which is not t, a coordinate, a velocity or a parameter", text_of(e)));
      return found->second;
    }
    if (GiNaC::is_exactly_a<GiNaC::add>(e)) {
      int sum = emit(e.op(0), original);
      for (std::size_t i = 1; i < e.nops(); ++i) sum = program_.push(Op::add, sum, emit(e.op(i), original));
      return sum;
    }
    if (GiNaC::is_exactly_a<GiNaC::mul>(e)) {
      int product = emit(e.op(0), original);
      for (std::size_t i = 1; i < e.nops(); ++i) product = program_.push(Op::mul, product, emit(e.op(i), original));
      return product;
    }
    if (GiNaC::is_exactly_a<GiNaC::power>(e)) {
      const int base = emit(e.op(0), original);
      const GiNaC::ex exponent = e.op(1);
      if (GiNaC::is_exactly_a<GiNaC::numeric>(exponent)) {
        const double k = number(exponent, original);
        if (k == 0.5) return program_.push(Op::sqrt, base);
        if (k == std::round(k) && std::abs(k) <= 64.0) return program_.push(Op::powi, base, 0, 0, k);
        return program_.push(Op::pow_k, base, 0, 0, k);
      }
      return program_.push(Op::pow, base, emit(exponent, original));
    }
    if (GiNaC::is_a<GiNaC::function>(e)) {
      const std::string name = GiNaC::ex_to<GiNaC::function>(e).get_name();
      static const std::map<std::string, Op> unary = {
          {"sin", Op::sin},   {"cos", Op::cos},   {"tan", Op::tan},   {"exp", Op::exp},   {"log", Op::log},
          {"abs", Op::abs},   {"sqrt", Op::sqrt}, {"asin", Op::asin}, {"acos", Op::acos}, {"atan", Op::atan},
          {"sinh", Op::sinh}, {"cosh", Op::cosh}, {"tanh", Op::tanh}};
      const auto op = unary.find(name);
      if (op != unary.end() && e.nops() == 1) return program_.push(op->second, emit(e.op(0), original));
      if (name == "atan2" && e.nops() == 2)
        return program_.push(Op::atan2, emit(e.op(0), original), emit(e.op(1), original));
      fail(original, fmt::format("calls {}(), which the scene cannot evaluate", name));
    }
    fail(original, fmt::format("contains '{}', which is not a scalar expression", text_of(e)));
  }

  const Spec& spec_;
  Program program_;
  const VisualItem* item_ = nullptr;
  std::map<GiNaC::ex, int, GiNaC::ex_is_less> registers_;
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

// Semi-axes and principal directions of the uniform solid ellipsoid with the body's mass and
// inertia: I_1 = m (b^2 + c^2) / 5 and so on, hence a^2 = 5 (I_2 + I_3 - I_1) / (2 m). A body whose
// moments leave an axis at zero or below (a point mass, a thin rod) gets a tenth of its largest
// semi-axis there, so that it stays visible.
std::array<double, 3> equivalent_ellipsoid(double mass, const Eigen::Matrix3d& inertia, Eigen::Matrix3d& axes) {
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> solver(inertia);
  axes = solver.eigenvectors();
  if (axes.determinant() < 0.0) axes.col(2) = -axes.col(2);
  const Eigen::Vector3d I = solver.eigenvalues();
  std::array<double, 3> semi{};
  double largest = 0.0;
  for (int i = 0; i < 3; ++i) {
    const double square = 5.0 * (I((i + 1) % 3) + I((i + 2) % 3) - I(i)) / (2.0 * mass);
    semi[static_cast<std::size_t>(i)] = square > 0.0 ? std::sqrt(square) : 0.0;
    largest = std::max(largest, semi[static_cast<std::size_t>(i)]);
  }
  if (largest == 0.0) largest = 0.05;  // a point mass: a small ball
  for (double& a : semi) a = std::max(a, 0.1 * largest);
  return semi;
}

}  // namespace

int visual_outputs(VisualKind kind) {
  switch (kind) {
    case VisualKind::sphere: return 3;
    case VisualKind::segment: return 6;
    default: return 12;
  }
}

VisualScene compile_visual(const Spec& spec) {
  VisualScene scene;
  scene.planar = spec.visual.planar;
  scene.ground = spec.visual.ground;
  scene.angles.assign(static_cast<std::size_t>(spec.n()), false);
  mark_angles(spec, spec.kinetic_energy, scene.angles);
  mark_angles(spec, spec.potential_energy, scene.angles);
  for (const GiNaC::ex& f : spec.forces) mark_angles(spec, f, scene.angles);
  for (const SpecConstraint& c : spec.constraints) mark_angles(spec, c.expression, scene.angles);

  Emitter emitter(spec);
  int offset = 0;
  for (const VisualItem& item : spec.visual.items) {
    for (const GiNaC::ex& e : item.at) mark_angles(spec, e, scene.angles);
    for (const GiNaC::ex& e : item.other) mark_angles(spec, e, scene.angles);
    VisualShape shape;
    shape.kind = item.kind;
    shape.name = item.name;
    shape.offset = offset;
    shape.axis = item.axis;
    std::vector<GiNaC::ex> outputs = item.at;
    if (item.kind == VisualKind::sphere || item.kind == VisualKind::wheel) {
      const double radius = emitter.constant(item.size, item, "radius");
      if (!(radius > 0.0))
        throw ModelError(fmt::format("{}{}[visual] {} '{}': the radius must be positive; it is {}", item.where,
                                     item.where.empty() ? "" : ": ", kind_name(item.kind), item.name, radius));
      shape.size = {radius, radius, radius};
    }
    if (item.kind == VisualKind::body) {
      const double mass = emitter.constant(item.size, item, "mass");
      Eigen::Matrix3d inertia;
      for (int i = 0; i < 3; ++i)
        for (int j = 0; j < 3; ++j)
          inertia(i, j) = emitter.constant(item.inertia[static_cast<std::size_t>(3 * i + j)], item, "inertia");
      Eigen::Matrix3d axes;
      shape.size = mass > 0.0 ? equivalent_ellipsoid(mass, inertia, axes) : std::array<double, 3>{0.05, 0.05, 0.05};
      if (!(mass > 0.0)) axes.setIdentity();
      // R E: the ellipsoid's principal axes in world components.
      std::vector<GiNaC::ex> rotated(9);
      for (int i = 0; i < 3; ++i)
        for (int j = 0; j < 3; ++j) {
          GiNaC::ex sum = 0;
          for (int k = 0; k < 3; ++k)
            if (axes(k, j) != 0.0) sum += item.other[static_cast<std::size_t>(3 * i + k)] * GiNaC::numeric(axes(k, j));
          rotated[static_cast<std::size_t>(3 * i + j)] = sum;
        }
      outputs.insert(outputs.end(), rotated.begin(), rotated.end());
    } else {
      outputs.insert(outputs.end(), item.other.begin(), item.other.end());
    }
    if (static_cast<int>(outputs.size()) != visual_outputs(item.kind))
      throw ModelError(fmt::format("{}{}[visual] {} '{}': {} values given, {} expected", item.where,
                                   item.where.empty() ? "" : ": ", kind_name(item.kind), item.name, outputs.size(),
                                   visual_outputs(item.kind)));
    for (const GiNaC::ex& e : outputs) emitter.output(e, item);
    offset += visual_outputs(item.kind);
    scene.shapes.push_back(shape);
  }
  scene.program = emitter.take();
  return scene;
}

}  // namespace nhdyn::symbolic
