// The shapes a rolling body may have ([[contacts]] of a model file, docs/multibody.md): one type
// per shape, each in a file of its own (shapes/), registered once in the table of
// contact_shapes.cpp. A shape knows the key that names it in `shape = { KEY = ... }`, how many
// sizes that key takes and which further keys it has, and its geometry: the support mapping
// y*(nu), the point of the shape lowest along a unit direction nu (body axes), and the reach
// rho(nu) = -nu . y*(nu) (docs/derivations/rolling-bodies.md section 2). The rolling-contact
// builder (rolling_contact.hpp), the loader and the scene go through this table; none of them
// lists shapes.
#pragma once

#include <ginac/ginac.h>

#include <array>
#include <optional>
#include <string>
#include <vector>

#include "nhdyn/symbolic/kinematics.hpp"
#include "nhdyn/symbolic/visual.hpp"

namespace nhdyn::symbolic {

// A shape's sizes once parsed (expressions in the parameters) and its axis where it has one.
struct ShapeValues {
  std::vector<GiNaC::ex> sizes;  // sphere: r; ellipsoid: a, b, c; disk: r; torus: R, r
  int axis = -1;                 // disk, torus: 0, 1, 2 for the body's x, y, z
  // An implicit surface: f in the three coordinates that hold the contact point in body axes
  // (`point`, their symbols; `at`, their indices).
  GiNaC::ex surface = 0;
  Vector3 point = {0, 0, 0};
  std::array<int, 3> at = {-1, -1, -1};
  bool added = false;  // those coordinates were added by nhdyn (no `coordinates` key), not the user's
};

// The support mapping at the unit direction nu (body axes): the shape's point lowest along nu,
// relative to the shape's centre, and its reach rho = -nu . point (> 0).
struct ShapeSupport {
  Vector3 point;
  GiNaC::ex reach;
};

class ContactShape {
 public:
  virtual ~ContactShape() = default;
  // The key naming the shape: shape = { sphere = "r" }.
  virtual std::string key() const = 0;
  // How many sizes the key takes: 1 is a single value, more a list of that many.
  virtual int size_count() const = 0;
  // The names of the sizes, for messages ("r"; "a", "b", "c").
  virtual std::vector<std::string> size_names() const = 0;
  // The further keys of the shape's table (an axle: "axis").
  virtual std::vector<std::string> options() const { return {}; }
  // An example of the table, for messages.
  virtual std::string example() const = 0;
  // y*(nu) and rho(nu) for the unit direction nu / length in body axes, `length` > 0 the length
  // of nu (1 when nu is unit): a quaternion frame's nu is taken without its fraction, R_2^T n,
  // whose length is e.e (docs/derivations/rolling-bodies.md sections 2 and 2.1).
  virtual ShapeSupport support(const ShapeValues& values, const Vector3& nu, const GiNaC::ex& length) const = 0;
  // An implicit surface f(X, Y, Z) = 0 (body axes): its contact point is not a closed form but
  // three coordinates of the model, held by f = 0 and the normals' alignment
  // (docs/derivations/rolling-bodies.md section 9). Its support() returns those coordinates.
  virtual bool implicit() const { return false; }
  // The radius when the shape is a ball (the only shape offered on curved grounds so far).
  virtual std::optional<GiNaC::ex> ball_radius(const ShapeValues&) const { return std::nullopt; }
  // The shape's curvature matrix (body axes) at its support point y*(nu) for nu / length: the
  // Hessian of a defining f over |grad f| there, positive along the directions the surface bends
  // away from the ground (docs/derivations/rolling-bodies.md sections 9 and 11), which the
  // convexity check holds against a curved ground's. Nothing for a shape without one (a disk,
  // infinitely curved across its rim: rim() below) or an implicit shape (whose check uses its f).
  virtual std::optional<GiNaC::matrix> curvature(const ShapeValues&, const Vector3&, const GiNaC::ex&) const {
    return std::nullopt;
  }
  // A shape curved toward the ground along one direction only, infinitely across it (a thin disk:
  // its rim): that direction at the support point y*(nu) for nu / length (body axes, any length)
  // and the curvature along it, which the convexity check holds against the ground's along the
  // same direction (docs/derivations/rolling-bodies.md section 11). Nothing for other shapes.
  struct Rim {
    Vector3 tangent;
    GiNaC::ex curvature;
  };
  virtual std::optional<Rim> rim(const ShapeValues&, const Vector3&, const GiNaC::ex&) const { return std::nullopt; }
  // Whether its sizes must stay within kLargestSizeRatio of each other (model/parameters.hpp): an
  // ellipsoid whose semi-axes are further apart is flat or a needle to double precision, its
  // contact point undefined across its rim; a thin torus is a hoop, well defined.
  virtual bool sizes_in_proportion() const { return false; }
  // The size of the shape for the moment rows of the contact-force solve (a length).
  virtual GiNaC::ex length(const ShapeValues& values) const { return values.sizes.front(); }
  // Where the closed-form contact point is singular along the motion: a measure that is positive
  // where it is defined and 0 where it is not (a disk or torus lying flat: 1 - (e . nu)^2, e its
  // axle), with the reason for the message that ends a run there; nothing for a shape whose
  // contact point is defined for every nu (docs/derivations/rolling-bodies.md section 2).
  struct Singularity {
    GiNaC::ex measure;
    std::string reason;
  };
  virtual std::optional<Singularity> singularity(const ShapeValues&, const Vector3&) const { return std::nullopt; }
  // How the report's scene draws it (symbolic/visual.hpp): the item's kind, sizes, axle and, for
  // an implicit shape, the function whose zero set is drawn, in the body's axes about the shape's
  // centre; the loader places it (`at`, `other`: the centre and the body frame's rotation) and
  // names it.
  virtual VisualItem drawing(const ShapeValues& values) const = 0;
};

// The registered shapes, in the order the docs list them.
const std::vector<const ContactShape*>& contact_shapes();
// The shape called `key`, or nullptr.
const ContactShape* find_contact_shape(const std::string& key);
// "sphere, ellipsoid, disk, torus".
std::string contact_shape_keys();

}  // namespace nhdyn::symbolic
