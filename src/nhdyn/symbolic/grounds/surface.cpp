// A fixed smooth surface: ground = { surface = "g(X, Y, Z)", side = ... } (docs/multibody.md;
// rolling-bodies.md sections 3 and 11).
#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <exception>

#include "nhdyn/core/error.hpp"
#include "nhdyn/symbolic/detail/contact_geometry.hpp"
#include "nhdyn/symbolic/detail/grounds.hpp"
#include "nhdyn/symbolic/multibody.hpp"
#include "nhdyn/symbolic/simplify.hpp"

namespace nhdyn::symbolic::grounds {
namespace {

// A fixed smooth surface g(X, Y, Z) = 0, the body on the side `side` names. A ball on a sphere
// (g a quadratic whose Hessian is a nonzero multiple of the identity) has its contact point in
// closed form (rolling-bodies.md section 3); any other shape or surface, or a ball on a sphere
// given `coordinates`, has it held by three coordinates of the model (section 11).
class SurfaceGround final : public ContactGround {
 public:
  std::string key() const override { return "surface"; }
  std::vector<std::string> options() const override { return {"side", "coordinates"}; }
  std::string example() const override {
    return "ground = { surface = \"X^2 + Y^2 + (Z - R)^2 - R^2\", side = \"inside\" }";
  }
  void parse(const GroundText& text, const ContactParsers& p, const std::string& context, const ContactShape& shape,
             const ShapeValues& values, ParsedGround& out) const override {
    const Spec& spec = *p.spec;
    const std::string written = text.value.at(0);
    const GiNaC::symbol X("X"), Y("Y"), Z("Z");
    const GiNaC::ex g = p.surface(written, Vector3{X, Y, Z}, text.where, context + ": surface").expand();
    const std::string side = contact_option_of(text.options, "side", "");
    if (side != "inside" && side != "outside")
      throw_model_error(text.where, context,
                        side.empty() ? "a surface ground needs side = \"inside\" (the body is where g < 0, e.g. in a "
                                       "bowl) or side = \"outside\" (where g > 0)"
                                     : fmt::format("unknown side '{}'; choose \"inside\" (the body is where g < 0) or "
                                                   "\"outside\" (where g > 0)",
                                                   side));
    if (contact_has_coordinates(g, spec))
      throw_model_error(text.where, context,
                        fmt::format("the surface \"{}\" depends on t or on a coordinate; a surface ground is fixed: "
                                    "write it in X, Y, Z and the parameters",
                                    written));
    // Smooth: the contact's normal is grad g, and the equations take two more derivatives of it.
    if (!g.has(X) && !g.has(Y) && !g.has(Z))
      throw_model_error(text.where, context,
                        fmt::format("the surface \"{}\" does not depend on X, Y or Z, so it is no surface; write "
                                    "g(X, Y, Z) = 0, e.g. {}",
                                    written, example()));
    for (const GiNaC::ex& e : {g, g.diff(X), g.diff(Y), g.diff(Z)})
      if (contact_not_smooth(e))
        throw_model_error(text.where, context,
                          fmt::format("the surface \"{}\" is not differentiable (it uses abs or a step): the contact's "
                                      "normal and its derivatives must exist everywhere the body rolls; write a "
                                      "smooth g, e.g. sqrt(X^2 + eps^2) for |X|",
                                      written));
    out.written = g;
    out.variables = {X, Y, Z};
    const std::string names = contact_option_of(text.options, "coordinates", "");
    if (names.empty() && shape.ball_radius(values) && sphere(g, text, p, context, side, out)) return;
    // The contact point U on the ground as coordinates (section 11); the body's side: g < 0 inside.
    out.inside = side == "inside";
    const std::vector<int> at = contact_point_coordinates(names, ContactPointOn::surface, p, text.where, context,
                                                          "a surface ground", kCoordinatesExample, out.added);
    for (std::size_t i = 0; i < 3; ++i) out.point[i] = at[i];
    out.surface = g.subs(GiNaC::lst{X == spec.symbols.coordinate(at[0]), Y == spec.symbols.coordinate(at[1]),
                                    Z == spec.symbols.coordinate(at[2])});
  }
  // A sphere's zero set sampled along rays from its centre (every ray meets it once); any other
  // surface over its tangent plane at the contact path's mean point (the report, io/report.cpp).
  std::optional<VisualItem> drawing(const ParsedContact& c, const Spec&, const std::optional<Vector3>&) const override {
    VisualItem item;
    item.kind = VisualKind::surface;
    const bool rays = c.ground.point[0] < 0;
    item.sizes = {c.shape->length(c.values), c.ground.centre_x, c.ground.centre_y, c.ground.centre_z, rays ? 1 : 0};
    item.field = c.ground.written;
    item.field_variables = c.ground.variables;
    return item;
  }
  void check(const ParsedContact& c, const Spec& spec, const std::string& context) const override {
    if (c.ground.point[0] >= 0) return;  // a ball flatter than the ground: checked at the start (SpecConvexity)
    const double ball = contact_number_of(*c.shape->ball_radius(c.values), spec).value_or(0.0);
    const double sphere = contact_number_of(c.ground.radius, spec).value_or(0.0);
    if (c.ground.inside && !(ball < sphere))
      throw_model_error(c.where, context,
                        fmt::format("the ball (radius {:.6g}) is not smaller than the bowl (radius {:.6g}): it cannot "
                                    "roll inside it with a single contact point; the ball's radius must be less than "
                                    "the bowl's",
                                    ball, sphere));
  }
  Touch touch(const ParsedContact& c, const PlacedFrame& F, const Spec& spec, const std::optional<Vector3>& gravity,
              const std::string&) const override {
    if (c.ground.point[0] >= 0) return located(c, F, spec, gravity);
    Touch out;
    const GiNaC::ex r = *c.shape->ball_radius(c.values);
    const Vector3 K = {c.ground.centre_x, c.ground.centre_y, c.ground.centre_z};
    const Vector3 C = add(F.origin, multiply(F.rotation, c.centre));
    const Vector3 KC = subtract(C, K);
    const GiNaC::ex distance = GiNaC::sqrt(dot(KC, KC));
    // Inside, the normal out of the wall points to the sphere's centre; outside, away from it.
    out.normal = scale((c.ground.inside ? -1 : 1) / distance, KC);
    out.point = subtract(C, scale(r, out.normal));
    out.gap = c.ground.inside ? c.ground.radius - r - distance : distance - c.ground.radius - r;
    // Tangent rows e x (C - K) and (C - K) x (e x (C - K)), e the world axis least aligned with
    // gravity (docs/derivations/rolling-bodies.md section 4.2).
    const Vector3 e = unit(contact_least_aligned_axis(gravity ? *gravity : unit(2), spec));
    out.tangent1 = cross(e, KC);
    out.tangent2 = cross(KC, out.tangent1);
    return out;
  }

 private:
  static constexpr const char* kCoordinatesExample =
      "ground = { surface = \"X^2/a^2 + Y^2/b^2 + (Z - c)^2/c^2 - 1\", side = \"inside\", coordinates = [\"gx\", "
      "\"gy\", \"gz\"] }";

  // g = alpha |X - K|^2 - alpha R^2 (equal square terms, no products, degree 2): fills the
  // sphere's centre K and radius and returns true; false for any other g.
  static bool sphere(const GiNaC::ex& g, const GroundText& text, const ContactParsers& p, const std::string& context,
                     const std::string& side, ParsedGround& out) {
    const GiNaC::ex X = out.variables[0], Y = out.variables[1], Z = out.variables[2];
    if (!g.is_polynomial(GiNaC::lst{X, Y, Z})) return false;
    const GiNaC::ex alpha = g.coeff(X, 2);
    bool quadric = g.degree(X) == 2 && g.degree(Y) == 2 && g.degree(Z) == 2 &&
                   symbolic::is_zero(g.coeff(Y, 2) - alpha) && symbolic::is_zero(g.coeff(Z, 2) - alpha) &&
                   !symbolic::is_zero(alpha);
    for (const GiNaC::ex& cross_term : {g.coeff(X, 1).coeff(Y, 1), g.coeff(X, 1).coeff(Z, 1), g.coeff(Y, 1).coeff(Z, 1)})
      quadric = quadric && symbolic::is_zero(cross_term);
    const std::optional<double> a = quadric ? contact_number_of(alpha, *p.spec) : std::nullopt;
    if (!quadric || !a || *a == 0.0) return false;
    const GiNaC::ex zero = g.subs(GiNaC::lst{X == 0, Y == 0, Z == 0});
    out.centre_x = simplify(-g.coeff(X, 1).subs(GiNaC::lst{Y == 0, Z == 0}) / (2 * alpha));
    out.centre_y = simplify(-g.coeff(Y, 1).subs(GiNaC::lst{X == 0, Z == 0}) / (2 * alpha));
    out.centre_z = simplify(-g.coeff(Z, 1).subs(GiNaC::lst{X == 0, Y == 0}) / (2 * alpha));
    const GiNaC::ex squared = simplify(out.centre_x * out.centre_x + out.centre_y * out.centre_y +
                                       out.centre_z * out.centre_z - zero / alpha);
    const std::optional<double> r2 = contact_number_of(squared, *p.spec);
    if (!r2 || !(*r2 > 0.0))
      throw_model_error(text.where, context,
                        fmt::format("the sphere \"{}\" has no points (its radius squared is {}); check its radius",
                                    text.value.at(0), r2 ? fmt::format("{:.6g}", *r2) : "not a number"));
    // A perfect square R^2 gives R (positive at the parameter values).
    GiNaC::ex radius = GiNaC::sqrt(squared);
    if (GiNaC::is_a<GiNaC::power>(squared) && squared.op(1) == 2) {
      const std::optional<double> base = contact_number_of(squared.op(0), *p.spec);
      if (base) radius = *base > 0 ? squared.op(0) : -squared.op(0);
    }
    out.radius = radius;
    // g < 0 is inside the sphere when alpha > 0.
    out.inside = (side == "inside") == (*a > 0.0);
    return true;
  }

  // The contact point U = (X, Y, Z) held by coordinates (rolling-bodies.md section 11):
  // n = sigma grad g / |grad g|, tangents e x grad g and grad g x (e x grad g), B the body's
  // support point along n; g(U) = 0 and the tangential components of B - U hold U.
  static Touch located(const ParsedContact& c, const PlacedFrame& F, const Spec& spec,
                       const std::optional<Vector3>& gravity) {
    Touch out;
    const Vector3 U = {spec.symbols.coordinate(c.ground.point[0]), spec.symbols.coordinate(c.ground.point[1]),
                       spec.symbols.coordinate(c.ground.point[2])};
    Vector3 gradient;
    for (std::size_t i = 0; i < 3; ++i) gradient[i] = c.ground.surface.diff(GiNaC::ex_to<GiNaC::symbol>(U[i]));
    const GiNaC::ex length = GiNaC::sqrt(dot(gradient, gradient));
    const int sigma = c.ground.inside ? -1 : 1;
    out.normal = scale(sigma / length, gradient);
    // Divided by g's scale (a number), so that the rows are about as large as lengths whatever
    // the scale of g, without a root of |grad g| in the expressions that are differentiated twice.
    const Vector3 C = add(F.origin, multiply(F.rotation, c.centre));
    const GiNaC::numeric size = exact_scale(gradient_scale(gradient, U, C, spec));
    const int axis = contact_least_aligned_axis(gravity ? *gravity : unit(2), spec);
    const Vector3 e = unit(axis);
    out.tangent1 = scale(1 / size, cross(e, gradient));
    out.tangent2 = scale(1 / size, cross(gradient, out.tangent1));
    out.singular = std::make_pair(
        dot(cross(e, gradient), cross(e, gradient)) / dot(gradient, gradient),
        fmt::format("the ground's normal turns along the world's {} axis, where the two directions of its rolling rows "
                    "(e x grad g and grad g x (e x grad g), e that axis) vanish; a bowl's wall or a hill's side steeper "
                    "than that is not offered: keep the motion away from it, or turn the model so that gravity is "
                    "along another axis",
                    "xyz"[axis]));
    // The support point along sigma N^T grad g, whose length is s |grad g| (R = N / s), so that
    // |grad g| stays out of the expressions that are differentiated twice (as on a plane,
    // rolling-bodies.md section 2.1).
    const auto [body_point, reach] =
        body_support(c, F, C, out.normal, multiply_transposed(F.rotation_numerator, scale(sigma, gradient)),
                     F.rotation_denominator * length);
    out.gap = dot(out.normal, subtract(C, U)) - reach;
    const Vector3 apart = subtract(body_point, U);
    // g over its scale: about U's distance from the surface, in length units whatever g's scale.
    out.locate = {{"_ground", c.ground.surface / size}, {"_at1", dot(out.tangent1, apart)},
                  {"_at2", dot(out.tangent2, apart)}};
    // The ground rises along n by 1/2 w^T K w, K = -sigma H / |grad g| (a hollow where positive).
    for (unsigned i = 0; i < 3; ++i)
      for (unsigned j = 0; j < 3; ++j)
        out.curvature(i, j) = -sigma * gradient[i].diff(GiNaC::ex_to<GiNaC::symbol>(U[j])) / length;
    if (c.shape->implicit()) implicit_shape_rows(c, F, out.tangent1, out.tangent2, out);
    // The force acts at the body's point, as on terrain (section 8).
    out.point = body_point;
    return out;
  }
};

}  // namespace

const ContactGround& surface() {
  static const SurfaceGround ground;
  return ground;
}

}  // namespace nhdyn::symbolic::grounds
