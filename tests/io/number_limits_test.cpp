// Inputs that used to end in an internal error or a hang now get a user error naming what is
// wrong (the CLI's exit 2), at once: a subnormal parameter value or literal (CLN's "floating
// point underflow", Tape::push's powi), and a product of powers of sums that multiplied out
// has millions of terms (minutes in expand) or thousands (seconds). Timed loosely (a hang is minutes; the refusal is
// milliseconds), so that the test fails on a hang, not on a slow machine.
#include <gtest/gtest.h>

#include <chrono>
#include <string>

#include "nhdyn/core/error.hpp"
#include "nhdyn/frontend/model_file.hpp"
#include "nhdyn/symbolic/compile.hpp"

namespace nhdyn {
namespace {

std::string oscillator(const std::string& T, const std::string& V, const std::string& m) {
  return "name = \"osc\"\ncoordinates = [\"x\", \"y\", \"z\"]\nkinetic_energy = \"" + T + "\"\npotential_energy = \"" +
         V + "\"\n[parameters]\nm = " + m +
         "\n[initial]\nposition = { x = 1, y = 0, z = 0 }\nvelocity = { x = 0, y = 0, z = 0 }\n";
}

// The message of the nhdyn::Error that loading and compiling throw ("" if none), and how long.
std::string refusal(const std::string& text, double& seconds) {
  const auto start = std::chrono::steady_clock::now();
  std::string message;
  try {
    symbolic::compile_model(load_model_string(text, "osc.toml"));
  } catch (const Error& e) {
    message = e.what();
  }
  seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return message;
}

TEST(NumberLimits, ASubnormalParameterIsAUserError) {
  double seconds = 0;
  const std::string m = refusal(oscillator("m/2*(x'^2+y'^2+z'^2)", "x^2", "1e-320"), seconds);
  EXPECT_NE(m.find("parameter 'm'"), std::string::npos) << m;
  EXPECT_NE(m.find("subnormal"), std::string::npos) << m;
}

TEST(NumberLimits, ASubnormalLiteralIsAUserError) {
  double seconds = 0;
  for (const char* V : {"x^4.9e-324", "1e-320*x^2", "0.00000000001e-310*x^2"}) {
    const std::string m = refusal(oscillator("m/2*(x'^2+y'^2+z'^2)", V, "1"), seconds);
    EXPECT_NE(m.find("smallest normal double"), std::string::npos) << V << ": " << m;
  }
  // Zero written with an exponent is zero, not an underflow.
  EXPECT_EQ(refusal(oscillator("m/2*(x'^2+y'^2+z'^2)", "0e-400*x^2 + x^2", "1"), seconds), "");
}

// A literal beyond 1.3e154, as a parameter's value: its square overflows (a turntable's rate of
// 1e200 wrote a column of NaN slip speeds with exit 0).
TEST(NumberLimits, AHugeLiteralIsAUserError) {
  double seconds = 0;
  for (const char* V : {"1e200*x^2", "x^2 - 2e154*y", "1.7e308*x^2"}) {
    const std::string m = refusal(oscillator("m/2*(x'^2+y'^2+z'^2)", V, "1"), seconds);
    EXPECT_NE(m.find("is too large: above 1.3e154 in magnitude its square"), std::string::npos) << V << ": " << m;
  }
  EXPECT_EQ(refusal(oscillator("m/2*(x'^2+y'^2+z'^2)", "1e154*x^2", "1"), seconds), "");
}

TEST(NumberLimits, AProductOfPowersOfSumsIsRefusedAtOnce) {
  double seconds = 0;
  const std::string m = refusal(oscillator("(x'^2+y'^2+z'^2)*(1+(x+y+z)^2)^32", "0", "1"), seconds);
  EXPECT_NE(m.find("multiplied out"), std::string::npos) << m;
  EXPECT_LT(seconds, 5.0);
}

// (x + y + z + m)^20 multiplies out to 1771 terms and T to about 5300: seconds of derivation
// (15 s in a release build for the sled's T times (x + y + phi + a)^30), refused at the 1000-term
// limit; a power of a sum of 138 terms loads.
TEST(NumberLimits, APowerOfASumOfThousandsOfTermsIsRefused) {
  double seconds = 0;
  const std::string m = refusal(oscillator("(x'^2+y'^2+z'^2)*(3+(x+y+z+m)^20)", "0", "1"), seconds);
  EXPECT_NE(m.find("multiplied out, this expression could have about 5.3e+03 terms (the limit is 1000)"),
            std::string::npos)
      << m;
  EXPECT_LT(seconds, 5.0);
  EXPECT_EQ(refusal(oscillator("(x'^2+y'^2+z'^2)*(3+(x+y+z)^8)", "0", "1"), seconds), "");
}

}  // namespace
}  // namespace nhdyn
