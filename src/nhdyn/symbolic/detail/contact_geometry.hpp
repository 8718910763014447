// The helpers that the rolling-contact builder (rolling_contact.cpp) and its grounds (grounds/)
// share: numbers of expressions at the parameters' values, the coordinates that hold a contact
// point, a shape's support point, the rows that hold an implicit shape's contact point.
// Internal: part of the rolling-contact builder, not of the public API (nhdyn/nhdyn.hpp).
#pragma once

#include <ginac/ginac.h>

#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "nhdyn/symbolic/rolling_contact.hpp"

namespace nhdyn::symbolic {

// The value once the parameters are set (t and the coordinates at 0 with `at_reference`);
// nullopt when it is not a finite real number.
std::optional<double> contact_number_of(const GiNaC::ex& e, const Spec& spec, bool at_reference = false);

// The expression as GiNaC prints it, for messages.
std::string contact_printed(const GiNaC::ex& e);

// Whether the expression depends on t or a coordinate.
bool contact_has_coordinates(const GiNaC::ex& e, const Spec& spec);

// Whether e, which depends on the coordinates or t, is zero for every state: 0 as written, or zero
// to round-off of its terms' sizes at three fixed generic points (coordinates in [-1, 1], t in
// (0, 1), the parameters at their values). A disk's gap in coordinates that eliminate its height,
// rR cos(phi) - rR sqrt(cos(phi)^2), is such a zero that simplify() leaves as it is.
bool contact_vanishes_identically(const GiNaC::ex& e, const Spec& spec);

// e with every root of a perfect square, sqrt(u^2) (and its odd powers), written as +-u with the
// sign u has at the reference configuration (coordinates and t at 0, the parameters at their
// values); each such +-u is added to `roots` (once). |u| = +-u while u keeps its sign, and where
// it is 0 the shape's closed-form contact point is singular anyway (a disk lying flat), which the
// run watches through `roots` (rolling_contact.cpp). Roots of other arguments, and of a u that is
// 0 or not a number there, stay. A disk on a plane in angles, |e x nu| = sqrt(1 - sin(theta)^2)
// = cos(theta), keeps no root in what is differentiated twice: the form a [[wheels]] entry has.
GiNaC::ex contact_roots_of_squares(const GiNaC::ex& e, const Spec& spec, std::vector<GiNaC::ex>& roots);

// A kink or a step (abs, csgn, step) anywhere in e: a ground or shape written with one has no
// normal there.
bool contact_not_smooth(const GiNaC::ex& e);

// The text of a table's option `key`, or `fallback` where it is not given.
std::string contact_option_of(const KeyTexts& options, const std::string& key, const std::string& fallback);

// The index of the world axis least aligned with `direction` (the first of ties).
int contact_least_aligned_axis(const Vector3& direction, const Spec& spec);

// The unit normal of a plane ground: the given one, else opposite to gravity.
Vector3 ground_plane_normal(const ParsedGround& ground, const Spec& spec, const std::optional<Vector3>& gravity,
                            const std::string& context);

// The coordinates named in an option's text ("u, v"): `count` of them, distinct, each a coordinate
// of the model (docs/multibody.md: they hold a contact point).
std::vector<int> contact_coordinates(const std::string& names, std::size_t count, const Spec& spec,
                                     const SourceLocation& where, const std::string& context, const std::string& what,
                                     const std::string& example);

// The coordinates that hold a contact point: those named by the `coordinates` key, or, without
// it, new ones that nhdyn adds, named after the contact (added_contact_coordinates). `added` says
// which.
std::vector<int> contact_point_coordinates(const std::string& names, ContactPointOn on, const ContactParsers& p,
                                           const SourceLocation& where, const std::string& context,
                                           const std::string& what, const std::string& example, bool& added);

// The body's point whose outward normal is -n, and its reach along n from the shape's centre C
// (world): for a ball C - r n directly, without R R^T; otherwise the shape's support point along
// `direction` (body axes, of length `length`: the support mapping reads the direction only, so
// that a ground may pass an unnormalized one and keep a root out of what is differentiated).
std::pair<Vector3, GiNaC::ex> body_support(const ParsedContact& c, const PlacedFrame& F, const Vector3& C,
                                           const Vector3& normal, const Vector3& direction, const GiNaC::ex& length);

// The rows that hold an implicit shape's contact point y (body axes) where the ground's normal is
// n with tangents t1, t2: f(y) = 0 and (R grad f(y)) . t_k = 0 (rolling-bodies.md section 9).
void implicit_shape_rows(const ParsedContact& c, const PlacedFrame& F, const Vector3& t1, const Vector3& t2,
                         ContactGround::Touch& out);

// A positive scale as an exact rational: between 1e-3 and 1e3 a convergent of its continued
// fraction with a denominator up to 10^6 (short to print: 1, 19/25; within 1e-15 of it where one
// is, and within about 1e-6 at worst, for a value just off a simple fraction: the scale only
// normalizes rows), else the double's own binary value. A float in the derived expressions would
// combine with their exact coefficients in GiNaC's term order, which changes from process to
// process: the equations printed "-1.0 x" in one run and "-x" in another.
GiNaC::numeric exact_scale(double value);

// The double's own binary value as an exact rational (exact_rational of precise_reference.hpp; 0
// for a value that is not finite, where a search has failed and says so itself): a number
// put into an expression that GiNaC then evaluates in its term order, so that the order does not
// reach the result (a float would round differently from process to process).
GiNaC::numeric exact_double(double value);

// |grad g| at the shape's centre where the run starts (the file's initial values and parameters),
// g's scale as a number: 1 where that is not a positive number (a start written nowhere).
double gradient_scale(const Vector3& gradient, const Vector3& U, const Vector3& C, const Spec& spec);

}  // namespace nhdyn::symbolic
