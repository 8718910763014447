#include "nhdyn/symbolic/contact_shapes.hpp"

#include "nhdyn/core/join.hpp"

namespace nhdyn::symbolic {
namespace {

// e (e . nu) - nu over |e x nu|: the unit direction in the plane normal to e closest to -nu
// (the rim point of a disk, docs/derivations/rolling-wheel.md), the same for every length of nu;
// `across` = |e x nu| = sqrt(nu . nu - (e . nu)^2), with nu . nu = length^2.
Vector3 rim_direction(const Vector3& nu, const GiNaC::ex& length, int axis, GiNaC::ex& across) {
  const Vector3 e = unit(axis);
  const GiNaC::ex en = nu[static_cast<std::size_t>(axis)];
  across = GiNaC::sqrt(length * length - en * en);
  return scale(1 / across, subtract(scale(en, e), nu));
}

VisualItem drawn(VisualKind kind, std::vector<GiNaC::ex> sizes) {
  VisualItem item;
  item.kind = kind;
  item.sizes = std::move(sizes);
  return item;
}

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

// x^T M x = 1, M = diag(1/a^2, 1/b^2, 1/c^2): y* = -M^{-1} nu / sqrt(nu^T M^{-1} nu), the same for
// every length of nu; the reach sqrt(nu^T M^{-1} nu) is of degree 1 in nu, so divided by its length.
class Ellipsoid final : public ContactShape {
 public:
  std::string key() const override { return "ellipsoid"; }
  int size_count() const override { return 3; }
  std::vector<std::string> size_names() const override { return {"a", "b", "c"}; }
  std::string example() const override { return "shape = { ellipsoid = [\"a\", \"b\", \"c\"] }"; }
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

const std::vector<const ContactShape*>& contact_shapes() {
  static const Sphere sphere;
  static const Ellipsoid ellipsoid;
  static const Disk disk;
  static const Torus torus;
  static const ImplicitSurface surface;
  static const std::vector<const ContactShape*> table = {&sphere, &ellipsoid, &disk, &torus, &surface};
  return table;
}

const ContactShape* find_contact_shape(const std::string& key) {
  for (const ContactShape* shape : contact_shapes())
    if (shape->key() == key) return shape;
  return nullptr;
}

std::string contact_shape_keys() {
  std::vector<std::string> keys;
  for (const ContactShape* shape : contact_shapes()) keys.push_back(shape->key());
  return join(keys);
}

}  // namespace nhdyn::symbolic
