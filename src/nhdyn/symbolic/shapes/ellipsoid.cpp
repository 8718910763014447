// The ellipsoid on its axes: shape = { ellipsoid = ["a", "b", "c"] } (rolling-bodies.md section 2).
#include "nhdyn/symbolic/detail/shapes.hpp"

namespace nhdyn::symbolic::shapes {
namespace {

// x^T M x = 1, M = diag(1/a^2, 1/b^2, 1/c^2): y* = -M^{-1} nu / sqrt(nu^T M^{-1} nu), the same for
// every length of nu; the reach sqrt(nu^T M^{-1} nu) is of degree 1 in nu, so divided by its length.
class Ellipsoid final : public ContactShape {
 public:
  std::string key() const override { return "ellipsoid"; }
  int size_count() const override { return 3; }
  std::vector<std::string> size_names() const override { return {"a", "b", "c"}; }
  std::string example() const override { return "shape = { ellipsoid = [\"a\", \"b\", \"c\"] }"; }
  bool sizes_in_proportion() const override { return true; }
  ShapeSupport support(const ShapeValues& v, const Vector3& nu, const GiNaC::ex& length) const override {
    const Vector3 Minv_nu = {v.sizes[0] * v.sizes[0] * nu[0], v.sizes[1] * v.sizes[1] * nu[1],
                             v.sizes[2] * v.sizes[2] * nu[2]};
    const GiNaC::ex root = GiNaC::sqrt(dot(nu, Minv_nu));
    return {scale(-1 / root, Minv_nu), root / length};
  }
  // f = y^T M y - 1: H = 2 M and grad f = 2 M y*, of length |nu| / sqrt(nu^T M^{-1} nu) at y*, so
  // K = M sqrt(nu^T M^{-1} nu) / length.
  std::optional<GiNaC::matrix> curvature(const ShapeValues& v, const Vector3& nu, const GiNaC::ex& length) const override {
    GiNaC::ex quadratic = 0;
    for (std::size_t i = 0; i < 3; ++i) quadratic += v.sizes[i] * v.sizes[i] * nu[i] * nu[i];
    const GiNaC::ex factor = GiNaC::sqrt(quadratic) / length;
    GiNaC::matrix K(3, 3);
    for (unsigned i = 0; i < 3; ++i) K(i, i) = factor / (v.sizes[i] * v.sizes[i]);
    return K;
  }
  GiNaC::ex length(const ShapeValues& v) const override { return v.sizes[0]; }
  VisualItem drawing(const ShapeValues& v) const override { return drawn(VisualKind::ellipsoid, v.sizes); }
};

}  // namespace

const ContactShape& ellipsoid() {
  static const Ellipsoid shape;
  return shape;
}

}  // namespace nhdyn::symbolic::shapes
