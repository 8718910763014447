// GiNaC's derivative of an expression by a symbol, the same expression, made with less work. A
// derivation spends a quarter of its time in GiNaC's product rule, which builds a term for every
// factor of a product (D(a b c) = D(a) b c + a D(b) c + a b D(c)), only for evaluation to find
// that the factors without the symbol give 0: the terms of a large model's T, V and constraints
// have a few factors each and most of them do not contain the symbol differentiated by.
// Internal: a helper of the derivation, not part of the public API (nhdyn/nhdyn.hpp).
#pragma once

#include <ginac/ginac.h>

namespace nhdyn::symbolic::detail {

// e.diff(s): sums, products and powers with a number exponent by GiNaC's own rules (add::, mul::
// and power::derivative), without the terms of the subexpressions that do not contain s, which are
// 0; everything else by GiNaC.
// tests/symbolic/derivative_test.cpp compares the two.
GiNaC::ex derivative(const GiNaC::ex& e, const GiNaC::symbol& s);
// The same for an `e` that contains s (a term listed as holding it): e is not searched for it first.
GiNaC::ex derivative_of_container(const GiNaC::ex& e, const GiNaC::symbol& s);

}  // namespace nhdyn::symbolic::detail
