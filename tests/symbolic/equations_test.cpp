// The display of `nhdyn equations`: the paper's equations as a reader expects them (text and
// LaTeX), well-formed LaTeX, the cases without a D, and output that does not depend on anything
// but the model (not on GiNaC's term order, which follows the creation order of symbols).
#include "nhdyn/symbolic/equations.hpp"

#include <gtest/gtest.h>

#include <string>
#include <tuple>
#include <vector>

#include "nhdyn/symbolic/spec_builder.hpp"
#include "support/text.hpp"

namespace nhdyn::symbolic {
namespace {

// Builds the paper's sled; `noise(k)` creates k unrelated GiNaC symbols at several points of the
// construction, which shifts the serial numbers (and so the hashes and term order) of every symbol.
Spec sled_paper(bool with_independent, int noise = 0) {
  std::vector<GiNaC::symbol> unrelated;
  const auto make_noise = [&] {
    for (int i = 0; i < noise; ++i) unrelated.emplace_back("noise");
  };
  make_noise();
  SpecBuilder b("sled-paper");
  b.description("Sled on an inclined plane, the paper's potential");
  b.coordinate("x");
  make_noise();
  b.coordinate("y").coordinate("phi");
  b.parameter("m", 1.0, "kg").parameter("a", 0.5, "m");
  make_noise();
  b.parameter("rho", 0.7, "m").parameter("alpha", 0.5235987755982988, "rad").parameter("g", 9.81, "m/s^2");
  b.kinetic_energy("m/2*(x'^2 + y'^2) - m*a*sin(phi)*x'*phi' + m*a*cos(phi)*y'*phi' + m*rho^2/2*phi'^2");
  make_noise();
  b.potential_energy("-m*g*sin(alpha)*x");
  b.constraint("blade", ConstraintLevel::velocity, "y' - tan(phi)*x'");
  if (with_independent) b.independent({"x", "phi"});
  return b.build();
}

Spec appell(bool with_independent) {
  SpecBuilder b("appell");
  b.coordinate("x").coordinate("y").coordinate("z").parameter("m", 1.0).parameter("g", 9.81).parameter("a", 0.5);
  b.kinetic_energy("m/2*(x'^2 + y'^2 + z'^2)").potential_energy("-m*g*z");
  b.constraint("appell", ConstraintLevel::velocity, "z'^2 - a^2*(x'^2 + y'^2)");
  if (with_independent) b.independent({"x", "y"});
  return b.build();
}

std::string show(const Spec& spec, EquationFormat format) { return format_equations(spec, derive(spec), format); }

using nhdyn::test::contains;

int count(const std::string& haystack, const std::string& needle) {
  int n = 0;
  for (std::size_t at = haystack.find(needle); at != std::string::npos; at = haystack.find(needle, at + 1)) ++n;
  return n;
}

// The math of a LaTeX display: one align* environment, balanced braces, \left/\right and pmatrix,
// no characters of the text notation (primes, the internal "__", '*').
void expect_valid_latex(const std::string& latex) {
  ASSERT_EQ(count(latex, "\\begin{align*}"), 1) << latex;
  ASSERT_EQ(count(latex, "\\end{align*}"), 1) << latex;
  const std::size_t begin = latex.find("\\begin{align*}") + std::string("\\begin{align*}").size();
  const std::string body = latex.substr(begin, latex.find("\\end{align*}") - begin);
  int depth = 0;
  for (std::size_t i = 0; i < body.size(); ++i) {
    if (body[i] == '\\' && i + 1 < body.size() && (body[i + 1] == '{' || body[i + 1] == '}')) {
      ++i;
      continue;
    }
    if (body[i] == '{') ++depth;
    if (body[i] == '}') --depth;
    ASSERT_GE(depth, 0) << "unbalanced '}' at " << i << " in " << body;
  }
  EXPECT_EQ(depth, 0) << body;
  EXPECT_EQ(count(body, "\\left"), count(body, "\\right")) << body;
  EXPECT_EQ(count(body, "\\begin{pmatrix}"), count(body, "\\end{pmatrix}")) << body;
  EXPECT_FALSE(contains(body, "__")) << body;
  EXPECT_FALSE(contains(body, "'")) << body;
  EXPECT_FALSE(contains(body, "*")) << body;
  EXPECT_FALSE(contains(body, "\\\\\n\\end")) << "a row break before \\end{align*}";
}

// The partition shown for a model that gives none is one regular at its initial state: a
// pendulum x^2 + y^2 = l^2 started at y = 0 gets y independent (D = [-y/x, 1]), not x (D =
// [1, -x/y], singular there; the suggestion to add it failed at t = 0); started at x = 0, x.
TEST(Equations, ThePartitionShownIsRegularAtTheInitialState) {
  for (const auto& [x0, y0, independent] : {std::tuple{"1", "0", "y"}, std::tuple{"0", "-1", "x"}}) {
    SpecBuilder b("pendulum");
    b.coordinate("x").coordinate("y").parameter("m", 1.0).parameter("g", 9.81).parameter("l", 1.0);
    b.kinetic_energy("m/2*(x'^2 + y'^2)").potential_energy("m*g*y");
    b.constraint("rod", ConstraintLevel::position, "x^2 + y^2 - l^2");
    b.initial("x", x0, "0").initial("y", y0, "0");
    const std::string text = show(b.build(), EquationFormat::text);
    EXPECT_TRUE(contains(text, std::string("with ") + independent + " independent; add independent = [\"" +
                                   independent + "\"] to the model"))
        << text;
  }
}

TEST(Equations, SledPaperTextShowsThePapersEquations) {
  const std::string text = show(sled_paper(true), EquationFormat::text);
  // The paper's pair (docs/notation.md section 6) and the constraint at acceleration level.
  EXPECT_TRUE(contains(text, "m x'' + m tan(phi) y'' = m a phi'^2/cos(phi) + m g sin(alpha)\n")) << text;
  EXPECT_TRUE(contains(text, "-m a sin(phi) x'' + m a cos(phi) y'' + m rho^2 phi'' = 0\n")) << text;
  EXPECT_TRUE(contains(text, "-tan(phi) x'' + y'' - x' phi'/cos(phi)^2 = 0   (blade)")) << text;
  EXPECT_TRUE(contains(text, "partitioned with x, phi independent")) << text;
  EXPECT_TRUE(contains(text, "[ 1  tan(phi)  0 ]")) << text;
  EXPECT_TRUE(contains(text, "blade (velocity level)")) << text;
  EXPECT_TRUE(contains(text, "G_x   = m a cos(phi) phi'^2")) << text;
  // In the paper's order.
  const std::vector<std::string> order = {"T = ", "V = ", "Inertia matrix A", "Q_x", "G_x", "b  = ", "b0 = ",
                                          "Complement D", "A0 = D A", "C = D (Q + G)", "Equations of motion"};
  std::size_t at = 0;
  for (const std::string& item : order) {
    const std::size_t next = text.find(item, at);
    ASSERT_NE(next, std::string::npos) << "'" << item << "' missing or out of order in\n" << text;
    at = next;
  }
  EXPECT_FALSE(contains(text, "__")) << text;
}

TEST(Equations, SledPaperLatexIsValidAndUsesDots) {
  const std::string latex = show(sled_paper(true), EquationFormat::latex);
  expect_valid_latex(latex);
  EXPECT_TRUE(contains(latex, "\\ddot{x}")) << latex;
  EXPECT_TRUE(contains(latex, "\\ddot{\\varphi}")) << latex;
  EXPECT_TRUE(contains(latex, "\\dot{\\varphi}^{2}")) << latex;
  EXPECT_TRUE(contains(latex, "\\rho^{2}")) << latex;
  EXPECT_TRUE(contains(latex, "\\sin(\\alpha)")) << latex;
  EXPECT_TRUE(contains(latex, "\\cos^{2}(\\varphi)")) << latex;
  EXPECT_TRUE(contains(latex, "m \\ddot{x} + m \\tan(\\varphi) \\ddot{y} &= \\frac{m a \\dot{\\varphi}^{2}}{\\cos(\\varphi)} + m g \\sin(\\alpha)"))
      << latex;
  EXPECT_TRUE(contains(latex, "\\begin{pmatrix}")) << latex;
}

TEST(Equations, AppellShowsThePapersEquations) {
  const Spec spec = appell(true);
  const std::string text = show(spec, EquationFormat::text);
  EXPECT_TRUE(contains(text, "m x'' + (m a^2 x'/z') z'' = m g a^2 x'/z'\n")) << text;
  EXPECT_TRUE(contains(text, "m y'' + (m a^2 y'/z') z'' = m g a^2 y'/z'\n")) << text;
  EXPECT_TRUE(contains(text, "-2 a^2 x' x'' - 2 a^2 y' y'' + 2 z' z'' = 0   (appell)")) << text;
  const std::string latex = show(spec, EquationFormat::latex);
  expect_valid_latex(latex);
  EXPECT_TRUE(contains(latex, "\\frac{m a^{2} \\dot{x}}{\\dot{z}} \\ddot{z}")) << latex;
}

TEST(Equations, WithoutDThePartitionedChoiceIsShownWithAHint) {
  const std::string text = show(appell(false), EquationFormat::text);
  EXPECT_TRUE(contains(text, "none in the model")) << text;
  EXPECT_TRUE(contains(text, "independent = [\"x\", \"y\"]")) << text;
  EXPECT_TRUE(contains(text, "m x'' + (m a^2 x'/z') z'' = m g a^2 x'/z'")) << text;
  expect_valid_latex(show(appell(false), EquationFormat::latex));

  // Two constraints with the same velocity part: no partition is regular, so A0 and C are unavailable.
  SpecBuilder b("degenerate");
  b.coordinate("x").coordinate("y").coordinate("z").kinetic_energy("(x'^2 + y'^2 + z'^2)/2");
  b.constraint("one", "x' + y'").constraint("two", "2*x' + 2*y' + t");
  const Spec spec = b.build();
  const std::string none = show(spec, EquationFormat::text);
  EXPECT_TRUE(contains(none, "unavailable")) << none;
  EXPECT_TRUE(contains(none, "independent = [...]")) << none;
  const std::string latex = show(spec, EquationFormat::latex);
  expect_valid_latex(latex);
  EXPECT_TRUE(contains(latex, "unavailable")) << latex;
}

TEST(Equations, UnconstrainedSystemAndNames) {
  SpecBuilder b("double");
  b.coordinate("theta_1").coordinate("x2").parameter("m_cart", 2.0).parameter("Omega", 1.0).parameter("k", 3.0);
  b.kinetic_energy("m_cart/2*(theta_1'^2 + x2'^2) + Omega*theta_1'*x2'*cos(theta_1)");
  b.potential_energy("k/2*x2^2 - sqrt(1 + theta_1^2)").force("x2", "-k*abs(x2')*x2' + exp(-t)");
  const Spec spec = b.build();
  const std::string text = show(spec, EquationFormat::text);
  EXPECT_TRUE(contains(text, "no constraints, D = I")) << text;
  EXPECT_TRUE(contains(text, "theta_1''")) << text;
  const std::string latex = show(spec, EquationFormat::latex);
  expect_valid_latex(latex);
  EXPECT_TRUE(contains(latex, "\\ddot{\\theta}_{1}")) << latex;
  EXPECT_TRUE(contains(latex, "\\dot{x}_{2}")) << latex;
  EXPECT_TRUE(contains(latex, "m_{\\mathrm{cart}}")) << latex;
  EXPECT_TRUE(contains(latex, "\\Omega")) << latex;
  EXPECT_TRUE(contains(latex, "\\sqrt{")) << latex;
  EXPECT_TRUE(contains(latex, "\\left|")) << latex;
  EXPECT_TRUE(contains(latex, "e^{")) << latex;
}

TEST(Equations, PositionConstraintIsShownWithItsLevel) {
  SpecBuilder b("pendulum");
  b.coordinate("x").coordinate("y").parameter("m", 1.0).parameter("g", 9.81).parameter("l", 1.0);
  b.kinetic_energy("m/2*(x'^2 + y'^2)").potential_energy("m*g*y");
  b.constraint("rod", ConstraintLevel::position, "x^2 + y^2 - l^2").independent({"x"});
  const std::string text = show(b.build(), EquationFormat::text);
  EXPECT_TRUE(contains(text, "rod (position level)")) << text;
  EXPECT_TRUE(contains(text, "2 x x'' + 2 y y'' + 2 x'^2 + 2 y'^2 = 0   (rod)")) << text;
}

TEST(Equations, OutputIsDeterministic) {
  const std::string text = show(sled_paper(true), EquationFormat::text);
  const std::string latex = show(sled_paper(true), EquationFormat::latex);
  EXPECT_EQ(show(sled_paper(true), EquationFormat::text), text);
  // Unrelated symbols created before and between the declarations change GiNaC's internal order.
  for (const int noise : {1, 2, 3, 5, 8, 13, 21}) {
    EXPECT_EQ(show(sled_paper(true, noise), EquationFormat::text), text) << noise;
    EXPECT_EQ(show(sled_paper(true, noise), EquationFormat::latex), latex) << noise;
    EXPECT_EQ(show(sled_paper(false, noise), EquationFormat::text), show(sled_paper(false), EquationFormat::text))
        << noise;
  }
}

TEST(Equations, SimplifiedExpressionsPrintTheSameWhateverTheSymbolOrder) {
  // A quotient of sums, whose sign GiNaC picks by its hash order.
  const auto printed = [](int noise, EquationFormat format) {
    std::vector<GiNaC::symbol> unrelated;
    for (int i = 0; i < noise; ++i) unrelated.emplace_back("noise");
    SpecBuilder b("q");
    b.coordinate("x").parameter("a", 1.0);
    for (int i = 0; i < noise; ++i) unrelated.emplace_back("noise");
    b.parameter("b", 2.0).kinetic_energy("x'^2/2");
    const Spec spec = b.build();
    const GiNaC::ex e = b.parse("(a - b)/(b - a*cos(x)) + tan(x)*a/(2*b - 2*x) - (x - a)^3/(b - x)^2");
    return format_expression(spec, e, format);
  };
  const std::string text = printed(0, EquationFormat::text);
  const std::string latex = printed(0, EquationFormat::latex);
  for (int noise = 1; noise < 40; noise += 3) {
    EXPECT_EQ(printed(noise, EquationFormat::text), text) << noise;
    EXPECT_EQ(printed(noise, EquationFormat::latex), latex) << noise;
  }
}

}  // namespace
}  // namespace nhdyn::symbolic
