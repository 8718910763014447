// Exams of derive() and simplify(): the derived terms of the paper's examples against the
// hand-written models (to 1e-12 at random states), the paper's reduced equations A0 q'' = C
// (by symbolic difference), holonomic and time-dependent constraints against GiNaC's own time
// derivatives along an arbitrary path, and the errors of ill-posed models.
#include "nhdyn/symbolic/derivation.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <random>
#include <string>
#include <vector>

#include "nhdyn/core/error.hpp"
#include "nhdyn/model/appell.hpp"
#include "nhdyn/model/sled.hpp"
#include "nhdyn/symbolic/simplify.hpp"
#include "nhdyn/symbolic/spec_builder.hpp"

// Unknown functions of time, for derivatives along an arbitrary path q(t).
DECLARE_FUNCTION_1P(path_q0)
REGISTER_FUNCTION(path_q0, dummy())
DECLARE_FUNCTION_1P(path_q1)
REGISTER_FUNCTION(path_q1, dummy())
DECLARE_FUNCTION_1P(path_q2)
REGISTER_FUNCTION(path_q2, dummy())

namespace nhdyn::symbolic {
namespace {

using GiNaC::ex;

Spec appell_spec(bool with_independent) {
  const AppellParameters p;
  SpecBuilder b("appell");
  b.coordinate("x").coordinate("y").coordinate("z");
  b.parameter("m", p.m, "kg").parameter("g", p.g, "m/s^2").parameter("a", p.a);
  b.kinetic_energy("m/2*(x'^2 + y'^2 + z'^2)");
  b.potential_energy("-m*g*z");
  b.constraint("appell", ConstraintLevel::velocity, "z'^2 - a^2*(x'^2 + y'^2)");
  if (with_independent) b.independent({"x", "y"});
  return b.build();
}

Spec sled_spec(SledVariant variant, bool with_independent) {
  const SledParameters p;
  const bool paper = variant == SledVariant::paper;
  SpecBuilder b(paper ? "sled-paper" : "sled");
  b.coordinate("x").coordinate("y").coordinate("phi");
  b.parameter("m", p.m, "kg").parameter("a", p.a, "m").parameter("rho", p.rho, "m");
  b.parameter("alpha", p.alpha, "rad").parameter("g", p.g, "m/s^2");
  b.kinetic_energy("m/2*(x'^2 + y'^2) - m*a*sin(phi)*x'*phi' + m*a*cos(phi)*y'*phi' + m*rho^2/2*phi'^2");
  b.potential_energy(paper ? "-m*g*sin(alpha)*x" : "-m*g*sin(alpha)*(x + a*cos(phi))");
  b.constraint("blade", ConstraintLevel::velocity, paper ? "y' - tan(phi)*x'" : "-sin(phi)*x' + cos(phi)*y'");
  if (with_independent) b.independent({"x", "phi"});
  return b.build();
}

// The value of `e` at (t, q, q') with the spec's parameter values.
double value(const Spec& spec, const ex& e, double t, const std::vector<double>& q, const std::vector<double>& v) {
  GiNaC::lst at = spec.parameter_values();
  at.append(spec.symbols.time() == t);
  for (int i = 0; i < spec.n(); ++i) {
    at.append(spec.symbols.coordinate(i) == q[static_cast<std::size_t>(i)]);
    at.append(spec.symbols.velocity(i) == v[static_cast<std::size_t>(i)]);
  }
  const ex number = GiNaC::evalf(e.subs(at));
  EXPECT_TRUE(GiNaC::is_a<GiNaC::numeric>(number)) << e << " -> " << number;
  if (!GiNaC::is_a<GiNaC::numeric>(number)) return NAN;
  return GiNaC::ex_to<GiNaC::numeric>(number).to_double();
}

void expect_close(double actual, double expected, const std::string& what) {
  EXPECT_NEAR(actual, expected, 1e-12 * (1.0 + std::abs(expected))) << what;
}

struct Numeric {
  std::vector<double> A, Q, G, b, b0;
  explicit Numeric(int n, int s)
      : A(static_cast<std::size_t>(n * n)), Q(static_cast<std::size_t>(n)), G(static_cast<std::size_t>(n)),
        b(static_cast<std::size_t>(s * n)), b0(static_cast<std::size_t>(s)) {}
  TermsOut out() { return {A.data(), Q.data(), G.data(), b.data(), b0.data()}; }
};

// Compares A, Q, G, b (row scaled by `b_scale`), b0, f and the energy with the hand-written model.
template <class Scale>
void compare_with_model(const Spec& spec, const Model& model, Scale b_scale, std::uint32_t seed) {
  const Derivation d = derive(spec);
  const int n = spec.n(), s = spec.s();
  ASSERT_EQ(n, model.n());
  ASSERT_EQ(s, model.s());
  ASSERT_TRUE(d.energy.has_value());
  ASSERT_EQ(d.f.size(), static_cast<std::size_t>(s));
  std::mt19937 random(seed);
  std::uniform_real_distribution<double> uniform(-1.2, 1.2);
  for (int trial = 0; trial < 20; ++trial) {
    const double t = uniform(random);
    std::vector<double> q(static_cast<std::size_t>(n)), v(static_cast<std::size_t>(n));
    for (auto& x : q) x = uniform(random);
    for (auto& x : v) x = uniform(random);
    if (std::abs(v[2]) < 0.2) v[2] += 0.5;  // Appell's paper form divides by z'
    Numeric hand(n, s);
    model.evaluator->terms(t, q.data(), v.data(), nullptr, hand.out());
    const auto un = static_cast<unsigned>(n);
    for (unsigned i = 0; i < un; ++i) {
      for (unsigned j = 0; j < un; ++j)
        expect_close(value(spec, d.A(i, j), t, q, v), hand.A[i + j * un], "A");
      expect_close(value(spec, d.Q(i, 0), t, q, v), hand.Q[i], "Q");
      expect_close(value(spec, d.G(i, 0), t, q, v), hand.G[i], "G");
    }
    std::vector<double> f(static_cast<std::size_t>(s));
    model.evaluator->velocity_residual(t, q.data(), v.data(), nullptr, f.data());
    for (unsigned r = 0; r < static_cast<unsigned>(s); ++r) {
      const double scale = b_scale(v);
      for (unsigned j = 0; j < un; ++j)
        expect_close(value(spec, d.b(r, j), t, q, v) / scale, hand.b[r + j * static_cast<unsigned>(s)], "b");
      expect_close(value(spec, d.b0(r, 0), t, q, v) / scale, hand.b0[r], "b0");
      expect_close(value(spec, d.f[r], t, q, v), f[r], "f");
    }
    expect_close(value(spec, *d.energy, t, q, v), model.evaluator->energy(t, q.data(), v.data(), nullptr), "energy");
  }
}

TEST(Derivation, AppellMatchesTheHandWrittenModel) {
  // The hand-written model keeps the paper's acceleration form: the derivative of f divided by 2 z'.
  compare_with_model(appell_spec(false), make_appell_model(), [](const std::vector<double>& v) { return 2 * v[2]; },
                     11);
}

TEST(Derivation, SledMatchesTheHandWrittenModel) {
  compare_with_model(sled_spec(SledVariant::centre_of_mass, false), make_sled_model(SledVariant::centre_of_mass),
                     [](const std::vector<double>&) { return 1.0; }, 12);
}

TEST(Derivation, SledPaperMatchesTheHandWrittenModel) {
  compare_with_model(sled_spec(SledVariant::paper, false), make_sled_model(SledVariant::paper),
                     [](const std::vector<double>&) { return 1.0; }, 13);
}

void expect_zero(const GiNaC::matrix& difference, const std::string& what) {
  for (unsigned i = 0; i < difference.rows(); ++i)
    for (unsigned j = 0; j < difference.cols(); ++j)
      EXPECT_TRUE(symbolic::is_zero(difference(i, j)))
          << what << "(" << i << ", " << j << "): difference " << simplify(difference(i, j));
}

TEST(Derivation, AppellReducedEquationsAreThePapers) {
  const Spec spec = appell_spec(true);
  const Derivation d = derive(spec);
  const SymbolTable& S = spec.symbols;
  const ex m = S.parameter("m"), g = S.parameter("g"), a = S.parameter("a");
  const ex xd = S.velocity(0), yd = S.velocity(1), zd = S.velocity(2);
  ASSERT_TRUE(d.D.has_value());
  const GiNaC::matrix D = {{1, 0, a * a * xd / zd}, {0, 1, a * a * yd / zd}};
  const GiNaC::matrix A0 = {{m, 0, m * a * a * xd / zd}, {0, m, m * a * a * yd / zd}};
  const GiNaC::matrix C = {{m * g * a * a * xd / zd}, {m * g * a * a * yd / zd}};
  expect_zero(d.D->sub(D), "D");
  expect_zero(reduced_inertia(d).sub(A0), "A0");
  expect_zero(reduced_forces(d).sub(C), "C");
  // A = m I, G = 0, Q = (0, 0, m g).
  expect_zero(d.A.sub(GiNaC::matrix{{m, 0, 0}, {0, m, 0}, {0, 0, m}}), "A");
  expect_zero(d.G, "G");
  expect_zero(d.Q.sub(GiNaC::matrix{{0}, {0}, {m * g}}), "Q");
}

TEST(Derivation, SledPaperReducedEquationsAreThePapers) {
  const Spec spec = sled_spec(SledVariant::paper, true);
  const Derivation d = derive(spec);
  const SymbolTable& S = spec.symbols;
  const ex m = S.parameter("m"), g = S.parameter("g"), a = S.parameter("a"), rho = S.parameter("rho"),
           alpha = S.parameter("alpha");
  const ex phi = S.coordinate(2), w = S.velocity(2);
  ASSERT_TRUE(d.D.has_value());
  const GiNaC::matrix D = {{1, GiNaC::tan(phi), 0}, {0, 0, 1}};
  // m x'' + m tan(phi) y'' = m g sin(alpha) + m a phi'^2 / cos(phi)
  // -m a sin(phi) x'' + m a cos(phi) y'' + m rho^2 phi'' = 0
  const GiNaC::matrix A0 = {{m, m * GiNaC::tan(phi), 0},
                            {-m * a * GiNaC::sin(phi), m * a * GiNaC::cos(phi), m * rho * rho}};
  const GiNaC::matrix C = {{m * g * GiNaC::sin(alpha) + m * a * w * w / GiNaC::cos(phi)}, {0}};
  expect_zero(d.D->sub(D), "D");
  expect_zero(reduced_inertia(d).sub(A0), "A0");
  expect_zero(reduced_forces(d).sub(C), "C");
  // A wrong sign of the phi'^2 term must not pass.
  const GiNaC::matrix wrong = {{m * g * GiNaC::sin(alpha) - m * a * w * w / GiNaC::cos(phi)}, {0}};
  EXPECT_FALSE(symbolic::is_zero(reduced_forces(d).sub(wrong)));
}

TEST(Derivation, RegularSledWithTheSameIndependentCoordinatesHasThePapersD) {
  const Spec spec = sled_spec(SledVariant::centre_of_mass, true);
  const Derivation d = derive(spec);
  const ex phi = spec.symbols.coordinate(2);
  ASSERT_TRUE(d.D.has_value());
  expect_zero(d.D->sub(GiNaC::matrix{{1, GiNaC::tan(phi), 0}, {0, 0, 1}}), "D");
  // D b^T = 0 identically.
  expect_zero(d.D->mul(d.b.transpose()), "D b^T");
}

TEST(Derivation, AnalyticComplementIsKept) {
  SpecBuilder b("sled");
  const SledParameters p;
  b.coordinate("x").coordinate("y").coordinate("phi");
  b.parameter("m", p.m).parameter("a", p.a).parameter("rho", p.rho);
  b.kinetic_energy("m/2*(x'^2 + y'^2) - m*a*sin(phi)*x'*phi' + m*a*cos(phi)*y'*phi' + m*rho^2/2*phi'^2");
  b.constraint("blade", "-sin(phi)*x' + cos(phi)*y' = 0");
  b.complement({{"cos(phi)", "sin(phi)", "0"}, {"0", "0", "1"}});
  const Spec spec = b.build();
  const Derivation d = derive(spec);
  ASSERT_TRUE(d.D.has_value());
  expect_zero(d.D->sub(*spec.complement), "D");
  expect_zero(d.D->mul(d.b.transpose()), "D b^T");
}

// Substitutes the path q(t) = (path_q0(t), ...) into an expression in (q, q', q'').
ex along_path(const Spec& spec, const ex& e) {
  const GiNaC::symbol& t = spec.symbols.time();
  const std::vector<ex> path = {path_q0(t), path_q1(t), path_q2(t)};
  GiNaC::lst at;
  for (int i = 0; i < spec.n(); ++i) {
    const ex& x = path[static_cast<std::size_t>(i)];
    at.append(spec.symbols.coordinate(i) == x);
    at.append(spec.symbols.velocity(i) == x.diff(t));
    at.append(spec.symbols.acceleration(i) == x.diff(t, 2));
  }
  return e.subs(at);
}

// For every constraint: b q'' + b0 is the second time derivative of phi (position level) or the
// first of f (velocity level) along an arbitrary path, and f is the first derivative of phi.
void check_time_derivatives(const Spec& spec) {
  const Derivation d = derive(spec);
  const GiNaC::symbol& t = spec.symbols.time();
  std::size_t position = 0, velocity = 0;
  for (unsigned r = 0; r < static_cast<unsigned>(spec.s()); ++r) {
    const SpecConstraint& c = spec.constraints[r];
    ex acceleration = d.b0(r, 0);
    for (int j = 0; j < spec.n(); ++j)
      acceleration += d.b(r, static_cast<unsigned>(j)) * spec.symbols.acceleration(j);
    const ex on_path = along_path(spec, acceleration);
    const ex given = along_path(spec, c.expression);
    if (c.level == ConstraintLevel::position) {
      EXPECT_TRUE(symbolic::is_zero(on_path - given.diff(t, 2))) << c.name << ": " << simplify(on_path - given.diff(t, 2));
      EXPECT_TRUE(symbolic::is_zero(along_path(spec, d.phi[position++]) - given)) << c.name;
      EXPECT_TRUE(symbolic::is_zero(along_path(spec, d.f[velocity++]) - given.diff(t))) << c.name;
    } else if (c.level == ConstraintLevel::velocity) {
      EXPECT_TRUE(symbolic::is_zero(on_path - given.diff(t))) << c.name << ": " << simplify(on_path - given.diff(t));
      EXPECT_TRUE(symbolic::is_zero(along_path(spec, d.f[velocity++]) - given)) << c.name;
    } else {
      EXPECT_TRUE(symbolic::is_zero(on_path - given)) << c.name;
    }
  }
  EXPECT_EQ(position, d.phi.size());
  EXPECT_EQ(velocity, d.f.size());
}

TEST(Derivation, PendulumInCartesianCoordinates) {
  SpecBuilder b("pendulum");
  b.coordinate("x").coordinate("y").parameter("m", 1.3).parameter("g", 9.81).parameter("l", 0.7);
  b.kinetic_energy("m/2*(x'^2 + y'^2)").potential_energy("m*g*y");
  b.constraint("rod", ConstraintLevel::position, "x^2 + y^2 - l^2");
  const Spec spec = b.build();
  check_time_derivatives(spec);
  const Derivation d = derive(spec);
  const ex x = spec.symbols.coordinate(0), y = spec.symbols.coordinate(1);
  const ex xd = spec.symbols.velocity(0), yd = spec.symbols.velocity(1);
  // b = (2 x, 2 y), b0 = 2 (x'^2 + y'^2).
  expect_zero(d.b.sub(GiNaC::matrix{{2 * x, 2 * y}}), "b");
  EXPECT_TRUE(symbolic::is_zero(d.b0(0, 0) - 2 * (xd * xd + yd * yd)));
  ASSERT_TRUE(d.energy.has_value());
}

TEST(Derivation, TimeDependentConstraints) {
  SpecBuilder b("driven");
  b.coordinate("x").coordinate("y").coordinate("z").parameter("m", 2.0).parameter("w", 1.5);
  b.kinetic_energy("m/2*(x'^2 + y'^2 + z'^2) + m*t*x'*y'");
  b.constraint("drive", ConstraintLevel::position, "x - sin(t)");
  b.constraint("mixed", ConstraintLevel::position, "x*cos(w*t) + y^2*t - exp(z)*t^2");
  const Spec spec = b.build();
  check_time_derivatives(spec);
  const Derivation d = derive(spec);
  // T depends on t explicitly: E = T + V is given, and the power of the explicit time dependence,
  // -dT/dt = -m x' y', is not zero (docs/derivations/energy-balance.md (E3)).
  ASSERT_TRUE(d.energy.has_value());
  EXPECT_FALSE(d.conservative);
  EXPECT_TRUE(symbolic::is_zero(d.power_time + spec.symbols.parameter("m") * spec.symbols.velocity(0) *
                                                  spec.symbols.velocity(1)));
  EXPECT_TRUE(symbolic::is_zero(d.power_forces));
  // x - sin(t): b = (1, 0, 0), b0 = sin(t).
  expect_zero(d.b.sub(GiNaC::matrix{{1, 0, 0}, {d.b(1, 0), d.b(1, 1), d.b(1, 2)}}), "b");
  EXPECT_TRUE(symbolic::is_zero(d.b0(0, 0) - GiNaC::sin(spec.symbols.time())));

  SpecBuilder c("rheonomic-velocity");
  c.coordinate("x").coordinate("y").coordinate("z").parameter("k", 0.3);
  c.kinetic_energy("(x'^2 + y'^2 + z'^2)/2");
  c.constraint("nonlinear", ConstraintLevel::velocity, "x'^2*cos(t) + y*z' - k*t*exp(x)");
  c.constraint("given", ConstraintLevel::acceleration, "z'' + t*x'*y'' - sin(y)");
  check_time_derivatives(c.build());
}

TEST(Derivation, GeneralKineticEnergyGivesLagrangesEquations) {
  // T with linear and velocity-free parts and explicit t: A q'' - Q - G must equal
  // d/dt dT/dq' - dT/dq - Q along any path.
  SpecBuilder b("general");
  b.coordinate("x").coordinate("y").parameter("m", 1.0).parameter("c", 0.4);
  b.kinetic_energy("m/2*(1 + y^2)*x'^2 + m/2*exp(t)*y'^2 + c*t*x*y'*x + c*sin(x)*y' + c*x^2*y^2");
  b.potential_energy("c*cos(x)*y^2").force("x", "-c*x'*t");
  const Spec spec = b.build();
  const Derivation d = derive(spec);
  const GiNaC::symbol& t = spec.symbols.time();
  for (int i = 0; i < 2; ++i) {
    const auto ui = static_cast<unsigned>(i);
    ex lhs = -d.Q(ui, 0) - d.G(ui, 0);
    for (int j = 0; j < 2; ++j) lhs += d.A(ui, static_cast<unsigned>(j)) * spec.symbols.acceleration(j);
    const ex T = spec.kinetic_energy;
    const ex lagrange = along_path(spec, T.diff(spec.symbols.velocity(i))).diff(t) -
                        along_path(spec, T.diff(spec.symbols.coordinate(i))) -
                        along_path(spec, -spec.potential_energy.diff(spec.symbols.coordinate(i)) + spec.forces[ui]);
    EXPECT_TRUE(symbolic::is_zero(along_path(spec, lhs) - lagrange)) << i;
  }
  // The energy balance (docs/derivations/energy-balance.md): h = T2 - T0 + V, Q_nc . q' and
  // -dL/dt|explicit, against the parts of T written out by hand.
  const ex x = spec.symbols.coordinate(0), y = spec.symbols.coordinate(1);
  const ex xd = spec.symbols.velocity(0), yd = spec.symbols.velocity(1);
  const ex m = spec.symbols.parameter("m"), c = spec.symbols.parameter("c");
  const ex T2 = m / 2 * (1 + y * y) * xd * xd + m / 2 * GiNaC::exp(t) * yd * yd;
  const ex T0 = c * x * x * y * y;
  const ex V = c * GiNaC::cos(x) * y * y;
  ASSERT_TRUE(d.energy.has_value());
  ASSERT_TRUE(d.energy_function.has_value());
  EXPECT_FALSE(d.conservative);
  EXPECT_TRUE(symbolic::is_zero(*d.energy_function - (T2 - T0 + V)));
  EXPECT_TRUE(symbolic::is_zero(d.power_forces + c * xd * t * xd));
  EXPECT_TRUE(symbolic::is_zero(d.power_time + m / 2 * GiNaC::exp(t) * yd * yd + c * x * x * yd));
  // A T quadratic in the velocities (the rod above) has h = E: no separate program.
}

template <class F>
std::string error_of(F&& f) {
  try {
    f();
  } catch (const ModelError& e) {
    return e.what();
  }
  return "(no ModelError)";
}

TEST(DerivationErrors, KineticEnergyNotQuadratic) {
  SpecBuilder b("cubic", {"cubic.toml", 1, 1});
  b.coordinate("x").parameter("m", 1.0).kinetic_energy("m*x'^3");
  const Spec spec = b.build();
  const std::string message = error_of([&] { derive(spec); });
  EXPECT_NE(message.find("cubic.toml:1:1"), std::string::npos) << message;
  EXPECT_NE(message.find("not quadratic"), std::string::npos) << message;
  EXPECT_NE(message.find("degree 3"), std::string::npos) << message;
}

TEST(DerivationErrors, ConstraintWithoutVelocitiesAfterDifferentiation) {
  SpecBuilder b("m");
  b.coordinate("x").coordinate("y").kinetic_energy("(x'^2 + y'^2)/2");
  b.constraint("c", ConstraintLevel::velocity, "sin(x')^2 + cos(x')^2 + y", {"m.toml", 7, 3});
  const Spec spec = b.build();
  const std::string message = error_of([&] { derive(spec); });
  EXPECT_NE(message.find("m.toml:7:3: constraint 'c' does not involve the velocities"), std::string::npos)
      << message;

  SpecBuilder p("p");
  p.coordinate("x").coordinate("y").kinetic_energy("(x'^2 + y'^2)/2");
  p.constraint("clock", ConstraintLevel::position, "t - 1", {"p.toml", 4, 1});
  const std::string position = error_of([&] { derive(p.build()); });
  EXPECT_NE(position.find("p.toml:4:1: constraint 'clock' does not involve the velocities"), std::string::npos)
      << position;
}

TEST(DerivationErrors, AccelerationConstraintNotLinear) {
  SpecBuilder b("m");
  b.coordinate("x").coordinate("y").kinetic_energy("(x'^2 + y'^2)/2");
  b.constraint("c", ConstraintLevel::acceleration, "x''^2 + y''", {"m.toml", 9, 5});
  const std::string message = error_of([&] { derive(b.build()); });
  EXPECT_NE(message.find("m.toml:9:5: constraint 'c'"), std::string::npos) << message;
  EXPECT_NE(message.find("linear in the accelerations"), std::string::npos) << message;
}

TEST(DerivationErrors, SingularPartition) {
  SpecBuilder b("sled", {"sled.toml", 1, 1});
  b.coordinate("x").coordinate("y").coordinate("phi").kinetic_energy("(x'^2 + y'^2 + phi'^2)/2");
  b.constraint("blade", "-sin(phi)*x' + cos(phi)*y'");
  b.independent({"x", "y"});
  const std::string message = error_of([&] { derive(b.build()); });
  EXPECT_NE(message.find("cannot keep x, y independent"), std::string::npos) << message;
  EXPECT_NE(message.find("(phi)"), std::string::npos) << message;
}

TEST(DerivationErrors, ReducedTermsNeedD) {
  const Derivation d = derive(appell_spec(false));
  EXPECT_FALSE(d.D.has_value());
  EXPECT_THROW(reduced_inertia(d), ModelError);
  EXPECT_THROW(reduced_forces(d), ModelError);
}

TEST(Simplify, TrigonometricIdentitiesReduceToZero) {
  const GiNaC::symbol x("x"), y("y"), u("u");
  const ex s = GiNaC::sin(x), c = GiNaC::cos(x);
  EXPECT_TRUE(simplify(s * s + c * c - 1).is_zero());
  EXPECT_TRUE(symbolic::is_zero((1 + GiNaC::pow(GiNaC::tan(x), 2)) * c * c - 1));
  EXPECT_TRUE(symbolic::is_zero(GiNaC::pow(s, 4) - GiNaC::pow(c, 4) - s * s + c * c));
  EXPECT_TRUE(symbolic::is_zero(GiNaC::tan(x) - s / c));
  EXPECT_TRUE(symbolic::is_zero(GiNaC::pow(GiNaC::cosh(y), 2) - GiNaC::pow(GiNaC::sinh(y), 2) - 1));
  EXPECT_TRUE(symbolic::is_zero(GiNaC::exp(GiNaC::sin(u) * GiNaC::sin(u) + GiNaC::cos(u) * GiNaC::cos(u)) -
                                GiNaC::exp(ex(1))));
  EXPECT_TRUE(symbolic::is_zero(u * (s * s + c * c) * GiNaC::sin(y) - u * GiNaC::sin(y)));
  // Not identities.
  EXPECT_FALSE(symbolic::is_zero(s * s - c * c));
  EXPECT_FALSE(symbolic::is_zero(s - c * GiNaC::tan(y)));
  EXPECT_FALSE(symbolic::is_zero(x - y));
  // Shorter forms are kept: 1 - sin^2 becomes cos^2, sin/cos stays a quotient.
  EXPECT_EQ(canonical_key(simplify(1 - s * s)), canonical_key(c * c));
  EXPECT_EQ(canonical_key(simplify(GiNaC::tan(x) * c * c)), canonical_key(s * c));
  // A single product below the line is distributed.
  EXPECT_EQ(canonical_key(simplify((u * c + 1) / c)), canonical_key(u + 1 / c));
}

// The reduction of sin^2 (or cos^2) works on every family and every power of a term at once when
// the coefficients are rational, family by family otherwise (a float's sums depend on their order):
// both reach the same remainder.
TEST(Simplify, PowersOfSeveralFamiliesReduceTogether) {
  const GiNaC::symbol x("x"), y("y"), z("z"), u("u");
  const ex sx = GiNaC::sin(x), cx = GiNaC::cos(x), sy = GiNaC::sin(y), cy = GiNaC::cos(y);
  const ex shz = GiNaC::sinh(z), chz = GiNaC::cosh(z);
  const ex reduced = GiNaC::pow(1 - cx * cx, 2) * sy * (1 - cy * cy) * (chz * chz - 1);
  EXPECT_TRUE(symbolic::is_zero(GiNaC::pow(sx, 4) * GiNaC::pow(sy, 3) * GiNaC::pow(shz, 2) - reduced));
  EXPECT_TRUE(symbolic::is_zero(u * GiNaC::pow(sx, 5) / 3 - u * sx * GiNaC::pow(1 - cx * cx, 2) / 3));
  EXPECT_TRUE(symbolic::is_zero(0.5 * GiNaC::pow(sx, 2) * GiNaC::pow(cy, 2) - 0.5 * (1 - cx * cx) * (1 - sy * sy)));
  EXPECT_FALSE(symbolic::is_zero(GiNaC::pow(sx, 4) * GiNaC::pow(sy, 3) - GiNaC::pow(cx, 4) * GiNaC::pow(sy, 3)));
}

TEST(Simplify, ValueDoesNotDependOnSymbolCreationOrder) {
  // GiNaC orders terms (and picks the sign of a sum inside a product) by hashes of symbol serial
  // numbers; simplify()'s value must not depend on that. The printed form is checked to be
  // identical in equations_test.cpp, where the canonical printer lives.
  const auto build = [](bool reversed, std::vector<GiNaC::symbol>& out) {
    std::vector<GiNaC::symbol> unrelated;
    for (int i = 0; i < 37; ++i) unrelated.emplace_back("unrelated");
    GiNaC::symbol a, b, x;
    if (reversed) {
      x = GiNaC::symbol("x");
      b = GiNaC::symbol("b");
      a = GiNaC::symbol("a");
    } else {
      a = GiNaC::symbol("a");
      b = GiNaC::symbol("b");
      x = GiNaC::symbol("x");
    }
    out = {a, b, x};
    return simplify((a - b) / (b - a * GiNaC::cos(x)) + GiNaC::tan(x) * a / (2 * b - 2 * x));
  };
  std::vector<GiNaC::symbol> first, second;
  const ex e1 = build(false, first);
  const ex e2 = build(true, second);
  const ex moved = e2.subs(GiNaC::lst{second[0] == first[0], second[1] == first[1], second[2] == first[2]});
  EXPECT_TRUE(symbolic::is_zero(e1 - moved));
  EXPECT_EQ(simplify(e1 - moved), 0);
}

// A square root of a quotient with a number on one side is split into roots of polynomials:
// sqrt(-1/P) is (-P)^(-1/2). GiNaC's normal() alone writes it as a root of a quotient beside the
// roots of P, and on such mixtures its gcd failed in some runs ("heur_gcd: not an integer
// polynomial": a tilted wheel's derivation, wheel_modes_test.cpp).
bool has_root_of_quotient(const ex& e) {
  if (GiNaC::is_a<GiNaC::power>(e) && !e.op(1).info(GiNaC::info_flags::integer) &&
      !e.op(0).denom().is_equal(1))
    return true;
  for (std::size_t i = 0; i < e.nops(); ++i)
    if (has_root_of_quotient(e.op(i))) return true;
  return false;
}

TEST(Simplify, ARootOfAQuotientIsSplitIntoRootsOfPolynomials) {
  const GiNaC::symbol x("x"), r("r");
  const ex P = -25 + 9 * GiNaC::pow(GiNaC::cos(x), 2);  // negative for every x
  for (const ex& e : {GiNaC::sqrt(-1 / P), GiNaC::pow(-1 / P, ex(-1) / 2) * r, GiNaC::sqrt(-P / 25) / r,
                      GiNaC::sqrt(-1 / P) * GiNaC::cos(x) + GiNaC::pow(-1 / P, ex(3) / 2)}) {
    const ex s = simplify(e);
    EXPECT_FALSE(has_root_of_quotient(s)) << e << " -> " << s;
    // The value is kept: at x = 0.3, r = 2, against the expression evaluated as written.
    const GiNaC::lst at{x == 0.3, r == 2};
    const double expected = GiNaC::ex_to<GiNaC::numeric>(e.subs(at).evalf()).to_double();
    const double value = GiNaC::ex_to<GiNaC::numeric>(s.subs(at).evalf()).to_double();
    EXPECT_NEAR(value, expected, 1e-14 * std::abs(expected)) << e << " -> " << s;
  }
  // With the same polynomial on both sides, the roots cancel.
  EXPECT_EQ(simplify(GiNaC::sqrt(x * x + 1) * GiNaC::sqrt(1 / (x * x + 1))), 1);
  EXPECT_EQ(simplify(GiNaC::sqrt(-1 / (-x * x - 1)) * GiNaC::pow(x * x + 1, ex(3) / 2)), simplify(x * x + 1));
  // A root of a quotient of two polynomials has no number to take the sign from: kept as it is.
  EXPECT_TRUE(has_root_of_quotient(simplify(GiNaC::sqrt((x + 2) / (x + 3)))));
}

// A kinetic energy written as a parameter times one long sum (m/2 * (x0'^2 + ... + x19'^2) + ...)
// is split into its terms before differentiation (derivation.cpp, terms_of): the terms must come
// out as the hand-derived ones, A = diag(m) with the coupling k between neighbours, G = 0 and
// Q = -dV/dq for V = m g/2 * (x0 + ... + x19)^2 (whose sum is a power, not a factor, and stays).
TEST(Derivation, AParameterTimesALongSumIsSplitIntoItsTerms) {
  constexpr int n = 20;
  SpecBuilder b("long_sum");
  std::string velocities, positions;
  for (int i = 0; i < n; ++i) {
    b.coordinate("x" + std::to_string(i));
    velocities += (i ? " + " : "") + ("x" + std::to_string(i) + "'^2");
    positions += (i ? " + " : "") + ("x" + std::to_string(i));
  }
  b.parameter("m", 1.5).parameter("k", 0.25).parameter("g", 9.81);
  b.kinetic_energy("m/2 * (" + velocities + ") + k * x0' * x1'");
  b.potential_energy("m*g/2 * (" + positions + ")^2");
  const Spec spec = b.build();
  const Derivation d = derive(spec);
  const SymbolTable& S = spec.symbols;
  const ex m = S.parameter("m"), k = S.parameter("k"), g = S.parameter("g");
  ex sum = 0;
  for (int i = 0; i < n; ++i) sum += S.coordinate(i);
  GiNaC::matrix A(n, n), Q(n, 1);
  for (int i = 0; i < n; ++i) {
    A(i, i) = m;
    Q(i, 0) = -m * g * sum;
  }
  A(0, 1) = A(1, 0) = k;
  expect_zero(d.A.sub(A), "A");
  expect_zero(d.G, "G");
  expect_zero(d.Q.sub(Q), "Q");
}

}  // namespace
}  // namespace nhdyn::symbolic
