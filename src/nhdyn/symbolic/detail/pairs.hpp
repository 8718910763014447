// The sums and products of GiNaC as GiNaC keeps them, for walks that must not build anything.
// Internal: a helper of the symbolic front end, not part of the public API (nhdyn/nhdyn.hpp).
#pragma once

#include <ginac/ginac.h>

namespace nhdyn::symbolic::detail {

// A sum or a product (is_exactly_a<add> or <mul>): its pairs, a term being coefficient * rest and
// a factor rest ^ exponent with the coefficients and exponents numbers, and its number (the sum's
// constant, the product's coefficient). op(i) builds each term c x and each factor x^k anew.
// Protected members of GiNaC's class, which a derived class may name.
struct Pairs : GiNaC::expairseq {
  static const GiNaC::epvector& of(const GiNaC::ex& e) { return GiNaC::ex_to<GiNaC::expairseq>(e).*(&Pairs::seq); }
  static const GiNaC::ex& number(const GiNaC::ex& e) {
    return GiNaC::ex_to<GiNaC::expairseq>(e).*(&Pairs::overall_coeff);
  }
};

}  // namespace nhdyn::symbolic::detail
