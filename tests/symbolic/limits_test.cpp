// Inputs that would make the derivation run away (huge symbolic powers) are refused with a
// located error instead of hanging.
#include <gtest/gtest.h>

#include <string>

#include "nhdyn/core/error.hpp"
#include "nhdyn/symbolic/spec_builder.hpp"

namespace nhdyn::symbolic {
namespace {

TEST(Limits, HugeExponentsAreRefusedWithTheirLocation) {
  SpecBuilder b("a");
  b.coordinate("x");
  try {
    b.kinetic_energy("x'^2*(1+x)^999999", SourceLocation{"m.toml", 3, 19});
    FAIL() << "expected ModelError";
  } catch (const ModelError& e) {
    EXPECT_NE(std::string(e.what()).find("m.toml:3:"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("exponent larger than 64"), std::string::npos) << e.what();
  }
  // Ordinary powers are fine.
  SpecBuilder ok("b");
  ok.coordinate("x");
  EXPECT_NO_THROW(ok.kinetic_energy("x'^2*(1+x)^3/2"));
}

}  // namespace
}  // namespace nhdyn::symbolic
