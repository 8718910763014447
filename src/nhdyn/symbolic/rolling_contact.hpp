// A convex body rolling on a ground ([[contacts]] of a model file, docs/multibody.md): the
// description as the user wrote it (ContactText), the grounds (one type each in grounds/,
// registered once in rolling_contact.cpp, as the shapes are in shapes/ and contact_shapes.cpp), and
// what the multibody builder
// adds for one contact: the contact condition (the gap), the rolling constraints, the no-spin
// constraint of rubber rolling, the contact point, and the contact-force description.
// docs/derivations/rolling-bodies.md derives every expression here.
//
//     model file [[contacts]] -> ContactText -> parse_contact -> ParsedContact
//         -> (MultibodyBuilder::apply) make_rolling_contact -> constraints, ContactPoint, outputs
#pragma once

#include <ginac/ginac.h>

#include <array>
#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "nhdyn/symbolic/contact_forces.hpp"
#include "nhdyn/symbolic/contact_shapes.hpp"
#include "nhdyn/symbolic/kinematics.hpp"
#include "nhdyn/symbolic/spec.hpp"

namespace nhdyn::symbolic {

struct PlacedFrame;

using KeyTexts = std::vector<std::pair<std::string, std::string>>;  // further keys of a table, as text

// The ground as written: ground = "plane", or a table whose identifying key is `key`.
struct GroundText {
  std::string key = "plane";
  std::vector<std::string> value;  // plane: the normal (3 expressions) or none; surface: g (one);
                                   // terrain: h (one)
  KeyTexts options;                // angular_velocity = "Omega", side = "inside", coordinates = "u, v"
                                   // (terrain) or "gx, gy, gz" (surface)
                                   // (an array option's elements joined by ", ")
  SourceLocation where;
};

// One [[contacts]] entry as written (every value an expression in quotes or a number as text).
struct ContactText {
  std::string name;
  std::string body;
  std::string shape;                // the key naming the shape: "sphere", "ellipsoid", ...
  std::vector<std::string> sizes;   // its value(s)
  KeyTexts shape_options;           // axis = "y"
  std::optional<std::array<std::string, 3>> centre;
  GroundText ground;
  std::string rolling = "rolling";  // "rolling" or "rubber"
  KeyTexts modes;                   // friction (or mu_s, mu_k), unilateral, restitution, mode (contact_modes.hpp)
  // The no-slip rows are NAME + this + 1 and 2: "_roll"; a [[wheels]] entry without the contact
  // modes' keys keeps its rows' names, "_slip" (docs/multibody.md). With modes they are "_roll"
  // whatever this says (the contact modes find them by that name).
  std::string no_slip_suffix = "_roll";
  // What the messages call the entry ("contact 'NAME'"; "wheel" for a [[wheels]] entry), and the
  // names of its sizes where they are keys of their own (a wheel's "radius"; empty: the shape's).
  std::string entry = "contact";
  std::vector<std::string> size_keys;
  SourceLocation where, shape_where, ground_where;
};

class ContactGround;

// A ground once parsed.
struct ParsedGround {
  const ContactGround* type = nullptr;
  std::optional<Vector3> normal;    // plane: given (not yet normalized), else opposite to gravity
  GiNaC::ex angular_velocity = 0;   // plane: the turntable's rate Omega(t) about its normal
  GiNaC::ex centre_x = 0, centre_y = 0, centre_z = 0;  // surface (a sphere, closed form): its centre K
  GiNaC::ex radius = 0;             // surface (a sphere, closed form): its radius R_g
  bool inside = false;              // surface: the body is where g < 0 (a bowl)
  // plane: how the entry writes a normal, for the messages (a [[wheels]] entry: normal = [...]).
  std::string normal_example = "ground = { plane = [0, 0, 1] }";
  std::array<int, 2> at = {-1, -1};  // terrain: the coordinates holding the contact point's X and Y
  GiNaC::ex height = 0;             // terrain: h(X, Y) at X, Y = those coordinates
  // surface, not a closed form (rolling-bodies.md section 11): the coordinates holding the contact
  // point U on the ground (X, Y, Z), and g at U. Empty (-1) for a ball on a sphere in closed form.
  std::array<int, 3> point = {-1, -1, -1};
  GiNaC::ex surface = 0;
  bool added = false;               // terrain, surface: those coordinates were added by nhdyn (no `coordinates` key)
  // terrain: h in `variables` X, Y; surface: g in X, Y, Z (world): what the report draws.
  GiNaC::ex written = 0;
  std::vector<GiNaC::ex> variables;
  SourceLocation where;
};

// A contact once parsed: the body's index among the builder's bodies, the shape and its values.
struct ParsedContact {
  std::string name;
  int body = -1;
  const ContactShape* shape = nullptr;
  ShapeValues values;
  std::vector<SpecPositive> positive;  // its sizes, judged again when the parameters change
  Vector3 centre = {0, 0, 0};  // the shape's centre in the body frame's axes
  ParsedGround ground;
  bool rubber = false;
  // unilateral = true: the body may leave the ground and tumble in the air, where a disk's |e x nu|
  // takes both signs (its contact point keeps the root; grounds/plane.cpp).
  bool unilateral = false;
  std::string no_slip_suffix = "_roll";  // ContactText::no_slip_suffix
  std::string entry = "contact";         // ContactText::entry
  SourceLocation where;
};

// What parse_contact needs from the multibody builder. Every function throws ModelError naming
// `where` and `context`.
struct ContactParsers {
  const Spec* spec = nullptr;
  // A constant: parameters only.
  std::function<GiNaC::ex(const std::string& text, const SourceLocation& where, const std::string& context)> constant;
  // An expression in t and the parameters (no coordinates): a turntable's rate.
  std::function<GiNaC::ex(const std::string& text, const SourceLocation& where, const std::string& context)> of_time;
  // A surface g(X, Y, Z) with X, Y, Z replaced by `at`.
  std::function<GiNaC::ex(const std::string& text, const Vector3& at, const SourceLocation& where,
                          const std::string& context)>
      surface;
  // The index of a body, or a failure listing the bodies.
  std::function<int(const std::string& name, const SourceLocation& where, const std::string& context)> body;
  // Adds a coordinate to the model (a contact point's, when the contact names none) and returns
  // its index; unset where coordinates may not be added.
  std::function<int(const std::string& name, const SourceLocation& where)> add_coordinate;
  std::string contact;  // the contact's name, set by parse_contact (the added coordinates' prefix)
};

// What one contact adds to the model.
struct RollingContact {
  struct Row {
    std::string name;
    ConstraintLevel level;
    GiNaC::ex expression;
    std::string text;
  };
  std::vector<Row> constraints;   // NAME_contact (the gap; left out when it holds identically),
                                  // NAME_at1, NAME_at2 on terrain (the contact point's coordinates),
                                  // NAME_on, NAME_normal1, NAME_normal2 for an implicit surface,
                                  // NAME_roll1, NAME_roll2, and NAME_spin for rubber
  ContactPoint force;             // for the contact forces (system left for the builder to set)
  Vector3 point;                  // the contact point P, world
  GiNaC::ex length;               // a length of the shape, for the moment rows
  Vector3 normal, tangent1, tangent2;  // world: the ground's normal and the no-slip rows' directions
  std::optional<SpecConvexity> convexity;  // an implicit shape: checked at the initial state
  // The contact point's coordinates that nhdyn added (no `coordinates` key): found at the start.
  std::optional<SpecContactCoordinates> added;
  // What turns singular along the motion (a disk lying flat, a surface's normal along the axis its
  // tangents are built from): watched by the run.
  std::vector<SpecContactWatch> watches;
};

// A ground type: its key, the further keys of its table, and where a shape touches it.
class ContactGround {
 public:
  virtual ~ContactGround() = default;
  virtual std::string key() const = 0;
  virtual std::vector<std::string> options() const = 0;
  virtual std::string example() const = 0;
  // Reads the ground's value and options into `out` (out.type is set already); `shape` and
  // `values` are the contact's shape, parsed before its ground.
  virtual void parse(const GroundText& text, const ContactParsers& parsers, const std::string& context,
                     const ContactShape& shape, const ShapeValues& values, ParsedGround& out) const = 0;
  // Checks that `contact`'s shape may roll on this ground (a ball smaller than a bowl).
  virtual void check(const ParsedContact& contact, const Spec& spec, const std::string& context) const = 0;
  // The contact of the shape of `contact`, whose body moves with `frame`, on this ground
  // (docs/derivations/rolling-bodies.md sections 2 to 4): fills point, normal, gap, the ground's
  // velocity and angular velocity there, and two tangent directions.
  struct Touch {
    Vector3 point, normal;
    GiNaC::ex gap;
    Vector3 ground_velocity = {0, 0, 0}, ground_omega = {0, 0, 0};
    Vector3 tangent1, tangent2;
    // Position rows that hold the coordinates of the contact point on the ground (terrain: the
    // two tangential components of body point - ground point, rolling-bodies.md section 8); none
    // when the contact point is a closed form in the body's coordinates.
    // Each row with the suffix of its constraint's name (NAME_at1, ...).
    std::vector<std::pair<std::string, GiNaC::ex>> locate;
    // The ground's curvature along the normal, world axes (SpecConvexity::ground); zero for a plane.
    GiNaC::matrix curvature = GiNaC::matrix(3, 3);
    // Where the tangents vanish along the motion: a measure positive where they are defined and
    // the reason for the message that ends a run where it falls below 1e-4 (none when they never do).
    std::optional<std::pair<GiNaC::ex, std::string>> singular;
    // Roots of perfect squares that the contact point writes as +-u (contact_roots_of_squares):
    // each is positive where the shape's contact point is defined and changes sign where it is
    // singular (a disk's |e x nu| where it lies flat), so the run watches it at every step.
    std::vector<GiNaC::ex> signed_roots;
  };
  virtual Touch touch(const ParsedContact& contact, const PlacedFrame& frame, const Spec& spec,
                      const std::optional<Vector3>& gravity, const std::string& context) const = 0;
  // How the report's scene draws the ground of `contact` (symbolic/visual.hpp): a terrain's
  // height field, a surface's zero set, each near the contact point's path (the loader fills
  // at_outputs with NAME_X, NAME_Y, NAME_Z, for an item whose `at` it leaves empty); a plane's
  // axes and a turntable's rate (`gravity` gives the normal of a plane that has none). Throws as
  // touch() for a plane whose normal is zero.
  virtual std::optional<VisualItem> drawing(const ParsedContact&, const Spec&, const std::optional<Vector3>&) const {
    return std::nullopt;
  }
};

const std::vector<const ContactGround*>& contact_grounds();
const ContactGround* find_contact_ground(const std::string& key);

// Checks the text against the registered shapes and grounds and parses its expressions.
ParsedContact parse_contact(const ContactText& text, const ContactParsers& parsers);

// The constraints, contact point and force description of one contact whose body moves with
// `frame` (docs/derivations/rolling-bodies.md). Throws ModelError when the body can never touch the
// ground (the gap is a nonzero constant) or cannot move along it.
RollingContact make_rolling_contact(const ParsedContact& contact, const PlacedFrame& frame, const Spec& spec,
                                    const std::optional<Vector3>& gravity);

// Unit tangents of the plane of unit normal n: t1 from the world axis least aligned with n (at
// the parameters' values; the first of ties), t2 = n x t1. The directions of the no-slip rows of
// every contact on a plane ([[contacts]], [[wheels]], [[knife_edges]]) and the axes of the plane's
// drawing.
std::pair<Vector3, Vector3> plane_tangents(const Vector3& n, const Spec& spec);

// Throws ModelError when an implicit shape is not convex toward the ground where the run starts
// (spec.t0, spec.q0 with the parameter values), or is flatter than a hollow of the terrain there
// (the contact would not be unique): names the contact, where it was written, the principal
// curvatures found and what to do (docs/derivations/rolling-bodies.md section 9). States where
// the expressions do not evaluate to finite reals are left to the other checks.
void check_contact_convexity(const Spec& spec);

// Throws ModelError when a wheel's |axle x normal|, written +-u with the sign u has at the
// reference configuration (SpecContactWatch::signed_root), is below its threshold where the run
// starts: the wheel lies flat there, or stands turned past lying flat from its reference
// configuration, where its rim's lowest point as written is the highest. Names the wheel, where
// it was written, the value and what to do.
void check_contact_watches_at_start(const Spec& spec);

// What holds a contact point by coordinates of the model: a terrain (2: u, v), an implicit shape
// (3: its point in body axes), a surface ground (3: the point on it, world).
enum class ContactPointOn { terrain, shape, surface };

// The names nhdyn gives a contact point's coordinates when the contact names none: NAME_u, NAME_v
// on a terrain, NAME_px, NAME_py, NAME_pz for an implicit shape's point (body axes), NAME_gx,
// NAME_gy, NAME_gz on a surface.
std::vector<std::string> added_contact_coordinates(const std::string& contact, ContactPointOn on);

// Sets spec.q0 and spec.v0 of the coordinates nhdyn added for contact points
// (spec.contact_coordinates) from the rest of the initial state, at spec.t0 and the parameter
// values: Newton's method on the position constraints that hold them, started on the shape's
// surface below its centre (docs/derivations/rolling-bodies.md section 10); then their velocities
// from those constraints' time derivatives, which are linear in them. Throws ModelError naming the
// contact, where it was written, the constraint left unsatisfied and its residual, when Newton
// does not converge or the start does not define them (the shape's centre outside it).
void solve_contact_coordinates(Spec& spec);

}  // namespace nhdyn::symbolic
