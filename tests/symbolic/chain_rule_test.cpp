// The chain rule given to GiNaC as its elementary functions' explicit derivative
// (symbolic/detail/chain_rule.hpp): each derivative is the expression GiNaC's own chain rule builds
// with its own partial derivatives (function::pderivative), term for term, and no function's
// explicit derivative is missing any more (GiNaC threw an exception per call for it).
#include "nhdyn/symbolic/detail/chain_rule.hpp"

#include <gtest/gtest.h>
#include <ginac/ginac.h>

#include <functional>
#include <string>
#include <vector>

namespace nhdyn::symbolic::chain_rule_test {
namespace {

using GiNaC::ex;

// GiNaC's partial derivative and explicit derivative of a call, protected members of its class
// function, named through a derived class.
struct Call : GiNaC::function {
  static ex partial(const GiNaC::function& f, unsigned i) { return (f.*&Call::pderivative)(i); }
  static ex explicit_derivative(const GiNaC::function& f, const GiNaC::symbol& s) {
    return (f.*&Call::expl_derivative)(s);
  }
};

struct Case {
  std::string name;
  std::function<ex(const std::vector<ex>&)> make;
  unsigned arguments;
};

TEST(ChainRule, EachDerivativeIsGiNaCsOwnChainRuleTermForTerm) {
  detail::install_chain_rule();
  const GiNaC::symbol x("x"), y("y");
  // Arguments that depend on x (and, for the second, on y only: a zero term of the chain rule).
  const std::vector<ex> u = {GiNaC::pow(x, 2) + 3 * x * y, GiNaC::sin(y) + x / 5};
  const std::vector<Case> cases = {
      {"sin", [](const std::vector<ex>& a) { return GiNaC::sin(a[0]); }, 1},
      {"cos", [](const std::vector<ex>& a) { return GiNaC::cos(a[0]); }, 1},
      {"tan", [](const std::vector<ex>& a) { return GiNaC::tan(a[0]); }, 1},
      {"exp", [](const std::vector<ex>& a) { return GiNaC::exp(a[0]); }, 1},
      {"log", [](const std::vector<ex>& a) { return GiNaC::log(a[0]); }, 1},
      {"asin", [](const std::vector<ex>& a) { return GiNaC::asin(a[0]); }, 1},
      {"acos", [](const std::vector<ex>& a) { return GiNaC::acos(a[0]); }, 1},
      {"atan", [](const std::vector<ex>& a) { return GiNaC::atan(a[0]); }, 1},
      {"atan2", [](const std::vector<ex>& a) { return GiNaC::atan2(a[0], a[1]); }, 2},
      {"sinh", [](const std::vector<ex>& a) { return GiNaC::sinh(a[0]); }, 1},
      {"cosh", [](const std::vector<ex>& a) { return GiNaC::cosh(a[0]); }, 1},
      {"tanh", [](const std::vector<ex>& a) { return GiNaC::tanh(a[0]); }, 1},
  };
  for (const Case& c : cases) {
    const ex call = c.make(u);
    ASSERT_TRUE(GiNaC::is_exactly_a<GiNaC::function>(call)) << c.name;
    const auto& f = GiNaC::ex_to<GiNaC::function>(call);
    for (const GiNaC::symbol& s : {x, y}) {
      // GiNaC's chain rule (function::derivative when no explicit derivative exists).
      ex expected;
      for (unsigned i = 0; i < c.arguments; ++i) {
        const ex d = f.op(i).diff(s);
        if (!d.is_zero()) expected += Call::partial(f, i) * d;
      }
      ex got;
      ASSERT_NO_THROW(got = Call::explicit_derivative(f, s)) << c.name << " has no explicit derivative";
      EXPECT_TRUE(got.is_equal(expected)) << c.name << " d/d" << s << ": " << got << " against GiNaC's " << expected;
      EXPECT_TRUE(call.diff(s).is_equal(expected)) << c.name;
    }
  }
}

// A nested expression: the second derivative through the installed rule, against the closed form
// d^2/dx^2 sin(cos(x)) = -sin(x)^2 sin(cos(x)) - cos(x) cos(cos(x)), written out by hand.
TEST(ChainRule, NestedSecondDerivativeIsTheClosedForm) {
  detail::install_chain_rule();
  const GiNaC::symbol x("x");
  const ex e = GiNaC::sin(GiNaC::cos(x));
  const ex closed = -GiNaC::pow(GiNaC::sin(x), 2) * GiNaC::sin(GiNaC::cos(x)) - GiNaC::cos(x) * GiNaC::cos(GiNaC::cos(x));
  EXPECT_TRUE((e.diff(x, 2) - closed).expand().is_zero()) << e.diff(x, 2);
  // abs keeps GiNaC's own derivative (it is not given one here): its value at x = -2 is -1.
  const ex d_abs = GiNaC::abs(x).diff(x);
  EXPECT_EQ(GiNaC::ex_to<GiNaC::numeric>(GiNaC::evalf(d_abs.subs(x == -2))).to_double(), -1.0) << d_abs;
}

}  // namespace
}  // namespace nhdyn::symbolic::chain_rule_test
