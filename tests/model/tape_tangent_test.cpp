// The tangent mode of tapes (straight-line code) (model/detail/tape_tangent.hpp): every op's derivative
// against Richardson-extrapolated central differences of the program itself, the exact derivative
// of a small polynomial, and the structural input dependence.
#include <gtest/gtest.h>

#include <cmath>
#include <vector>

#include "nhdyn/model/tape.hpp"
#include "nhdyn/model/detail/tape_tangent.hpp"

namespace nhdyn {
namespace {

// A program of two coordinates (inputs t, q0, q1, v0, v1) with one output per op, each applied to
// values where it is smooth: u = 0.3 + 0.2 sin-free mix of the inputs keeps asin/acos/log defined.
Tape every_op_tape() {
  Tape p(2);
  const int t = Tape::time_register(), q0 = p.coordinate_register(0), q1 = p.coordinate_register(1),
            v0 = p.velocity_register(0), v1 = p.velocity_register(1);
  const int u = p.push(Op::mulk_add, q0, p.push(Op::mul_k, q1, 0, 0, 0.1), 0, 0.2);  // 0.2 q0 + 0.1 q1
  const int w = p.push(Op::add_k, p.push(Op::mul, v0, t), 0, 0, 1.5);                 // v0 t + 1.5
  const std::vector<int> outs = {
      p.push(Op::add, u, w), p.push(Op::sub, u, v1), p.push(Op::mul, u, w), p.push(Op::div, u, w),
      p.push(Op::neg, v1), p.push(Op::add_k, u, 0, 0, 2.0), p.push(Op::mul_k, w, 0, 0, -3.0),
      p.push(Op::mulk, u, w, 0, 0.7), p.push(Op::div_k, w, 0, 0, 2.5), p.push(Op::muladd, u, w, v1),
      p.push(Op::mulsub, u, w, v1), p.push(Op::mulk_add, u, w, 0, 1.3), p.push(Op::mulk_muladd, u, w, v1, 0.9),
      p.push(Op::square, w), p.push(Op::cube, u), p.push(Op::powi, w, 0, 0, 5.0), p.push(Op::powi, w, 0, 0, -3.0),
      p.push(Op::powi, w, 0, 0, 1.0), p.push(Op::pow, w, u), p.push(Op::pow_k, w, 0, 0, 2.5),
      p.push(Op::sqrt, w), p.push(Op::sin, u), p.push(Op::cos, u), p.push(Op::tan, u), p.push(Op::exp, u),
      p.push(Op::log, w), p.push(Op::abs, v1), p.push(Op::asin, u), p.push(Op::acos, u), p.push(Op::atan, w),
      p.push(Op::atan2, u, w), p.push(Op::sinh, u), p.push(Op::cosh, u), p.push(Op::tanh, w)};
  for (int r : outs) p.add_output(r);
  const int sc = p.push(Op::sincos, w);
  p.add_output(sc);
  p.add_output(sc + 1);
  p.add_constant_output(4.0);
  return p;
}

std::vector<double> outputs_at(const Tape& p, const std::vector<double>& x) {
  std::vector<double> registers(static_cast<std::size_t>(p.registers())), out(static_cast<std::size_t>(p.outputs()));
  p.run(x[0], &x[1], &x[3], registers.data(), out.data());
  return out;
}

TEST(ProgramTangent, EveryOpAgreesWithRichardsonDifferences) {
  const Tape p = every_op_tape();
  const std::vector<double> x = {0.4, 0.9, -0.7, 1.1, -0.6};  // t, q0, q1, v0, v1
  std::vector<double> values(static_cast<std::size_t>(p.registers())), tangents(values.size());
  p.execute(x[0], &x[1], &x[3], values.data());
  const std::vector<double> direction = {0.3, -1.0, 0.5, 0.8, -0.2};
  std::vector<double> d(static_cast<std::size_t>(p.outputs()));
  run_tangent(p, values.data(), direction[0], &direction[1], &direction[3], tangents.data(), d.data());
  const auto shifted = [&](double h) {
    std::vector<double> y = x;
    for (std::size_t i = 0; i < y.size(); ++i) y[i] += h * direction[i];
    return outputs_at(p, y);
  };
  const double h = 1e-3;
  const std::vector<double> p1 = shifted(h), m1 = shifted(-h), p2 = shifted(h / 2), m2 = shifted(-h / 2);
  for (std::size_t i = 0; i < d.size(); ++i) {
    const double d1 = (p1[i] - m1[i]) / (2 * h), d2 = (p2[i] - m2[i]) / h;
    const double richardson = (4 * d2 - d1) / 3;
    EXPECT_NEAR(d[i], richardson, 1e-9 * std::max(1.0, std::abs(richardson))) << "output " << i;
  }
  EXPECT_EQ(d.back(), 0.0);  // the constant output
}

TEST(ProgramTangent, PolynomialIsExact) {
  // y = q0^2 q1 + 3 v1: dy = 2 q0 q1 dq0 + q0^2 dq1 + 3 dv1.
  Tape p(2);
  const int q0 = p.coordinate_register(0), q1 = p.coordinate_register(1), v1 = p.velocity_register(1);
  p.add_output(p.push(Op::mulk_add, v1, p.push(Op::mul, p.push(Op::square, q0), q1), 0, 3.0));
  const double q[2] = {1.25, -0.5}, v[2] = {0.0, 2.0};
  std::vector<double> values(static_cast<std::size_t>(p.registers())), tangents(values.size());
  p.execute(0.0, q, v, values.data());
  const double dq[2] = {1.0, 2.0}, dv[2] = {0.0, -1.0};
  double d = 0.0;
  run_tangent(p, values.data(), 0.0, dq, dv, tangents.data(), &d);
  EXPECT_EQ(d, 2 * 1.25 * -0.5 * 1.0 + 1.25 * 1.25 * 2.0 + 3.0 * -1.0);
}

TEST(ProgramTangent, InputDependenceIsStructural) {
  Tape p(3);
  const int q0 = p.coordinate_register(0), q2 = p.coordinate_register(2), v1 = p.velocity_register(1);
  const int unused = p.push(Op::sin, p.coordinate_register(1));  // computed, but no output reads it
  (void)unused;
  const int sc = p.push(Op::sincos, q2);
  p.add_output(p.push(Op::mul, q0, v1));
  p.add_output(sc + 1);  // only the cosine of the sincos: still depends on q2
  const std::vector<char> d = calc_input_dependence(p);
  ASSERT_EQ(d.size(), 7u);  // t, q0..q2, v0..v2
  EXPECT_EQ(d, (std::vector<char>{0, 1, 0, 1, 0, 1, 0}));
}

}  // namespace
}  // namespace nhdyn
