// The signs the equations printer chooses on its own (symbolic/equations.cpp, EquationPrinter):
// the sign of a sum that is a factor or the base of an integer power, the merging of terms that
// print alike and of like factors, cos(-x) = cos(x) and sin(-x)^n = (-1)^n sin(x)^n, the tangents
// folded back, complex coefficients. Each printed expression is read back into GiNaC and must
// equal the expression at a generic point. Large entries (more than kSimplifyLimit nodes, the
// bicycle's) are printed as GiNaC holds them, unsimplified: the cases below are built with
// hold() in exactly the structure under test and padded past the limit with the terms w^k, which
// are then left out of the printed text; the rest must read back to the case alone.
#include <gtest/gtest.h>

#include <complex>
#include <functional>
#include <set>
#include <sstream>
#include <string>
#include <vector>

#include "nhdyn/symbolic/derivation.hpp"
#include "nhdyn/symbolic/equations.hpp"
#include "nhdyn/symbolic/simplify.hpp"
#include "nhdyn/symbolic/spec_builder.hpp"
#include "support/equation_reader.hpp"
#include "support/text.hpp"

namespace nhdyn::symbolic {
namespace {

using GiNaC::ex;

// The terms of a printed sum at its top level, each with its sign in front ("+ " or "- ").
std::vector<std::string> signs_terms(const std::string& sum) {
  std::vector<std::string> out;
  std::string term = "+ ";
  int depth = 0;
  for (std::size_t i = 0; i < sum.size(); ++i) {
    const char c = sum[i];
    if (c == '(' || c == '{') ++depth;
    if (c == ')' || c == '}') --depth;
    if (depth == 0 && (sum.compare(i, 3, " + ") == 0 || sum.compare(i, 3, " - ") == 0)) {
      out.push_back(term);
      term = std::string(1, sum[i + 1]) + " ";
      i += 2;
      continue;
    }
    if (i == 0 && c == '-') {
      term = "- ";
      continue;
    }
    term += c;
  }
  out.push_back(term);
  return out;
}

bool signs_is_padding(const std::string& term) {
  const std::string body = term.substr(2);
  return body == "w" || body.rfind("w^", 0) == 0;
}

// The case e of the spec made by `make`, as the printer shows it in a large entry: V = e + the
// padding. Returns the printed V without the padding ("0" when nothing is left).
struct SignsPrinted {
  Spec spec;
  ex e;               // the case, in the spec's symbols
  std::string text;   // the case alone, in the text format
  std::string latex;  // the whole LaTeX display
};

constexpr int kSignsPadding = 400;  // w + w^2 + ... + w^400: some 1200 nodes

SignsPrinted signs_print(const std::function<ex(const SpecBuilder&)>& make, int noise = 0) {
  std::vector<GiNaC::symbol> unrelated;  // shifts GiNaC's hash order, and with it the signs it holds
  for (int i = 0; i < noise; ++i) unrelated.emplace_back("noise");
  SpecBuilder b("signs");
  b.coordinate("x").coordinate("y").parameter("a", 0.7);
  for (int i = 0; i < noise; ++i) unrelated.emplace_back("noise");
  b.parameter("b", 1.3).parameter("c", -0.4).parameter("w", 0.5);
  b.kinetic_energy("x'^2/2 + y'^2/2");
  ex padding = 0;
  for (int k = 1; k <= kSignsPadding; ++k) padding += GiNaC::pow(b.parse("w"), k);
  const ex e = make(b);
  b.add_energies(b.parse("x'^2/2") * padding, e + padding);
  SignsPrinted out{b.build(), e, "", ""};
  const Derivation d = derive(out.spec);
  const std::string text = format_equations(out.spec, d, EquationFormat::text);
  out.latex = format_equations(out.spec, d, EquationFormat::latex);
  const std::size_t at = text.find("\n  V = ");
  if (at == std::string::npos) throw std::runtime_error("no V in\n" + text);
  const std::size_t begin = at + 7;
  std::string rest;
  for (const std::string& term : signs_terms(text.substr(begin, text.find('\n', begin) - begin))) {
    if (signs_is_padding(term)) continue;
    rest += rest.empty() ? (term[0] == '-' ? "-" + term.substr(2) : term.substr(2)) : " " + term;
  }
  out.text = rest.empty() ? "0" : rest;
  return out;
}

// The case read back equals the case at the generic point.
void expect_signs_read_back(const std::function<ex(const SpecBuilder&)>& make, const std::string& what) {
  const SignsPrinted printed = signs_print(make);
  const std::complex<double> got = nhdyn::test::equation_value_at(printed.spec, nhdyn::test::EquationReader(printed.spec).read(printed.text));
  const std::complex<double> want = nhdyn::test::equation_value_at(printed.spec, printed.e);
  EXPECT_LT(std::abs(got - want), 1e-12 * (1.0 + std::abs(want)))
      << what << " printed as " << printed.text << ": " << got << " instead of " << want;
}

// Shorthands for building exactly the structure under test: GiNaC would otherwise pick the sign
// of each sum by its hash order.
ex signs_mul(std::initializer_list<ex> factors) { return GiNaC::mul(GiNaC::exvector(factors)).hold(); }
ex signs_add(std::initializer_list<ex> terms) { return GiNaC::add(GiNaC::exvector(terms)).hold(); }
ex signs_pow(const ex& base, const ex& exponent) { return GiNaC::power(base, exponent).hold(); }

struct SignsCase {
  const char* what;
  std::function<ex(const SpecBuilder&)> make;
};

std::vector<SignsCase> signs_cases() {
  using GiNaC::numeric;
  const auto s = [](const SpecBuilder& b, const char* name) { return b.parse(name); };
  const auto b_minus_a = [s](const SpecBuilder& b) { return signs_add({s(b, "b"), -s(b, "a")}); };
  const auto a_minus_b = [s](const SpecBuilder& b) { return signs_add({s(b, "a"), -s(b, "b")}); };
  return {
      {"x (b - a)", [=](const SpecBuilder& b) { return signs_mul({s(b, "x"), b_minus_a(b)}); }},
      {"-3/7 x (b - a)",
       [=](const SpecBuilder& b) { return signs_mul({numeric(-3, 7), s(b, "x"), b_minus_a(b)}); }},
      {"-3/10 / (b - a)", [=](const SpecBuilder& b) { return signs_mul({numeric(-3, 10), signs_pow(b_minus_a(b), -1)}); }},
      {"(b - a)^3", [=](const SpecBuilder& b) { return signs_pow(b_minus_a(b), 3); }},
      {"(b - a)^-2 y (a - b)^3",
       [=](const SpecBuilder& b) { return signs_mul({signs_pow(b_minus_a(b), -2), s(b, "y"), signs_pow(a_minus_b(b), 3)}); }},
      {"sqrt(b - a)", [=](const SpecBuilder& b) { return signs_pow(b_minus_a(b), numeric(1, 2)); }},
      {"(b - a)^(-3/2)", [=](const SpecBuilder& b) { return signs_pow(b_minus_a(b), numeric(-3, 2)); }},
      {"(b - a)^c", [=](const SpecBuilder& b) { return signs_pow(b_minus_a(b), s(b, "c")); }},
      {"(b - a)^(-c) y", [=](const SpecBuilder& b) { return signs_mul({signs_pow(b_minus_a(b), -s(b, "c")), s(b, "y")}); }},
      {"x (a - b) + x (b - a) + y",
       [=](const SpecBuilder& b) {
         return signs_add({signs_mul({s(b, "x"), a_minus_b(b)}), signs_mul({s(b, "x"), b_minus_a(b)}), s(b, "y")});
       }},
      {"y (x (a - b) + x (b - a)), a zero factor",
       [=](const SpecBuilder& b) {
         return signs_mul({s(b, "y"), signs_add({signs_mul({s(b, "x"), a_minus_b(b)}), signs_mul({s(b, "x"), b_minus_a(b)})})});
       }},
      {"y / (x (a - b) + 2 x (b - a) + x)",
       [=](const SpecBuilder& b) {
         return signs_mul({s(b, "y"), signs_pow(signs_add({signs_mul({s(b, "x"), a_minus_b(b)}),
                                                           signs_mul({numeric(2), s(b, "x"), b_minus_a(b)}), s(b, "x")}),
                                                -1)});
       }},
      {"5 cos(-x)^2 / cos(x)^2", [=](const SpecBuilder& b) {
         return signs_mul({numeric(5), signs_pow(GiNaC::cos(-s(b, "x")), 2), signs_pow(GiNaC::cos(s(b, "x")), -2)});
       }},
      {"cos(-x) / cos(x)", [=](const SpecBuilder& b) {
         return signs_mul({GiNaC::cos(-s(b, "x")), signs_pow(GiNaC::cos(s(b, "x")), -1)});
       }},
      {"sin(-x)^3 y / cos(x)^2", [=](const SpecBuilder& b) {
         return signs_mul({signs_pow(GiNaC::sin(-s(b, "x")), 3), s(b, "y"), signs_pow(GiNaC::cos(s(b, "x")), -2)});
       }},
      {"sin(-x)^-1", [=](const SpecBuilder& b) { return signs_pow(GiNaC::sin(-s(b, "x")), -1); }},
      {"sin(-x)^(1/2) sin(-x)^(1/2)", [=](const SpecBuilder& b) {
         return signs_mul({signs_pow(GiNaC::sin(-s(b, "x")), numeric(1, 2)), signs_pow(GiNaC::sin(-s(b, "x")), numeric(1, 2))});
       }},
      {"sin(-x)^(3/2) / sin(x)^(3/2)", [=](const SpecBuilder& b) {
         return signs_mul({signs_pow(GiNaC::sin(-s(b, "x")), numeric(3, 2)), signs_pow(GiNaC::sin(s(b, "x")), numeric(-3, 2))});
       }},
      {"sin(-x)^c", [=](const SpecBuilder& b) { return signs_pow(GiNaC::sin(-s(b, "x")), s(b, "c")); }},
      {"cos(-x)^c cos(x)", [=](const SpecBuilder& b) {
         return signs_mul({signs_pow(GiNaC::cos(-s(b, "x")), s(b, "c")), GiNaC::cos(s(b, "x"))});
       }},
      {"sin(x) sin(-x)", [=](const SpecBuilder& b) { return signs_mul({GiNaC::sin(s(b, "x")), GiNaC::sin(-s(b, "x"))}); }},
      {"tan(x) tan(-x)", [=](const SpecBuilder& b) { return signs_mul({GiNaC::tan(s(b, "x")), GiNaC::tan(-s(b, "x"))}); }},
      {"y abs(-x)", [=](const SpecBuilder& b) { return signs_mul({s(b, "y"), GiNaC::abs(signs_mul({-1, s(b, "x")}))}); }},
      {"sinh(-x) / cosh(-x)", [=](const SpecBuilder& b) {
         return signs_mul({GiNaC::sinh(signs_mul({-1, s(b, "x")})), signs_pow(GiNaC::cosh(signs_mul({-1, s(b, "x")})), -1)});
       }},
      {"sin(-2 x) / cos(2 x)", [=](const SpecBuilder& b) {
         return signs_mul({GiNaC::sin(-2 * s(b, "x")), signs_pow(GiNaC::cos(2 * s(b, "x")), -1)});
       }},
      {"asin(-x) acos(-x) atan(-x) atanh(-x) asinh(-x)", [=](const SpecBuilder& b) {
         const ex m = signs_mul({-1, s(b, "x")});
         return signs_mul({GiNaC::asin(m), GiNaC::acos(m), GiNaC::atan(m), GiNaC::atanh(m), GiNaC::asinh(m)});
       }},
      {"sin(b - a) / cos(a - b)", [=](const SpecBuilder& b) {
         return signs_mul({GiNaC::sin(b_minus_a(b)), signs_pow(GiNaC::cos(a_minus_b(b)), -1)});
       }},
      {"cos(b - a) cos(a - b) + sin(x (b - a)) - sin(x (a - b))", [=](const SpecBuilder& b) {
         return signs_add({signs_mul({GiNaC::cos(b_minus_a(b)), GiNaC::cos(a_minus_b(b))}),
                           GiNaC::sin(signs_mul({s(b, "x"), b_minus_a(b)})),
                           signs_mul({-1, GiNaC::sin(signs_mul({s(b, "x"), a_minus_b(b)}))})});
       }},
      {"exp(x)^2 y", [=](const SpecBuilder& b) { return signs_mul({signs_pow(GiNaC::exp(s(b, "x")), 2), s(b, "y")}); }},
      {"(1/2 + 3/2 I) x", [=](const SpecBuilder& b) {
         return signs_mul({numeric(1, 2) + numeric(3, 2) * GiNaC::I, s(b, "x")});
       }},
      {"-2 I x (b - a)", [=](const SpecBuilder& b) { return signs_mul({-2 * GiNaC::I, s(b, "x"), b_minus_a(b)}); }},
      {"I/10 y", [=](const SpecBuilder& b) { return signs_mul({GiNaC::I / 10, s(b, "y")}); }},
      {"(y - I x)^3 x", [=](const SpecBuilder& b) {
         return signs_mul({signs_pow(signs_add({s(b, "y"), -GiNaC::I * s(b, "x")}), 3), s(b, "x")});
       }},
      {"(a + (1 - I) x)^-1", [=](const SpecBuilder& b) {
         return signs_pow(signs_add({s(b, "a"), (1 - GiNaC::I) * s(b, "x")}), -1);
       }},
  };
}

const SignsCase& signs_case(const std::vector<SignsCase>& cases, const std::string& what) {
  for (const SignsCase& c : cases)
    if (c.what == what) return c;
  throw std::runtime_error("no case " + what);
}

TEST(EquationSigns, UnsimplifiedTermsReadBack) {
  for (const SignsCase& c : signs_cases()) {
    SCOPED_TRACE(c.what);
    expect_signs_read_back(c.make, c.what);
  }
}

TEST(EquationSigns, ASumWhoseTermsCancelMakesItsTermZero) {
  // y (x (a - b) + x (b - a)) is 0: no "(0)" factor left in the text.
  const std::vector<SignsCase> cases = signs_cases();
  EXPECT_EQ(signs_print(signs_case(cases, "y (x (a - b) + x (b - a)), a zero factor").make).text, "0");
  EXPECT_EQ(signs_print(signs_case(cases, "x (a - b) + x (b - a) + y").make).text, "y");
}

TEST(EquationSigns, LikeFactorsThatCancelLeaveTheCoefficient) {
  const std::vector<SignsCase> cases = signs_cases();
  EXPECT_EQ(signs_print(signs_case(cases, "5 cos(-x)^2 / cos(x)^2").make).text, "5");
  EXPECT_EQ(signs_print(signs_case(cases, "cos(-x) / cos(x)").make).text, "1");
}

// The same expression built with the symbols created in another order: GiNaC holds
// sin(x (a - b)) as sin(-x (b - a)) for some orders; the printed text is the same for all.
TEST(EquationSigns, FunctionsOfNegatedSumsPrintTheSameWhateverTheSymbolOrder) {
  const std::vector<std::string> cases = {"sin(x*(a-b))", "cos(x*(a-b))*sin(x*(b-a))", "sin(x*(a-b))/cos(x*(b-a))",
                                          "sin((a-b)*x)^3/(a-x)", "cos(x*(a-b))*cos(x*(b-a))", "sin(b-a)/cos(a-b)"};
  for (const std::string& text : cases) {
    SCOPED_TRACE(text);
    const auto make = [&](const SpecBuilder& b) { return b.parse(text); };
    const std::string first = signs_print(make).text;
    expect_signs_read_back(make, text);
    for (int noise = 1; noise < 40; noise += 2) EXPECT_EQ(signs_print(make, noise).text, first) << noise;
  }
}

TEST(EquationSigns, TangentsFoldAcrossTheSignOfTheirArgument) {
  // sin(u)/cos(-u) and sin(-u)/cos(u) are +-tan(u), whichever sign GiNaC holds u in.
  for (const char* text : {"sin(x*(a-b))/cos(x*(b-a))", "sin(b-a)/cos(a-b)", "y*sin(x*(b-a))^2/cos(x*(a-b))^3"}) {
    SCOPED_TRACE(text);
    const std::string printed = signs_print([&](const SpecBuilder& b) { return b.parse(text); }).text;
    EXPECT_TRUE(nhdyn::test::contains(printed, "tan(")) << printed;
    EXPECT_FALSE(nhdyn::test::contains(printed, "sin(")) << printed;
  }
}

// LaTeX: e^{x} squared is (e^{x})^{2}, never e^{x}^{2} (a double superscript TeX refuses).
TEST(EquationSigns, LatexPowersOfExponentialsHaveOneSuperscriptEach) {
  const SignsPrinted printed = signs_print([](const SpecBuilder& b) {
    return signs_add({signs_pow(GiNaC::exp(b.parse("x")), 2),
                      signs_mul({signs_pow(GiNaC::exp(b.parse("y")), GiNaC::numeric(1, 3)), b.parse("y")})});
  });
  const std::string& latex = printed.latex;
  for (std::size_t at = latex.find("^{"); at != std::string::npos; at = latex.find("^{", at + 1)) {
    int depth = 0;
    std::size_t close = at + 1;
    for (; close < latex.size(); ++close) {
      if (latex[close] == '{') ++depth;
      if (latex[close] == '}' && --depth == 0) break;
    }
    ASSERT_LT(close + 1, latex.size());
    EXPECT_NE(latex[close + 1], '^') << latex.substr(at > 20 ? at - 20 : 0, close - at + 40);
  }
  const std::string v = latex.substr(latex.find("V &="), 300);
  EXPECT_TRUE(nhdyn::test::contains(v, "\\left(e^{x}\\right)^{2}")) << v;
  EXPECT_TRUE(nhdyn::test::contains(v, "\\left(e^{y}\\right)^{1/3}")) << v;
}

// Complex coefficients through the simplified path (format_expression): sqrt(-4) is 2 I.
TEST(EquationSigns, ComplexCoefficientsReadBack) {
  SpecBuilder b("complex");
  b.coordinate("x").parameter("a", 0.7).kinetic_energy("x'^2/2");
  const Spec spec = b.build();
  for (const char* text : {"sqrt(-4)*x + x", "sqrt(-4)*x", "-sqrt(-9)*x/2 + a", "(1 + sqrt(-1))*x/(a - x)"}) {
    const ex e = b.parse(text);
    const std::string printed = format_expression(spec, e, EquationFormat::text);
    const std::complex<double> got = nhdyn::test::equation_value_at(spec, nhdyn::test::EquationReader(spec).read(printed));
    const std::complex<double> want = nhdyn::test::equation_value_at(spec, e);
    EXPECT_LT(std::abs(got - want), 1e-12 * (1.0 + std::abs(want))) << text << " printed as " << printed;
    EXPECT_FALSE(nhdyn::test::contains(format_expression(spec, e, EquationFormat::latex), "*"))
        << format_expression(spec, e, EquationFormat::latex);
  }
}

// The row of the equations of motion, whose coefficient here is a sum (1 + w + ... + w^400),
// reads back to A0 q'' with C on the right.
TEST(EquationSigns, ARowWithASumCoefficientReadsBack) {
  const SignsPrinted printed = signs_print([](const SpecBuilder& b) {
    return signs_mul({b.parse("x"), signs_add({b.parse("b"), -b.parse("a")})});
  });
  const Derivation d = derive(printed.spec);
  const std::string text = format_equations(printed.spec, d, EquationFormat::text);
  const std::size_t at = text.find("\nEquations of motion");
  ASSERT_NE(at, std::string::npos) << text;
  const std::size_t begin = text.find('\n', at + 1) + 1;
  const std::string row = text.substr(begin, text.find('\n', begin) - begin);
  const std::size_t equals = row.find(" = ");
  ASSERT_NE(equals, std::string::npos) << row;
  const nhdyn::test::EquationReader reader(printed.spec);
  const ex lhs = reader.read(row.substr(2, equals - 2));
  const ex want = d.A(0, 0) * printed.spec.symbols.acceleration(0) + d.A(0, 1) * printed.spec.symbols.acceleration(1);
  EXPECT_LT(std::abs(nhdyn::test::equation_value_at(printed.spec, lhs) - nhdyn::test::equation_value_at(printed.spec, want)), 1e-12 * 10.0)
      << row.substr(0, 200);
  EXPECT_LT(std::abs(nhdyn::test::equation_value_at(printed.spec, reader.read(row.substr(equals + 3))) -
                     nhdyn::test::equation_value_at(printed.spec, d.Q(0, 0) + d.G(0, 0))),
            1e-12 * 10.0);
}

}  // namespace
}  // namespace nhdyn::symbolic
