// The plane ground, fixed or a turntable: ground = "plane" or
// { plane = [0, 0, 1], angular_velocity = "Omega" } (docs/multibody.md; rolling-bodies.md sections 2
// to 4).
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

// The plane through the origin, fixed or turning about its normal (a turntable).
class PlaneGround final : public ContactGround {
 public:
  std::string key() const override { return "plane"; }
  std::vector<std::string> options() const override { return {"angular_velocity"}; }
  std::string example() const override { return "ground = { plane = [0, 0, 1], angular_velocity = \"Omega\" }"; }
  void parse(const GroundText& text, const ContactParsers& p, const std::string& context, const ContactShape&,
             const ShapeValues&, ParsedGround& out) const override {
    if (text.value.size() == 3)
      out.normal = Vector3{p.constant(text.value[0], text.where, context + ": plane normal"),
                           p.constant(text.value[1], text.where, context + ": plane normal"),
                           p.constant(text.value[2], text.where, context + ": plane normal")};
    const std::string rate = contact_option_of(text.options, "angular_velocity", "");
    if (!rate.empty()) out.angular_velocity = p.of_time(rate, text.where, context + ": angular_velocity");
  }
  void check(const ParsedContact&, const Spec&, const std::string&) const override {}
  Touch touch(const ParsedContact& c, const PlacedFrame& F, const Spec& spec, const std::optional<Vector3>& gravity,
              const std::string& context) const override {
    Touch out;
    const Vector3 n = ground_plane_normal(c.ground, spec, gravity, context);
    const Vector3 C = add(F.origin, multiply(F.rotation, c.centre));
    // nu = R^T n, the normal in the body's axes; the support point lowest along it. Taken as
    // N^T n, R = N / s (a quaternion frame: N = R_2(e), s = e.e), of length s: the support
    // mapping depends on the direction only, and without the fraction the expressions that are
    // differentiated twice stay polynomial inside the root (rolling-bodies.md section 2.1).
    const Vector3 nu = multiply_transposed(F.rotation_numerator, n);
    const Vector3 nu_s = {simplify_moderate(nu[0]), simplify_moderate(nu[1]), simplify_moderate(nu[2])};
    if (c.values.axis >= 0) {
      // A disk or torus whose axle is along the normal in every position has no lowest rim point
      // anywhere: |e x nu|^2 = |nu|^2 - (e . nu)^2 is 0 whatever the coordinates.
      const GiNaC::ex along = nu_s[static_cast<std::size_t>(c.values.axis)];
      if (symbolic::is_zero(F.rotation_denominator * F.rotation_denominator - along * along))
        throw_model_error(c.where, context,
                          "the axle is along the plane's normal in every position: the disk lies flat whatever the "
                          "coordinates, so it has no lowest rim point to roll on; give as `axis` the axle of the "
                          "body's frame that is parallel to the plane when the wheel stands");
    }
    ShapeSupport s = c.shape->support(c.values, nu_s, F.rotation_denominator);
    // A wheel's |e x nu| in angles is often a perfect square's root, sqrt(cos(theta)^2): written
    // cos(theta) (docs/derivations/rolling-wheel.md), for a wheel that stays on the plane. One that
    // may lift off keeps the root (in the air it may turn over: its gap is z - r |cos(theta)|
    // whatever its lean), and so does a [[contacts]] disk, which may start on either side of its
    // reference configuration.
    if (c.entry == "wheel" && !c.unilateral) {
      for (GiNaC::ex& x : s.point) x = contact_roots_of_squares(x, spec, out.signed_roots);
      s.reach = contact_roots_of_squares(s.reach, spec, out.signed_roots);
    }
    out.point = add(C, multiply(F.rotation, s.point));
    out.normal = n;
    out.gap = dot(n, C) - s.reach;
    out.ground_omega = scale(c.ground.angular_velocity, n);
    out.ground_velocity = cross(out.ground_omega, out.point);
    std::tie(out.tangent1, out.tangent2) = plane_tangents(n, spec);
    if (c.shape->implicit()) implicit_shape_rows(c, F, out.tangent1, out.tangent2, out);
    return out;
  }
  // The plane's own axes (t1, t2, n) at the origin; a turntable's turning is its rate, integrated
  // by the report (io/report.hpp). The level plane that does not turn is the scene's grid in z = 0:
  // compile_visual leaves it to that grid unless another plane is drawn.
  std::optional<VisualItem> drawing(const ParsedContact& c, const Spec& spec,
                                    const std::optional<Vector3>& gravity) const override {
    // Without a normal or a gravity the contact itself is refused (make_rolling_contact).
    if (!c.ground.normal && !gravity) return std::nullopt;
    const Vector3 n = ground_plane_normal(c.ground, spec, gravity, fmt::format("{} '{}'", c.entry, c.name));
    const auto [t1, t2] = plane_tangents(n, spec);
    VisualItem item;
    item.kind = VisualKind::plane;
    item.at = {0, 0, 0};
    for (std::size_t i = 0; i < 3; ++i) item.other.insert(item.other.end(), {t1[i], t2[i], n[i]});
    item.field = c.ground.angular_velocity;
    item.field_variables = {spec.symbols.time()};
    return item;
  }
};

}  // namespace

const ContactGround& plane() {
  static const PlaneGround ground;
  return ground;
}

}  // namespace nhdyn::symbolic::grounds
