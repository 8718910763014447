// Parameters as data (model/parameters.hpp): the GiNaC-free expression evaluator against values
// computed independently, derived parameters that follow their base ones, refusals by name
// (unknown, cyclic, subnormal, too large), and the built-in C++ models taking new values without
// being rebuilt: a sled set to m = 2 computes what a sled made with m = 2 computes, bit for bit.
#include "nhdyn/model/parameters.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <string>
#include <vector>

#include "nhdyn/core/error.hpp"
#include "nhdyn/model/appell.hpp"
#include "nhdyn/model/builtin.hpp"
#include "nhdyn/model/sled.hpp"

namespace nhdyn {
namespace {

std::string error_of(const auto& f) {
  try {
    f();
  } catch (const InputError& e) {
    return e.what();
  }
  return "(no InputError)";
}

bool contains(const std::string& text, const std::string& part) { return text.find(part) != std::string::npos; }

TEST(ParameterExpression, EvaluatesNumbersConstantsAndParameters) {
  const std::vector<Parameter> known{{"m", 2.0, "kg", ""}, {"a", 0.5, "m", ""}};
  EXPECT_EQ(calc_parameter_expression("pi/10", known), std::numbers::pi / 10);
  EXPECT_EQ(calc_parameter_expression("2/3", known), 2.0 / 3.0);
  EXPECT_EQ(calc_parameter_expression("2*m", known), 4.0);
  EXPECT_EQ(calc_parameter_expression(" -2^2 ", known), -4.0);  // ^ binds tighter than unary minus
  EXPECT_EQ(calc_parameter_expression("2^3^2", known), 512.0);  // right associative
  EXPECT_EQ(calc_parameter_expression("2**3", known), 8.0);
  EXPECT_EQ(calc_parameter_expression("m*a^2 + (1 - a)/m", known), 2.0 * 0.25 + 0.5 / 2.0);
  EXPECT_EQ(calc_parameter_expression("sqrt(m) * cos(pi/3)", known), std::sqrt(2.0) * std::cos(std::numbers::pi / 3));
  EXPECT_EQ(calc_parameter_expression("atan2(1, m)", known), std::atan2(1.0, 2.0));
  EXPECT_EQ(calc_parameter_expression("e", known), std::numbers::e);
  EXPECT_EQ(calc_parameter_expression("1e-3", known), 1e-3);
  // A parameter named e hides the constant.
  EXPECT_EQ(calc_parameter_expression("e", {{"e", 0.3, "", ""}}), 0.3);
}

TEST(ParameterExpression, RefusesWhatItCannotRead) {
  const std::vector<Parameter> known{{"mass", 2.0, "kg", ""}};
  const std::string unknown = error_of([&] { calc_parameter_expression("2*mas", known); });
  EXPECT_TRUE(contains(unknown, "'mas'")) << unknown;
  EXPECT_TRUE(contains(unknown, "did you mean 'mass'")) << unknown;
  EXPECT_TRUE(contains(error_of([&] { calc_parameter_expression("2*(mass", known); }), "')' is missing"));
  EXPECT_TRUE(contains(error_of([&] { calc_parameter_expression("2 mass", known); }), "column 3"));
  EXPECT_TRUE(contains(error_of([&] { calc_parameter_expression("", known); }), "empty"));
  EXPECT_TRUE(contains(error_of([&] { calc_parameter_expression("sine(1)", known); }), "'sine' is not a function"));
  EXPECT_TRUE(contains(error_of([&] { calc_parameter_expression("1e-320", known); }), "subnormal"));
  EXPECT_TRUE(contains(error_of([&] { calc_parameter_expression("1e400", known); }), "too large"));
}

// 0^0 was 1 and 1/0 "too large, rescale the units": an undefined or infinite value of finite
// operands is named where it happens, as in the model file's other expressions.
TEST(ParameterExpression, UndefinedAndInfiniteOperationsAreNamed) {
  const std::vector<Parameter> known{{"m", 2.0, "kg", ""}};
  for (const char* text : {"0^0", "(1-1)^0", "(m-m)**0", "0^(m-2)"})
    EXPECT_TRUE(contains(error_of([&] { calc_parameter_expression(text, known); }), "contains 0^0, which is undefined"))
        << text;
  EXPECT_TRUE(contains(error_of([&] { calc_parameter_expression("1/0", known); }), "it divides by zero (column 3)"));
  EXPECT_TRUE(contains(error_of([&] { calc_parameter_expression("m/(m-2)", known); }), "it divides by zero"));
  EXPECT_TRUE(contains(error_of([&] { calc_parameter_expression("0/0", known); }), "it divides by zero"));
  EXPECT_TRUE(contains(error_of([&] { calc_parameter_expression("0^(-1)", known); }), "negative power divides by zero"));
  EXPECT_TRUE(contains(error_of([&] { calc_parameter_expression("log(0)", known); }), "log(0) is infinite"));
  EXPECT_TRUE(contains(error_of([&] { calc_parameter_expression("exp(1000)", known); }), "exp(1000) is infinite"));
  EXPECT_TRUE(contains(error_of([&] { calc_parameter_expression("1e300/1e-300", known); }), "a quotient overflows"));
  EXPECT_TRUE(contains(error_of([&] { calc_parameter_expression("10^400", known); }), "a power overflows"));
  // Their neighbours that have a value keep it; names are still collected from any text.
  EXPECT_EQ(calc_parameter_expression("0^2", known), 0.0);
  EXPECT_EQ(calc_parameter_expression("m^0", known), 1.0);
  EXPECT_EQ(calc_parameter_expression("0/m", known), 0.0);
  EXPECT_EQ(calc_parameter_expression("log(1)", known), 0.0);
  EXPECT_EQ(calc_expression_names("m/(m-m) + 0^0", known), std::vector<std::string>{"m"});
}

TEST(ParameterValue, SubnormalAndTooLargeAreNamed) {
  EXPECT_TRUE(contains(error_of([] { check_parameter_value("m", 1e-320); }), "subnormal"));
  EXPECT_TRUE(contains(error_of([] { check_parameter_value("k", 1e308); }), "too large"));
  EXPECT_TRUE(contains(error_of([] { check_parameter_value("k", -1e200); }), "too large"));
  EXPECT_TRUE(contains(error_of([] { check_parameter_value("k", NAN); }), "NaN"));
  EXPECT_EQ(error_of([] { check_parameter_value("k", 0.0); }), "(no InputError)");
  EXPECT_EQ(error_of([] { check_parameter_value("k", 1e150); }), "(no InputError)");
  EXPECT_EQ(error_of([] { check_parameter_value("k", 3e-300); }), "(no InputError)");
}

TEST(DerivedParameters, FollowTheirBaseParametersInAnyOrder) {
  // k uses w, which is defined after it and uses m.
  std::vector<Parameter> p{{"k", 0.0, "N/m", "m*w^2"}, {"m", 2.0, "kg", ""}, {"w", 0.0, "rad/s", "3*m"}};
  update_parameters(p, "test");
  EXPECT_EQ(p[2].value, 6.0);
  EXPECT_EQ(p[0].value, 72.0);
  set_parameter_expression(p, "m", "1/2", "test");
  EXPECT_EQ(p[1].value, 0.5);
  EXPECT_TRUE(p[1].expression.empty());  // a constant expression makes a base parameter
  EXPECT_EQ(p[2].value, 1.5);
  EXPECT_EQ(p[0].value, 0.5 * 1.5 * 1.5);
  // A derived parameter set to a number stops following.
  set_parameter_expression(p, "w", "10", "test");
  EXPECT_TRUE(p[2].expression.empty());
  EXPECT_EQ(p[0].value, 50.0);
  // And one set to an expression of others starts.
  set_parameter_expression(p, "w", "4*m", "test");
  EXPECT_EQ(p[2].expression, "4*m");
  EXPECT_EQ(p[0].value, 0.5 * 2.0 * 2.0);
}

TEST(DerivedParameters, CyclesAndUnknownNamesAreRefusedByName) {
  std::vector<Parameter> p{{"m", 2.0, "kg", ""}, {"k", 0.0, "N/m", "4*m"}};
  update_parameters(p, "spring");
  const std::vector<Parameter> before = p;
  const std::string cycle = error_of([&] { set_parameter_expression(p, "m", "k/4", "spring"); });
  EXPECT_TRUE(contains(cycle, "cycle")) << cycle;
  EXPECT_TRUE(contains(cycle, "m = \"k/4\"")) << cycle;
  EXPECT_TRUE(contains(cycle, "k = \"4*m\"")) << cycle;
  EXPECT_EQ(p[0].value, before[0].value);  // unchanged after a refusal
  EXPECT_TRUE(p[0].expression.empty());
  const std::string self = error_of([&] { set_parameter_expression(p, "m", "2*m", "spring"); });
  EXPECT_TRUE(contains(self, "cycle")) << self;
  std::vector<Parameter> bad{{"m", 2.0, "kg", ""}, {"k", 0.0, "N/m", "4*mm"}};
  const std::string unknown = error_of([&] { update_parameters(bad, "spring"); });
  EXPECT_TRUE(contains(unknown, "parameter 'k'")) << unknown;
  EXPECT_TRUE(contains(unknown, "'mm'")) << unknown;
  EXPECT_TRUE(contains(unknown, "did you mean 'm'")) << unknown;
  const std::string name = error_of([&] { set_parameter_expression(p, "kk", "1", "spring"); });
  EXPECT_TRUE(contains(name, "no parameter 'kk'")) << name;
  EXPECT_TRUE(contains(name, "did you mean 'k'")) << name;
}

TEST(ParameterSets, ParseNameEqualsExpression) {
  std::vector<Parameter> p{{"m", 2.0, "kg", ""}, {"lambda", 0.0, "rad", ""}};
  apply_parameter_sets(p, {"lambda=pi/10", "m = 2/3"}, "test");
  EXPECT_EQ(p[1].value, std::numbers::pi / 10);
  EXPECT_EQ(p[0].value, 2.0 / 3.0);
  EXPECT_TRUE(contains(error_of([&] { apply_parameter_sets(p, {"m"}, "test"); }), "NAME=VALUE"));
  EXPECT_TRUE(contains(error_of([&] { apply_parameter_sets(p, {"m=1e-320"}, "test"); }), "subnormal"));
  EXPECT_TRUE(contains(error_of([&] { apply_parameter_sets(p, {"m=1e308"}, "test"); }), "too large"));
}

struct Terms {
  std::vector<double> A, Q, G, b, b0, D;
  double energy = 0.0;
};

Terms terms_of(const Model& model, const double* q, const double* v) {
  const std::size_t n = static_cast<std::size_t>(model.n()), s = static_cast<std::size_t>(model.s());
  Terms t;
  t.A.resize(n * n);
  t.Q.resize(n);
  t.G.resize(n);
  t.b.resize(s * n);
  t.b0.resize(s);
  t.D.resize((n - s) * n);
  std::vector<double> scratch(model.evaluator->scratch_size() + 1);
  model.evaluator->terms(0.3, q, v, scratch.data(), TermsOut{t.A.data(), t.Q.data(), t.G.data(), t.b.data(), t.b0.data()});
  model.evaluator->complement(0.3, q, v, scratch.data(), t.D.data());
  t.energy = model.evaluator->energy(0.3, q, v, scratch.data());
  return t;
}

void expect_same_terms(const Model& a, const Model& b) {
  const double q[3] = {0.2, -0.4, 0.7}, v[3] = {1.1, -0.3, 0.9};
  const Terms x = terms_of(a, q, v), y = terms_of(b, q, v);
  EXPECT_EQ(x.A, y.A);
  EXPECT_EQ(x.Q, y.Q);
  EXPECT_EQ(x.G, y.G);
  EXPECT_EQ(x.b, y.b);
  EXPECT_EQ(x.b0, y.b0);
  EXPECT_EQ(x.D, y.D);
  EXPECT_EQ(x.energy, y.energy);
  EXPECT_EQ(a.q0, b.q0);
  EXPECT_EQ(a.v0, b.v0);
}

TEST(BuiltinParameters, SledSetAtRunTimeComputesAsASledMadeWithTheValues) {
  for (const SledVariant variant : {SledVariant::centre_of_mass, SledVariant::paper}) {
    Model model = make_sled_model(variant);
    const Model copy = model;  // shares the evaluator until one of them sets a parameter
    set_parameter(model, "m", 2.0);
    set_parameter_expression(model, "alpha", "pi/10");
    SledParameters p;
    p.m = 2.0;
    p.alpha = std::numbers::pi / 10;
    expect_same_terms(model, make_sled_model(variant, p));
    EXPECT_EQ(get_parameter(model, "m"), 2.0);
    EXPECT_EQ(get_parameter(copy, "m"), 1.0);  // the copy keeps its values and evaluator
    expect_same_terms(copy, make_sled_model(variant));
  }
}

TEST(BuiltinParameters, SledRefusesValuesThatBreakItAndStaysUnchanged) {
  Model model = make_builtin_model("sled");
  const std::string message = error_of([&] { set_parameter(model, "a", 0.9); });
  EXPECT_TRUE(contains(message, "rho > a")) << message;
  EXPECT_EQ(get_parameter(model, "a"), 0.5);
  const std::string unknown = error_of([&] { set_parameter(model, "rh0", 1.0); });
  EXPECT_TRUE(contains(unknown, "no parameter 'rh0'")) << unknown;
  EXPECT_TRUE(contains(unknown, "did you mean 'rho'")) << unknown;
}

TEST(BuiltinParameters, AppellInitialStateAndSolutionFollowA) {
  Model model = make_appell_model();
  set_parameter(model, "a", 0.8);
  AppellParameters p;
  p.a = 0.8;
  const Model made = make_appell_model(p);
  expect_same_terms(model, made);
  EXPECT_EQ(model.v0[2], 0.8 * std::sqrt(1.25));
  std::vector<double> x(9), y(9), scratch(1);
  model.evaluator->solution(1.5, scratch.data(), x.data());
  made.evaluator->solution(1.5, scratch.data(), y.data());
  EXPECT_EQ(x, y);
}

TEST(BuiltinParameters, ApplySetsTakesExpressions) {
  Model model = make_builtin_model("sled-paper");
  apply_parameter_sets(model, {"g=9.80665", "alpha=pi/12", "m=2*rho"});
  EXPECT_EQ(get_parameter(model, "alpha"), std::numbers::pi / 12);
  EXPECT_EQ(get_parameter(model, "m"), 1.4);
  set_parameter(model, "rho", 0.8);  // m = 2*rho follows
  EXPECT_EQ(get_parameter(model, "m"), 1.6);
  SledParameters p;
  p.g = 9.80665;
  p.alpha = std::numbers::pi / 12;
  p.rho = 0.8;
  p.m = 1.6;
  expect_same_terms(model, make_sled_model(SledVariant::paper, p));
}

}  // namespace
}  // namespace nhdyn
