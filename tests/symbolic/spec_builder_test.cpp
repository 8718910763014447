// SpecBuilder: expressions read the way a user writes them (primes, exact decimals, lhs = rhs),
// and every bad input rejected with a ModelError that names the problem and points at it
// (file:line:column, moved to the offending character inside the expression).
#include "nhdyn/symbolic/spec_builder.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <string>

#include "nhdyn/core/error.hpp"
#include "nhdyn/symbolic/simplify.hpp"

namespace nhdyn::symbolic {
namespace {

using GiNaC::ex;

SpecBuilder sled() {
  SpecBuilder b("sled", {"sled.toml", 1, 1});
  b.coordinate("x").coordinate("y").coordinate("phi");
  b.parameter("m", 1.0, "kg").parameter("a", 0.5, "m").parameter("rho", 0.7, "m").parameter("g", 9.81);
  return b;
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

// The message of the ModelError thrown by f() contains every one of `parts`.
template <class F>
void expect_error(F&& f, std::initializer_list<std::string> parts) {
  const std::string message = error_of(f);
  for (const std::string& part : parts) EXPECT_NE(message.find(part), std::string::npos) << "'" << part << "' not in: " << message;
}

TEST(SpecBuilder, ReadsPrimesDecimalsAndConstants) {
  SpecBuilder b = sled();
  const Spec spec = b.kinetic_energy("0.5*m*(x'^2 + y'^2) + m*rho^2/2*phi'^2").build();
  const SymbolTable& S = spec.symbols;
  const ex m = S.parameter("m"), rho = S.parameter("rho");
  const ex xd = S.velocity(0), yd = S.velocity(1), w = S.velocity(2);
  // 0.5 is read exactly, so the difference is exactly zero, not 1e-17.
  EXPECT_TRUE(simplify(spec.kinetic_energy - (m * (xd * xd + yd * yd) / 2 + m * rho * rho * w * w / 2)).is_zero());
  EXPECT_TRUE(b.parse("1.25e-3 - 1/800").is_zero());
  EXPECT_TRUE(b.parse("2.5E+2 - 250").is_zero());
  EXPECT_TRUE(b.parse("cos(pi) + 1").is_zero());
  EXPECT_TRUE(simplify(b.parse("x''*t - x''*t + atan2(y, x) - atan2(y,x)")).is_zero());
  EXPECT_TRUE(simplify(b.parse("-x^2 + (x^2)") ).is_zero());
  EXPECT_TRUE(simplify(b.parse("-m*g + (-1)*g*m") + 2 * S.parameter("m") * S.parameter("g")).is_zero());
  // Names that are GiNaC literals elsewhere (I, the imaginary unit) are ordinary names here.
  SpecBuilder inertia("disc");
  inertia.coordinate("phi").parameter("I", 0.2);
  const ex half = inertia.parse("I/2*phi'^2");
  const ex I = inertia.kinetic_energy("I/2*phi'^2").build().symbols.parameter("I");
  EXPECT_TRUE(GiNaC::is_a<GiNaC::symbol>(I));
  EXPECT_TRUE(half.has(I));
  EXPECT_FALSE(half.has(GiNaC::I));
  // A leading sign binds like a product: -a*b/c + d.
  EXPECT_TRUE(simplify(b.parse("-a/m + g") - (-S.parameter("a") / m + S.parameter("g"))).is_zero());
}

TEST(SpecBuilder, ConstraintsWithEqualsAndInferredLevels) {
  SpecBuilder b = sled();
  b.kinetic_energy("m/2*(x'^2 + y'^2 + phi'^2)");
  b.constraint("blade", "y' = tan(phi)*x'");
  const Spec spec = b.build();
  ASSERT_EQ(spec.s(), 1);
  EXPECT_EQ(spec.constraints[0].level, ConstraintLevel::velocity);
  EXPECT_EQ(spec.constraints[0].text, "y' = tan(phi)*x'");
  const SymbolTable& S = spec.symbols;
  EXPECT_TRUE(simplify(spec.constraints[0].expression - (S.velocity(1) - GiNaC::tan(S.coordinate(2)) * S.velocity(0)))
                  .is_zero());

  SpecBuilder c = sled();
  c.kinetic_energy("m/2*(x'^2 + y'^2 + phi'^2)");
  c.constraint("p", "x^2 + y^2 = a^2").constraint("acc", "x'' + phi = 0");
  const Spec two = c.build();
  EXPECT_EQ(two.constraints[0].level, ConstraintLevel::position);
  EXPECT_EQ(two.constraints[1].level, ConstraintLevel::acceleration);
}

TEST(SpecBuilder, InitialValuesAndDefaults) {
  SpecBuilder b = sled();
  b.kinetic_energy("m/2*(x'^2 + y'^2 + phi'^2)");
  const Spec none = b.build();
  ASSERT_EQ(none.q0.size(), 3u);
  EXPECT_TRUE(none.q0[2].is_zero());
  b.initial("x", "0", "1").initial("y", "a", "0").initial("phi", "pi/4", "2*g");
  const Spec all = b.build();
  EXPECT_TRUE((all.q0[1] - all.symbols.parameter("a")).is_zero());
  EXPECT_TRUE((all.v0[2] - 2 * all.symbols.parameter("g")).is_zero());
}

TEST(SpecBuilderErrors, UnknownSymbolWithNearestNameAndColumn) {
  SpecBuilder b = sled();
  // 'rh0' starts at column 3 of the text, which starts at column 7 of line 12.
  expect_error([&] { b.kinetic_energy("m*rh0^2*phi'^2", {"model.toml", 12, 7}); },
               {"model.toml:12:9: kinetic energy T: unknown symbol 'rh0'; did you mean 'rho'?"});
  // Without a location, the column is spelled out.
  expect_error([&] { b.parse("m*rh0^2"); }, {"unknown symbol 'rh0'", "did you mean 'rho'?", "column 3"});
  // A far-off name gets no suggestion.
  const std::string message = error_of([&] { b.parse("zzzzzzz"); });
  EXPECT_NE(message.find("unknown symbol 'zzzzzzz'"), std::string::npos) << message;
  EXPECT_EQ(message.find("did you mean"), std::string::npos) << message;
  // Internal names are not a back door.
  expect_error([&] { b.parse("x__dot"); }, {"unknown symbol 'x__dot'"});
  // GiNaC's own literals are not names here.
  expect_error([&] { b.parse("Pi + I"); }, {"unknown symbol 'Pi'", "did you mean 'pi'?"});
}

TEST(SpecBuilderErrors, VelocityOrAccelerationOfUnknownCoordinate) {
  SpecBuilder b = sled();
  expect_error([&] { b.parse("m*u'^2", {"f.toml", 3, 1}); },
               {"f.toml:3:3: ", "'u'' is the velocity of 'u', which is not a coordinate"});
  expect_error([&] { b.parse("m''"); }, {"'m''' is the acceleration of 'm', which is a parameter, not a coordinate"});
  expect_error([&] { b.parse("phj'"); }, {"'phj'' is the velocity of 'phj'", "did you mean 'phi''?"});
  expect_error([&] { b.parse("x'''"); }, {"'x'''': only velocities"});
}

TEST(SpecBuilderErrors, SyntaxErrorsPointAtTheColumn) {
  SpecBuilder b = sled();
  const SourceLocation at{"m.toml", 5, 10};
  expect_error([&] { b.parse("m*(x'^2 + 1", at); }, {"m.toml:5:12: ", "syntax error", "'(' is never closed"});
  expect_error([&] { b.parse("m x'^2", at); }, {"m.toml:5:12: ", "missing operator between 'm' and 'x''"});
  expect_error([&] { b.parse("2 (x + y)", at); }, {"m.toml:5:12: ", "missing operator"});
  expect_error([&] { b.parse("x^-1", at); }, {"m.toml:5:12: ", "a sign directly after '^' needs parentheses"});
  expect_error([&] { b.parse("x*-y", at); }, {"m.toml:5:12: ", "needs parentheses"});
  expect_error([&] { b.parse("x^2^3", at); }, {"m.toml:5:13: ", "ambiguous"});
  expect_error([&] { b.parse("x + ", at); }, {"m.toml:5:14: ", "syntax error"});
  expect_error([&] { b.parse("x + y)", at); }, {"m.toml:5:15: ", "unmatched ')'"});
  expect_error([&] { b.parse("x @ y", at); }, {"m.toml:5:12: ", "unexpected character '@'"});
  // ** is a power too (SymPy's and Python's spelling), with ^'s rules.
  EXPECT_TRUE((b.parse("x**2*phi**(1/2)", at) - b.parse("x^2*phi^(1/2)", at)).is_zero());
  expect_error([&] { b.parse("x**2**3", at); }, {"m.toml:5:14: ", "ambiguous"});
  expect_error([&] { b.parse("x**-1", at); }, {"m.toml:5:13: ", "a sign directly after '**' needs parentheses"});
  expect_error([&] { b.parse("  ", at); }, {"m.toml:5:", "empty expression"});
  expect_error([&] { b.parse("x ' + y", at); }, {"m.toml:5:12: ", "prime must follow"});
  expect_error([&] { b.parse("x = y", at); }, {"m.toml:5:12: ", "unexpected '='"});
  // Functions.
  expect_error([&] { b.parse("sinn(phi)", at); }, {"m.toml:5:10: ", "unknown function 'sinn'; did you mean 'sin'?"});
  expect_error([&] { b.parse("atan2(y)", at); }, {"atan2 takes 2 arguments, not 1"});
  expect_error([&] { b.parse("m(x + 1)", at); }, {"'m' is not a function; write m*(...) for a product"});
  expect_error([&] { b.parse("sin*phi", at); }, {"'sin' is a function; write sin(...)"});
  expect_error([&] { b.parse("sin(phi", at); }, {"m.toml:5:13: ", "never closed"});
  // A multi-line text: the error is on the text's second line.
  expect_error([&] { b.parse("m*x'^2\n  + rh0", at); }, {"m.toml:6:5: ", "unknown symbol 'rh0'"});
}

TEST(SpecBuilderErrors, DuplicatedAndReservedNames) {
  SpecBuilder b = sled();
  expect_error([&] { b.coordinate("x", {"d.toml", 2, 3}); }, {"d.toml:2:3: ", "duplicated name", "'x' is already a coordinate"});
  expect_error([&] { b.parameter("phi", 1.0); }, {"duplicated name", "'phi' is already a coordinate"});
  expect_error([&] { b.parameter("m", 2.0); }, {"duplicated name", "'m' is already a parameter"});
  expect_error([&] { b.coordinate("rho"); }, {"duplicated name", "'rho' is already a parameter"});
  expect_error([&] { b.parameter("t", 1.0); }, {"'t' is the time"});
  expect_error([&] { b.parameter("pi", 3.0); }, {"'pi' is the constant pi"});
  expect_error([&] { b.parameter("sin", 1.0); }, {"'sin' is the name of a function"});
  expect_error([&] { b.coordinate("t"); }, {"'t' is the time"});
  expect_error([&] { b.parameter("k 2", 1.0); }, {"not a valid name"});
  expect_error([&] { b.parameter("x__dot", 1.0); }, {"not a valid name"});
  expect_error([&] { b.parameter("k", NAN); }, {"not a finite number"});
  b.kinetic_energy("m/2*(x'^2 + y'^2 + phi'^2)");
  b.constraint("blade", "y' - tan(phi)*x'", {"d.toml", 8, 1});
  expect_error([&] { b.constraint("blade", "x' - y'", {"d.toml", 9, 1}); },
               {"d.toml:9:1: constraint 'blade': duplicated constraint name 'blade' (first given at d.toml:8:1)"});
}

TEST(SpecBuilderErrors, ConstraintLevelMustMatchTheExpression) {
  SpecBuilder b = sled();
  const SourceLocation at{"c.toml", 4, 20};
  expect_error([&] { b.constraint("c", ConstraintLevel::position, "x + y'", at); },
               {"c.toml:4:24: constraint 'c': a position-level constraint may not contain velocities (found y')"});
  expect_error([&] { b.constraint("c", ConstraintLevel::position, "x + y''", at); },
               {"c.toml:4:24: ", "position-level constraint may not contain accelerations (found y'')"});
  expect_error([&] { b.constraint("c", ConstraintLevel::velocity, "x + y", at); },
               {"c.toml:4:20: constraint 'c': a velocity-level constraint must contain some velocity"});
  expect_error([&] { b.constraint("c", ConstraintLevel::velocity, "x' + phi''", at); },
               {"c.toml:4:25: ", "velocity-level constraint may not contain accelerations (found phi'')"});
  expect_error([&] { b.constraint("c", ConstraintLevel::acceleration, "x' + y", at); },
               {"c.toml:4:20: ", "acceleration-level constraint must contain some acceleration"});
  // A velocity that cancels does not count.
  expect_error([&] { b.constraint("c", ConstraintLevel::velocity, "x' - x' + y", at); }, {"must contain some velocity"});
  expect_error([&] { b.constraint("", ConstraintLevel::velocity, "x'", at); }, {"not a valid constraint name"});
  // A refused name's control characters are escaped: a line break broke the message's line.
  const std::string broken = error_of([&] { b.constraint("bl\nade\x1b", ConstraintLevel::velocity, "x'", at); });
  EXPECT_NE(broken.find("constraint 'bl\\nade\\x1b': not a valid constraint name"), std::string::npos) << broken;
  EXPECT_EQ(broken.find('\n'), std::string::npos) << broken;
  expect_error([&] { b.constraint("c", "x' = y' = phi'", at); }, {"c.toml:4:28: ", "at most one '='"});
  // The right-hand side of `=` keeps its columns.
  expect_error([&] { b.constraint("c", "x' = rh0", at); }, {"c.toml:4:25: ", "unknown symbol 'rh0'"});
}

TEST(SpecBuilderErrors, EnergiesAndForces) {
  SpecBuilder b = sled();
  expect_error([&] { b.potential_energy("m*g*x + x'", {"e.toml", 6, 8}); },
               {"e.toml:6:16: potential energy V: the potential energy may not contain velocities (found x')"});
  expect_error([&] { b.potential_energy("m*g*x''"); }, {"potential energy V", "accelerations (found x'')"});
  expect_error([&] { b.kinetic_energy("m/2*x'^2 + x''"); }, {"kinetic energy T", "accelerations (found x'')"});
  expect_error([&] { b.force("x", "-m*x''"); }, {"force on 'x'", "accelerations (found x'')"});
  expect_error([&] { b.force("u", "-m*x'", {"e.toml", 9, 1}); },
               {"e.toml:9:1: force on 'u': 'u' is not a coordinate"});
  expect_error([&] { b.force("phj", "0"); }, {"'phj' is not a coordinate; did you mean 'phi'?"});
  // Forces on one coordinate add up.
  b.kinetic_energy("m/2*(x'^2 + y'^2 + phi'^2)").force("x", "-a*x'").force("x", "g");
  const Spec spec = b.build();
  EXPECT_TRUE(simplify(spec.forces[0] - (-spec.symbols.parameter("a") * spec.symbols.velocity(0) +
                                         spec.symbols.parameter("g")))
                  .is_zero());
}

TEST(SpecBuilderErrors, IndependentCoordinates) {
  SpecBuilder b = sled();
  b.kinetic_energy("m/2*(x'^2 + y'^2 + phi'^2)").constraint("blade", "y' - tan(phi)*x'");
  const SourceLocation at{"i.toml", 11, 1};
  expect_error([&] { b.independent({"x", "phj"}, at); },
               {"i.toml:11:1: independent coordinates: 'phj' is not a coordinate; did you mean 'phi'?"});
  expect_error([&] { b.independent({"x", "x"}, at); }, {"i.toml:11:1: ", "duplicated: 'x' is listed twice"});
  b.independent({"x"}, at);
  expect_error([&] { b.build(); }, {"i.toml:11:1: independent coordinates: 1 given (x), but k = n - s = 3 - 1 = 2"});
  b.independent({"x", "y", "phi"}, at);
  expect_error([&] { b.build(); }, {"3 given", "k = n - s = 3 - 1 = 2"});
  b.independent({"x", "phi"}, at);
  EXPECT_NO_THROW(b.build());
}

TEST(SpecBuilderErrors, Complement) {
  SpecBuilder b = sled();
  b.kinetic_energy("m/2*(x'^2 + y'^2 + phi'^2)").constraint("blade", "y' - tan(phi)*x'");
  const SourceLocation at{"k.toml", 14, 1};
  b.complement({{"1", "tan(phi)", "0"}}, at);
  expect_error([&] { b.build(); }, {"k.toml:14:1: complement D: D is 1 x 3 but must be k x n = 2 x 3"});
  b.complement({{"1", "tan(phi)"}, {"0", "0"}}, at);
  expect_error([&] { b.build(); }, {"D is 2 x 2 but must be k x n = 2 x 3"});
  expect_error([&] { b.complement({{"1", "tan(phi)", "0"}, {"0", "1"}}, at); }, {"row 2 has 2 entries"});
  expect_error([&] { b.complement({{"1", "tan(ph)", "0"}, {"0", "0", "1"}}, at); },
               {"complement D, row 1, column 2", "unknown symbol 'ph'"});
  expect_error([&] { b.complement({{"1", "x''", "0"}, {"0", "0", "1"}}, at); }, {"accelerations (found x'')"});
  b.complement({{"1", "tan(phi)", "0"}, {"0", "0", "1"}}, at);
  EXPECT_NO_THROW(b.build());
}

TEST(SpecBuilderErrors, CompletenessChecks) {
  SpecBuilder empty("empty", {"x.toml", 1, 1});
  expect_error([&] { empty.build(); }, {"x.toml:1:1: model 'empty': no coordinates"});

  SpecBuilder b = sled();
  expect_error([&] { b.build(); }, {"sled.toml:1:1: model 'sled': missing kinetic energy T"});
  b.kinetic_energy("m/2*(x'^2 + y'^2 + phi'^2)");
  b.constraint("c1", "x'").constraint("c2", "y'").constraint("c3", "phi'");
  expect_error([&] { b.build(); }, {"model 'sled': 3 constraints for 3 coordinates", "s < n"});

  SpecBuilder c = sled();
  c.kinetic_energy("m/2*(x'^2 + y'^2 + phi'^2)");
  c.initial("x", "1", "0");
  expect_error([&] { c.build(); }, {"initial values are given for some coordinates but not for y, phi"});
  expect_error([&] { c.initial("y", "x", "0", {"x.toml", 3, 5}); },
               {"x.toml:3:5: initial value of 'y': an initial value may depend on the parameters only, not on 'x'"});
  expect_error([&] { c.initial("y", "0", "t", {"x.toml", 3, 5}); }, {"initial velocity of 'y'", "not on 't'"});
  expect_error([&] { c.initial("w", "0", "0"); }, {"initial value of 'w': 'w' is not a coordinate"});
  expect_error([&] { c.path("x", "yy"); }, {"'yy' is not a coordinate; did you mean 'y'?"});
  expect_error([&] { c.tolerances(-1.0, std::nullopt); }, {"rtol must be a positive number"});
}

}  // namespace
}  // namespace nhdyn::symbolic
