#include "nhdyn/symbolic/kinematics.hpp"

#include "nhdyn/symbolic/detail/derivative.hpp"

namespace nhdyn::symbolic {

Vector3 add(const Vector3& a, const Vector3& b) { return {a[0] + b[0], a[1] + b[1], a[2] + b[2]}; }
Vector3 subtract(const Vector3& a, const Vector3& b) { return {a[0] - b[0], a[1] - b[1], a[2] - b[2]}; }
Vector3 scale(const GiNaC::ex& s, const Vector3& a) { return {s * a[0], s * a[1], s * a[2]}; }
GiNaC::ex dot(const Vector3& a, const Vector3& b) { return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]; }

Vector3 cross(const Vector3& a, const Vector3& b) {
  return {a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]};
}

Vector3 unit(int axis) {
  Vector3 e{0, 0, 0};
  e[static_cast<std::size_t>(axis)] = 1;
  return e;
}

GiNaC::matrix rotation_about(int axis, const GiNaC::ex& angle) {
  const GiNaC::ex c = GiNaC::cos(angle), s = GiNaC::sin(angle);
  switch (axis) {
    case 0: return GiNaC::matrix{{1, 0, 0}, {0, c, -s}, {0, s, c}};
    case 1: return GiNaC::matrix{{c, 0, s}, {0, 1, 0}, {-s, 0, c}};
    default: return GiNaC::matrix{{c, -s, 0}, {s, c, 0}, {0, 0, 1}};
  }
}

Vector3 multiply(const GiNaC::matrix& R, const Vector3& v) {
  Vector3 out;
  for (unsigned i = 0; i < 3; ++i) out[i] = R(i, 0) * v[0] + R(i, 1) * v[1] + R(i, 2) * v[2];
  return out;
}

Vector3 multiply_transposed(const GiNaC::matrix& R, const Vector3& v) {
  Vector3 out;
  for (unsigned i = 0; i < 3; ++i) out[i] = R(0, i) * v[0] + R(1, i) * v[1] + R(2, i) * v[2];
  return out;
}

GiNaC::ex quaternion_squared_norm(const Quaternion& e) { return e[0] * e[0] + e[1] * e[1] + e[2] * e[2] + e[3] * e[3]; }

GiNaC::matrix quaternion_rotation_polynomial(const Quaternion& e) {
  const GiNaC::ex &e0 = e[0], &e1 = e[1], &e2 = e[2], &e3 = e[3];
  return GiNaC::matrix{{e0 * e0 + e1 * e1 - e2 * e2 - e3 * e3, 2 * (e1 * e2 - e0 * e3), 2 * (e1 * e3 + e0 * e2)},
                       {2 * (e1 * e2 + e0 * e3), e0 * e0 - e1 * e1 + e2 * e2 - e3 * e3, 2 * (e2 * e3 - e0 * e1)},
                       {2 * (e1 * e3 - e0 * e2), 2 * (e2 * e3 + e0 * e1), e0 * e0 - e1 * e1 - e2 * e2 + e3 * e3}};
}

GiNaC::matrix quaternion_rotation(const Quaternion& e) {
  const GiNaC::ex &e0 = e[0], &e1 = e[1], &e2 = e[2], &e3 = e[3];
  const GiNaC::ex s = 1 / quaternion_squared_norm(e);
  return GiNaC::matrix{{s * (e0 * e0 + e1 * e1 - e2 * e2 - e3 * e3), s * 2 * (e1 * e2 - e0 * e3), s * 2 * (e1 * e3 + e0 * e2)},
                       {s * 2 * (e1 * e2 + e0 * e3), s * (e0 * e0 - e1 * e1 + e2 * e2 - e3 * e3), s * 2 * (e2 * e3 - e0 * e1)},
                       {s * 2 * (e1 * e3 - e0 * e2), s * 2 * (e2 * e3 + e0 * e1), s * (e0 * e0 - e1 * e1 - e2 * e2 + e3 * e3)}};
}

Vector3 quaternion_omega(const Quaternion& e, const Quaternion& d) {
  // 2 E(e) e' / (e.e), E = [-e~ | e0 I + [e~ x]].
  const GiNaC::ex s = 2 / quaternion_squared_norm(e);
  return {s * (-e[1] * d[0] + e[0] * d[1] - e[3] * d[2] + e[2] * d[3]),
          s * (-e[2] * d[0] + e[3] * d[1] + e[0] * d[2] - e[1] * d[3]),
          s * (-e[3] * d[0] - e[2] * d[1] + e[1] * d[2] + e[0] * d[3])};
}

Vector3 quaternion_omega_local(const Quaternion& e, const Quaternion& d) {
  // 2 G(e) e' / (e.e), G = [-e~ | e0 I - [e~ x]].
  const GiNaC::ex s = 2 / quaternion_squared_norm(e);
  return {s * (-e[1] * d[0] + e[0] * d[1] + e[3] * d[2] - e[2] * d[3]),
          s * (-e[2] * d[0] - e[3] * d[1] + e[0] * d[2] + e[1] * d[3]),
          s * (-e[3] * d[0] + e[2] * d[1] - e[1] * d[2] + e[0] * d[3])};
}

Vector3 column(const GiNaC::matrix& R, int axis) {
  const auto j = static_cast<unsigned>(axis);
  return {R(0, j), R(1, j), R(2, j)};
}

GiNaC::ex time_derivative(const GiNaC::ex& e, const SymbolTable& symbols) {
  // detail::derivative: GiNaC's derivative, 0 at once for the coordinates e does not contain.
  GiNaC::ex out = detail::derivative(e, symbols.time());
  for (int i = 0; i < symbols.coordinates(); ++i)
    out += detail::derivative(e, symbols.coordinate(i)) * symbols.velocity(i);
  return out;
}

Vector3 time_derivative(const Vector3& v, const SymbolTable& symbols) {
  return {time_derivative(v[0], symbols), time_derivative(v[1], symbols), time_derivative(v[2], symbols)};
}

}  // namespace nhdyn::symbolic
