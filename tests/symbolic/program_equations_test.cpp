// `nhdyn equations` of a model with programs (docs/derivations/program-motion.md): the programs are
// shown like the constraints, each with its actuator, then the actuator matrix B, D B, and the
// equations of (P2): A0 q'' - D B u = C, b q'' + b0 = 0, b_p q'' + b_p0 = 0. The entries are
// checked by evaluating what the display is built from against the hand derivation of section 6
// (the sled turning at a prescribed rate), the text by its structure.
#include <gtest/gtest.h>

#include <string>

#include "nhdyn/symbolic/equations.hpp"
#include "nhdyn/symbolic/spec_builder.hpp"
#include "support/text.hpp"

namespace nhdyn::symbolic {
namespace {

// examples/sled_heading_program.toml with D partitioned on (x, phi).
Spec sled_heading(bool second_program = false) {
  SpecBuilder b("sled-heading");
  b.coordinate("x").coordinate("y").coordinate("phi");
  b.parameter("m", 1.0).parameter("a", 0.5).parameter("rho", 0.7).parameter("alpha", 0.5).parameter("g", 9.81);
  b.parameter("omega", 1.0);
  b.kinetic_energy("m/2 * (x'^2 + y'^2) + m*a*phi' * (cos(phi)*y' - sin(phi)*x') + m*rho^2/2 * phi'^2");
  b.potential_energy("-m*g*sin(alpha) * (x + a*cos(phi))");
  b.constraint("blade", ConstraintLevel::velocity, "-sin(phi)*x' + cos(phi)*y'");
  b.program("heading", ConstraintLevel::position, "phi - omega*t", std::string("phi"));
  if (second_program) b.program("push", ConstraintLevel::velocity, "x' - 1", std::vector<std::string>{"1", "0", "0"});
  b.independent({"x", "phi"});
  return b.build();
}

using nhdyn::test::contains;

TEST(ProgramEquations, TextShowsTheProgramsTheActuatorMatrixAndTheStackedEquations) {
  const Spec spec = sled_heading();
  const std::string text = format_equations(spec, derive(spec), EquationFormat::text);
  EXPECT_TRUE(contains(text, "Programs (m = 1), at acceleration level b_p q'' + b_p0 = 0")) << text;
  EXPECT_TRUE(contains(text, "heading (position level, actuator phi): ")) << text;
  EXPECT_TRUE(contains(text, "b_p  = [ 0  0  1 ]")) << text;
  EXPECT_TRUE(contains(text, "Actuator matrix B (3 x 1): the generalized force B u, u = (u_heading)")) << text;
  EXPECT_TRUE(contains(text, "Reduced actuator matrix D B")) << text;
  EXPECT_TRUE(contains(text, "Equations of motion A0 q'' - D B u = C, b q'' + b0 = 0, b_p q'' + b_p0 = 0")) << text;
  // The torque enters the row of phi (D partitioned on x, phi: D B = (0, 1)) and only that one.
  int rows_with_u = 0;
  for (std::size_t at = text.find("u_heading ="); at != std::string::npos; at = text.find("u_heading =", at + 1))
    ++rows_with_u;
  EXPECT_EQ(rows_with_u, 1) << text;
  EXPECT_TRUE(contains(text, "(program heading)")) << text;
  // A model without programs shows none of it.
  SpecBuilder b("plain");
  b.coordinate("x").parameter("m", 1.0).kinetic_energy("m/2*x'^2");
  const Spec plain = b.build();
  const std::string plain_text = format_equations(plain, derive(plain), EquationFormat::text);
  EXPECT_FALSE(contains(plain_text, "Program")) << plain_text;
  EXPECT_FALSE(contains(plain_text, "D B")) << plain_text;
}

TEST(ProgramEquations, DerivationHoldsTheHandDerivedBAndBp) {
  const Spec spec = sled_heading(true);
  const Derivation d = derive(spec);
  ASSERT_EQ(d.B.rows(), 3u);
  ASSERT_EQ(d.B.cols(), 2u);
  // B: the torque on phi and the direction (1, 0, 0) as given.
  const double expected_B[3][2] = {{0, 1}, {0, 0}, {1, 0}};
  for (unsigned i = 0; i < 3; ++i)
    for (unsigned j = 0; j < 2; ++j) EXPECT_TRUE((d.B(i, j) - expected_B[i][j]).is_zero()) << i << "," << j;
  // b_p: phi'' for the heading, x'' for the push; b_p0 = 0 for both (phi'' = 0 holds omega t).
  EXPECT_TRUE((d.b_p(0, 2) - 1).is_zero());
  EXPECT_TRUE((d.b_p(1, 0) - 1).is_zero());
  EXPECT_TRUE(d.b_p0(0, 0).is_zero());
  EXPECT_TRUE(d.b_p0(1, 0).is_zero());
  const std::string text = format_equations(spec, d, EquationFormat::text);
  EXPECT_TRUE(contains(text, "Programs (m = 2)")) << text;
  EXPECT_TRUE(contains(text, "push (velocity level, actuator [1, 0, 0]): ")) << text;
  EXPECT_TRUE(contains(text, "Actuator matrix B (3 x 2): the generalized force B u, u = (u_heading, u_push)")) << text;
}

TEST(ProgramEquations, LatexHasEveryProgramAndBalancedBraces) {
  const Spec spec = sled_heading(true);
  const std::string latex = format_equations(spec, derive(spec), EquationFormat::latex);
  EXPECT_TRUE(contains(latex, "\\intertext{Program \\texttt{heading}, given at position level, realized by the "
                              "actuator \\texttt{phi}:}"))
      << latex;
  EXPECT_TRUE(contains(latex, "\\texttt{push}")) << latex;
  EXPECT_TRUE(contains(latex, "B &= \\begin{pmatrix}")) << latex;
  EXPECT_TRUE(contains(latex, "D B &= ")) << latex;
  EXPECT_TRUE(contains(latex, "u_{\\text{heading}}")) << latex;
  EXPECT_TRUE(contains(latex, "$A_0 \\ddot{q} - D B u = C$")) << latex;
  int depth = 0;
  for (const char c : latex) {
    depth += c == '{' ? 1 : c == '}' ? -1 : 0;
    ASSERT_GE(depth, 0) << latex;
  }
  EXPECT_EQ(depth, 0) << latex;
}

}  // namespace
}  // namespace nhdyn::symbolic
