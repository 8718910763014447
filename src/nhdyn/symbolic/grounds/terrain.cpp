// A terrain Z = h(X, Y): ground = { terrain = "h" } (docs/multibody.md; rolling-bodies.md section 8).
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

// Terrain Z = h(X, Y): a fixed smooth graph over the horizontal world plane. The contact point
// P = (u, v, h(u, v)) is held by two coordinates of the model's own (named by `coordinates`), with
// no inertia of their own, fixed by the two tangential components of body point - P
// (docs/derivations/rolling-bodies.md section 8): A is singular, [D A; b] regular.
class TerrainGround final : public ContactGround {
 public:
  std::string key() const override { return "terrain"; }
  std::vector<std::string> options() const override { return {"coordinates"}; }
  std::string example() const override {
    return "ground = { terrain = \"0.05*sin(X)*cos(2*Y)\", coordinates = [\"u\", \"v\"] }";
  }
  void parse(const GroundText& text, const ContactParsers& p, const std::string& context, const ContactShape&,
             const ShapeValues&, ParsedGround& out) const override {
    const Spec& spec = *p.spec;
    const std::string written = text.value.at(0);
    const GiNaC::symbol X("X"), Y("Y"), Z("Z");
    const GiNaC::ex h = p.surface(written, Vector3{X, Y, Z}, text.where, context + ": terrain");
    if (h.has(Z))
      throw_model_error(text.where, context,
                        fmt::format("the terrain \"{}\" contains Z: a terrain is the height Z = h(X, Y), a function of "
                                    "X and Y only; write h without Z, or a surface g(X, Y, Z) = 0 as ground = {{ "
                                    "surface = \"...\", side = \"outside\" }}",
                                    written));
    if (contact_has_coordinates(h, spec))
      throw_model_error(text.where, context,
                        fmt::format("the terrain \"{}\" depends on t or on a coordinate; a terrain is fixed: write it in "
                                    "X, Y and the parameters",
                                    written));
    // Smooth: the contact's normal is grad h, and the equations take two more derivatives of it.
    for (const GiNaC::ex& e : {h, h.diff(X), h.diff(Y)})
      if (contact_not_smooth(e))
        throw_model_error(text.where, context,
                          fmt::format("the terrain \"{}\" is not differentiable (it uses abs): the contact's normal "
                                      "and its derivatives must exist everywhere the body rolls; write a smooth "
                                      "height, e.g. sqrt(X^2 + eps^2) for |X|",
                                      written));
    const std::vector<int> at = contact_point_coordinates(contact_option_of(text.options, "coordinates", ""), ContactPointOn::terrain, p,
                                                          text.where, context, "a terrain", example(), out.added);
    out.at = {at[0], at[1]};
    out.height = h.subs(GiNaC::lst{X == spec.symbols.coordinate(out.at[0]), Y == spec.symbols.coordinate(out.at[1])});
    out.written = h;
    out.variables = {X, Y};
  }
  std::optional<VisualItem> drawing(const ParsedContact& c, const Spec&, const std::optional<Vector3>&) const override {
    VisualItem item;
    item.kind = VisualKind::terrain;
    item.sizes = {c.shape->length(c.values)};
    item.field = c.ground.written;
    item.field_variables = c.ground.variables;
    return item;
  }
  void check(const ParsedContact&, const Spec&, const std::string&) const override {}
  Touch touch(const ParsedContact& c, const PlacedFrame& F, const Spec& spec, const std::optional<Vector3>&,
              const std::string&) const override {
    Touch out;
    const GiNaC::ex u = spec.symbols.coordinate(c.ground.at[0]), v = spec.symbols.coordinate(c.ground.at[1]);
    const GiNaC::ex h = c.ground.height, hu = h.diff(GiNaC::ex_to<GiNaC::symbol>(u)),
                    hv = h.diff(GiNaC::ex_to<GiNaC::symbol>(v));
    const GiNaC::ex length = GiNaC::sqrt(1 + hu * hu + hv * hv);
    const Vector3 ground_point = {u, v, h};
    out.point = ground_point;
    out.normal = {-hu / length, -hv / length, 1 / length};
    // The tangents P_u, P_v of the graph: not unit, not orthogonal (a row may be scaled).
    out.tangent1 = {1, 0, hu};
    out.tangent2 = {0, 1, hv};
    const Vector3 C = add(F.origin, multiply(F.rotation, c.centre));
    // The body's point whose outward normal is -n (section 2, with n the terrain's normal at P).
    const auto [body_point, reach] = body_support(
        c, F, C, out.normal, multiply_transposed(F.rotation_numerator, out.normal), F.rotation_denominator);
    out.gap = dot(out.normal, subtract(C, ground_point)) - reach;
    const Vector3 apart = subtract(body_point, ground_point);
    out.locate = {{"_at1", dot(out.tangent1, apart)}, {"_at2", dot(out.tangent2, apart)}};
    // As the implicit surface h(X, Y) - Z = 0, whose gradient is -n |grad|: the ground rises
    // along n by 1/2 w^T [h_ij] w / length (a hollow where positive).
    const GiNaC::symbol& us = GiNaC::ex_to<GiNaC::symbol>(u);
    const GiNaC::symbol& vs = GiNaC::ex_to<GiNaC::symbol>(v);
    out.curvature(0, 0) = hu.diff(us) / length;
    out.curvature(0, 1) = out.curvature(1, 0) = hu.diff(vs) / length;
    out.curvature(1, 1) = hv.diff(vs) / length;
    if (c.shape->implicit()) implicit_shape_rows(c, F, out.tangent1, out.tangent2, out);
    // The force acts at the body's point (the same as the ground's on the constraints): there the
    // gap's gradient, the rolling rows and the force's moment agree also off the constraints,
    // where a drifting integration goes (rolling-bodies.md section 8).
    out.point = body_point;
    return out;
  }
};

}  // namespace

const ContactGround& terrain() {
  static const TerrainGround ground;
  return ground;
}

}  // namespace nhdyn::symbolic::grounds
