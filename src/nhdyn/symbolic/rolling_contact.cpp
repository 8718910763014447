#include "nhdyn/symbolic/rolling_contact.hpp"

#include <fmt/format.h>

#include <Eigen/Dense>

#include <algorithm>
#include <cmath>
#include <exception>
#include <limits>
#include <sstream>
#include <tuple>
#include <utility>

#include "nhdyn/core/error.hpp"
#include "nhdyn/core/join.hpp"
#include "nhdyn/core/detail/suggest.hpp"
#include "nhdyn/symbolic/multibody.hpp"
#include "nhdyn/symbolic/simplify.hpp"

#include "nhdyn/symbolic/detail/contact_geometry.hpp"
#include "nhdyn/symbolic/detail/digits_scope.hpp"
#include "nhdyn/symbolic/detail/grounds.hpp"

namespace nhdyn::symbolic {

std::pair<Vector3, Vector3> plane_tangents(const Vector3& n, const Spec& spec) {
  const int k = contact_least_aligned_axis(n, spec);
  const GiNaC::ex nk = n[static_cast<std::size_t>(k)];
  Vector3 t1 = scale(1 / GiNaC::sqrt(simplify(1 - nk * nk)), subtract(unit(k), scale(nk, n)));
  for (GiNaC::ex& e : t1) e = simplify(e);
  Vector3 t2 = cross(n, t1);
  for (GiNaC::ex& e : t2) e = simplify(e);
  return {t1, t2};
}

// The table of grounds (one file each in grounds/), in the order the docs list them.
const std::vector<const ContactGround*>& contact_grounds() {
  static const std::vector<const ContactGround*> table = {&grounds::plane(), &grounds::surface(), &grounds::terrain()};
  return table;
}

const ContactGround* find_contact_ground(const std::string& key) {
  for (const ContactGround* ground : contact_grounds())
    if (ground->key() == key) return ground;
  return nullptr;
}

namespace {

std::string contact_unknown_key(const std::string& what, const std::string& key, const std::vector<std::string>& known) {
  const std::string nearest = nearest_name(key, known);
  return fmt::format("unknown {} '{}'; {}choose one of: {}", what, key,
                     nearest.empty() ? "" : fmt::format("did you mean '{}'? ", nearest), join(known));
}

// shape = { surface = "f(X, Y, Z)", coordinates = [...] }: f in the body's axes, smooth; the
// coordinates that hold the contact point.
void parse_implicit_shape(const ContactText& text, const ContactParsers& p, const std::string& context,
                          ShapeValues& out) {
  const Spec& spec = *p.spec;
  const GiNaC::symbol X("X"), Y("Y"), Z("Z");
  const std::string written = text.sizes.at(0);
  const GiNaC::ex f = p.surface(written, Vector3{X, Y, Z}, text.shape_where, context + ": surface");
  if (contact_has_coordinates(f, spec))
    throw_model_error(text.shape_where, context,
                      fmt::format("the surface \"{}\" depends on t or on a coordinate; a body's shape is fixed in its "
                                  "axes: write it in X, Y, Z (body axes) and the parameters",
                                  written));
  for (const GiNaC::ex& e : {f, f.diff(X), f.diff(Y), f.diff(Z)})
    if (contact_not_smooth(e))
      throw_model_error(text.shape_where, context,
                        fmt::format("the surface \"{}\" is not differentiable (it uses abs): its normal and curvature "
                                    "must exist at every point that may touch; write a smooth f",
                                    written));
  const std::vector<int> at = contact_point_coordinates(contact_option_of(text.shape_options, "coordinates", ""), ContactPointOn::shape,
                                                        p, text.shape_where, context, "a surface shape",
                                                        find_contact_shape("surface")->example(), out.added);
  for (std::size_t i = 0; i < 3; ++i) {
    out.at[i] = at[i];
    out.point[i] = spec.symbols.coordinate(at[i]);
  }
  out.surface = f.subs(GiNaC::lst{X == out.point[0], Y == out.point[1], Z == out.point[2]});
}

}  // namespace

ParsedContact parse_contact(const ContactText& text, const ContactParsers& parsers) {
  ContactParsers p = parsers;
  p.contact = text.name;
  const std::string context = fmt::format("{} '{}'", text.entry, text.name);
  ParsedContact out;
  out.name = text.name;
  out.where = text.where;
  out.body = p.body(text.body, text.where, context + ": body");

  std::vector<std::string> shape_keys;
  for (const ContactShape* shape : contact_shapes()) shape_keys.push_back(shape->key());
  out.shape = find_contact_shape(text.shape);
  if (out.shape == nullptr) throw_model_error(text.shape_where, context, contact_unknown_key("shape", text.shape, shape_keys));
  const ContactShape& shape = *out.shape;
  const std::vector<std::string> names = shape.size_names();
  if (static_cast<int>(text.sizes.size()) != shape.size_count())
    throw_model_error(text.shape_where, context,
                      fmt::format("a {} takes {} ({}), e.g. {}; {} given", shape.key(),
                                  shape.size_count() == 1 ? "one size" : fmt::format("{} sizes", shape.size_count()),
                                  join(names), shape.example(), text.sizes.size()));
  if (shape.implicit()) parse_implicit_shape(text, p, context, out.values);
  for (std::size_t i = 0; i < text.sizes.size() && !shape.implicit(); ++i) {
    const std::string what = i < text.size_keys.size() ? fmt::format("{}: {}", context, text.size_keys[i])
                                                       : fmt::format("{}: {} {}", context, shape.key(), names[i]);
    const GiNaC::ex size = p.constant(text.sizes[i], text.shape_where, what);
    const std::optional<double> v = contact_number_of(size, *p.spec);
    if (!v || !(*v > 0.0))
      throw_model_error(text.shape_where, what,
                        fmt::format("\"{}\" must be positive, but it is {}", text.sizes[i],
                                    v ? fmt::format("{}", *v) : "not a number"));
    out.positive.push_back(SpecPositive{text.shape_where, what, text.sizes[i], size,
                                        shape.sizes_in_proportion() ? context : std::string()});
    out.values.sizes.push_back(size);
  }
  const std::vector<std::string> options = shape.options();
  for (const auto& [key, value] : text.shape_options) {
    if (std::find(options.begin(), options.end(), key) == options.end())
      throw_model_error(text.shape_where, context,
                        options.empty() ? fmt::format("a {} has no key '{}' (e.g. {})", shape.key(), key, shape.example())
                                        : contact_unknown_key(fmt::format("key of a {}", shape.key()), key, options));
    if (key == "axis") {
      out.values.axis = value == "x" ? 0 : value == "y" ? 1 : value == "z" ? 2 : -1;
      if (out.values.axis < 0)
        throw_model_error(text.shape_where, context,
                          fmt::format("unknown axis '{}'; the axle is the \"x\", \"y\" or \"z\" axis of the body's frame",
                                      value));
    }
  }
  if (std::find(options.begin(), options.end(), "axis") != options.end() && out.values.axis < 0)
    throw_model_error(text.shape_where, context,
                      fmt::format("a {} needs its axle, e.g. {}", shape.key(), shape.example()));
  if (text.centre)
    for (std::size_t i = 0; i < 3; ++i) out.centre[i] = p.constant((*text.centre)[i], text.where, context + ": centre");

  std::vector<std::string> ground_keys;
  for (const ContactGround* ground : contact_grounds()) ground_keys.push_back(ground->key());
  const ContactGround* ground = find_contact_ground(text.ground.key);
  if (ground == nullptr)
    throw_model_error(text.ground.where, context, contact_unknown_key("ground", text.ground.key, ground_keys));
  const std::vector<std::string> ground_options = ground->options();
  for (const auto& option : text.ground.options)
    if (std::find(ground_options.begin(), ground_options.end(), option.first) == ground_options.end())
      throw_model_error(text.ground.where, context,
                        contact_unknown_key(fmt::format("key of a {} ground", ground->key()), option.first, ground_options));
  out.ground.type = ground;
  out.ground.where = text.ground.where;
  if (text.entry == "wheel") out.ground.normal_example = "normal = [0, 0, 1]";
  // A wheel has no `ground` key: its plane's messages name the wheel (and point at its `normal`).
  ground->parse(text.ground, p, text.entry == "wheel" ? context : context + ": ground", shape, out.values, out.ground);

  if (text.rolling != "rolling" && text.rolling != "rubber")
    throw_model_error(text.where, context,
                      fmt::format("unknown rolling '{}'; choose \"rolling\" (no slip) or \"rubber\" (no slip and no "
                                  "spin about the normal)",
                                  text.rolling));
  out.rubber = text.rolling == "rubber";
  // The contact modes find the no-slip rows as NAME_roll1, NAME_roll2 (contact_modes.cpp).
  out.no_slip_suffix = text.modes.empty() ? text.no_slip_suffix : "_roll";
  out.entry = text.entry;
  out.unilateral = std::find(text.modes.begin(), text.modes.end(), KeyTexts::value_type{"unilateral", "true"}) !=
                   text.modes.end();
  ground->check(out, *p.spec, context);
  return out;
}

namespace {

// The convexity check of an implicit shape: near y the surface f = 0 leaves its tangent plane
// along -grad f by 1/2 w^T H w / |grad f|; along n that is -(unit grad f . n) times it, in world
// axes with R (rolling-bodies.md section 9).
SpecConvexity convexity_check(const ParsedContact& c, const PlacedFrame& F, const ContactGround::Touch& touch) {
  const ShapeValues& v = c.values;
  Vector3 gradient;
  for (std::size_t i = 0; i < 3; ++i) gradient[i] = v.surface.diff(GiNaC::ex_to<GiNaC::symbol>(v.point[i]));
  const GiNaC::ex size = GiNaC::sqrt(dot(gradient, gradient));
  const GiNaC::ex along = -dot(multiply(F.rotation, gradient), touch.normal) / size;
  GiNaC::matrix H(3, 3);
  for (unsigned i = 0; i < 3; ++i)
    for (unsigned j = 0; j < 3; ++j) H(i, j) = gradient[i].diff(GiNaC::ex_to<GiNaC::symbol>(v.point[j]));
  SpecConvexity check;
  check.contact = c.name;
  check.where = c.where;
  check.normal = {touch.normal[0], touch.normal[1], touch.normal[2]};
  check.body = F.rotation.mul(H).mul(F.rotation.transpose()).mul_scalar(along / size);
  check.ground = touch.curvature;
  return check;
}

// The determinant and the trace of a symmetric K restricted to the plane normal to n (n not
// necessarily unit): n^T adj(K) n / |n|^2 and tr K - n^T K n / |n|^2, the product and the sum of
// the principal curvatures when K is a curvature matrix (rolling-bodies.md section 9.1).
std::pair<GiNaC::ex, GiNaC::ex> tangent_determinant_and_trace(const GiNaC::matrix& K, const Vector3& n) {
  const auto minor = [&](unsigned i, unsigned j) {  // the 2x2 minor without row i and column j
    const unsigned r0 = i == 0 ? 1 : 0, r1 = i == 2 ? 1 : 2, c0 = j == 0 ? 1 : 0, c1 = j == 2 ? 1 : 2;
    return K(r0, c0) * K(r1, c1) - K(r0, c1) * K(r1, c0);
  };
  GiNaC::ex adjugate = 0, along = 0;
  for (unsigned i = 0; i < 3; ++i)
    for (unsigned j = 0; j < 3; ++j) {
      adjugate += n[i] * n[j] * ((i + j) % 2 == 0 ? 1 : -1) * minor(j, i);
      along += n[i] * K(i, j) * n[j];
    }
  const GiNaC::ex nn = dot(n, n);
  return {adjugate / nn, K(0, 0) + K(1, 1) + K(2, 2) - along / nn};
}

// The start's convexity check carried along the motion (SpecContactWatch, checked at every
// accepted step): the shape's curvature less the ground's on the tangent plane, as
// det(K_shape - K_ground) / (tr K_shape / 2)^2 there, which is (1 - r k1)(1 - r k2) for a ball of
// radius r on a ground of principal curvatures k1, k2, and falls to 0 where the ground's hollow
// becomes as curved as the shape (past it the contact is not unique and the motion not the body's).
// Where both principal differences cross 0 together (an isotropic hollow) the determinant only
// touches 0, so its trace tr(K_shape - K_ground) / tr K_shape is watched too: it turns negative
// there. For an implicit shape also its own det K / (tr K / 2)^2, 0 where it stops being strictly
// convex, and not a number where both its curvatures vanish (which ends the run as well).
std::vector<SpecContactWatch> convexity_watches(const SpecConvexity& check, bool own) {
  const Vector3 n = {check.normal[0], check.normal[1], check.normal[2]};
  // A thin disk: its rim's curvature along t against the ground's, 1 - k_ground(t) / k_rim, 1 on a
  // plane and 0 where the hollow is as curved as the rim (the disk touches it at two points).
  if (!check.rim.empty()) {
    const Vector3 t = {check.rim[0], check.rim[1], check.rim[2]};
    GiNaC::ex along = 0;
    for (unsigned i = 0; i < 3; ++i)
      for (unsigned j = 0; j < 3; ++j) along += t[i] * check.ground(i, j) * t[j];
    return {SpecContactWatch{
        check.contact, check.where, 1 - along / dot(t, t) / check.rim_curvature, 1e-4,
        "the ground's hollow is as curved as the disk's rim here (along the rim the ground bends as much as the "
        "rim does): past this point the rim would dip into the ground beside the contact point, and the motion is "
        "not the body's; use a smaller disk or a smoother ground",
        "1 - k_ground / k_rim along the rim", true, true}};
  }
  const auto [body_det, body_trace] = tangent_determinant_and_trace(check.body, n);
  const GiNaC::ex scale = body_trace * body_trace / 4;
  // A surface without curvature (a plane f = Z - r, linear in X, Y, Z) has no contact point of its
  // own to roll on: refused here, where its measures would divide by its zero curvature.
  if (own && scale.is_zero())
    throw_model_error(check.where, fmt::format("contact '{}'", check.contact),
                      "the shape's surface is flat (its curvature is zero everywhere): a contact shape is a closed, "
                      "strictly convex body surface such as \"X^2/a^2 + Y^2/b^2 + Z^2/c^2 - 1\"; a flat ground is "
                      "the contact's ground, not its shape");
  const GiNaC::matrix relative = check.body.sub(check.ground);
  std::vector<SpecContactWatch> watches;
  // The shape's own first: on a plane (K = 0) the two are the same measure, and the cause is the shape.
  if (own)
    watches.push_back(SpecContactWatch{
        check.contact, check.where, body_det / scale, 1e-4,
        "the shape is no longer strictly convex at its contact point (a principal curvature reaches 0): it would roll "
        "on a point that is not its lowest; write a strictly convex f",
        "det K_shape / (tr K_shape / 2)^2 on the tangent plane", true, true});
  bool flat = true;
  for (unsigned i = 0; i < 3; ++i)
    for (unsigned j = 0; j < 3; ++j) flat = flat && check.ground(i, j).is_zero();
  if (!flat) {
    const std::string reason =
        "the ground's hollow is as curved as the shape here (the shape's principal curvatures less the ground's "
        "reach 0): the contact is no longer a single point, and the motion past it is not the body's; use a more "
        "curved shape or a smoother ground";
    const auto [relative_det, relative_trace] = tangent_determinant_and_trace(relative, n);
    watches.push_back(SpecContactWatch{check.contact, check.where, relative_det / scale, 1e-4, reason,
                                       "det(K_shape - K_ground) / (tr K_shape / 2)^2 on the tangent plane", true,
                                       true});
    watches.push_back(SpecContactWatch{check.contact, check.where, relative_trace / body_trace, 1e-4, reason,
                                       "tr(K_shape - K_ground) / tr K_shape on the tangent plane", true, true});
  }
  return watches;
}

// What the start checks and the run watches of the shape's convexity against the ground's
// (sections 9 and 11): an implicit shape's from its f; a closed-form shape (a ball, an ellipsoid, a
// torus) on a surface or a terrain held by coordinates, its curvature at the support point; a thin
// disk's along its rim. Nothing on a plane for a closed-form shape (convex by construction).
std::optional<SpecConvexity> shape_convexity(const ParsedContact& c, const PlacedFrame& F,
                                             const ContactGround::Touch& touch) {
  if (c.shape->implicit()) return convexity_check(c, F, touch);
  if (c.ground.point[0] < 0 && c.ground.at[0] < 0) return std::nullopt;
  SpecConvexity check;
  check.contact = c.name;
  check.where = c.where;
  check.normal = {touch.normal[0], touch.normal[1], touch.normal[2]};
  check.ground = touch.curvature;
  const Vector3 nu = multiply_transposed(F.rotation, touch.normal);
  const GiNaC::ex length = GiNaC::sqrt(dot(nu, nu));
  if (const std::optional<GiNaC::matrix> K = c.shape->curvature(c.values, nu, length)) {
    // A ball's I / r is the same in every axes: not turned, so that its watch stays short.
    check.body = c.shape->ball_radius(c.values) ? *K : F.rotation.mul(*K).mul(F.rotation.transpose());
    return check;
  }
  if (const std::optional<ContactShape::Rim> rim = c.shape->rim(c.values, nu, length)) {
    const Vector3 t = multiply(F.rotation, rim->tangent);
    check.rim = {t[0], t[1], t[2]};
    check.rim_curvature = rim->curvature;
    return check;
  }
  return std::nullopt;
}

// The contact coordinates nhdyn adds, and where Newton starts (rolling-bodies.md sections 10 and
// 11): on a terrain below the centre; on a surface along grad F from the centre; an implicit
// shape's point on its surface along -nu from its centre.
SpecContactCoordinates added_coordinates(const ParsedContact& c, const PlacedFrame& F,
                                         const ContactGround::Touch& touch) {
  SpecContactCoordinates added;
  added.contact = c.name;
  added.where = c.where;
  const Vector3 C = add(F.origin, multiply(F.rotation, c.centre));
  if (c.ground.added && c.ground.point[0] >= 0) {
    for (std::size_t i = 0; i < 3; ++i) {
      added.coordinates.push_back(c.ground.point[i]);
      added.start.push_back(0);
      added.from.push_back(C[i]);
      added.ground_point[i] = c.ground.point[i];
    }
    for (const char* suffix : {"_ground", "_at1", "_at2"}) added.constraints.push_back(c.name + suffix);
    added.ground = c.ground.inside ? c.ground.surface : -c.ground.surface;
  } else if (c.ground.added) {
    for (std::size_t i = 0; i < 2; ++i) {
      added.coordinates.push_back(c.ground.at[i]);
      added.constraints.push_back(fmt::format("{}_at{}", c.name, i + 1));
      added.start.push_back(C[i]);
    }
  }
  if (c.values.added) {
    const Vector3 down = multiply_transposed(F.rotation, scale(-1, touch.normal));
    for (std::size_t i = 0; i < 3; ++i) {
      added.coordinates.push_back(c.values.at[i]);
      added.start.push_back(0);
      added.ray.push_back(down[i]);
    }
    for (const char* suffix : {"_on", "_normal1", "_normal2"}) added.constraints.push_back(c.name + suffix);
    added.surface = c.values.surface;
    added.point = c.values.at;
  }
  return added;
}

// The contact point as the contact forces see it: its point, velocity, normal, and the axle's
// directions for a disk or torus.
ContactPoint contact_force_point(const ParsedContact& c, const PlacedFrame& F, const ContactGround::Touch& touch,
                                 const Vector3& vP) {
  ContactPoint f;
  f.name = c.name;
  f.kind = ContactKind::rolling;
  f.point = touch.point;
  f.velocity = vP;
  f.directions = {unit(0), unit(1), unit(2)};
  f.normal = touch.normal;
  f.longitudinal = {0, 0, 0};
  f.lateral = {0, 0, 0};
  if (c.values.axis >= 0) {
    // A shape with an axle a (world): e_long = (a x n) / |a x n|, the direction the wheel rolls
    // along the ground, and e_lat = n x e_long, as a [[wheels]] entry has (rolling-bodies.md
    // section 5); |a x n| = sqrt(1 - (a . n)^2) vanishes only lying flat, where the run stops. The
    // axle's direction from R's numerator (a positive multiple of it, quaternion-frame.md section 8).
    const Vector3 a = column(F.rotation_numerator, c.values.axis);
    const Vector3 along = cross(a, touch.normal);
    f.longitudinal = scale(1 / GiNaC::sqrt(dot(along, along)), along);
    f.lateral = cross(touch.normal, f.longitudinal);
    f.axle = true;
  }
  f.omega = F.omega;
  f.spin = c.rubber;
  return f;
}

}  // namespace

RollingContact make_rolling_contact(const ParsedContact& c, const PlacedFrame& F, const Spec& spec,
                                    const std::optional<Vector3>& gravity) {
  const std::string context = fmt::format("{} '{}'", c.entry, c.name);
  const ContactGround::Touch touch = c.ground.type->touch(c, F, spec, gravity, context);
  RollingContact out;
  out.point = touch.point;
  out.length = c.shape->length(c.values);
  out.normal = touch.normal;
  out.tangent1 = touch.tangent1;
  out.tangent2 = touch.tangent2;

  // The contact condition: the gap, zero when touching (rolling-bodies.md section 4.1).
  const GiNaC::ex gap = smaller_form(touch.gap);
  // A gap that holds in every position (the coordinates eliminate the height, as a bicycle's
  // do) adds no row: it would be a zero row of b.
  if (!contact_vanishes_identically(gap, spec)) {
    if (!contact_has_coordinates(gap, spec))
      throw_model_error(c.where, context,
                        fmt::format("the body can never touch the ground: the gap between them is the constant {}; "
                                    "place the body's frame so that it touches the ground",
                                    contact_printed(gap)));
    // A surface's side decides which way the gap is measured: a body on the other side starts
    // with a gap of about minus twice its size.
    const std::string side =
        c.ground.type->key() == "surface"
            ? fmt::format("; the body is where g {} 0 (side = \"{}\"): a gap of about minus twice the body's size "
                          "says it is on the other side",
                          c.ground.inside ? "<" : ">", c.ground.inside ? "inside" : "outside")
            : "";
    out.constraints.push_back({c.name + "_contact", ConstraintLevel::position, gap,
                               fmt::format("{}: the gap between the body and the ground = 0 (its position residual is the "
                                           "gap, in length units; --fix-initial moves the body onto the ground{})",
                                           context, side)});
  }
  // The contact point's coordinates on the ground, where they are coordinates (section 8).
  for (const auto& [suffix, row] : touch.locate)
    out.constraints.push_back({c.name + suffix, ConstraintLevel::position, smaller_form(row),
                               fmt::format("{}: the contact point is where the body's normal is opposite "
                                           "to the ground's ({})",
                                           context, suffix.substr(1))});
  // Rolling: the material point of the body at P has the ground's velocity there (section 4.2).
  const Vector3 vP = add(time_derivative(F.origin, spec.symbols), cross(F.omega, subtract(touch.point, F.origin)));
  const Vector3 relative = subtract(vP, touch.ground_velocity);
  int k = 0;
  for (const Vector3& t : {touch.tangent1, touch.tangent2}) {
    ++k;
    const GiNaC::ex row = smaller_form(dot(t, relative));
    if (row.is_zero())
      throw_model_error(c.where, context,
                        fmt::format("the contact point's velocity along the ground (direction {}) is zero whatever "
                                    "the velocities: the body's frame cannot move there, so it has nothing to roll on",
                                    k));
    out.constraints.push_back({fmt::format("{}{}{}", c.name, c.no_slip_suffix, k), ConstraintLevel::velocity, row,
                               fmt::format("{}: no slip, t{}.(v_P - v_ground) = 0", context, k)});
  }
  if (c.rubber) {
    const GiNaC::ex spin = simplify_moderate(dot(touch.normal, subtract(F.omega, touch.ground_omega)));
    if (spin.is_zero())
      throw_model_error(c.where, context,
                        "the body cannot spin about the contact normal in these coordinates, so rubber rolling adds "
                        "nothing: write rolling = \"rolling\"");
    out.constraints.push_back({c.name + "_spin", ConstraintLevel::velocity, spin,
                               fmt::format("{}: no spin about the normal, n.(omega - omega_ground) = 0", context)});
  }
  out.convexity = shape_convexity(c, F, touch);
  if (out.convexity)
    for (SpecContactWatch& watch : convexity_watches(*out.convexity, c.shape->implicit()))
      out.watches.push_back(std::move(watch));
  // A ball in the air over a ground held by coordinates (contact modes, free): the ground's point
  // below its centre, which measures the gap, is the nearest one only while the centre is nearer
  // than the ground's radii of curvature there (r + gap < 1/k): the ball's curvature 1/r becomes
  // 1/(r + gap) in the same measures (rolling-bodies.md section 11).
  if (out.convexity && c.shape->ball_radius(c.values)) {
    const GiNaC::ex reach = *c.shape->ball_radius(c.values) + touch.gap;
    SpecConvexity flying = *out.convexity;
    for (unsigned i = 0; i < 3; ++i) flying.body(i, i) = 1 / reach;
    const std::string reason =
        "the ball flies farther from the ground than the ground's radius of curvature below it, where the ground's "
        "point below the ball (which measures the gap) is no longer the nearest one and nhdyn cannot follow the flight "
        "over this ground; a ground in closed form (a plane, a sphere) has no such limit";
    const Vector3 n = {touch.normal[0], touch.normal[1], touch.normal[2]};
    const auto [det, trace] = tangent_determinant_and_trace(flying.body.sub(flying.ground), n);
    out.watches.push_back(SpecContactWatch{c.name, c.where, det * reach * reach, 1e-4, reason,
                                           "(1 - (r + gap) k1)(1 - (r + gap) k2)", true, false, true});
    out.watches.push_back(SpecContactWatch{c.name, c.where, trace * reach / 2, 1e-4, reason,
                                           "(2 - (r + gap)(k1 + k2)) / 2", true, false, true});
  }
  // 1 - (e . nu)^2 below 1e-4: the axle within 0.6 degree of the normal (rolling-bodies.md section 2).
  // Where |e x nu| is written +-u (touch.signed_roots), u's fall through 1e-2, at every step: the
  // equations do not fail there (u changes sign, 1 - (e . nu)^2 = u^2 only touches 0).
  if (const std::optional<ContactShape::Singularity> singular =
          c.shape->singularity(c.values, multiply_transposed(F.rotation, touch.normal))) {
    out.watches.push_back(SpecContactWatch{c.name, c.where, singular->measure, 1e-4, singular->reason});
    for (const GiNaC::ex& u : touch.signed_roots) {
      SpecContactWatch watch{c.name, c.where, u, 1e-2, singular->reason, "|axle x normal|", true};
      watch.signed_root = true;
      out.watches.push_back(std::move(watch));
    }
  }
  if (touch.singular)
    out.watches.push_back(
        SpecContactWatch{c.name, c.where, touch.singular->first, 1e-4, touch.singular->second, "1 - (e . n)^2", true});
  for (SpecContactWatch& watch : out.watches) watch.entry = c.entry;
  if (c.ground.added || c.values.added) out.added = added_coordinates(c, F, touch);
  out.force = contact_force_point(c, F, touch, vP);
  return out;
}

namespace {

// Values of expressions in t and q where the run starts (spec.t0, spec.q0 at the parameter values):
// what the start checks below judge.
class StartValues {
 public:
  explicit StartValues(const Spec& spec) : values_(spec.parameter_values()) {
    at_[spec.symbols.time()] = GiNaC::numeric(spec.t0);
    for (std::size_t i = 0; i < spec.coordinates.size(); ++i)
      if (i < spec.q0.size()) at_[spec.symbols.coordinate(static_cast<int>(i))] = spec.q0[i].subs(values_);
  }
  // False where e is not a finite real number there (left to the other checks).
  bool operator()(const GiNaC::ex& e, double& out) const {
    try {
      const GiNaC::ex x = e.subs(at_, GiNaC::subs_options::no_pattern).subs(values_).subs(values_).evalf();
      if (!GiNaC::is_a<GiNaC::numeric>(x) || !GiNaC::ex_to<GiNaC::numeric>(x).is_real()) return false;
      out = GiNaC::ex_to<GiNaC::numeric>(x).to_double();
      return std::isfinite(out);
    } catch (const std::exception&) {
      return false;
    }
  }

 private:
  GiNaC::lst values_;
  GiNaC::exmap at_;
};

}  // namespace

void check_contact_watches_at_start(const Spec& spec) {
  const StartValues value(spec);
  for (const SpecContactWatch& w : spec.contact_watches) {
    double measure = 0.0;
    if (!w.signed_root || !value(w.measure, measure)) continue;
    if (measure >= w.threshold) continue;
    const std::string context = fmt::format("{} '{}'", w.entry, w.contact);
    if (measure > -w.threshold)
      throw_model_error(w.where, context,
                        fmt::format("{} at the start ({} = {:.3g}, below {}); start it leaning less", w.reason,
                                    w.quantity, measure, w.threshold));
    throw_model_error(w.where, context,
                      fmt::format("at the start the wheel is turned past lying flat from its reference configuration "
                                  "(every coordinate 0): its rim's {} is written as {}, with the sign it has there, "
                                  "and is {:.3g} at the start, where that rim point is the highest, not the lowest. "
                                  "Start the wheel on the side of lying flat that its reference configuration is on, "
                                  "or place its frames so that it stands upright where the coordinates are 0",
                                  w.quantity, contact_printed(w.measure), measure));
  }
}

void check_contact_convexity(const Spec& spec) {
  if (spec.convexity.empty()) return;
  const StartValues value(spec);
  for (const SpecConvexity& check : spec.convexity) {
    Eigen::Vector3d n;
    Eigen::Matrix3d body, ground;
    bool ok = true;
    for (int i = 0; i < 3 && ok; ++i) {
      ok = value(check.normal[static_cast<std::size_t>(i)], n(i));
      for (int j = 0; j < 3 && ok; ++j)
        ok = value(check.body(static_cast<unsigned>(i), static_cast<unsigned>(j)), body(i, j)) &&
             value(check.ground(static_cast<unsigned>(i), static_cast<unsigned>(j)), ground(i, j));
    }
    if (!ok || !(n.norm() > 0)) continue;
    n.normalize();
    const std::string context = fmt::format("contact '{}'", check.contact);
    if (!check.rim.empty()) {
      // A thin disk: the ground's curvature along the rim, t^T K t / |t|^2, below the rim's.
      Eigen::Vector3d t;
      double rim = 0;
      for (int i = 0; i < 3 && ok; ++i) ok = value(check.rim[static_cast<std::size_t>(i)], t(i));
      if (!ok || !value(check.rim_curvature, rim) || !(t.norm() > 0) || !(rim > 0)) continue;
      const double along = t.dot(ground * t) / t.squaredNorm();
      if (!(rim - along > 1e-12 * rim))
        throw_model_error(check.where, context, fmt::format(
            "the disk's rim is flatter than the hollow of the ground at the initial contact point, so the contact is "
            "not unique: along the rim the rim's curvature is {:.6g} (|e x n| / r, e the axle) and the ground's "
            "{:.6g} (it must be smaller). Use a smaller disk, a smoother ground, or start where the ground's hollow "
            "is shallower",
            rim, along));
      continue;
    }
    // An orthonormal basis E of the tangent plane; the curvatures are the eigenvalues of E^T K E.
    Eigen::Vector3d e1 = n.unitOrthogonal();
    Eigen::Matrix<double, 3, 2> E;
    E << e1, n.cross(e1);
    const auto curvatures = [&](const Eigen::Matrix3d& K) {
      const Eigen::Matrix2d k = E.transpose() * K * E;
      return Eigen::SelfAdjointEigenSolver<Eigen::Matrix2d>(0.5 * (k + k.transpose())).eigenvalues();
    };
    const Eigen::Vector2d own = curvatures(body), relative = curvatures(body - ground);
    // Relative to the shape's own size: a curvature 1e-12 of its largest counts as flat.
    const double small = 1e-12 * std::max(own.cwiseAbs().maxCoeff(), 1e-300);
    if (!(own(0) > small))
      throw_model_error(check.where, context, fmt::format(
          "the shape is not strictly convex toward the ground at the initial contact point: its "
          "principal curvatures there are {:.6g} and {:.6g} (the Hessian of f on the tangent plane divided by |grad f|, "
          "positive where the surface bends away from the ground); a saddle or a hollow would roll on a point that is "
          "not the lowest. Write a strictly convex f with f < 0 inside, and start the contact coordinates at the "
          "shape's lowest point",
          own(0), own(1)));
    if (!(relative(0) > small))
      throw_model_error(check.where, context, fmt::format(
          "the shape is flatter than the hollow of the ground at the initial contact point, so the contact is not "
          "unique: the shape's principal curvatures there are {:.6g} and {:.6g}, and those of the shape less the "
          "ground's are {:.6g} and {:.6g} (both must be positive). Use a more curved shape, a smoother ground, or start "
          "where the ground's hollow is shallower",
          own(0), own(1), relative(0), relative(1)));
  }
}

}  // namespace nhdyn::symbolic

namespace nhdyn::symbolic {

std::vector<std::string> added_contact_coordinates(const std::string& contact, ContactPointOn on) {
  switch (on) {
    case ContactPointOn::terrain: return {contact + "_u", contact + "_v"};
    case ContactPointOn::shape: return {contact + "_px", contact + "_py", contact + "_pz"};
    case ContactPointOn::surface: return {contact + "_gx", contact + "_gy", contact + "_gz"};
  }
  return {};
}

namespace {

// A numeric value, NaN when `e` is not a finite real number once everything is substituted.
// The values in `at` are exact (exact_double) and the evaluation carries 40 digits, so that the
// rounding of GiNaC's sums, taken in its term order (which changes from process to process), stays
// far below a double's: the contact point found at the start is the same in every process.
double contact_value(const GiNaC::ex& e, const GiNaC::exmap& at) {
  const DigitsScope digits(40);
  try {
    const GiNaC::ex x = e.subs(at, GiNaC::subs_options::no_pattern).evalf();
    if (!GiNaC::is_a<GiNaC::numeric>(x) || !GiNaC::ex_to<GiNaC::numeric>(x).is_real())
      return std::numeric_limits<double>::quiet_NaN();
    return GiNaC::ex_to<GiNaC::numeric>(x).to_double();
  } catch (const std::exception&) {
    return std::numeric_limits<double>::quiet_NaN();
  }
}

// The point where the ray o + s d (s > 0) leaves f < 0, as s; NaN when f(o) is not negative or f
// stays negative out to a huge distance. o is the shape's centre (0 in its own axes), or a point
// in world axes for a ground.
double ray_exit(const GiNaC::ex& f, const std::array<GiNaC::ex, 3>& y, const Eigen::Vector3d& d, GiNaC::exmap at,
                const Eigen::Vector3d& o = Eigen::Vector3d::Zero()) {
  const auto value = [&](double s) {
    for (int i = 0; i < 3; ++i) at[y[static_cast<std::size_t>(i)]] = exact_double(o(i) + s * d(i));
    return contact_value(f, at);
  };
  if (!(value(0.0) < 0.0)) return std::numeric_limits<double>::quiet_NaN();
  double low = 0.0, high = 1e-6;
  while (!(value(high) >= 0.0)) {
    low = high;
    high *= 2.0;
    if (high > 1e12) return std::numeric_limits<double>::quiet_NaN();
  }
  for (int k = 0; k < 200 && high - low > 1e-15 * high; ++k) {
    const double middle = 0.5 * (low + high);
    (value(middle) < 0.0 ? low : high) = middle;
  }
  return 0.5 * (low + high);
}

// Where a surface ground's contact point U starts (rolling-bodies.md section 11): where the line
// from the shape's centre C along grad F(C) meets F = 0, F = -sigma g negative on the body's side
// (along -grad F from a centre on the other side).
Eigen::Vector3d ground_start(const Spec& spec, const SpecContactCoordinates& added, const GiNaC::exmap& at,
                             const std::string& context) {
  std::array<GiNaC::ex, 3> U;
  for (std::size_t i = 0; i < 3; ++i) U[i] = spec.symbols.coordinate(added.ground_point[i]);
  Eigen::Vector3d C, d;
  for (int i = 0; i < 3; ++i) C(i) = contact_value(added.from[static_cast<std::size_t>(i)], at);
  GiNaC::exmap here = at;
  for (std::size_t i = 0; i < 3; ++i) here[U[i]] = exact_double(C(static_cast<Eigen::Index>(i)));
  const double F = contact_value(added.ground, here);
  for (std::size_t i = 0; i < 3; ++i)
    d(static_cast<Eigen::Index>(i)) = contact_value(added.ground.diff(GiNaC::ex_to<GiNaC::symbol>(U[i])), here);
  if (!C.allFinite() || !std::isfinite(F))
    throw_model_error(added.where, context,
                      "cannot find the contact point on the ground at the start: the shape's centre or the surface "
                      "g there is not a finite number; check the initial state and the parameters g uses (a "
                      "division by zero, a root of a negative number)");
  if (F == 0.0) return C;
  // A centre on the other side (its height not yet written: --fix-initial moves it afterwards)
  // looks for the ground the other way.
  const double sign = F < 0.0 ? 1.0 : -1.0;
  d *= sign;
  const double s = d.allFinite() && d.norm() > 0 ? ray_exit(sign * added.ground, U, d.normalized(), at, C)
                                                   : std::numeric_limits<double>::quiet_NaN();
  if (!std::isfinite(s))
    throw_model_error(added.where, context,
                      "cannot find the contact point on the ground at the start: the line from the shape's centre "
                      "along the surface's steepest approach meets no point of g = 0; start the body nearer the "
                      "ground, or name the contact point's coordinates and give their initial values");
  return C + s * d.normalized();
}

// The parameters' values exact (a value given as a double is its binary value), as every number
// put into the expressions evaluated by contact_value.
GiNaC::lst exact_parameter_values(const Spec& spec) {
  GiNaC::lst out;
  for (const GiNaC::ex& p : spec.parameter_values()) {
    const GiNaC::ex& value = p.op(1);
    const bool inexact = GiNaC::is_a<GiNaC::numeric>(value) && !GiNaC::ex_to<GiNaC::numeric>(value).is_rational() &&
                         GiNaC::ex_to<GiNaC::numeric>(value).is_real();
    out.append(p.op(0) == (inexact ? GiNaC::ex(exact_double(GiNaC::ex_to<GiNaC::numeric>(value).to_double())) : value));
  }
  return out;
}

const SpecConstraint& constraint_named(const Spec& spec, const std::string& name) {
  for (const SpecConstraint& c : spec.constraints)
    if (c.name == name) return c;
  throw ModelError(fmt::format("model '{}': no constraint '{}' holds a contact point's coordinates", spec.name, name));
}

}  // namespace

void solve_contact_coordinates(Spec& spec) {
  if (spec.contact_coordinates.empty()) return;
  const GiNaC::lst parameters = exact_parameter_values(spec);
  for (const SpecContactCoordinates& added : spec.contact_coordinates) {
    const std::string context = fmt::format("contact '{}'", added.contact);
    const auto k = static_cast<Eigen::Index>(added.coordinates.size());
    std::vector<bool> unknown(spec.coordinates.size(), false);
    for (int i : added.coordinates) unknown[static_cast<std::size_t>(i)] = true;
    // Everything else at its initial value (numbers: the parameters substituted).
    GiNaC::exmap at;
    for (const GiNaC::ex& p : parameters) at[p.op(0)] = p.op(1);
    at[spec.symbols.time()] = exact_double(spec.t0);
    for (std::size_t i = 0; i < spec.coordinates.size(); ++i)
      if (!unknown[i]) {
        const double q = contact_value(spec.q0[i].subs(parameters), at);
        at[spec.symbols.coordinate(static_cast<int>(i))] = exact_double(q);
      }
    // The start: a surface's point along the steepest approach from the centre, or a terrain's
    // point below the centre; then the shape's point along -nu.
    Eigen::VectorXd x(k);
    std::size_t first = 0;
    if (!added.from.empty()) {
      x.head(3) = ground_start(spec, added, at, context);
      for (std::size_t i = 0; i < 3; ++i)
        at[spec.symbols.coordinate(added.ground_point[i])] = exact_double(x(static_cast<Eigen::Index>(i)));
      first = 3;
    }
    std::size_t ray_from = added.coordinates.size();
    if (!added.ray.empty()) ray_from -= 3;
    for (std::size_t j = first; j < ray_from; ++j) {
      x(static_cast<Eigen::Index>(j)) = contact_value(added.start[j], at);
      at[spec.symbols.coordinate(added.coordinates[j])] = exact_double(x(static_cast<Eigen::Index>(j)));
    }
    if (!added.ray.empty()) {
      Eigen::Vector3d d;
      for (int i = 0; i < 3; ++i) d(i) = contact_value(added.ray[static_cast<std::size_t>(i)], at);
      std::array<GiNaC::ex, 3> y;
      for (std::size_t i = 0; i < 3; ++i) y[i] = spec.symbols.coordinate(added.point[i]);
      const double s = d.allFinite() && d.norm() > 0 ? ray_exit(added.surface, y, d.normalized(), at)
                                                       : std::numeric_limits<double>::quiet_NaN();
      if (!std::isfinite(s))
        throw_model_error(added.where, context,
                          "cannot find the contact point at the start: the shape's surface f = 0 must enclose its "
                          "centre (f < 0 there) and cross the line from it toward the ground; check the surface's "
                          "sign (f < 0 inside) and the body's initial orientation, or name the contact point's "
                          "coordinates and give their initial values");
      for (std::size_t i = 0; i < 3; ++i) x(static_cast<Eigen::Index>(ray_from + i)) = s * d.normalized()(static_cast<Eigen::Index>(i));
    }
    // Newton on the rows that hold them, the Jacobian exact.
    std::vector<GiNaC::ex> rows;
    for (const std::string& name : added.constraints) rows.push_back(constraint_named(spec, name).expression);
    const auto symbol = [&](std::size_t j) { return GiNaC::ex_to<GiNaC::symbol>(spec.symbols.coordinate(added.coordinates[j])); };
    std::vector<std::vector<GiNaC::ex>> jacobian(rows.size());
    for (std::size_t r = 0; r < rows.size(); ++r)
      for (std::size_t j = 0; j < added.coordinates.size(); ++j) jacobian[r].push_back(rows[r].diff(symbol(j)));
    const auto set_x = [&] {
      for (std::size_t j = 0; j < added.coordinates.size(); ++j)
        at[spec.symbols.coordinate(added.coordinates[j])] = exact_double(x(static_cast<Eigen::Index>(j)));
    };
    Eigen::VectorXd r(static_cast<Eigen::Index>(rows.size()));
    const auto residual = [&] {
      set_x();
      for (std::size_t i = 0; i < rows.size(); ++i) r(static_cast<Eigen::Index>(i)) = contact_value(rows[i], at);
      return r.allFinite() ? r.cwiseAbs().maxCoeff() : std::numeric_limits<double>::infinity();
    };
    double worst = residual();
    for (int iteration = 0; iteration < 50 && worst > 0.0 && std::isfinite(worst); ++iteration) {
      Eigen::MatrixXd J(r.size(), k);
      for (std::size_t i = 0; i < rows.size(); ++i)
        for (std::size_t j = 0; j < added.coordinates.size(); ++j)
          J(static_cast<Eigen::Index>(i), static_cast<Eigen::Index>(j)) = contact_value(jacobian[i][j], at);
      if (!J.allFinite()) break;
      const Eigen::FullPivLU<Eigen::MatrixXd> lu(J);
      if (!lu.isInvertible()) break;
      const Eigen::VectorXd step = lu.solve(-r);
      x += step;
      worst = residual();
      if (step.cwiseAbs().maxCoeff() <= 4 * std::numeric_limits<double>::epsilon() * (1.0 + x.cwiseAbs().maxCoeff()))
        break;
    }
    if (!(worst <= 1e-10)) {
      Eigen::Index row = 0;
      if (r.allFinite()) r.cwiseAbs().maxCoeff(&row);
      throw_model_error(added.where, context,
                        fmt::format("cannot find the contact point at the start: Newton's method on the constraints "
                                    "that hold it ({}) stops with '{}' at the residual {:.3g}; the body may be too far "
                                    "from the ground, or its shape not convex there. Start the body on the ground, or "
                                    "name the contact point's coordinates and give their initial values",
                                    join(added.constraints), added.constraints[static_cast<std::size_t>(row)],
                                    r.allFinite() ? r(row) : std::numeric_limits<double>::infinity()));
    }
    for (std::size_t j = 0; j < added.coordinates.size(); ++j)
      spec.q0[static_cast<std::size_t>(added.coordinates[j])] = GiNaC::numeric(x(static_cast<Eigen::Index>(j)));
    // Velocities: d/dt row = sum_i (d row / d q_i) q_i' + d row / dt = 0, linear in the unknown ones.
    Eigen::MatrixXd J(r.size(), k);
    Eigen::VectorXd known = Eigen::VectorXd::Zero(r.size());
    for (std::size_t i = 0; i < rows.size(); ++i) {
      const auto ii = static_cast<Eigen::Index>(i);
      for (std::size_t j = 0; j < added.coordinates.size(); ++j)
        J(ii, static_cast<Eigen::Index>(j)) = contact_value(jacobian[i][j], at);
      known(ii) = contact_value(rows[i].diff(spec.symbols.time()), at);
      for (std::size_t q = 0; q < spec.coordinates.size(); ++q) {
        if (unknown[q]) continue;
        const GiNaC::ex partial = rows[i].diff(GiNaC::ex_to<GiNaC::symbol>(spec.symbols.coordinate(static_cast<int>(q))));
        if (partial.is_zero()) continue;
        known(ii) += contact_value(partial, at) * contact_value(spec.v0[q].subs(parameters), at);
      }
    }
    const Eigen::FullPivLU<Eigen::MatrixXd> lu(J);
    const Eigen::VectorXd v = lu.solve(-known);
    if (!lu.isInvertible() || !v.allFinite())
      throw_model_error(added.where, context,
                        fmt::format("the constraints that hold the contact point ({}) do not fix its velocity at the "
                                    "start: the contact is not unique there (the shape as flat as the ground)",
                                    join(added.constraints)));
    for (std::size_t j = 0; j < added.coordinates.size(); ++j)
      spec.v0[static_cast<std::size_t>(added.coordinates[j])] = GiNaC::numeric(v(static_cast<Eigen::Index>(j)));
  }
}

}  // namespace nhdyn::symbolic
