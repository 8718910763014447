// Exams of the high-precision reference (precise_reference.hpp): the exact rational of a double;
// q'', R and the multipliers of Appell's particle (docs/derivations/appell.md (2.1)) and of a
// pendulum in Cartesian coordinates (a holonomic constraint) against closed forms evaluated by
// GiNaC at 60 digits, to 1e-30 relative at states off the constraints; agreement with the double
// formulations to round-off only; and the refusal of bad input.
#include "nhdyn/symbolic/precise_reference.hpp"

#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <vector>

#include "nhdyn/core/error.hpp"
#include "nhdyn/formulation/formulation.hpp"
#include "nhdyn/model/data.hpp"
#include "nhdyn/model/terms.hpp"
#include "nhdyn/symbolic/compile.hpp"
#include "nhdyn/symbolic/spec_builder.hpp"

namespace nhdyn::symbolic {
namespace {

using GiNaC::numeric;

// Appell's particle with parameters that are not short binary fractions, so that the exact
// rationals matter.
Spec appell_spec() {
  SpecBuilder b("appell");
  b.coordinate("x").coordinate("y").coordinate("z");
  b.parameter("m", 1.7).parameter("g", 9.81).parameter("a", 0.6);
  b.kinetic_energy("m/2*(x'^2 + y'^2 + z'^2)");
  b.potential_energy("-m*g*z");
  b.constraint("appell", ConstraintLevel::velocity, "z'^2 - a^2*(x'^2 + y'^2)");
  return b.build();
}

// A point mass on a rod of length l, y up: x^2 + y^2 - l^2 = 0.
Spec pendulum_spec() {
  SpecBuilder b("pendulum");
  b.coordinate("x").coordinate("y");
  b.parameter("m", 0.3).parameter("g", 9.81).parameter("l", 1.3);
  b.kinetic_energy("m/2*(x'^2 + y'^2)");
  b.potential_energy("m*g*y");
  b.constraint("rod", ConstraintLevel::position, "x^2 + y^2 - l^2");
  return b.build();
}

// |x - y| / |y| at 60 digits.
double relative(const numeric& x, const numeric& y) {
  GiNaC::Digits = 60;
  const double out = GiNaC::abs((x - y) / y).to_double();
  GiNaC::Digits = 17;
  return out;
}

// Appell's q'', R and lambda from docs/derivations/appell.md (2.1), with N = a^4 (x'^2 + y'^2) + z'^2,
// lambda = -m g z' / (2 N) for b = (-2 a^2 x', -2 a^2 y', 2 z'), R = m q'' - (0, 0, m g).
struct AppellExact {
  std::array<numeric, 3> qdd, R;
  numeric lambda;
};
AppellExact appell_exact(const numeric& m, const numeric& g, const numeric& a, const std::array<numeric, 3>& v) {
  const numeric a2 = a * a;
  const numeric N = a2 * a2 * (v[0] * v[0] + v[1] * v[1]) + v[2] * v[2];
  AppellExact out;
  out.qdd = {g * a2 * v[0] * v[2] / N, g * a2 * v[1] * v[2] / N, g * a2 * a2 * (v[0] * v[0] + v[1] * v[1]) / N};
  out.R = {m * out.qdd[0], m * out.qdd[1], m * out.qdd[2] - m * g};
  out.lambda = -m * g * v[2] / (2 * N);
  return out;
}

TEST(PreciseReference, ExactRationalIsTheDoublesValue) {
  // 0.1 is stored as 3602879701896397 / 2^55, not 1/10.
  EXPECT_EQ(exact_rational(0.1), numeric(3602879701896397L) / numeric(2).power(55));
  EXPECT_NE(exact_rational(0.1), numeric(1, 10));
  EXPECT_EQ(exact_rational(-3.0), numeric(-3));
  EXPECT_EQ(exact_rational(0.0), numeric(0));
  EXPECT_EQ(exact_rational(std::ldexp(1.0, -1074)), numeric(2).power(-1074));  // the smallest subnormal
  EXPECT_EQ(exact_rational(1e300).to_double(), 1e300);
  EXPECT_TRUE(exact_rational(1e300).is_integer());
  EXPECT_THROW(exact_rational(std::nan("")), InputError);
  EXPECT_THROW(exact_rational(INFINITY), InputError);
}

TEST(PreciseReference, AppellMatchesTheClosedFormTo30Digits) {
  const Spec spec = appell_spec();
  const Derivation derivation = derive(spec);
  // Off the constraint (z' != a |u|), with velocities that are not short binary fractions.
  const std::vector<std::array<double, 3>> velocities{{1.0, 0.5, 0.7}, {-0.3, 2.1, -1.9}, {1e-3, 7.0, 0.11}};
  for (const auto& v : velocities) {
    const std::vector<double> q{0.2, -1.1, 3.3};
    const PreciseAcceleration ref = calc_precise_acceleration(spec, derivation, 0.0, q, v);
    const AppellExact exact = appell_exact(exact_rational(1.7), exact_rational(9.81), exact_rational(0.6),
                                           {exact_rational(v[0]), exact_rational(v[1]), exact_rational(v[2])});
    for (int i = 0; i < 3; ++i) {
      EXPECT_LT(relative(ref.qdd[i], exact.qdd[i]), 1e-30) << "q''[" << i << "]";
      EXPECT_LT(relative(ref.R[i], exact.R[i]), 1e-30) << "R[" << i << "]";
    }
    ASSERT_EQ(ref.lambda.size(), 1u);
    EXPECT_LT(relative(ref.lambda[0], exact.lambda), 1e-30);
    EXPECT_EQ(ref.digits, 50);
    EXPECT_LT(ref.estimated_error, 1e-40);
  }
}

TEST(PreciseReference, UsesTheDoublesTheModelIsGivenNotTheDecimals) {
  // The reference solves the problem with the double 0.1 in it, which differs from 1/10 in the
  // 17th digit: the closed form at 1/10 is off by about 1e-17, at the double's value by < 1e-30.
  const Spec spec = appell_spec();
  const Derivation derivation = derive(spec);
  const std::vector<double> q{0.0, 0.0, 0.0};
  const std::vector<double> v{0.1, 0.3, 0.7};
  const PreciseAcceleration ref = calc_precise_acceleration(spec, derivation, 0.0, q, v);
  const AppellExact at_double = appell_exact(exact_rational(1.7), exact_rational(9.81), exact_rational(0.6),
                                             {exact_rational(0.1), exact_rational(0.3), exact_rational(0.7)});
  const AppellExact at_decimal = appell_exact(exact_rational(1.7), exact_rational(9.81), exact_rational(0.6),
                                              {numeric(1, 10), numeric(3, 10), numeric(7, 10)});
  EXPECT_LT(relative(ref.qdd[0], at_double.qdd[0]), 1e-30);
  EXPECT_GT(relative(ref.qdd[0], at_decimal.qdd[0]), 1e-19);
  EXPECT_EQ(static_cast<long>(GiNaC::Digits), 17) << "GiNaC::Digits must be restored";
}

TEST(PreciseReference, PendulumMatchesTheClosedFormOffTheCircle) {
  // KKT with b = 2 r, b0 = 2 |v|^2, F = (0, -m g): r . q'' = -|v|^2, so
  // q'' = F/m + mu r with mu = (-|v|^2 - r . F/m) / |r|^2 and R = m mu r, exact at any state.
  const Spec spec = pendulum_spec();
  const Derivation derivation = derive(spec);
  const std::vector<double> q{0.7, -1.05};  // not on the circle of radius 1.3
  const std::vector<double> v{0.9, 0.45};
  const PreciseAcceleration ref = calc_precise_acceleration(spec, derivation, 0.0, q, v);
  const numeric m = exact_rational(0.3), g = exact_rational(9.81);
  const numeric x = exact_rational(q[0]), y = exact_rational(q[1]);
  const numeric vv = exact_rational(v[0]) * exact_rational(v[0]) + exact_rational(v[1]) * exact_rational(v[1]);
  const numeric mu = (-vv + y * g) / (x * x + y * y);
  EXPECT_LT(relative(ref.qdd[0], mu * x), 1e-30);
  EXPECT_LT(relative(ref.qdd[1], -g + mu * y), 1e-30);
  EXPECT_LT(relative(ref.R[0], m * mu * x), 1e-30);
  EXPECT_LT(relative(ref.R[1], m * mu * y), 1e-30);
}

TEST(PreciseReference, DoubleFormulationsAgreeToRoundOffOnly) {
  // Every double formulation is within round-off of the reference, and not exactly on it: the
  // reference carries digits the doubles cannot hold.
  const Spec spec = appell_spec();
  const Derivation derivation = derive(spec);
  const Model model = compile_model(spec, derivation);
  Data data = make_data(model);
  const std::vector<double> q{0.2, -1.1, 3.3};
  const std::vector<double> v{1.0, 0.5, 0.7};
  const PreciseAcceleration ref = calc_precise_acceleration(spec, derivation, 0.0, q, v);
  for (Formulation method : {Formulation::sanh, Formulation::lagrange, Formulation::udwadia_kalaba, Formulation::nullspace}) {
    ASSERT_EQ(compute_terms(model, data, 0.0, q.data(), v.data()), Status::ok);
    ASSERT_EQ(compute_acceleration(model, data, FormulationOptions(method)), Status::ok);
    const double error = calc_relative_error({data.qdd.data(), 3}, ref.qdd);
    EXPECT_LT(error, 1e-14) << formulation_name(method);
    EXPECT_GT(error, 1e-30) << formulation_name(method);
    EXPECT_LT(calc_relative_error({data.R.data(), 3}, ref.R), 1e-14) << formulation_name(method);
  }
}

TEST(PreciseReference, SolutionOfDoubleTermsIsTheExactOneOfThoseTerms) {
  // Pendulum terms given as doubles: A = m I, Q + G = (0, -m g), b = 2 (x, y), b0 = 2 |v|^2. Its
  // exact solution is the closed form above at those rationals (to 1e-30), and it differs from the
  // reference of the spec only by the rounding of the terms (here exact but for m g and 2 |v|^2).
  const numeric m = exact_rational(0.3);
  const double x = 0.7, y = -1.05, vx = 0.9, vy = 0.45;
  Matrix A = Matrix::Identity(2, 2) * 0.3;
  Vector h(2);
  h << 0.0, -0.3 * 9.81;
  Matrix b(1, 2);
  b << 2 * x, 2 * y;
  Vector b0(1);
  b0 << 2 * (vx * vx + vy * vy);
  const PreciseAcceleration solution = calc_precise_solution(A, h, b, b0);
  const numeric gd = exact_rational(-h(1)) / m;  // the g these rounded terms imply
  const numeric mu = (-exact_rational(b0(0)) / 2 + exact_rational(y) * gd) / (exact_rational(x) * exact_rational(x) +
                                                                         exact_rational(y) * exact_rational(y));
  EXPECT_LT(relative(solution.qdd[0], mu * exact_rational(x)), 1e-30);
  EXPECT_LT(relative(solution.qdd[1], -gd + mu * exact_rational(y)), 1e-30);
  const Spec spec = pendulum_spec();
  const PreciseAcceleration ref = calc_precise_acceleration(spec, derive(spec), 0.0, std::vector<double>{x, y},
                                                            std::vector<double>{vx, vy});
  EXPECT_LT(relative(solution.qdd[1], ref.qdd[1]), 1e-15);
  EXPECT_GT(relative(solution.qdd[1], ref.qdd[1]), 1e-30) << "m g rounded in double should show";
  EXPECT_THROW(calc_precise_solution(A, h, Matrix::Zero(1, 3), b0), InputError);
}

TEST(PreciseReference, RefusesBadInput) {
  const Spec spec = appell_spec();
  const Derivation derivation = derive(spec);
  const std::vector<double> q{0.0, 0.0, 0.0};
  const std::vector<double> v{1.0, 0.5, 0.7};
  EXPECT_THROW(calc_precise_acceleration(spec, derivation, 0.0, q, std::vector<double>{1.0, 0.5}), InputError);
  EXPECT_THROW(calc_precise_acceleration(spec, derivation, 0.0, q, v, 16), InputError);
  EXPECT_THROW(calc_precise_acceleration(spec, derivation, 0.0, q, std::vector<double>{1.0, NAN, 0.7}), InputError);
  // At rest b = 0: the system is singular.
  EXPECT_THROW(calc_precise_acceleration(spec, derivation, 0.0, q, std::vector<double>{0.0, 0.0, 0.0}), ModelError);
  EXPECT_EQ(static_cast<long>(GiNaC::Digits), 17);
}

}  // namespace
}  // namespace nhdyn::symbolic
