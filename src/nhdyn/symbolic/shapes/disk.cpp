// The thin disk (a wheel's rim): shape = { disk = "r", axis = "y" } (rolling-bodies.md section 2).
#include "nhdyn/symbolic/detail/shapes.hpp"

namespace nhdyn::symbolic::shapes {
namespace {

// A thin disk of radius r normal to its axis.
class Disk final : public ContactShape {
 public:
  std::string key() const override { return "disk"; }
  int size_count() const override { return 1; }
  std::vector<std::string> size_names() const override { return {"r"}; }
  std::vector<std::string> options() const override { return {"axis"}; }
  std::string example() const override { return "shape = { disk = \"r\", axis = \"y\" }"; }
  ShapeSupport support(const ShapeValues& v, const Vector3& nu, const GiNaC::ex& length) const override {
    GiNaC::ex across;
    const Vector3 d = rim_direction(nu, length, v.axis, across);
    return {scale(v.sizes[0], d), v.sizes[0] * across / length};
  }
  std::optional<Singularity> singularity(const ShapeValues& v, const Vector3& nu) const override {
    const GiNaC::ex along = nu[static_cast<std::size_t>(v.axis)];
    return Singularity{1 - along * along, "the disk lies flat: its axle is along the ground's normal, where every point of "
                                          "its rim is lowest and the contact point is not defined"};
  }
  // The rim circle's curvature along t = e x nu at its lowest point, |e x nu| / (R |nu|): the
  // torus's with no tube (docs/derivations/rolling-bodies.md section 11).
  std::optional<Rim> rim(const ShapeValues& v, const Vector3& nu, const GiNaC::ex& length) const override {
    const GiNaC::ex en = nu[static_cast<std::size_t>(v.axis)];
    return Rim{cross(unit(v.axis), nu), GiNaC::sqrt(length * length - en * en) / (v.sizes[0] * length)};
  }
  VisualItem drawing(const ShapeValues& v) const override {
    VisualItem item = drawn(VisualKind::wheel, {});
    item.size = v.sizes[0];
    item.axis = v.axis;
    return item;
  }
};

}  // namespace

const ContactShape& disk() {
  static const Disk shape;
  return shape;
}

}  // namespace nhdyn::symbolic::shapes
