#include "nhdyn/symbolic/kinematics.hpp"

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

Vector3 column(const GiNaC::matrix& R, int axis) {
  const auto j = static_cast<unsigned>(axis);
  return {R(0, j), R(1, j), R(2, j)};
}

GiNaC::ex time_derivative(const GiNaC::ex& e, const SymbolTable& symbols) {
  GiNaC::ex out = e.diff(symbols.time());
  for (int i = 0; i < symbols.coordinates(); ++i) out += e.diff(symbols.coordinate(i)) * symbols.velocity(i);
  return out;
}

Vector3 time_derivative(const Vector3& v, const SymbolTable& symbols) {
  return {time_derivative(v[0], symbols), time_derivative(v[1], symbols), time_derivative(v[2], symbols)};
}

}  // namespace nhdyn::symbolic
