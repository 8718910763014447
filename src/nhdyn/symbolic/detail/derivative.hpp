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

// While it lives, the derivatives that derivative() and derivative_of_container() take on this
// thread are remembered by the object differentiated and the symbol, and the same object
// differentiated again by the same symbol gives the expression made the first time: the same
// expression, since a derivative depends on the expression and the symbol alone. A derivation
// differentiates the same subexpressions many times: GiNaC shares the parts of an expression that
// an operation leaves as they are, so the rotations that a multibody T is built of stand in every
// dT/dq'_i, and d/dq_j of each is taken for every i. The memo holds each object it has seen, so
// that no other object can take its address while it lives, and so it holds memory: it lives for
// a stage of the multibody front end, the derivation or the compilation, not longer. A memo made while another lives on
// the thread adds nothing: the first one serves both.
class DerivativeMemo {
 public:
  DerivativeMemo();
  ~DerivativeMemo();
  DerivativeMemo(const DerivativeMemo&) = delete;
  DerivativeMemo& operator=(const DerivativeMemo&) = delete;

 private:
  bool active_ = false;
};

}  // namespace nhdyn::symbolic::detail
