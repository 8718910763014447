// The ball: shape = { sphere = "r" } (docs/multibody.md; rolling-bodies.md section 2).
#include "nhdyn/symbolic/detail/shapes.hpp"

namespace nhdyn::symbolic::shapes {
namespace {

class Sphere final : public ContactShape {
 public:
  std::string key() const override { return "sphere"; }
  int size_count() const override { return 1; }
  std::vector<std::string> size_names() const override { return {"r"}; }
  std::string example() const override { return "shape = { sphere = \"r\" }"; }
  ShapeSupport support(const ShapeValues& v, const Vector3& nu, const GiNaC::ex& length) const override {
    return {scale(-v.sizes[0] / length, nu), v.sizes[0]};
  }
  std::optional<GiNaC::ex> ball_radius(const ShapeValues& v) const override { return v.sizes[0]; }
  std::optional<GiNaC::matrix> curvature(const ShapeValues& v, const Vector3&, const GiNaC::ex&) const override {
    GiNaC::matrix K(3, 3);
    for (unsigned i = 0; i < 3; ++i) K(i, i) = 1 / v.sizes[0];
    return K;
  }
  VisualItem drawing(const ShapeValues& v) const override { return drawn(VisualKind::ellipsoid, {v.sizes[0], v.sizes[0], v.sizes[0]}); }
};

}  // namespace

const ContactShape& sphere() {
  static const Sphere shape;
  return shape;
}

}  // namespace nhdyn::symbolic::shapes
