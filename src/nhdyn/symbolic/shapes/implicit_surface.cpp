// Any smooth, strictly convex f = 0 in the body's axes: shape = { surface = "f" } (rolling-bodies.md
// section 9).
#include "nhdyn/symbolic/detail/shapes.hpp"

namespace nhdyn::symbolic::shapes {
namespace {

// A smooth, strictly convex surface f(X, Y, Z) = 0 in the body's axes (f < 0 inside). The contact
// point y is three coordinates of the model: the support point is y itself, its reach -nu . y.
class ImplicitSurface final : public ContactShape {
 public:
  std::string key() const override { return "surface"; }
  int size_count() const override { return 1; }
  std::vector<std::string> size_names() const override { return {"f"}; }
  std::vector<std::string> options() const override { return {"coordinates"}; }
  std::string example() const override {
    return "shape = { surface = \"X^2/a^2 + Y^4/b^4 + Z^2/c^2 - 1\", coordinates = [\"px\", \"py\", \"pz\"] }";
  }
  bool implicit() const override { return true; }
  ShapeSupport support(const ShapeValues& v, const Vector3& nu, const GiNaC::ex& length) const override {
    return {v.point, -dot(nu, v.point) / length};
  }
  GiNaC::ex length(const ShapeValues&) const override { return 1; }
  // The zero set of f in the contact point's coordinates, which stand for the body's axes about
  // the centre: the report samples it once, along rays from the centre (f < 0 there).
  VisualItem drawing(const ShapeValues& v) const override {
    VisualItem item = drawn(VisualKind::solid, {});
    item.field = v.surface;
    item.field_variables.assign(v.point.begin(), v.point.end());
    return item;
  }
};

}  // namespace

const ContactShape& implicit_surface() {
  static const ImplicitSurface shape;
  return shape;
}

}  // namespace nhdyn::symbolic::shapes
