#include "nhdyn/symbolic/multibody.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <exception>
#include <memory>
#include <sstream>
#include <utility>

#include "nhdyn/core/error.hpp"
#include "nhdyn/core/join.hpp"
#include "nhdyn/symbolic/simplify.hpp"
#include "nhdyn/core/detail/suggest.hpp"
#include "nhdyn/symbolic/detail/contact_geometry.hpp"
#include "nhdyn/symbolic/detail/derivative.hpp"

namespace nhdyn::symbolic {
namespace {

// "'heding' is not a frame; did you mean 'heading'? (the frames are: ground, heading)"
std::string unknown(const std::string& name, const char* kind, const std::vector<std::string>& known) {
  const std::string nearest = nearest_name(name, known);
  std::string out = fmt::format("'{}' is not a {}", name, kind);
  if (!nearest.empty()) out += fmt::format("; did you mean '{}'?", nearest);
  if (known.empty()) return out + fmt::format(" (none is defined yet: define a {} before using it)", kind);
  return out + fmt::format(" (the {}s defined so far: {})", kind, join(known));
}

int axis_index(const std::string& axis) {
  if (axis == "x") return 0;
  if (axis == "y") return 1;
  if (axis == "z") return 2;
  return -1;
}

std::string printed(const GiNaC::ex& e) {
  std::ostringstream out;
  out << e;
  return out.str();
}

// The value of an expression with the parameters set (and, at the reference configuration, every
// coordinate and t at 0); nullopt when it is not a finite real number.
std::optional<double> value_of(const GiNaC::ex& e, const Spec& spec, bool at_reference = false) {
  try {
    GiNaC::lst values = spec.parameter_values();
    if (at_reference) {
      values.append(spec.symbols.time() == 0);
      for (int i = 0; i < spec.n(); ++i) values.append(spec.symbols.coordinate(i) == 0);
    }
    const GiNaC::ex v = e.subs(values).evalf();
    if (!GiNaC::is_a<GiNaC::numeric>(v)) return std::nullopt;
    const GiNaC::numeric number = GiNaC::ex_to<GiNaC::numeric>(v);
    if (!number.is_real()) return std::nullopt;
    const double d = number.to_double();
    if (!std::isfinite(d)) return std::nullopt;
    return d;
  } catch (const std::exception&) {
    return std::nullopt;
  }
}

// The eigenvalues of a symmetric 3 x 3 matrix (the trigonometric closed form).
std::array<double, 3> principal_moments(const double (&A)[3][3]) {
  const double p1 = A[0][1] * A[0][1] + A[0][2] * A[0][2] + A[1][2] * A[1][2];
  if (p1 == 0.0) return {A[0][0], A[1][1], A[2][2]};
  const double q = (A[0][0] + A[1][1] + A[2][2]) / 3.0;
  const double p2 = (A[0][0] - q) * (A[0][0] - q) + (A[1][1] - q) * (A[1][1] - q) + (A[2][2] - q) * (A[2][2] - q) + 2.0 * p1;
  const double p = std::sqrt(p2 / 6.0);
  double B[3][3];
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) B[i][j] = (A[i][j] - (i == j ? q : 0.0)) / p;
  const double r = (B[0][0] * (B[1][1] * B[2][2] - B[1][2] * B[2][1]) - B[0][1] * (B[1][0] * B[2][2] - B[1][2] * B[2][0]) +
                    B[0][2] * (B[1][0] * B[2][1] - B[1][1] * B[2][0])) / 2.0;
  const double phi = r <= -1.0 ? std::acos(-1.0) / 3.0 : r >= 1.0 ? 0.0 : std::acos(r) / 3.0;
  const double e1 = q + 2.0 * p * std::cos(phi);
  const double e3 = q + 2.0 * p * std::cos(phi + 2.0 * std::acos(-1.0) / 3.0);
  return {e1, 3.0 * q - e1 - e3, e3};
}

}  // namespace

VisualItem frame_item(const PlacedFrame& frame, VisualKind kind, const SourceLocation& where) {
  VisualItem item;
  item.kind = kind;
  item.name = frame.name;
  item.where = where.describe();
  item.at.assign(frame.origin.begin(), frame.origin.end());
  for (unsigned i = 0; i < 3; ++i)
    for (unsigned j = 0; j < 3; ++j) item.other.push_back(frame.rotation(i, j));
  return item;
}

MultibodyBuilder::MultibodyBuilder(SpecBuilder& builder) : builder_(builder) {
  // A multibody model's scene stands on the ground's grid.
  builder_.visual_scene(builder_.current().visual.planar, true);
  PlacedFrame ground;
  ground.name = "ground";
  ground.origin = {0, 0, 0};
  ground.rotation = GiNaC::matrix{{1, 0, 0}, {0, 1, 0}, {0, 0, 1}};
  ground.rotation_numerator = ground.rotation;
  ground.omega = {0, 0, 0};
  ground.omega_local = {0, 0, 0};
  frames_.push_back(ground);
}

GiNaC::ex MultibodyBuilder::parse(const std::string& text, const SourceLocation& where, const std::string& context,
                                  bool coordinates_allowed) const {
  const GiNaC::ex e = builder_.parse(text, where);
  const Spec& spec = builder_.current();
  const SymbolTable& symbols = spec.symbols;
  for (int i = 0; i < spec.n(); ++i) {
    const std::string& name = spec.coordinates[static_cast<std::size_t>(i)];
    if (e.has(symbols.velocity(i)) || e.has(symbols.acceleration(i)))
      throw_model_error(where, context,
           fmt::format("\"{}\" contains a derivative of '{}'; positions, angles and constants may not contain "
                       "velocities or accelerations (the front end derives them)",
                       text, name));
    if (!coordinates_allowed && e.has(symbols.coordinate(i)))
      throw_model_error(where, context,
           fmt::format("\"{}\" depends on the coordinate '{}'; this value must be a constant, an expression in the "
                       "parameters only",
                       text, name));
  }
  if (!coordinates_allowed && e.has(symbols.time()))
    throw_model_error(where, context,
         fmt::format("\"{}\" depends on the time t; this value must be a constant, an expression in the parameters "
                     "only",
                     text));
  return e;
}

Vector3 MultibodyBuilder::parse(const Triple& texts, const SourceLocation& where, const std::string& context,
                                bool coordinates_allowed) const {
  return {parse(texts[0], where, context, coordinates_allowed), parse(texts[1], where, context, coordinates_allowed),
          parse(texts[2], where, context, coordinates_allowed)};
}

namespace {

// The index of the item called `name` among `items` (frames, points or bodies), or a failure that
// lists the known names of that kind.
template <class Items>
int index_in(const Items& items, const std::string& name, const char* kind, const SourceLocation& where,
             const std::string& context) {
  std::vector<std::string> known;
  for (std::size_t i = 0; i < items.size(); ++i) {
    if (items[i].name == name) return static_cast<int>(i);
    known.push_back(items[i].name);
  }
  throw_model_error(where, context, unknown(name, kind, known));
}

}  // namespace

int MultibodyBuilder::frame_index(const std::string& name, const SourceLocation& where,
                                  const std::string& context) const {
  return index_in(frames_, name, "frame", where, context);
}

int MultibodyBuilder::point_index(const std::string& name, const SourceLocation& where,
                                  const std::string& context) const {
  return index_in(points_, name, "point", where, context);
}

int MultibodyBuilder::body_index(const std::string& name, const SourceLocation& where,
                                 const std::string& context) const {
  return index_in(bodies_, name, "body", where, context);
}

namespace {

template <class Items>
void check_new(const Items& items, const std::string& name, const char* kind, const SourceLocation& where) {
  const std::string context = fmt::format("{} '{}'", kind, name);
  if (name.empty() || !std::isalpha(static_cast<unsigned char>(name[0])) ||
      !std::all_of(name.begin(), name.end(), [](char c) { return std::isalnum(static_cast<unsigned char>(c)) || c == '_'; }))
    throw_model_error(where, context, "not a valid name: use letters, digits and '_', starting with a letter");
  for (const auto& item : items)
    if (item.name == name) {
      const std::string first = item.where.describe();
      throw_model_error(where, context,
           fmt::format("a {} called '{}' is already defined{}; give each {} its own name", kind, name,
                       first.empty() ? "" : " (at " + first + ")", kind));
    }
}

}  // namespace

PlacedFrame MultibodyBuilder::child_frame(const std::string& name, const std::string& parent,
                                         const Triple& translation, SourceLocation where,
                                         const std::string& context) const {
  check_new(frames_, name, "frame", where);
  const int p = frame_index(parent, where, context + ": parent");
  const PlacedFrame& up = frames_[static_cast<std::size_t>(p)];
  PlacedFrame f;
  f.name = name;
  f.parent = p;
  f.where = where;
  f.origin = add(up.origin, multiply(up.rotation, parse(translation, where, context + ": translation", true)));
  f.rotation = up.rotation;
  f.rotation_numerator = up.rotation_numerator;
  f.rotation_denominator = up.rotation_denominator;
  f.omega = up.omega;
  f.omega_local = up.omega_local;
  return f;
}

MultibodyBuilder& MultibodyBuilder::frame(const std::string& name, const std::string& parent,
                                          const Triple& translation, const std::vector<FrameRotation>& rotations,
                                          SourceLocation where) {
  const std::string context = fmt::format("frame '{}'", name);
  PlacedFrame f = child_frame(name, parent, translation, where, context);
  const SymbolTable& symbols = builder_.current().symbols;
  for (std::size_t j = 0; j < rotations.size(); ++j) {
    const FrameRotation& r = rotations[j];
    const SourceLocation& at = r.where.line > 0 || r.where.file.size() > 0 ? r.where : where;
    const std::string which = fmt::format("{}: rotation {}", context, j + 1);
    const int axis = axis_index(r.axis);
    if (axis < 0)
      throw_model_error(at, which,
           fmt::format("unknown axis '{}'; rotate about \"x\", \"y\" or \"z\" (the axes of the frame produced by the "
                       "rotations before it)",
                       r.axis));
    const GiNaC::ex angle = parse(r.angle, at, which + " (its angle)", true);
    const GiNaC::ex rate = time_derivative(angle, symbols);
    // omega_F = omega_P + sum_j a_j' e_j with e_j the axis in world components before rotation j;
    // in the frame's own axes, omega <- R_j^T omega + a_j' k_j (docs/derivations/rolling-wheel.md).
    f.omega = add(f.omega, scale(rate, column(f.rotation, axis)));
    const GiNaC::matrix Rj = rotation_about(axis, angle);
    f.rotation = f.rotation.mul(Rj);
    f.rotation_numerator = f.rotation_numerator.mul(Rj);
    f.omega_local = add(multiply_transposed(Rj, f.omega_local), scale(rate, unit(axis)));
  }
  frames_.push_back(std::move(f));
  return *this;
}

int MultibodyBuilder::coordinate_index(const std::string& name, const SourceLocation& where,
                                       const std::string& context) const {
  const std::vector<std::string>& coordinates = builder_.current().coordinates;
  for (std::size_t i = 0; i < coordinates.size(); ++i)
    if (coordinates[i] == name) return static_cast<int>(i);
  const std::string nearest = nearest_name(name, coordinates);
  throw_model_error(where, context,
                    fmt::format("'{}' is not a coordinate of the model{}; list the quaternion's four components in "
                                "`coordinates` and name them here (the coordinates: {})",
                                name, nearest.empty() ? "" : fmt::format(" (did you mean '{}'?)", nearest),
                                coordinates.empty() ? std::string("none") : join(coordinates)));
}

MultibodyBuilder& MultibodyBuilder::quaternion_frame(const std::string& name, const std::string& parent,
                                                     const Triple& translation,
                                                     const std::array<std::string, 4>& quaternion,
                                                     SourceLocation where) {
  const std::string context = fmt::format("frame '{}'", name);
  PlacedFrame f = child_frame(name, parent, translation, where, context);
  const PlacedFrame& up = frames_[static_cast<std::size_t>(f.parent)];
  const SymbolTable& symbols = builder_.current().symbols;
  Quaternion e, rate;
  for (std::size_t k = 0; k < 4; ++k) {
    const int i = coordinate_index(quaternion[k], where, fmt::format("{}: quaternion component e{}", context, k));
    for (std::size_t j = 0; j < k; ++j)
      if (quaternion[j] == quaternion[k])
        throw_model_error(where, context,
                          fmt::format("the coordinate '{}' is named twice in the quaternion (as e{} and e{}); name "
                                      "four different coordinates",
                                      quaternion[k], j, k));
    for (const PlacedFrame& other : frames_)
      if (std::find(other.quaternion.begin(), other.quaternion.end(), i) != other.quaternion.end())
        throw_model_error(where, context,
                          fmt::format("the coordinate '{}' already holds the quaternion of frame '{}'; each "
                                      "quaternion frame needs four coordinates of its own",
                                      quaternion[k], other.name));
    f.quaternion.push_back(i);
    e[k] = symbols.coordinate(i);
    rate[k] = symbols.velocity(i);
  }
  // docs/derivations/quaternion-frame.md (3.2): R_F = R_P R(e), omega = omega_P + R_P 2 E(e) e',
  // omega_F = R(e)^T omega_P,F + 2 G(e) e'.
  const GiNaC::matrix Re = quaternion_rotation(e);
  f.rotation = up.rotation.mul(Re);
  f.rotation_numerator = up.rotation_numerator.mul(quaternion_rotation_polynomial(e));
  f.rotation_denominator = up.rotation_denominator * quaternion_squared_norm(e);
  f.omega = add(up.omega, multiply(up.rotation, quaternion_omega(e, rate)));
  f.omega_local = add(multiply_transposed(Re, up.omega_local), quaternion_omega_local(e, rate));
  frames_.push_back(std::move(f));
  return *this;
}

MultibodyBuilder& MultibodyBuilder::point(const std::string& name, const std::string& frame, const Triple& position,
                                          SourceLocation where) {
  const std::string context = fmt::format("point '{}'", name);
  check_new(points_, name, "point", where);
  const int f = frame_index(frame, where, context);
  const PlacedFrame& F = frames_[static_cast<std::size_t>(f)];
  const Vector3 local = parse(position, where, context + ": position", true);
  points_.push_back({name, f, add(F.origin, multiply(F.rotation, local)), where});
  return *this;
}

MultibodyBuilder& MultibodyBuilder::body(const std::string& name, const std::string& frame, const std::string& mass,
                                         const Triple& centre_of_mass, const InertiaText& inertia,
                                         SourceLocation where) {
  const std::string context = fmt::format("body '{}'", name);
  check_new(bodies_, name, "body", where);
  const Spec& spec = builder_.current();
  Body b;
  b.name = name;
  b.where = where;
  b.frame = frame_index(frame, where, context);
  b.mass = parse(mass, where, context + ": mass", false);
  const std::optional<double> m = value_of(b.mass, spec);
  if (!m || !(*m > 0.0))
    throw_model_error(where, context + ": mass",
         fmt::format("the mass \"{}\" must be a positive number, but it is {}", mass, m ? fmt::format("{}", *m) : "not a number"));
  builder_.positive_value(SpecPositive{where, context + ": mass", mass, b.mass});
  b.com = parse(centre_of_mass, where, context + ": centre of mass", false);
  b.inertia = GiNaC::matrix(3, 3);
  double I[3][3];
  for (unsigned i = 0; i < 3; ++i)
    for (unsigned j = 0; j < 3; ++j) {
      b.inertia(i, j) = parse(inertia[i][j], where, fmt::format("{}: inertia entry ({}, {})", context, i + 1, j + 1), false);
      const std::optional<double> value = value_of(b.inertia(i, j), spec);
      if (!value)
        throw_model_error(where, context, fmt::format("inertia entry ({}, {}) = \"{}\" is not a finite number", i + 1, j + 1,
                                         inertia[i][j]));
      I[i][j] = *value;
    }
  for (unsigned i = 0; i < 3; ++i)
    for (unsigned j = i + 1; j < 3; ++j)
      if (!symbolic::is_zero(b.inertia(i, j) - b.inertia(j, i)))
        throw_model_error(where, context,
             fmt::format("the inertia tensor is not symmetric: entry ({}, {}) is {} but entry ({}, {}) is {}; an "
                         "inertia tensor has I_ij = I_ji",
                         i + 1, j + 1, inertia[i][j], j + 1, i + 1, inertia[j][i]));
  // Sylvester's criterion; scale-free so that grams and tonnes are judged alike.
  const double d1 = I[0][0];
  const double d2 = I[0][0] * I[1][1] - I[0][1] * I[1][0];
  const double d3 = I[0][0] * (I[1][1] * I[2][2] - I[1][2] * I[2][1]) - I[0][1] * (I[1][0] * I[2][2] - I[1][2] * I[2][0]) +
                    I[0][2] * (I[1][0] * I[2][1] - I[1][1] * I[2][0]);
  const double size = std::max({std::fabs(I[0][0]), std::fabs(I[1][1]), std::fabs(I[2][2]), 1e-300});
  if (!(d1 > 0.0 && d2 > 1e-14 * size * size && d3 > 1e-14 * size * size * size))
    throw_model_error(where, context,
         fmt::format("the inertia tensor [[{}, {}, {}], [{}, {}, {}], [{}, {}, {}]] is not positive definite (its "
                     "leading principal minors are {:.6g}, {:.6g}, {:.6g}; all must be positive): every principal "
                     "moment must be positive and each at most the sum of the other two",
                     I[0][0], I[0][1], I[0][2], I[1][0], I[1][1], I[1][2], I[2][0], I[2][1], I[2][2], d1, d2, d3));
  // A rigid body's principal moments obey the triangle inequality (I1 = integral of y^2 + z^2
  // <= I2 + I3); equality is a planar lamina such as the thin disk.
  const std::array<double, 3> moments = principal_moments(I);
  for (std::size_t i = 0; i < 3; ++i) {
    const double others = moments[(i + 1) % 3] + moments[(i + 2) % 3];
    if (moments[i] > others + 1e-12 * size)
      throw_model_error(where, context,
           fmt::format("the inertia tensor's principal moments {:.6g}, {:.6g}, {:.6g} break the triangle inequality "
                       "({:.6g} > {:.6g} + {:.6g}): no rigid body has this inertia; check the moments and their "
                       "axes",
                       moments[0], moments[1], moments[2], moments[i], moments[(i + 1) % 3], moments[(i + 2) % 3]));
  }
  // The scene's ellipsoid of the body: its centre of mass, moving with its frame. Its expressions
  // are read again from the texts rather than taken from `b`: the scene's tape shares
  // subexpressions by identity (symbolic/visual.cpp), and this is the drawing a model file has
  // always had, to the last bit of the report's values.
  VisualItem item = frame_item(frames_[static_cast<std::size_t>(b.frame)], VisualKind::body, where);
  item.name = name;
  item.size = builder_.parse(mass, where);
  for (std::size_t i = 0; i < 3; ++i) {
    for (std::size_t j = 0; j < 3; ++j) {
      item.at[i] += item.other[3 * i + j] * builder_.parse(centre_of_mass[j], where);
      item.inertia.push_back(builder_.parse(inertia[i][j], where));
    }
  }
  builder_.visual_item(std::move(item));
  bodies_.push_back(std::move(b));
  return *this;
}

MultibodyBuilder& MultibodyBuilder::gravity(const Triple& g, SourceLocation where) {
  if (gravity_)
    throw_model_error(where, "gravity", fmt::format("gravity is given twice (first at {})", gravity_where_.describe()));
  gravity_ = parse(g, where, "gravity", false);
  gravity_where_ = std::move(where);
  return *this;
}

void MultibodyBuilder::check_helper_name(const std::string& name, const SourceLocation& where) const {
  check_new(helpers_, name, "constraint helper", where);
}

namespace {

// The drawing of a wheel's or a knife edge's own plane (their `normal`): the plane's axes t1, t2, n
// at the origin, as a [[contacts]] plane ground draws itself (rolling_contact.cpp); the report
// draws it in its own axes, and leaves a level one to its z = 0 grid (compile_visual).
VisualItem plane_item(const Vector3& n, const Spec& spec, const std::string& name, const SourceLocation& where) {
  const auto [t1, t2] = plane_tangents(n, spec);
  VisualItem item;
  item.kind = VisualKind::plane;
  item.name = name;
  item.where = where.describe();
  item.at = {0, 0, 0};
  for (std::size_t i = 0; i < 3; ++i) item.other.insert(item.other.end(), {t1[i], t2[i], n[i]});
  item.field_variables = {spec.symbols.time()};
  return item;
}
}  // namespace

ContactText wheel_contact_text(const std::string& name, const std::string& body, const std::string& axis,
                               const std::string& radius, const std::optional<Triple>& normal, SourceLocation where) {
  ContactText text;
  text.where = where;
  text.shape_where = where;
  text.name = name;
  text.body = body;
  // The wheel's rim: a thin disk of its radius about its axle, centred on the body frame's origin,
  // rolling without slip or spin limit on the plane through the world origin whose normal is
  // `normal` (or, without one, the opposite of gravity).
  text.shape = "disk";
  text.sizes = {radius};
  text.shape_options.emplace_back("axis", axis);
  text.ground.key = "plane";
  if (normal) text.ground.value.assign(normal->begin(), normal->end());
  text.ground.where = where;
  text.ground_where = where;
  text.rolling = "rolling";
  text.no_slip_suffix = "_slip";
  text.entry = "wheel";
  text.size_keys = {"radius"};
  return text;
}

MultibodyBuilder& MultibodyBuilder::rolling_wheel(const std::string& name, const std::string& body,
                                                  const std::string& axis, const std::string& radius,
                                                  const std::optional<Triple>& normal, SourceLocation where) {
  contact(wheel_contact_text(name, body, axis, radius, normal, where));
  if (normal) {  // a tilted plane is drawn in its axes; the level one is the report's grid
    const ParsedContact* parsed = parsed_contact(name);
    builder_.visual_item(plane_item(ground_plane_normal(parsed->ground, builder_.current(), gravity_,
                                                        fmt::format("wheel '{}'", name)),
                                    builder_.current(), name, where));
  }
  return wheel_drawing(name, body, axis, radius, std::move(where));
}

MultibodyBuilder& MultibodyBuilder::wheel_drawing(const std::string& name, const std::string& body,
                                                  const std::string& axis, const std::string& radius,
                                                  SourceLocation where) {
  const int index = body_index(body, where, fmt::format("wheel '{}'", name));
  VisualItem item =
      frame_item(frames_[static_cast<std::size_t>(bodies_[static_cast<std::size_t>(index)].frame)], VisualKind::wheel,
                 where);
  item.name = name;
  item.size = builder_.parse(radius, where);
  item.axis = axis == "x" ? 0 : axis == "y" ? 1 : 2;
  builder_.visual_item(std::move(item));
  return *this;
}

MultibodyBuilder& MultibodyBuilder::knife_edge(const std::string& name, const std::string& point,
                                               const std::string& axis, const std::optional<Triple>& normal,
                                               SourceLocation where) {
  const std::string context = fmt::format("knife edge '{}'", name);
  check_helper_name(name, where);
  Helper h;
  h.kind = Helper::Kind::knife_edge;
  h.name = name;
  h.where = where;
  h.index = point_index(point, where, context);
  h.axis = axis_index(axis);
  if (h.axis < 0)
    throw_model_error(where, context, fmt::format("unknown blade axis '{}'; the blade lies along the \"x\", \"y\" or \"z\" axis "
                                     "of the point's frame",
                                     axis));
  if (normal) h.normal = parse(*normal, where, context + ": normal", false);
  helpers_.push_back(std::move(h));
  if (helpers_.back().normal)
    builder_.visual_item(plane_item(plane_normal(helpers_.back(), context), builder_.current(), name, where));
  return *this;
}

GiNaC::ex MultibodyBuilder::parse_surface(const std::string& text, const Vector3& at, const SourceLocation& where,
                                          const std::string& context) const {
  // X, Y, Z are declared as extra parameters of a copy of the builder, then replaced by the point.
  SpecBuilder scratch = builder_;
  for (const char* name : {"X", "Y", "Z"})
    if (builder_.current().symbols.has(name))
      throw_model_error(where, context,
           fmt::format("a surface is written in the world coordinates X, Y, Z of the point, but '{}' is already a "
                       "coordinate or parameter of the model; rename it",
                       name));
  scratch.parameter("X", 0.0).parameter("Y", 0.0).parameter("Z", 0.0);
  const GiNaC::ex f = scratch.parse(text, where);
  const SymbolTable& symbols = scratch.current().symbols;
  for (int i = 0; i < scratch.current().n(); ++i)
    if (f.has(symbols.velocity(i)) || f.has(symbols.acceleration(i)))
      throw_model_error(where, context, fmt::format("the surface \"{}\" may not contain velocities or accelerations", text));
  return f.subs(GiNaC::lst{symbols.parameter("X") == at[0], symbols.parameter("Y") == at[1],
                           symbols.parameter("Z") == at[2]});
}

MultibodyBuilder& MultibodyBuilder::point_on_surface(const std::string& name, const std::string& point,
                                                     const std::string& surface, SourceLocation where) {
  const std::string context = fmt::format("surface constraint '{}'", name);
  check_helper_name(name, where);
  Helper h;
  h.kind = Helper::Kind::surface;
  h.name = name;
  h.where = where;
  h.index = point_index(point, where, context);
  h.surfaces.push_back(parse_surface(surface, points_[static_cast<std::size_t>(h.index)].world, where, context));
  helpers_.push_back(std::move(h));
  return *this;
}

MultibodyBuilder& MultibodyBuilder::point_on_curve(const std::string& name, const std::string& point,
                                                   const std::string& surface1, const std::string& surface2,
                                                   SourceLocation where) {
  const std::string context = fmt::format("curve constraint '{}'", name);
  check_helper_name(name, where);
  Helper h;
  h.kind = Helper::Kind::curve;
  h.name = name;
  h.where = where;
  h.index = point_index(point, where, context);
  const Vector3& at = points_[static_cast<std::size_t>(h.index)].world;
  h.surfaces.push_back(parse_surface(surface1, at, where, context + " (first surface)"));
  h.surfaces.push_back(parse_surface(surface2, at, where, context + " (second surface)"));
  helpers_.push_back(std::move(h));
  return *this;
}

Vector3 MultibodyBuilder::plane_normal(const Helper& helper, const std::string& context) const {
  Vector3 n;
  if (helper.normal) {
    n = *helper.normal;
  } else if (gravity_) {
    n = scale(-1, *gravity_);
  } else {
    throw_model_error(helper.where, context,
         "no contact plane: give the plane's normal (e.g. normal = [0, 0, 1] for the ground z = 0) or a gravity "
         "vector, whose opposite is then the normal");
  }
  const Spec& spec = builder_.current();
  std::array<double, 3> value{};
  for (std::size_t i = 0; i < 3; ++i) {
    const std::optional<double> v = value_of(n[i], spec);
    if (!v) throw_model_error(helper.where, context, fmt::format("the plane's normal component {} is not a number", i + 1));
    value[i] = *v;
  }
  const double length = std::sqrt(value[0] * value[0] + value[1] * value[1] + value[2] * value[2]);
  if (!(length > 0.0))
    throw_model_error(helper.where, context,
         helper.normal ? "the plane's normal is the zero vector; give a nonzero normal, e.g. [0, 0, 1]"
                       : "the gravity vector is zero, so it defines no contact plane; give the plane's normal, e.g. "
                         "normal = [0, 0, 1]");
  // A normal along an axis as written (its other two components zero, not only at the file's
  // parameter values: --set may change them) is kept exact (+-x, +-y, +-z); others are normalized
  // symbolically, so that the plane follows the parameters.
  for (std::size_t i = 0; i < 3; ++i)
    if (n[(i + 1) % 3].is_zero() && n[(i + 2) % 3].is_zero()) return scale(value[i] > 0 ? 1 : -1, unit(static_cast<int>(i)));
  const GiNaC::ex norm = GiNaC::sqrt(simplify(dot(n, n)));
  return {n[0] / norm, n[1] / norm, n[2] / norm};
}


void MultibodyBuilder::add_knife_edge(const Helper& h) {
  const std::string context = fmt::format("knife edge '{}'", h.name);
  const Spec& spec = builder_.current();
  const Point& p = points_[static_cast<std::size_t>(h.index)];
  const PlacedFrame& F = frames_[static_cast<std::size_t>(p.frame)];
  const Vector3 n = plane_normal(h, context);
  const Vector3 across = cross(n, column(F.rotation, h.axis));
  bool blade_in_plane = false;
  for (const GiNaC::ex& c : across) blade_in_plane = blade_in_plane || value_of(c, spec, true).value_or(1.0) != 0.0;
  if (!blade_in_plane)
    throw_model_error(h.where, context,
         "the blade is normal to the plane at the reference configuration (all coordinates 0): it must lie along the "
         "plane; choose another axis");
  const GiNaC::ex constraint = simplify_moderate(dot(across, time_derivative(p.world, spec.symbols)));
  builder_.constraint(h.name, ConstraintLevel::velocity, constraint,
                      fmt::format("knife edge '{}': no velocity across the blade", h.name), h.where);
  // The ideal blade takes no force along itself: unknowns along n and e_lat = (n x d)/|n x d|.
  ContactPoint contact;
  contact.name = h.name;
  contact.kind = ContactKind::knife_edge;
  contact.point = p.world;
  contact.velocity = time_derivative(p.world, spec.symbols);
  contact.normal = n;
  contact.lateral = scale(1 / GiNaC::sqrt(simplify(dot(across, across))), across);
  contact.longitudinal = cross(contact.lateral, n);
  contact.directions = {n, contact.lateral};
  contact.system = system_of(p.frame);
  contacts_.push_back(std::move(contact));
}

MultibodyBuilder& MultibodyBuilder::contact(const ContactText& text) {
  check_helper_name(text.name, text.where);
  ContactParsers parsers;
  parsers.spec = &builder_.current();
  parsers.constant = [this](const std::string& t, const SourceLocation& where, const std::string& context) {
    return parse(t, where, context, false);
  };
  parsers.of_time = [this](const std::string& t, const SourceLocation& where, const std::string& context) {
    const GiNaC::ex e = parse(t, where, context, true);
    const Spec& spec = builder_.current();
    for (int i = 0; i < spec.n(); ++i)
      if (e.has(spec.symbols.coordinate(i)))
        throw_model_error(where, context,
                          fmt::format("\"{}\" depends on the coordinate '{}'; this value may use t and the parameters "
                                      "only",
                                      t, spec.coordinates[static_cast<std::size_t>(i)]));
    return e;
  };
  parsers.surface = [this](const std::string& t, const Vector3& at, const SourceLocation& where,
                           const std::string& context) { return parse_surface(t, at, where, context); };
  parsers.body = [this](const std::string& name, const SourceLocation& where, const std::string& context) {
    return body_index(name, where, context);
  };
  parsers.add_coordinate = [this](const std::string& name, const SourceLocation& where) {
    builder_.coordinate(name, where);
    return builder_.current().n() - 1;
  };
  Helper h;
  h.kind = Helper::Kind::contact;
  h.name = text.name;
  h.where = text.where;
  h.contact = std::make_shared<const ParsedContact>(parse_contact(text, parsers));
  if (std::optional<SpecContactMode> mode = parse_contact_mode(text, parsers))
    h.mode = std::make_shared<const SpecContactMode>(std::move(*mode));
  h.index = h.contact->body;
  helpers_.push_back(std::move(h));
  return *this;
}

const ParsedContact* MultibodyBuilder::parsed_contact(const std::string& name) const {
  for (const Helper& h : helpers_)
    if (h.kind == Helper::Kind::contact && h.name == name) return h.contact.get();
  return nullptr;
}

void MultibodyBuilder::add_contact(const Helper& h) {
  const Body& body = bodies_[static_cast<std::size_t>(h.index)];
  const PlacedFrame& F = frames_[static_cast<std::size_t>(body.frame)];
  RollingContact contact = make_rolling_contact(*h.contact, F, builder_.current(), gravity_);
  for (const RollingContact::Row& row : contact.constraints)
    builder_.constraint(row.name, row.level, row.expression, row.text, h.where);
  static const char* const suffix[3] = {"_X", "_Y", "_Z"};
  for (std::size_t i = 0; i < 3; ++i) {
    try {
      builder_.output(h.name + suffix[i], contact.point[i], printed(contact.point[i]), h.where, /*automatic=*/true);
    } catch (const ModelError&) {
      // The name is taken (a coordinate, a parameter, an earlier output): left out.
    }
  }
  if (contact.convexity) builder_.convexity(std::move(*contact.convexity));
  if (contact.added) builder_.contact_coordinates(std::move(*contact.added));
  for (SpecContactWatch& watch : contact.watches) builder_.contact_watch(std::move(watch));
  for (const SpecPositive& size : h.contact->positive) builder_.positive_value(size);
  contact.force.system = system_of(body.frame);
  contacts_.push_back(std::move(contact.force));
  if (h.mode) {
    SpecContactMode mode = *h.mode;
    mode.normal = contact.normal;
    mode.tangent1 = contact.tangent1;
    mode.tangent2 = contact.tangent2;
    modes_.push_back(std::move(mode));
  }
}

GiNaC::ex MultibodyBuilder::kinetic_energy() const {
  // Left unexpanded: the nested products of the rotation chain are what GiNaC differentiates
  // fastest (gathering T as 1/2 M_ij q_i' q_j' with simplified M_ij was slower for the bicycle).
  const SymbolTable& symbols = builder_.current().symbols;
  GiNaC::ex T = 0;
  for (const Body& b : bodies_) {
    const PlacedFrame& F = frames_[static_cast<std::size_t>(b.frame)];
    const Vector3 vc = time_derivative(add(F.origin, multiply(F.rotation, b.com)), symbols);
    Vector3 Iw;
    for (unsigned i = 0; i < 3; ++i)
      Iw[i] = b.inertia(i, 0) * F.omega_local[0] + b.inertia(i, 1) * F.omega_local[1] +
              b.inertia(i, 2) * F.omega_local[2];
    T += b.mass / 2 * dot(vc, vc) + dot(F.omega_local, Iw) / 2;
  }
  return T;
}

GiNaC::ex MultibodyBuilder::potential_energy() const {
  if (!gravity_) return 0;
  GiNaC::ex V = 0;
  for (const Body& b : bodies_) {
    const PlacedFrame& F = frames_[static_cast<std::size_t>(b.frame)];
    V -= b.mass * dot(*gravity_, add(F.origin, multiply(F.rotation, b.com)));
  }
  return V;
}

void MultibodyBuilder::apply() {
  if (applied_) throw ModelError("MultibodyBuilder::apply() was called twice; call it once, after everything else");
  applied_ = true;
  // The contacts and energies differentiate the frames' kinematics again and again (detail/derivative.hpp).
  const detail::DerivativeMemo memo;
  const bool other_energy =
      !builder_.current().kinetic_energy.is_zero() || !builder_.current().potential_energy.is_zero();
  builder_.add_energies(kinetic_energy(), potential_energy());
  // The quaternion frames' unit norms (docs/derivations/quaternion-frame.md (4.1)): constraints of
  // the coordinates, not of a contact, so they act on no body.
  std::vector<std::string> unit_norms;
  const Spec& spec = builder_.current();
  for (const PlacedFrame& f : frames_) {
    if (f.quaternion.empty()) continue;
    GiNaC::ex norm = -1;
    std::vector<std::string> names;
    for (int i : f.quaternion) {
      norm += GiNaC::pow(spec.symbols.coordinate(i), 2);
      names.push_back(spec.coordinates[static_cast<std::size_t>(i)]);
    }
    unit_norms.push_back(f.name + "_unit");
    builder_.constraint(unit_norms.back(), ConstraintLevel::position, norm,
                        fmt::format("frame '{}': the quaternion ({}) has unit norm, {}^2 + {}^2 + {}^2 + {}^2 - 1 = 0 "
                                    "(the position residual is |e|^2 - 1, so |e| = sqrt(1 + residual); the velocity "
                                    "residual is 2 e.e'; --fix-initial moves e onto the unit sphere; a zero "
                                    "quaternion has no direction: e = (1, 0, 0, 0) is the parent's axes)",
                                    f.name, join(names), names[0], names[1], names[2], names[3]),
                        f.where);
  }
  const std::size_t first_helper = builder_.current().constraints.size();
  for (const Helper& h : helpers_) {
    switch (h.kind) {
      case Helper::Kind::knife_edge: add_knife_edge(h); break;
      case Helper::Kind::contact: add_contact(h); break;
      case Helper::Kind::surface:
        builder_.constraint(h.name, ConstraintLevel::position, h.surfaces[0],
                            fmt::format("point on a surface '{}'", h.name), h.where);
        break;
      case Helper::Kind::curve:
        builder_.constraint(h.name + "_1", ConstraintLevel::position, h.surfaces[0],
                            fmt::format("point on a curve '{}', first surface", h.name), h.where);
        builder_.constraint(h.name + "_2", ConstraintLevel::position, h.surfaces[1],
                            fmt::format("point on a curve '{}', second surface", h.name), h.where);
        break;
    }
    if (h.kind == Helper::Kind::surface || h.kind == Helper::Kind::curve) {
      // Unknowns: the world components (the solve finds them along the surfaces' normals).
      const Point& p = points_[static_cast<std::size_t>(h.index)];
      ContactPoint contact;
      contact.name = h.name;
      contact.kind = h.kind == Helper::Kind::surface ? ContactKind::surface : ContactKind::curve;
      contact.point = p.world;
      contact.velocity = time_derivative(p.world, builder_.current().symbols);
      contact.directions = {unit(0), unit(1), unit(2)};
      contact.system = system_of(p.frame);
      contacts_.push_back(std::move(contact));
    }
  }
  auto record = std::make_shared<SpecContactForces>();
  record->other_energy = other_energy;
  const std::vector<SpecConstraint>& constraints = builder_.current().constraints;
  for (std::size_t i = first_helper; i < constraints.size(); ++i) record->generated.push_back(constraints[i].name);
  record->internal = std::move(unit_norms);
  record_contact_forces(*record);
  std::vector<ReportedContact> reported;  // the knife edges and rolling bodies (wheels among them), whose columns events may name
  for (const ContactPoint& c : record->contacts)
    if (c.kind == ContactKind::knife_edge || c.kind == ContactKind::rolling)
      reported.emplace_back(c.name, contact_components(c.kind, c.spin, c.axle));
  record->columns = make_contact_force_symbols(reported);
  record->modes = modes_;
  builder_.contact_forces(std::move(record));
}

int MultibodyBuilder::system_of(int frame) const {
  if (frame <= 0) return -1;
  while (frames_[static_cast<std::size_t>(frame)].parent > 0) frame = frames_[static_cast<std::size_t>(frame)].parent;
  return frame;  // a frame index for now; record_contact_forces numbers the systems
}

void MultibodyBuilder::record_contact_forces(SpecContactForces& record) const {
  // Systems: the frames below ground that bodies or contacts hang from, numbered in frame order.
  std::vector<int> number(frames_.size(), -1);
  const auto use = [&](int root) {
    if (root >= 0) number[static_cast<std::size_t>(root)] = 0;
  };
  for (const Body& b : bodies_) use(system_of(b.frame));
  for (const ContactPoint& c : contacts_) use(c.system);
  for (std::size_t f = 0; f < frames_.size(); ++f) {
    if (number[f] < 0) continue;
    number[f] = static_cast<int>(record.origins.size());
    record.origins.push_back(frames_[f].origin);
    record.system_names.push_back(frames_[f].name);
  }
  const auto system = [&](int root) { return root >= 0 ? number[static_cast<std::size_t>(root)] : -1; };
  for (const Body& b : bodies_) {
    const PlacedFrame& F = frames_[static_cast<std::size_t>(b.frame)];
    ContactBody body;
    body.mass = b.mass;
    body.centre = add(F.origin, multiply(F.rotation, b.com));
    body.omega = F.omega;
    body.inertia = F.rotation.mul(b.inertia).mul(F.rotation.transpose());
    body.system = system(system_of(b.frame));
    record.bodies.push_back(std::move(body));
  }
  for (ContactPoint c : contacts_) {
    c.system = system(c.system);
    record.contacts.push_back(std::move(c));
  }
  if (gravity_) record.gravity = *gravity_;
  double largest = 0.0;  // L, the scale of the moment rows: the largest contact's size
  for (const Helper& h : helpers_) {
    if (h.kind == Helper::Kind::contact)
      largest = std::max(largest, value_of(h.contact->shape->length(h.contact->values), builder_.current()).value_or(0.0));
  }
  record.length = largest > 0.0 ? largest : 1.0;
}

const PlacedFrame& MultibodyBuilder::placed_frame(const std::string& name) const {
  return frames_[static_cast<std::size_t>(frame_index(name, {}, "placed_frame"))];
}

Vector3 MultibodyBuilder::point_position(const std::string& name) const {
  return points_[static_cast<std::size_t>(point_index(name, {}, "point_position"))].world;
}

}  // namespace nhdyn::symbolic
