// The round tyre: shape = { torus = ["R", "r"], axis = "y" } (rolling-bodies.md sections 2 and 11).
#include "nhdyn/symbolic/detail/shapes.hpp"

namespace nhdyn::symbolic::shapes {
namespace {

// The round tyre: the rim circle of radius R swept by a ball of radius r (its convex hull touches
// a plane where the torus does): support points add over the Minkowski sum.
class Torus final : public ContactShape {
 public:
  std::string key() const override { return "torus"; }
  int size_count() const override { return 2; }
  std::vector<std::string> size_names() const override { return {"R", "r"}; }
  std::vector<std::string> options() const override { return {"axis"}; }
  std::string example() const override { return "shape = { torus = [\"R\", \"r\"], axis = \"y\" }"; }
  ShapeSupport support(const ShapeValues& v, const Vector3& nu, const GiNaC::ex& length) const override {
    GiNaC::ex across;
    const Vector3 d = rim_direction(nu, length, v.axis, across);
    return {subtract(scale(v.sizes[0], d), scale(v.sizes[1] / length, nu)), v.sizes[0] * across / length + v.sizes[1]};
  }
  std::optional<Singularity> singularity(const ShapeValues& v, const Vector3& nu) const override {
    const GiNaC::ex along = nu[static_cast<std::size_t>(v.axis)];
    return Singularity{1 - along * along, "the torus lies flat: its axle is along the ground's normal, where every point of "
                                          "its rim is lowest and the contact point is not defined"};
  }
  // The radii of curvature add over the Minkowski sum: the rim circle's are R |nu| / |e x nu| along
  // t = e x nu / |e x nu| and 0 across, the tube's r in every direction; so on the tangent plane
  // K = k_t t t^T + (I - t t^T) / r, k_t = |e x nu| / (R |nu| + r |e x nu|)
  // (docs/derivations/rolling-bodies.md section 11).
  std::optional<GiNaC::matrix> curvature(const ShapeValues& v, const Vector3& nu, const GiNaC::ex& length) const override {
    const GiNaC::ex en = nu[static_cast<std::size_t>(v.axis)];
    const GiNaC::ex across_squared = length * length - en * en;
    const GiNaC::ex across = GiNaC::sqrt(across_squared);
    const Vector3 t = cross(unit(v.axis), nu);  // of length |e x nu|
    const GiNaC::ex k_tube = 1 / v.sizes[1];
    const GiNaC::ex k_rim = across / (v.sizes[0] * length + v.sizes[1] * across);
    GiNaC::matrix K(3, 3);
    for (unsigned i = 0; i < 3; ++i)
      for (unsigned j = 0; j < 3; ++j)
        K(i, j) = (i == j ? k_tube : GiNaC::ex(0)) + (k_rim - k_tube) * t[i] * t[j] / across_squared;
    return K;
  }
  GiNaC::ex length(const ShapeValues& v) const override { return v.sizes[0] + v.sizes[1]; }
  VisualItem drawing(const ShapeValues& v) const override {
    VisualItem item = drawn(VisualKind::torus, v.sizes);
    item.axis = v.axis;
    return item;
  }
};

}  // namespace

const ContactShape& torus() {
  static const Torus shape;
  return shape;
}

}  // namespace nhdyn::symbolic::shapes
