// The contact shapes' own files (shapes/*.cpp), one per shape, and what they share. Each file
// defines its shape's type (a ContactShape, contact_shapes.hpp) and the function that returns its
// one instance; contact_shapes.cpp lists those functions once, in the order the docs list the
// shapes. A new shape is a file in shapes/, its function here and a line in that table.
// Internal: the shapes are reached through contact_shapes() and find_contact_shape(), not by name.
#pragma once

#include <vector>

#include <ginac/ginac.h>

#include "nhdyn/symbolic/contact_shapes.hpp"

namespace nhdyn::symbolic::shapes {

const ContactShape& sphere();
const ContactShape& ellipsoid();
const ContactShape& disk();
const ContactShape& torus();
const ContactShape& implicit_surface();

// e (e . nu) - nu over |e x nu|: the unit direction in the plane normal to e closest to -nu
// (the rim point of a disk, docs/derivations/rolling-wheel.md), the same for every length of nu;
// `across` = |e x nu| = sqrt(nu . nu - (e . nu)^2), with nu . nu = length^2.
Vector3 rim_direction(const Vector3& nu, const GiNaC::ex& length, int axis, GiNaC::ex& across);

// A scene item of `kind` with `sizes` (the shape's drawing; symbolic/visual.hpp).
VisualItem drawn(VisualKind kind, std::vector<GiNaC::ex> sizes);

}  // namespace nhdyn::symbolic::shapes
