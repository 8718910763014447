// GiNaC's derivative without the terms that are 0 (derivative.hpp).
#include "nhdyn/symbolic/detail/derivative.hpp"

#include <memory_resource>
#include <unordered_map>
#include <utility>

#include "nhdyn/symbolic/detail/kind.hpp"
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
  const ExKind kind = kind_of(e);
  if (kind == ExKind::add || kind == ExKind::mul) {
    for (const GiNaC::expair& p : Pairs::of(e))
      if (contains(p.rest, s)) return true;
    return false;  // the coefficients and the number are numbers
  }
  // An object of another class than s's is not equal to it (basic::is_equal compares the classes
  // first), and a number or a symbol has no operands.
  if (kind == ExKind::numeric) return false;
  if (kind == ExKind::symbol) return e.is_equal(s);
  const std::size_t n = e.nops();
  if (n == 0) return e.is_equal(s);
  for (std::size_t i = 0; i < n; ++i)
    if (contains(e.op(i), s)) return true;
  return false;
}

// The memo of this thread while a DerivativeMemo lives, by the address of the object differentiated.
struct Remembered {
  ex e;  // the object differentiated, held so that its address stays its own
  ex s;
  ex derivative;
};
// Its entries' memory is given back at once when it ends: it is only ever added to.
struct Memo {
  std::pmr::monotonic_buffer_resource arena;
  std::pmr::unordered_multimap<const GiNaC::basic*, Remembered> entries{&arena};
};
thread_local Memo* active_memo = nullptr;

// derivative_of_container() by the rules, without the memo.
ex by_rules(const ex& e, const GiNaC::symbol& s) {
  const ExKind kind = kind_of(e);
  if (kind == ExKind::add) {
    // add::derivative: each term's rest differentiated, with its coefficient.
    GiNaC::epvector terms;
    terms.reserve(Pairs::of(e).size());
    for (const GiNaC::expair& p : Pairs::of(e)) terms.push_back(GiNaC::expair(derivative(p.rest, s), p.coeff));
    return GiNaC::dynallocate<GiNaC::add>(std::move(terms));
  }
  if (kind == ExKind::mul) {
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
  if (kind == ExKind::power && kind_of(e.op(1)) == ExKind::numeric) {
    // power::derivative for a number exponent r: D(b^r) = r b^(r - 1) D(b).
    const ex& base = e.op(0);
    const ex& r = e.op(1);
    GiNaC::epvector factors{GiNaC::expair(base, r - 1), GiNaC::expair(derivative_of_container(base, s), 1)};
    return GiNaC::dynallocate<GiNaC::mul>(std::move(factors), r);
  }
  return e.diff(s);
}

}  // namespace

DerivativeMemo::DerivativeMemo() {
  if (active_memo != nullptr) return;
  active_memo = new Memo;
  active_ = true;
}

DerivativeMemo::~DerivativeMemo() {
  if (!active_) return;
  delete active_memo;
  active_memo = nullptr;
}

// The factors of a product are tested before they are differentiated, and not again here.
ex derivative_of_container(const ex& e, const GiNaC::symbol& s) {
  // A symbol's or a number's derivative costs less than looking it up. Only objects held more than
  // once are remembered: one held by its parent alone comes again only with its parent, which the
  // memo answers first where it is shared (a large model's many small terms would only fill it).
  const GiNaC::basic* key = &GiNaC::ex_to<GiNaC::basic>(e);
  if (active_memo == nullptr || e.nops() == 0 || key->get_refcount() < 2) return by_rules(e, s);
  const auto [begin, end] = active_memo->entries.equal_range(key);
  for (auto it = begin; it != end; ++it)
    if (it->second.s.is_equal(s)) return it->second.derivative;
  const ex d = by_rules(e, s);
  active_memo->entries.emplace(key, Remembered{e, s, d});
  return d;
}

ex derivative(const ex& e, const GiNaC::symbol& s) { return contains(e, s) ? derivative_of_container(e, s) : ex(0); }

}  // namespace nhdyn::symbolic::detail
