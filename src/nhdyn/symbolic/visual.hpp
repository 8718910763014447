// What the 3-D scene of a report draws, and how its positions are computed. A model file's
// [visual] table (hand-written models: spheres and segments whose ends are expressions in t, the
// coordinates and the parameters) and its multibody description (bodies, wheels, frames) become
// VisualItems of the Spec; compile_visual() turns them into one straight-line Program
// (model/program.hpp) whose outputs, run on a row of results (t, q, q'), are every position and
// orientation the scene needs, and a list of shapes saying which outputs belong to which shape.
// io/report.hpp runs that program on the rows it shows; the browser only places the shapes.
//
//     model file [visual] / [[bodies]] --> Spec::visual --compile_visual--> VisualScene --> report
#pragma once

#include <ginac/ginac.h>

#include <array>
#include <string>
#include <vector>

#include "nhdyn/model/program.hpp"

namespace nhdyn::symbolic {

struct Spec;

enum class VisualKind {
  sphere,   // a point drawn as a ball
  segment,  // a straight segment between two points
  wheel,    // a multibody wheel: a disk of its radius about the axle of its frame
  body,     // a multibody body: its equivalent ellipsoid of inertia, moving with its frame
  frame,    // a multibody frame: three small axes at its origin
};

// One item of the scene, symbolic. Positions are world components (x, y, z); expressions may use
// t, the coordinates, their velocities and the parameters; sizes only the parameters.
struct VisualItem {
  VisualKind kind = VisualKind::sphere;
  std::string name;
  std::vector<GiNaC::ex> at;     // sphere: centre; segment: first end; wheel, body, frame: origin (3)
  std::vector<GiNaC::ex> other;  // segment: second end (3); wheel, body, frame: rotation R (9, row-major:
                                 // frame components -> world components)
  GiNaC::ex size = 0;            // sphere, wheel: radius; segment: 0 (a line); body: its mass
  std::vector<GiNaC::ex> inertia;  // body: inertia about the centre of mass in the frame's axes (9, row-major)
  int axis = 1;                  // wheel: the axle, 0, 1 or 2 for the frame's x, y or z axis
  std::string where;             // "file:line:column" for messages
};

struct SpecVisual {
  std::vector<VisualItem> items;
  bool planar = false;  // every position has two components: the scene is the (x, y) plane, y up
  bool ground = false;  // a multibody model: the ground plane z = 0 is drawn with a grid
};

// A shape of the compiled scene. Its outputs start at `offset` in the program's outputs:
// sphere 3 (centre), segment 6 (both ends), wheel, body and frame 12 (origin, then R row-major).
struct VisualShape {
  VisualKind kind = VisualKind::sphere;
  std::string name;
  int offset = 0;
  std::array<double, 3> size = {0.0, 0.0, 0.0};  // sphere, wheel: radius; body: semi-axes along R's columns
  int axis = 1;                                  // wheel: the axle's column of R
};

struct VisualScene {
  std::vector<VisualShape> shapes;
  Program program;      // inputs t, q, q'; outputs as the shapes say
  bool planar = false;
  bool ground = false;
  std::vector<bool> angles;  // per coordinate: it appears inside a trigonometric function (an angle)
};

// Compiles the spec's visual items with the parameters' current values; an empty spec.visual gives
// a scene without shapes (the report then draws the path). Cost: one pass over the expressions.
// Throws ModelError naming the item and its place when a size depends on the coordinates or is
// not a positive number, or an expression cannot be evaluated.
VisualScene compile_visual(const Spec& spec);

// Output count of a shape of this kind.
int visual_outputs(VisualKind kind);

}  // namespace nhdyn::symbolic
