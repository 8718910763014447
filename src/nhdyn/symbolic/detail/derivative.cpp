// GiNaC's derivative without the terms that are 0 (derivative.hpp).
#include "nhdyn/symbolic/detail/derivative.hpp"

#include <utility>

#include "nhdyn/symbolic/detail/pairs.hpp"

namespace nhdyn::symbolic::detail {
namespace {

using GiNaC::ex;

// A product's split of a factor into a pair: a protected member of GiNaC's class, which a derived
// class may name.
struct Product : GiNaC::mul {
  static GiNaC::expair split(const ex& product, const ex& factor) {
    return (GiNaC::ex_to<GiNaC::mul>(product).*(&Product::split_ex_to_pair))(factor);
  }
};

bool contains(const ex& e, const GiNaC::symbol& s) {
  if (GiNaC::is_exactly_a<GiNaC::add>(e) || GiNaC::is_exactly_a<GiNaC::mul>(e)) {
    for (const GiNaC::expair& p : Pairs::of(e))
      if (contains(p.rest, s)) return true;
    return false;  // the coefficients and the number are numbers
  }
  const std::size_t n = e.nops();
  if (n == 0) return e.is_equal(s);
  for (std::size_t i = 0; i < n; ++i)
    if (contains(e.op(i), s)) return true;
  return false;
}

}  // namespace

// The factors of a product are tested before they are differentiated, and not again here.
ex derivative_of_container(const ex& e, const GiNaC::symbol& s) {
  if (GiNaC::is_exactly_a<GiNaC::add>(e)) {
    // add::derivative: each term's rest differentiated, with its coefficient.
    GiNaC::epvector terms;
    terms.reserve(Pairs::of(e).size());
    for (const GiNaC::expair& p : Pairs::of(e)) terms.push_back(GiNaC::expair(derivative(p.rest, s), p.coeff));
    return GiNaC::dynallocate<GiNaC::add>(std::move(terms));
  }
  if (GiNaC::is_exactly_a<GiNaC::mul>(e)) {
    // mul::derivative: the product with each factor in turn replaced by its derivative, here only
    // the factors that contain s (the others' products are 0 and drop out of the sum).
    const GiNaC::epvector& factors = Pairs::of(e);
    GiNaC::exvector terms;
    GiNaC::epvector product = factors;
    for (std::size_t i = 0; i < factors.size(); ++i) {
      const GiNaC::expair& f = factors[i];
      if (!contains(f.rest, s)) continue;
      GiNaC::expair d = Product::split(e, GiNaC::pow(f.rest, f.coeff - 1) * derivative_of_container(f.rest, s));
      d.swap(product[i]);
      terms.push_back(GiNaC::dynallocate<GiNaC::mul>(product, Pairs::number(e) * f.coeff));
      d.swap(product[i]);
    }
    return GiNaC::dynallocate<GiNaC::add>(terms);
  }
  if (GiNaC::is_exactly_a<GiNaC::power>(e) && GiNaC::is_exactly_a<GiNaC::numeric>(e.op(1))) {
    // power::derivative for a number exponent r: D(b^r) = r b^(r - 1) D(b).
    const ex& base = e.op(0);
    const ex& r = e.op(1);
    GiNaC::epvector factors{GiNaC::expair(base, r - 1), GiNaC::expair(derivative_of_container(base, s), 1)};
    return GiNaC::dynallocate<GiNaC::mul>(std::move(factors), r);
  }
  return e.diff(s);
}

ex derivative(const ex& e, const GiNaC::symbol& s) { return contains(e, s) ? derivative_of_container(e, s) : ex(0); }

}  // namespace nhdyn::symbolic::detail
