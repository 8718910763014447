// What the 3-D scene of a report draws, and how its positions are computed. A model file's
// [visual] table (hand-written models: spheres and segments whose ends are expressions in t, the
// coordinates and the parameters) and its multibody description (bodies, wheels, frames) become
// VisualItems of the Spec; compile_visual() turns them into two straight-line Programs
// (model/tape.hpp) that read the parameters, like the model's own tapes: `tape`, whose
// outputs, run on a row of results (t, q, q'), are every position and orientation the scene
// needs, and `sizes`, which reads the parameters only (radii, masses, inertias). Parameters are
// data (docs/design.md): io/report.hpp binds both to the values of the run's Model, so a
// `--set r=0.3` or a set_parameter after compiling draws the wheel of the run, not of the file.
//
//     model file [visual] / [[bodies]] --> Spec::visual --compile_visual--> VisualScene
//         --(bind to the Model's parameter values, io/report.cpp)--> the report's scene
#pragma once

#include <ginac/ginac.h>

#include <string>
#include <vector>

#include "nhdyn/model/tape.hpp"

namespace nhdyn::symbolic {

struct Spec;

enum class VisualKind {
  sphere,   // a point drawn as a ball
  segment,  // a straight segment between two points
  wheel,    // a multibody wheel: a disk of its radius about the axle of its frame
  body,     // a multibody body: its equivalent ellipsoid of inertia, moving with its frame
  frame,    // a multibody frame: three small axes at its origin
  // The drawings of [[contacts]] (each shape and ground type says which it is: contact_shapes.hpp,
  // rolling_contact.hpp):
  ellipsoid,  // a contact's sphere or ellipsoid: its semi-axes along the frame's axes, at its centre
  torus,      // a contact's round tyre: the rim's radius and the tube's, about the axle of its frame
  solid,      // a contact's implicit shape f(X, Y, Z) = 0 in its frame's axes: a mesh of the zero set
  track,      // a contact point's path over the ground (a line through its positions)
  terrain,    // a terrain Z = h(X, Y): a height-field mesh over the region its contact point covers
  surface,    // a fixed ground surface g(X, Y, Z) = 0: a mesh of its zero set near its contact point
  plane,      // a plane ground through the origin, tilted or turning (a turntable): a grid in its axes
};

// One item of the scene, symbolic. Positions are world components (x, y, z); expressions may use
// t, the coordinates, their velocities and the parameters; sizes only the parameters.
struct VisualItem {
  VisualKind kind = VisualKind::sphere;
  std::string name;
  std::vector<GiNaC::ex> at;     // sphere: centre; segment: first end; wheel, body, frame, plane: origin (3)
  std::vector<GiNaC::ex> other;  // segment: second end (3); wheel, body, frame: rotation R (9, row-major:
                                 // frame components -> world components); plane: its axes t1, t2, n
                                 // as the columns of R, n its unit normal
  GiNaC::ex size = 0;            // sphere, wheel: radius; segment: 0 (a line); body: its mass
  std::vector<GiNaC::ex> inertia;  // body: inertia about the centre of mass in the frame's axes (9, row-major)
  int axis = 1;                  // wheel, torus: the axle, 0, 1 or 2 for the frame's x, y or z axis
  std::string where;             // "file:line:column" for messages
  // ellipsoid: the semi-axes (3); torus: the rim's radius and the tube's (2); terrain, surface: a
  // length of the contact's shape (1), the margin of the region drawn, then (surface) a point K
  // (3) and 1 when every ray from K meets the surface once (a sphere's centre: its mesh is sampled
  // along rays from K), 0 when the mesh is sampled over the tangent plane at the contact path's
  // mean point instead (any other surface). Parameters only.
  std::vector<GiNaC::ex> sizes;
  // solid, terrain, surface: the function whose zero set is drawn (terrain: the height h) in the
  // symbols `field_variables` (solid: 3, the frame's axes about `at`; terrain: 2, X and Y;
  // surface: 3, world X, Y, Z) and the parameters. plane: the turntable's rate Omega about n, in
  // the time (one field variable, t) and the parameters; 0 for a fixed plane.
  GiNaC::ex field = 0;
  std::vector<GiNaC::ex> field_variables;
  // track, terrain, surface: `at` is the value of these three outputs of the spec (a contact
  // point's NAME_X, NAME_Y, NAME_Z), resolved by compile_visual: the line drawn is the column.
  std::vector<std::string> at_outputs;
  std::string body;  // ellipsoid, torus, wheel, solid of a contact: the body it is the shape of
};

struct SpecVisual {
  std::vector<VisualItem> items;
  bool planar = false;  // every position has two components: the scene is the (x, y) plane, y up
  bool ground = false;  // a multibody model: the ground plane z = 0 is drawn with a grid (unless a
                        // plane item draws the grounds, see compile_visual)
};

// A shape of the compiled scene. Its outputs start at `offset` in the outputs of
// VisualScene::tape: sphere, track, terrain and surface 3 (centre; a contact point), segment 6
// (both ends), wheel, body, frame, ellipsoid, torus, solid and plane 12 (origin, then R row-major;
// a plane's R is its axes at rest, which the report turns by the angle of its rate); its
// sizes at `size_offset` in those of VisualScene::sizes: sphere and wheel 1 (radius), body 10
// (mass, then the inertia about the centre of mass in the frame's axes, 9 row-major), ellipsoid 3
// (semi-axes), torus 2 (R, r), terrain 1 (a length), surface 5 (a length, a point K, rays from K or not), segment,
// frame, track, solid and plane none.
struct VisualShape {
  VisualKind kind = VisualKind::sphere;
  std::string name;
  int offset = 0;
  int size_offset = 0;
  int axis = 1;       // wheel: the axle's column of R
  std::string where;  // "file:line:column" of the item, for messages about its values
  std::vector<std::string> expressions;  // the text of each of its outputs (at, then other), for messages
  std::string body;   // a contact's shape: the body it is the shape of (drawn instead of its ellipsoid)
  // solid, terrain, surface: the function drawn, its inputs the field variables in the places of
  // the coordinates (Tape::coordinate_register(i)); reads the parameters (bind them). plane: its
  // rate Omega(t), t in the place of coordinate 0; a tape without outputs for a plane that does
  // not turn.
  Tape field;
};

struct VisualScene {
  std::vector<VisualShape> shapes;
  Tape tape;  // inputs t, q, q'; reads the parameters; outputs as the shapes say
  Tape sizes;    // no coordinate input; reads the parameters only; outputs as the shapes say
  std::vector<std::string> parameters;  // the names the tapes' `parameter` instructions index
  bool planar = false;
  bool ground = false;
  std::vector<bool> angles;  // per coordinate: it appears inside a trigonometric function (an angle)
};

// Compiles the spec's visual items with the parameters left symbolic, in the order of
// spec.parameters (that of Model::parameters); an empty spec.visual gives a scene without shapes
// (the report then draws the path). Plane items are grounds: one is kept per distinct plane (the
// same axes and rate; several contacts on one incline draw it once), and none when every one is
// level (its normal +-z) and fixed, as the scene's grid in z = 0 draws that plane; a scene with a
// plane item draws no other grid. Cost: one pass over the expressions. Throws ModelError naming
// the item and its place when a size depends on t, the coordinates or the velocities, or an
// expression cannot be evaluated. The values of the sizes (a radius must be positive) are checked
// when they are known, by the report.
VisualScene compile_visual(const Spec& spec);

// Output count of a shape of this kind.
int visual_outputs(VisualKind kind);
// Size count of a shape of this kind (the outputs of VisualScene::sizes it has).
int visual_sizes(VisualKind kind);
// Its name in messages and in the report's page: "sphere", "ellipsoid", ...
const char* visual_kind_name(VisualKind kind);

}  // namespace nhdyn::symbolic
