// Vectors and rotation matrices of GiNaC expressions for the multibody front end (multibody.hpp):
// the three elementary rotations, products, cross products, and the total time derivative along
// a motion q(t). Everything is symbolic; nothing is differentiated numerically.
// docs/derivations/rolling-wheel.md uses this notation.
#pragma once

#include <ginac/ginac.h>

#include <array>

#include "nhdyn/symbolic/spec.hpp"

namespace nhdyn::symbolic {

// Three components in some frame's axes (the name of the variable says which frame).
using Vector3 = std::array<GiNaC::ex, 3>;

Vector3 add(const Vector3& a, const Vector3& b);
Vector3 subtract(const Vector3& a, const Vector3& b);
Vector3 scale(const GiNaC::ex& s, const Vector3& a);
GiNaC::ex dot(const Vector3& a, const Vector3& b);
Vector3 cross(const Vector3& a, const Vector3& b);
// The unit vector along axis 0 (x), 1 (y) or 2 (z).
Vector3 unit(int axis);

// The rotation by `angle` about axis 0, 1 or 2 (right-handed): maps a child frame's components to
// its parent's, v_parent = R v_child.
GiNaC::matrix rotation_about(int axis, const GiNaC::ex& angle);
Vector3 multiply(const GiNaC::matrix& R, const Vector3& v);
// R^T v (the inverse rotation, parent components to child components).
Vector3 multiply_transposed(const GiNaC::matrix& R, const Vector3& v);
// A quaternion e = (e0, e1, e2, e3), scalar first (docs/derivations/quaternion-frame.md).
using Quaternion = std::array<GiNaC::ex, 4>;
// The rotation of the unit quaternion e / |e|: ((e0^2 - |e~|^2) I + 2 e~ e~^T + 2 e0 [e~ x]) / (e.e),
// (2.3), a rotation for every e != 0.
GiNaC::matrix quaternion_rotation(const Quaternion& e);
// Its two factors, R(e) = R_2(e) / (e.e): the polynomial matrix R_2(e) of (2.1) and e.e. R_2 is
// homogeneous of degree 2, so R_2(e)^T n = (e.e) R(e)^T n has the direction of R(e)^T n with no
// fraction in it: what a shape's support mapping, homogeneous in its direction, needs (section 8).
GiNaC::matrix quaternion_rotation_polynomial(const Quaternion& e);
GiNaC::ex quaternion_squared_norm(const Quaternion& e);
// Its angular velocity 2 E(e) e' / (e.e) in the parent's axes and 2 G(e) e' / (e.e) in the frame's
// own, (3.3): exact for every e != 0 and every e' (a rate along e only rescales e).
Vector3 quaternion_omega(const Quaternion& e, const Quaternion& rate);
Vector3 quaternion_omega_local(const Quaternion& e, const Quaternion& rate);

// Column `axis` of R: the child frame's axis in parent components.
Vector3 column(const GiNaC::matrix& R, int axis);

// The total time derivative along the motion: de/dt + sum_i (de/dq_i) q_i' (e free of velocities).
GiNaC::ex time_derivative(const GiNaC::ex& e, const SymbolTable& symbols);
Vector3 time_derivative(const Vector3& v, const SymbolTable& symbols);

}  // namespace nhdyn::symbolic
