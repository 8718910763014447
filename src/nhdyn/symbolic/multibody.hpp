// The multibody front end: builds the kinetic energy, the potential of gravity and the constraints
// of rolling wheels, knife edges and points on surfaces from a description of frames, points and
// bodies, and hands them to a SpecBuilder — from there on the model is derived and compiled like a
// hand-written one (spec_builder.hpp -> derive -> compile_model). The model file's [[frames]],
// [[points]], [[bodies]], gravity, [[wheels]], [[knife_edges]] and [[surfaces]]
// (frontend/model_file_multibody.cpp) are a thin layer over this class. docs/multibody.md describes it for users;
// docs/derivations/rolling-wheel.md derives what it writes.
//
// Frames: "ground" is the world frame. A frame is placed in its parent by a translation (in the
// parent's axes) and then a body-fixed sequence of rotations about the x, y or z axis of the frame
// produced so far, each by an angle (an expression in t, the coordinates and the parameters).
// Angular velocities come from the rates of these angles, not from differentiating matrices.
// Instead of angles, a frame may turn by a unit quaternion held in four coordinates
// (quaternion_frame, docs/derivations/quaternion-frame.md): no orientation is singular, at the
// cost of one more coordinate and the position-level constraint "<frame>_unit", e.e - 1 = 0.
//
// Every expression is text parsed by the SpecBuilder (its coordinates and parameters must be
// declared first). Errors are ModelErrors that start with the SourceLocation given.
//
// The builder also fills the report's scene (visual.hpp) through the SpecBuilder, so that a model
// built in C++ is drawn as the same model written in a file: the ground's grid, each body as its
// ellipsoid of inertia and each wheel as a disk about its axle, in the order they are given.
#pragma once

#include <ginac/ginac.h>

#include <array>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "nhdyn/symbolic/contact_forces.hpp"
#include "nhdyn/symbolic/contact_modes.hpp"
#include "nhdyn/symbolic/kinematics.hpp"
#include "nhdyn/symbolic/rolling_contact.hpp"
#include "nhdyn/symbolic/spec_builder.hpp"

namespace nhdyn::symbolic {

// One rotation of a frame's sequence: about axis "x", "y" or "z" of the frame produced so far.
struct FrameRotation {
  std::string axis;
  std::string angle;  // expression in t, the coordinates and the parameters
  SourceLocation where;
};

using Triple = std::array<std::string, 3>;        // three expressions, a vector's components
using InertiaText = std::array<Triple, 3>;         // a 3 x 3 tensor, row by row

// A frame once placed: everything in world components except omega_local.
struct PlacedFrame {
  std::string name;
  int parent = -1;            // index among the frames; -1 for ground
  Vector3 origin;             // position of the origin
  GiNaC::matrix rotation;     // R: frame components -> world components
  // R = rotation_numerator / rotation_denominator, the denominator a positive scalar: the product
  // of e.e over the quaternion frames of the chain (R_2(e) in the numerator), 1 when there are
  // none. R^T n and rotation_numerator^T n have the same direction; the rolling contacts take the
  // direction without the fraction (docs/derivations/quaternion-frame.md section 8).
  GiNaC::matrix rotation_numerator;
  GiNaC::ex rotation_denominator = 1;
  Vector3 omega;              // angular velocity, world components (linear in q')
  Vector3 omega_local;        // the same in the frame's own axes
  std::vector<int> quaternion;  // a quaternion frame: the indices of its coordinates e0..e3; else empty
  SourceLocation where;
};

// A [[wheels]] entry as the [[contacts]] entry it is: shape = { disk = radius, axis = axis } on
// `body` (centred on its frame's origin), ground = { plane = normal } (without one, the plane
// normal to gravity), rolling = "rolling"; its no-slip rows named NAME_slip1, NAME_slip2 and its
// messages "wheel 'NAME'" with the key `radius` (docs/multibody.md).
ContactText wheel_contact_text(const std::string& name, const std::string& body, const std::string& axis,
                               const std::string& radius, const std::optional<Triple>& normal,
                               SourceLocation where = {});

class MultibodyBuilder {
 public:
  // Coordinates and parameters must already be declared on `builder`, which must outlive this.
  explicit MultibodyBuilder(SpecBuilder& builder);

  MultibodyBuilder& frame(const std::string& name, const std::string& parent, const Triple& translation,
                          const std::vector<FrameRotation>& rotations, SourceLocation where = {});
  // A frame placed by `translation` (parent's axes) and then turned relative to its parent by the
  // unit quaternion whose components (scalar first) are the four coordinates named in
  // `quaternion` (docs/derivations/quaternion-frame.md (2.1), (3.2)). apply() adds the
  // position-level constraint "<name>_unit": e0^2 + e1^2 + e2^2 + e3^2 - 1 = 0, after the
  // hand-written constraints and before the helpers'. Throws a ModelError naming `where` for a
  // name that is not a coordinate, a coordinate named twice or already another frame's.
  MultibodyBuilder& quaternion_frame(const std::string& name, const std::string& parent, const Triple& translation,
                                     const std::array<std::string, 4>& quaternion, SourceLocation where = {});
  // A point fixed in `frame`, at `position` in the frame's axes.
  MultibodyBuilder& point(const std::string& name, const std::string& frame, const Triple& position,
                          SourceLocation where = {});
  // A rigid body moving with `frame`: mass, centre of mass (in the frame's axes) and inertia tensor
  // about the centre of mass in the frame's axes (symmetric, positive definite; all expressions in
  // the parameters). Checked with the parameter values given so far. Drawn in the scene as its
  // ellipsoid of inertia at its centre of mass, moving with its frame.
  MultibodyBuilder& body(const std::string& name, const std::string& frame, const std::string& mass,
                         const Triple& centre_of_mass, const InertiaText& inertia, SourceLocation where = {});
  // The gravitational acceleration vector in world components (parameters only), e.g. {0, 0, -g}.
  MultibodyBuilder& gravity(const Triple& g, SourceLocation where = {});
  // The gravity given so far (none before gravity()): a contact's plane without a normal is
  // normal to it.
  const std::optional<Vector3>& gravity_vector() const { return gravity_; }

  // A thin wheel of `radius` that rolls without slipping: the body's frame origin is its centre,
  // its axle is the frame's `axis` ("x", "y" or "z"). The plane passes through the world origin
  // with the normal `normal` (world components, parameters only), or opposite to gravity when no
  // normal is given. It is the disk contact of wheel_contact_text() (contact()): adds
  // "<name>_contact" (position level, unless it holds identically) and "<name>_slip1",
  // "<name>_slip2" (velocity level). Drawn as wheel_drawing() draws it.
  MultibodyBuilder& rolling_wheel(const std::string& name, const std::string& body, const std::string& axis,
                                  const std::string& radius, const std::optional<Triple>& normal = std::nullopt,
                                  SourceLocation where = {});
  // Draws `body` in the scene as the wheel `name` (VisualKind::wheel): a disk of `radius` about
  // its frame's `axis`, centred on the frame's origin. rolling_wheel() calls it after contact(), as
  // the model file's [[wheels]] loader does (frontend/contacts_file.hpp). Throws a ModelError
  // naming `where` for a body not declared.
  MultibodyBuilder& wheel_drawing(const std::string& name, const std::string& body, const std::string& axis,
                                  const std::string& radius, SourceLocation where = {});
  // A knife edge at `point` along its frame's `axis`, on the plane of `normal` (default: opposite
  // to gravity): the velocity of the point across the blade within the plane vanishes. Adds one
  // velocity-level constraint called `name`.
  MultibodyBuilder& knife_edge(const std::string& name, const std::string& point, const std::string& axis,
                               const std::optional<Triple>& normal = std::nullopt, SourceLocation where = {});
  // A convex body rolling on a ground ([[contacts]], docs/derivations/rolling-bodies.md): adds
  // "<name>_contact" (position level, the gap, unless it holds identically), "<name>_roll1",
  // "<name>_roll2" (velocity level) and, for rubber rolling, "<name>_spin"; the contact point's
  // world position as the outputs <name>_X, <name>_Y, <name>_Z; its contact force.
  MultibodyBuilder& contact(const ContactText& text);
  // The shape and body of a contact given so far, for the scene (nullptr when unknown).
  const ParsedContact* parsed_contact(const std::string& name) const;
  // `point` stays on the fixed surface f(X, Y, Z) = 0 (world coordinates X, Y, Z; the expression
  // may also use t and the parameters). One position-level constraint called `name`.
  MultibodyBuilder& point_on_surface(const std::string& name, const std::string& point, const std::string& surface,
                                     SourceLocation where = {});
  // `point` stays on the curve where two surfaces meet: "<name>_1" and "<name>_2".
  MultibodyBuilder& point_on_curve(const std::string& name, const std::string& point, const std::string& surface1,
                                   const std::string& surface2, SourceLocation where = {});

  // T = sum (1/2 m v_c.v_c + 1/2 w.I w) and V = -sum m g.r_c over the bodies.
  GiNaC::ex kinetic_energy() const;
  GiNaC::ex potential_energy() const;
  // Adds T and V to the builder's energies and the helpers' constraints to its constraints, in the
  // order the helpers were given. Call once, after everything else.
  void apply();

  // For tests and other front ends.
  const PlacedFrame& placed_frame(const std::string& name) const;
  Vector3 point_position(const std::string& name) const;  // world components
  const PlacedFrame& placed_frame_at(int index) const { return frames_.at(static_cast<std::size_t>(index)); }

 private:
  struct Point {
    std::string name;
    int frame;
    Vector3 world;
    SourceLocation where;
  };
  struct Body {
    std::string name;
    int frame;
    GiNaC::ex mass;
    Vector3 com;             // in the frame's axes
    GiNaC::matrix inertia;   // about the com, in the frame's axes
    SourceLocation where;
  };
  // A helper's constraints, computed in apply() (the plane's default normal needs the gravity,
  // which may come later).
  struct Helper {
    enum class Kind { knife_edge, surface, curve, contact } kind;
    std::string name;
    int index = -1;          // the point (knife edge, surface, curve)
    int axis = 0;
    std::optional<Vector3> normal;
    std::vector<GiNaC::ex> surfaces;
    std::shared_ptr<const ParsedContact> contact;  // a rolling body
    std::shared_ptr<const SpecContactMode> mode;   // its friction and lift-off (contact_modes.hpp), or null
    SourceLocation where;
  };

  GiNaC::ex parse(const std::string& text, const SourceLocation& where, const std::string& context,
                  bool coordinates_allowed) const;
  Vector3 parse(const Triple& texts, const SourceLocation& where, const std::string& context,
                bool coordinates_allowed) const;
  int frame_index(const std::string& name, const SourceLocation& where, const std::string& context) const;
  // A new frame `name` under `parent` (both checked), at `translation` in the parent's axes, with
  // the parent's rotation and angular velocity: what frame() and quaternion_frame() then turn.
  PlacedFrame child_frame(const std::string& name, const std::string& parent, const Triple& translation,
                          SourceLocation where, const std::string& context) const;
  int point_index(const std::string& name, const SourceLocation& where, const std::string& context) const;
  int coordinate_index(const std::string& name, const SourceLocation& where, const std::string& context) const;
  int body_index(const std::string& name, const SourceLocation& where, const std::string& context) const;
  void check_helper_name(const std::string& name, const SourceLocation& where) const;
  GiNaC::ex parse_surface(const std::string& text, const Vector3& at, const SourceLocation& where,
                          const std::string& context) const;
  Vector3 plane_normal(const Helper& helper, const std::string& context) const;
  void add_knife_edge(const Helper& helper);
  void add_contact(const Helper& helper);
  // The bodies and contacts for the contact forces (symbolic/contact_forces.hpp), onto the builder.
  void record_contact_forces(SpecContactForces& record) const;
  int system_of(int frame) const;  // index of the frame below ground that `frame` hangs from

  SpecBuilder& builder_;
  std::vector<PlacedFrame> frames_;  // frames_[0] is ground
  std::vector<Point> points_;
  std::vector<Body> bodies_;
  std::vector<Helper> helpers_;
  std::vector<ContactPoint> contacts_;  // filled by add_knife_edge and apply()
  std::vector<SpecContactMode> modes_;  // the contacts with modes, filled by add_contact
  std::optional<Vector3> gravity_;
  SourceLocation gravity_where_;
  bool applied_ = false;
};

// A frame's origin and rotation as an item of the scene (visual.hpp) of the given kind: how the
// builder draws a body or a wheel, and the loader a frame's axes.
VisualItem frame_item(const PlacedFrame& frame, VisualKind kind, const SourceLocation& where);

}  // namespace nhdyn::symbolic
