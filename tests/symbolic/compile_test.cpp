// The compiler from symbols to programs: the sled and Appell's particle, built by hand as Spec and
// Derivation (tests/codegen/hand_built_specs.hpp), compile to Models whose terms, complement,
// residuals and energy equal the hand-written models' at random states; common subexpressions are
// computed once; what cannot be compiled is reported by name.
#include "nhdyn/symbolic/compile.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <random>
#include <string>
#include <vector>

#include "codegen/hand_built_specs.hpp"
#include "nhdyn/core/error.hpp"
#include "nhdyn/model/appell.hpp"
#include "nhdyn/model/sled.hpp"
#include "nhdyn/model/tape.hpp"
#include "nhdyn/symbolic/spec_builder.hpp"

namespace nhdyn::symbolic {
namespace {

using testing::HandBuilt;
using testing::make_hand_built_appell;
using testing::make_hand_built_sled;

struct Evaluated {
  std::vector<double> A, Q, G, b, b0, D, f;
  double energy = 0.0;
};

Evaluated evaluate(const Model& model, double t, const double* q, const double* v) {
  const int n = model.n(), s = model.s();
  Evaluated e;
  e.A.resize(static_cast<std::size_t>(n * n));
  e.Q.resize(static_cast<std::size_t>(n));
  e.G.resize(static_cast<std::size_t>(n));
  e.b.resize(static_cast<std::size_t>(s * n));
  e.b0.resize(static_cast<std::size_t>(s));
  e.D.resize(static_cast<std::size_t>((n - s) * n));
  e.f.resize(static_cast<std::size_t>(model.velocity_constraints()));
  std::vector<double> scratch(model.evaluator->scratch_size());
  model.evaluator->terms(t, q, v, scratch.data(), TermsOut{e.A.data(), e.Q.data(), e.G.data(), e.b.data(), e.b0.data()});
  model.evaluator->complement(t, q, v, scratch.data(), e.D.data());
  model.evaluator->velocity_residual(t, q, v, scratch.data(), e.f.data());
  e.energy = model.evaluator->energy(t, q, v, scratch.data());
  return e;
}

void expect_near(const std::vector<double>& got, const std::vector<double>& expected, const char* what,
                 double tolerance = 1e-13) {
  ASSERT_EQ(got.size(), expected.size()) << what;
  for (std::size_t i = 0; i < got.size(); ++i)
    EXPECT_NEAR(got[i], expected[i], tolerance * std::max(1.0, std::abs(expected[i]))) << what << "[" << i << "]";
}

const TapeEvaluator& programs_of(const Model& model) {
  return dynamic_cast<const TapeEvaluator&>(*model.evaluator);
}

void expect_same_description(const Model& compiled, const Model& hand) {
  EXPECT_EQ(compiled.name, hand.name);
  EXPECT_EQ(compiled.description, hand.description);
  EXPECT_EQ(compiled.coordinates, hand.coordinates);
  ASSERT_EQ(compiled.s(), hand.s());
  for (int i = 0; i < hand.s(); ++i) {
    EXPECT_EQ(compiled.constraints[i].name, hand.constraints[i].name);
    EXPECT_EQ(compiled.constraints[i].level, hand.constraints[i].level);
    EXPECT_EQ(compiled.constraints[i].expression, hand.constraints[i].expression);
  }
  ASSERT_EQ(compiled.parameters.size(), hand.parameters.size());
  for (std::size_t i = 0; i < hand.parameters.size(); ++i) {
    EXPECT_EQ(compiled.parameters[i].name, hand.parameters[i].name);
    EXPECT_EQ(compiled.parameters[i].value, hand.parameters[i].value);
    EXPECT_EQ(compiled.parameters[i].unit, hand.parameters[i].unit);
  }
  EXPECT_EQ(compiled.t0, hand.t0);
  for (int i = 0; i < hand.n(); ++i) {
    EXPECT_NEAR(compiled.q0[i], hand.q0[i], 1e-15) << "q0 " << i;
    EXPECT_NEAR(compiled.v0[i], hand.v0[i], 1e-15) << "v0 " << i;
  }
  EXPECT_EQ(compiled.defaults.t_end, hand.defaults.t_end);
  EXPECT_EQ(compiled.defaults.output_step, hand.defaults.output_step);
  ASSERT_TRUE(compiled.path.has_value());
  EXPECT_EQ(compiled.path->x, hand.path->x);
  EXPECT_EQ(compiled.path->y, hand.path->y);
  EXPECT_TRUE(compiled.evaluator->has_complement());
  EXPECT_TRUE(compiled.evaluator->has_energy());
}

TEST(Compile, SledEqualsTheHandWrittenModel) {
  SledParameters p;
  p.m = 2.3;
  p.a = 0.4;
  p.rho = 0.7;
  p.alpha = 0.35;
  for (const SledParameters& parameters : {SledParameters{}, p}) {
    const HandBuilt built = make_hand_built_sled(parameters);
    const Model compiled = compile_model(built.spec, built.derivation);
    const Model hand = make_sled_model(SledVariant::centre_of_mass, parameters);
    expect_same_description(compiled, hand);
    std::mt19937 random(7);
    std::uniform_real_distribution<double> uniform(-3.0, 3.0);
    for (int trial = 0; trial < 100; ++trial) {
      const double t = uniform(random);
      const double q[3] = {uniform(random), uniform(random), uniform(random)};
      const double v[3] = {uniform(random), uniform(random), uniform(random)};
      const Evaluated c = evaluate(compiled, t, q, v), h = evaluate(hand, t, q, v);
      expect_near(c.A, h.A, "A");
      expect_near(c.Q, h.Q, "Q");
      expect_near(c.G, h.G, "G");
      expect_near(c.b, h.b, "b");
      expect_near(c.b0, h.b0, "b0");
      expect_near(c.D, h.D, "D");
      expect_near(c.f, h.f, "f");
      EXPECT_NEAR(c.energy, h.energy, 1e-13 * std::max(1.0, std::abs(h.energy)));
    }
  }
}

TEST(Compile, AppellEqualsTheHandWrittenModelUpToTheScaleOfItsConstraintRow) {
  AppellParameters p;
  p.m = 1.7;
  p.a = 0.6;
  for (const AppellParameters& parameters : {AppellParameters{}, p}) {
    const HandBuilt built = make_hand_built_appell(parameters);
    const Model compiled = compile_model(built.spec, built.derivation);
    const Model hand = make_appell_model(parameters);
    expect_same_description(compiled, hand);
    std::mt19937 random(11);
    std::uniform_real_distribution<double> uniform(-3.0, 3.0);
    for (int trial = 0; trial < 100; ++trial) {
      const double t = uniform(random);
      const double q[3] = {uniform(random), uniform(random), uniform(random)};
      double v[3] = {uniform(random), uniform(random), uniform(random)};
      if (std::abs(v[2]) < 0.1) v[2] = 0.5;  // D and the hand-written b divide by z'
      const Evaluated c = evaluate(compiled, t, q, v), h = evaluate(hand, t, q, v);
      expect_near(c.A, h.A, "A");
      expect_near(c.Q, h.Q, "Q");
      expect_near(c.G, h.G, "G");
      // The hand-written row is df/dq' / (2 z'), its b0 zero.
      std::vector<double> b = c.b;
      for (double& x : b) x /= 2.0 * v[2];
      expect_near(b, h.b, "b / (2 z')");
      expect_near(c.b0, h.b0, "b0");
      expect_near(c.D, h.D, "D");
      expect_near(c.f, h.f, "f");
      EXPECT_NEAR(c.energy, h.energy, 1e-13 * std::max(1.0, std::abs(h.energy)));
    }
  }
}

// The whole pipeline: SpecBuilder, derive(), compile_model(spec), against the hand-written models.
TEST(Compile, BuiltAndDerivedModelsEqualTheHandWrittenOnes) {
  const SledParameters sled;
  SpecBuilder s("sled");
  s.description("Sled on an inclined plane, centre-of-mass potential");
  s.coordinate("x").coordinate("y").coordinate("phi");
  s.parameter("m", sled.m, "kg").parameter("a", sled.a, "m").parameter("rho", sled.rho, "m");
  s.parameter("alpha", sled.alpha, "rad").parameter("g", sled.g, "m/s^2");
  s.kinetic_energy("m/2*(x'^2 + y'^2) + m*a*phi'*(cos(phi)*y' - sin(phi)*x') + m*rho^2/2*phi'^2");
  s.potential_energy("-m*g*sin(alpha)*(x + a*cos(phi))");
  s.constraint("blade", ConstraintLevel::velocity, "-sin(phi)*x' + cos(phi)*y'");
  s.complement({{"cos(phi)", "sin(phi)", "0"}, {"0", "0", "1"}});
  s.initial("x", "0", "1").initial("y", "0", "0").initial("phi", "0", "1");
  s.path("x", "y");

  const AppellParameters appell;
  SpecBuilder a("appell");
  a.coordinate("x").coordinate("y").coordinate("z");
  a.parameter("m", appell.m, "kg").parameter("g", appell.g, "m/s^2").parameter("a", appell.a);
  a.kinetic_energy("m/2*(x'^2 + y'^2 + z'^2)");
  a.potential_energy("-m*g*z");
  a.constraint("appell", ConstraintLevel::velocity, "z'^2 - a^2*(x'^2 + y'^2)");
  a.complement({{"1", "0", "a^2*x'/z'"}, {"0", "1", "a^2*y'/z'"}});

  const Model models[2][2] = {{compile_model(s.build()), make_sled_model()},
                              {compile_model(a.build()), make_appell_model()}};
  std::mt19937 random(5);
  std::uniform_real_distribution<double> uniform(-3.0, 3.0);
  for (const auto& [compiled, hand] : models) {
    EXPECT_EQ(compiled.coordinates, hand.coordinates);
    for (int trial = 0; trial < 50; ++trial) {
      const double q[3] = {uniform(random), uniform(random), uniform(random)};
      double v[3] = {uniform(random), uniform(random), uniform(random)};
      if (std::abs(v[2]) < 0.1) v[2] = 0.5;
      const Evaluated c = evaluate(compiled, 0.0, q, v), h = evaluate(hand, 0.0, q, v);
      expect_near(c.A, h.A, "A");
      expect_near(c.Q, h.Q, "Q");
      expect_near(c.G, h.G, "G");
      // Rows of b, b0 and the residual may differ from the hand-written ones by a factor (Appell's
      // hand-written row is df/dq' / (2 z')): compare b0 and f scaled like b's last nonzero entry.
      const double scale = c.b[2] != 0.0 ? c.b[2] / h.b[2] : c.b[1] / h.b[1];
      std::vector<double> b = c.b, b0 = c.b0;
      for (double& x : b) x /= scale;
      for (double& x : b0) x /= scale;
      expect_near(b, h.b, "b");
      expect_near(b0, h.b0, "b0");
      expect_near(c.D, h.D, "D");
      expect_near(c.f, h.f, "f");
      EXPECT_NEAR(c.energy, h.energy, 1e-13 * std::max(1.0, std::abs(h.energy)));
    }
  }
}

TEST(Compile, CommonSubexpressionsAreComputedOnce) {
  const HandBuilt built = make_hand_built_sled();
  const Model model = compile_model(built.spec, built.derivation);
  const Tape& terms = programs_of(model).tapes().terms;
  // sin(phi) occurs in A twice, Q, G, b and b0; cos(phi) in A twice, G, b and b0: each once in the
  // program, and the two fused. (The program also computes sin(alpha), of a parameter: the
  // evaluator folds it once per parameter change, the parameter stage.)
  int of_phi = 0;
  for (const Instruction& in : terms.code())
    if ((in.op == Op::sin || in.op == Op::cos || in.op == Op::sincos) && in.a == terms.coordinate_register(2))
      of_phi += in.op == Op::sincos ? 2 : 1;
  EXPECT_EQ(of_phi, 2) << terms.describe();
  EXPECT_EQ(terms.count(Op::sincos), 1);
  // -m a sin(phi), written twice in A, is one instruction; constant entries cost none.
  const std::vector<Output>& out = terms.output_list();
  EXPECT_EQ(out[2].reg, out[6].reg);  // A(phi, x) = A(x, phi)
  EXPECT_EQ(out[5].reg, out[7].reg);  // A(phi, y) = A(y, phi)
  EXPECT_GE(out[2].reg, 0);
  EXPECT_LT(out[1].reg, 0);  // A(y, x) = 0
  EXPECT_EQ(out[1].value, 0.0);
  // What runs per call, the parameters folded: 13 operations when the values were literals in the
  // program; a parameter coefficient of a state product, (c p) (a b) + acc, is one mulk_muladd
  // step as k (a b) + acc was (model/tape.hpp), and terms differing only in their parameters
  // are one term (16 without either).
  EXPECT_LE(programs_of(model).terms_operations(), 14) << terms.describe();
  // The complement and residuals have their own sin and cos.
  EXPECT_EQ(programs_of(model).tapes().complement->count(Op::sincos), 1);
}

TEST(Compile, PowersQuotientsAndFunctions) {
  // One coordinate x, a parameter c = 0.5: terms written so that every translation rule runs.
  Spec spec;
  spec.name = "kitchen-sink";
  testing::add_coordinate(spec, "x");
  testing::add_parameter(spec, "c", 0.5, "");
  const GiNaC::ex x = spec.symbols.coordinate(0), v = spec.symbols.velocity(0), t = spec.symbols.time();
  const GiNaC::ex c = spec.symbols.parameter("c");
  const double X = 1.3, V = -0.7, T = 0.4, C = 0.5;
  const std::vector<std::pair<GiNaC::ex, double>> cases{
      {GiNaC::pow(x, 2) + 3 * GiNaC::pow(x, -2) - GiNaC::pow(x, 7), X * X + 3 / (X * X) - std::pow(X, 7)},
      {GiNaC::sqrt(x) + 1 / GiNaC::sqrt(x) + GiNaC::pow(x, GiNaC::numeric(3, 2)) + GiNaC::pow(x, GiNaC::numeric(-5, 2)),
       std::sqrt(X) + 1 / std::sqrt(X) + std::pow(X, 1.5) + std::pow(X, -2.5)},
      {GiNaC::pow(x, GiNaC::numeric(1, 3)) + GiNaC::pow(x, v) + GiNaC::pow(x, c), std::cbrt(X) + std::pow(X, V) + std::pow(X, C)},
      {2 * x * v / (t + 1) - c * v / (x * x * t), 2 * X * V / (T + 1) - C * V / (X * X * T)},
      {GiNaC::tan(x) + GiNaC::exp(v) + GiNaC::log(x) + GiNaC::abs(v) + GiNaC::asin(c) + GiNaC::acos(c * x / 2) +
           GiNaC::atan(v),
       std::tan(X) + std::exp(V) + std::log(X) + std::abs(V) + std::asin(C) + std::acos(C * X / 2) + std::atan(V)},
      {GiNaC::atan2(v, x) + GiNaC::sinh(x) + GiNaC::cosh(v) + GiNaC::tanh(x * v) + GiNaC::Pi * x,
       std::atan2(V, X) + std::sinh(X) + std::cosh(V) + std::tanh(X * V) + std::numbers::pi * X},
      {GiNaC::diff(GiNaC::abs(x * v), spec.symbols.coordinate(0)), V * X * V / std::abs(X * V)},  // brings in conjugate()
      {1 - x, 1 - X},
      {-x * v - 3, -X * V - 3},
      {GiNaC::ex(7), 7.0},
  };
  spec.coordinates = {"x"};
  spec.kinetic_energy = v * v / 2;
  Derivation d;
  d.A = GiNaC::matrix{{1}};
  d.Q = GiNaC::matrix{{0}};
  d.G = GiNaC::matrix{{0}};
  d.b = GiNaC::matrix(0, 1);
  d.b0 = GiNaC::matrix(0, 1);
  for (const auto& [e, expected] : cases) {
    d.Q = GiNaC::matrix{{e}};
    d.energy = e;
    const Model model = compile_model(spec, d);
    const double q[1] = {X}, vv[1] = {V};
    const Evaluated got = evaluate(model, T, q, vv);
    EXPECT_NEAR(got.Q[0], expected, 1e-14 * std::max(1.0, std::abs(expected))) << e;
    EXPECT_EQ(got.energy, got.Q[0]) << e;
  }
}

template <class F>
std::string model_error(F f) {
  try {
    f();
  } catch (const ModelError& e) {
    return e.what();
  }
  return "(no ModelError)";
}

TEST(Compile, UnknownFunctionIsNamed) {
  HandBuilt built = make_hand_built_sled();
  built.derivation.Q(2, 0) = GiNaC::lgamma(built.spec.symbols.coordinate(2));
  const std::string message = model_error([&] { compile_model(built.spec, built.derivation); });
  EXPECT_NE(message.find("'lgamma'"), std::string::npos) << message;
  EXPECT_NE(message.find("Q(phi)"), std::string::npos) << message;
}

TEST(Compile, LeftoverSymbolIsNamed) {
  // A parameter in the symbol table without a value, and a symbol from outside the table.
  HandBuilt built = make_hand_built_sled();
  built.spec.symbols.add_parameter("k");
  built.derivation.G(2, 0) = built.spec.symbols.parameter("k") * built.spec.symbols.velocity(2);
  std::string message = model_error([&] { compile_model(built.spec, built.derivation); });
  EXPECT_NE(message.find("'k'"), std::string::npos) << message;
  EXPECT_NE(message.find("G(phi)"), std::string::npos) << message;

  built = make_hand_built_sled();
  built.derivation.A(2, 2) = GiNaC::symbol("J");
  message = model_error([&] { compile_model(built.spec, built.derivation); });
  EXPECT_NE(message.find("'J'"), std::string::npos) << message;
  EXPECT_NE(message.find("A(phi, phi)"), std::string::npos) << message;

  built = make_hand_built_sled();
  built.derivation.b0(0, 0) = built.spec.symbols.acceleration(0);
  message = model_error([&] { compile_model(built.spec, built.derivation); });
  EXPECT_NE(message.find("x''"), std::string::npos) << message;
}

TEST(Compile, InitialValuesMustBeNumbers) {
  HandBuilt built = make_hand_built_sled();
  built.spec.v0[2] = built.spec.symbols.coordinate(0);
  const std::string message = model_error([&] { compile_model(built.spec, built.derivation); });
  EXPECT_NE(message.find("phi'"), std::string::npos) << message;
  EXPECT_NE(message.find("not a real number"), std::string::npos) << message;
}

TEST(Compile, ShapesAndPathAreChecked) {
  HandBuilt built = make_hand_built_sled();
  built.derivation.f.clear();
  EXPECT_THROW(compile_model(built.spec, built.derivation), ModelError);
  built = make_hand_built_sled();
  built.derivation.Q = GiNaC::matrix(2, 1);
  EXPECT_THROW(compile_model(built.spec, built.derivation), ModelError);
  built = make_hand_built_sled();
  built.spec.path = std::make_pair(std::string("x"), std::string("w"));
  EXPECT_NE(model_error([&] { compile_model(built.spec, built.derivation); }).find("'w'"), std::string::npos);
}

// The instructions of `program` that read t, q or q' (directly or through another): what runs at
// every call once the parameter stage is folded.
int state_instructions(const Tape& program) {
  std::vector<char> state(static_cast<std::size_t>(program.registers()), 0);
  for (int r = 0; r < program.inputs(); ++r) state[static_cast<std::size_t>(r)] = 1;
  int count = 0;
  const std::vector<Instruction>& code = program.code();
  for (std::size_t i = 0; i < code.size(); ++i) {
    const Instruction& in = code[i];
    const std::size_t reg = static_cast<std::size_t>(program.inputs()) + i;
    if (in.op == Op::nop) {  // the cosine of a sincos
      state[reg] = state[reg - 1];
      continue;
    }
    const int operands[3] = {in.a, in.b, in.c};
    bool reads = false;
    for (int k = 0; k < operand_count(in.op); ++k) reads = reads || state[static_cast<std::size_t>(operands[k])];
    state[reg] = reads ? 1 : 0;
    count += reads ? 1 : 0;
  }
  return count;
}

TEST(Compile, TermsThatDifferOnlyInTheirParametersAreOneTerm) {
  // m1 s + m2 s + m1 m2 s + r s + 3 s with s = sin(x) cos(x) x' is (m1 + m2 + m1 m2 + r + 3) s: the
  // coefficient in the parameter stage, s and its product with the coefficient per call (the sum
  // of the five terms would cost five multiplications and four additions per call).
  Spec spec;
  spec.name = "merged";
  testing::add_coordinate(spec, "x");
  testing::add_parameter(spec, "m1", 2.0, "");
  testing::add_parameter(spec, "m2", 3.0, "");
  testing::add_parameter(spec, "r", 0.25, "");
  const GiNaC::ex x = spec.symbols.coordinate(0), v = spec.symbols.velocity(0);
  const GiNaC::ex m1 = spec.symbols.parameter("m1"), m2 = spec.symbols.parameter("m2"), r = spec.symbols.parameter("r");
  const GiNaC::ex s = GiNaC::sin(x) * GiNaC::cos(x) * v;
  const GiNaC::ex e = m1 * s + m2 * s + m1 * m2 * s + r * s + 3 * s + m1 * r + m2 + 4 * x;
  const Tape program = compile_expression(spec, e, "merged");
  // sincos, sin cos, times x', times the coefficient; 4 x plus that; plus m1 r + m2 (one
  // parameter-stage number).
  EXPECT_EQ(state_instructions(program), 6) << program.describe();
  for (const std::vector<double>& values : {std::vector<double>{2.0, 3.0, 0.25}, std::vector<double>{-0.7, 5.5, 1e-3}}) {
    const Tape bound = program.bind(values.data(), values.size());
    const double M1 = values[0], M2 = values[1], R = values[2];
    for (const double X : {0.3, -2.1}) {
      const double V = 1.7 - X;
      std::vector<double> registers(static_cast<std::size_t>(bound.registers()));
      double got = 0.0;
      bound.run(0.0, &X, &V, registers.data(), &got);
      const double expected = (M1 + M2 + M1 * M2 + R + 3) * std::sin(X) * std::cos(X) * V + M1 * R + M2 + 4 * X;
      EXPECT_NEAR(got, expected, 1e-14 * (1.0 + std::abs(expected))) << "m1 = " << M1 << ", x = " << X;
    }
  }
}

TEST(Compile, ParameterValuesAreTakenWhenCompiling) {
  HandBuilt built = make_hand_built_sled();
  built.spec.set_parameter("m", 4.0);
  const Model model = compile_model(built.spec, built.derivation);
  const double q[3] = {0.0, 0.0, 0.3}, v[3] = {1.0, 0.0, 1.0};
  EXPECT_EQ(evaluate(model, 0.0, q, v).A[0], 4.0);
  EXPECT_EQ(model.parameters[0].value, 4.0);
}

TEST(Compile, ProgramsDoNotDependOnSymbolCreationOrder) {
  // GiNaC orders terms by hashes of symbol serial numbers; the compiler must not.
  const HandBuilt first = make_hand_built_sled();
  std::vector<GiNaC::symbol> noise;
  for (int i = 0; i < 17; ++i) noise.emplace_back("noise");
  const HandBuilt second = make_hand_built_sled();
  const Model a = compile_model(first.spec, first.derivation), b = compile_model(second.spec, second.derivation);
  EXPECT_EQ(programs_of(a).tapes().terms.describe(), programs_of(b).tapes().terms.describe());
}

}  // namespace
}  // namespace nhdyn::symbolic
