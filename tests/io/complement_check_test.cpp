// An analytic complement D given in a model file is checked where it is given (derive, at the
// initial state with the parameter values): D b^T = 0 and [D; b] of full rank, else a ModelError
// with the residual. The sled's blade b = (-sin phi, cos phi, 0): D = [[cos phi, sin phi, 0],
// [0, 0, 1]] is right; rows that are not orthogonal to b, or that repeat, are refused.
#include <gtest/gtest.h>

#include <string>

#include "nhdyn/core/error.hpp"
#include "nhdyn/frontend/model_file.hpp"
#include "nhdyn/symbolic/derivation.hpp"

namespace nhdyn {
namespace {

std::string sled(const std::string& complement) {
  return R"toml(name = "sled"
coordinates = ["x", "y", "phi"]
kinetic_energy = "m/2 * (x'^2 + y'^2) + m*a*phi' * (cos(phi)*y' - sin(phi)*x') + m*rho^2/2 * phi'^2"
complement = )toml" + complement + R"toml(
[parameters]
m = 1.0
a = 0.5
rho = 0.7
[[constraints]]
name = "blade"
velocity = "-sin(phi)*x' + cos(phi)*y'"
[initial]
position = { x = 0, y = 0, phi = 0.3 }
velocity = { x = "cos(0.3)", y = "sin(0.3)", phi = 1.0 }
)toml";
}

std::string refusal(const std::string& complement) {
  try {
    symbolic::derive(load_model_string(sled(complement), "sled.toml"));
  } catch (const ModelError& e) {
    return e.what();
  }
  return "";
}

TEST(AnalyticComplement, ARightOneIsAccepted) {
  EXPECT_EQ(refusal(R"d([["cos(phi)", "sin(phi)", 0], [0, 0, 1]])d"), "");
}

TEST(AnalyticComplement, OneNotOrthogonalToBIsRefusedWithItsResidual) {
  // Row 1 = (1, 0, 0): D b^T = -sin(0.3) = -0.2955 against the blade.
  const std::string m = refusal(R"d([[1, 0, 0], [0, 0, 1]])d");
  EXPECT_NE(m.find("D b^T is not zero"), std::string::npos) << m;
  EXPECT_NE(m.find("'blade'"), std::string::npos) << m;
  EXPECT_NE(m.find("-0.296"), std::string::npos) << m;
}

TEST(AnalyticComplement, ARankDeficientOneIsRefused) {
  const std::string m = refusal(R"d([["cos(phi)", "sin(phi)", 0], ["2*cos(phi)", "2*sin(phi)", 0]])d");
  EXPECT_NE(m.find("rank deficient"), std::string::npos) << m;
}

}  // namespace
}  // namespace nhdyn
