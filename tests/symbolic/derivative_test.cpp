// The derivation's derivative (symbolic/detail/derivative.hpp) is GiNaC's own e.diff(s), the same
// expression node for node: on terms of the shapes a derivation differentiates (products with
// factors that do and do not contain the symbol, powers, sums nested in products, functions of
// sums, roots, a symbol that does not occur) and on every entry a small model's derivation makes.
#include "nhdyn/symbolic/detail/derivative.hpp"

#include <gtest/gtest.h>
#include <ginac/ginac.h>

#include <sstream>
#include <string>
#include <vector>

#include "nhdyn/symbolic/derivation.hpp"
#include "nhdyn/symbolic/detail/chain_rule.hpp"
#include "nhdyn/symbolic/spec_builder.hpp"

namespace nhdyn::symbolic::derivative_test {
namespace {

using GiNaC::ex;

std::string printed(const ex& e) {
  std::ostringstream out;
  out << e;
  return out.str();
}

TEST(Derivative, IsGiNaCsDerivativeNodeForNode) {
  detail::install_chain_rule();
  const GiNaC::symbol x("x"), y("y"), v("v"), w("w"), m("m"), a("a");
  const std::vector<ex> terms = {
      m * a * v * (GiNaC::cos(x) * w - GiNaC::sin(x) * v),
      GiNaC::numeric(1, 2) * m * (GiNaC::pow(v, 2) + GiNaC::pow(w, 2)),
      GiNaC::numeric(1, 2) * (m * GiNaC::pow(a, 2) + 3) * GiNaC::pow(w, 2),
      -3 * m * GiNaC::pow(x, 3) * GiNaC::pow(y, 2) * GiNaC::sin(x * y + a),
      x + y * GiNaC::cos(x) - a * GiNaC::sin(y) + 7,
      GiNaC::sqrt(1 - GiNaC::pow(GiNaC::sin(x) * GiNaC::cos(y), 2)) * v * m,
      GiNaC::pow(x - y, -2) * GiNaC::exp(a * x) * (x + w),
      m * a * v,  // without x
      GiNaC::pow(x, y) * GiNaC::atan2(y, x),
      (x + y) * (x - y) * (x * a + 1),
  };
  for (const ex& e : terms)
    for (const GiNaC::symbol& s : {x, y, v, w, m}) {
      const ex ours = detail::derivative(e, s);
      EXPECT_TRUE(ours.is_equal(e.diff(s))) << "d/d" << s << " of " << e << ": " << ours << " vs " << e.diff(s);
      if (e.has(s)) {
        EXPECT_TRUE(detail::derivative_of_container(e, s).is_equal(e.diff(s))) << e << " by " << s;
      }
    }
}

// With a memo, a subexpression shared by several expressions (as the parts of T are by its
// derivatives) is differentiated once by each symbol: the expressions are GiNaC's all the same,
// asked once or twice, and a memo made inside another leaves the outer one at work.
TEST(Derivative, AMemoGivesTheSameExpressions) {
  detail::install_chain_rule();
  const GiNaC::symbol x("x"), y("y"), v("v"), m("m");
  const ex shared = GiNaC::cos(x) * y * v - GiNaC::sin(x) * GiNaC::pow(x + y, 2);
  const std::vector<ex> terms = {m * shared * v, GiNaC::pow(shared, 2) * y, shared + GiNaC::sqrt(1 + shared * x)};
  const detail::DerivativeMemo memo;
  for (int pass = 0; pass < 2; ++pass) {
    const detail::DerivativeMemo inner;
    for (const ex& e : terms)
      for (const GiNaC::symbol& s : {x, y, v}) {
        EXPECT_TRUE(detail::derivative(e, s).is_equal(e.diff(s))) << "d/d" << s << " of " << e;
        EXPECT_TRUE(detail::derivative(e, s).is_equal(e.diff(s))) << "again, d/d" << s << " of " << e;
      }
  }
}

TEST(Derivative, LeavesADerivationAsGiNaCMadeIt) {
  // The sleigh of docs/gallery: T with products of sines and velocities, a velocity constraint.
  SpecBuilder b("sleigh");
  b.coordinate("x").coordinate("y").coordinate("theta");
  b.parameter("m", 1.0).parameter("J", 0.1).parameter("a", 0.2);
  b.kinetic_energy("m/2*(x'^2 + y'^2) + m*a*theta'*(cos(theta)*y' - sin(theta)*x') + (J + m*a^2)/2*theta'^2");
  b.constraint("blade", "-sin(theta)*x' + cos(theta)*y'");
  const Spec spec = b.build();
  const Derivation d = derive(spec);
  const SymbolTable& symbols = spec.symbols;
  for (int i = 0; i < spec.n(); ++i) {
    const GiNaC::symbol& q = symbols.coordinate(i);
    for (const ex& e : {d.G(static_cast<unsigned>(i), 0), d.b0(0, 0), d.b(0, static_cast<unsigned>(i))}) {
      EXPECT_TRUE(detail::derivative(e, q).is_equal(e.diff(q))) << e;
      EXPECT_EQ(printed(detail::derivative(e, q)), printed(e.diff(q)));
    }
  }
}

}  // namespace
}  // namespace nhdyn::symbolic::derivative_test
