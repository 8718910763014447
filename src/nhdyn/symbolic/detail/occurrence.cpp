#include "nhdyn/symbolic/detail/occurrence.hpp"

#include <algorithm>

namespace nhdyn::symbolic {
namespace {

// The pairs of a sum or a product as GiNaC keeps them: op(i) would build c x for each term with a
// coefficient and x^k for each factor with an exponent, a temporary per operand. The coefficients
// and exponents are numbers, so the symbols are in the pairs' rests.
struct Pairs : GiNaC::expairseq {
  static const GiNaC::epvector& of(const GiNaC::ex& e) { return GiNaC::ex_to<GiNaC::expairseq>(e).*(&Pairs::seq); }
};

// Calls f on every leaf of e (symbols, numbers, constants), shared ones as often as they occur.
template <class F>
void for_each_leaf(const GiNaC::ex& e, F& f) {
  if (GiNaC::is_exactly_a<GiNaC::add>(e) || GiNaC::is_exactly_a<GiNaC::mul>(e)) {
    for (const GiNaC::expair& p : Pairs::of(e)) for_each_leaf(p.rest, f);
    return;
  }
  const std::size_t n = e.nops();
  if (n == 0) {
    f(e);
    return;
  }
  for (std::size_t i = 0; i < n; ++i) for_each_leaf(e.op(i), f);
}

void sort_unique(std::vector<int>& indices) {
  std::sort(indices.begin(), indices.end());
  indices.erase(std::unique(indices.begin(), indices.end()), indices.end());
}

}  // namespace

SymbolSet symbols_of(const GiNaC::ex& e) {
  SymbolSet out;
  const auto collect = [&](const GiNaC::ex& leaf) {
    if (GiNaC::is_a<GiNaC::symbol>(leaf)) out.insert(leaf);
  };
  for_each_leaf(e, collect);
  return out;
}

SymbolIndex::SymbolIndex(const SymbolTable& symbols) {
  const auto add = [&](const GiNaC::symbol& x, Kind kind, int i) {
    index_.emplace(x.gethash(), Entry{x, kind, i});
  };
  add(symbols.time(), Kind::time, 0);
  for (int i = 0; i < symbols.coordinates(); ++i) {
    add(symbols.coordinate(i), Kind::q, i);
    add(symbols.velocity(i), Kind::v, i);
    add(symbols.acceleration(i), Kind::a, i);
  }
}

Contained SymbolIndex::find(const GiNaC::ex& e) const {
  Contained out;
  const auto record = [&](const GiNaC::ex& leaf) {
    // By GiNaC's hash of a symbol (from its serial number, the same in every copy), then equality.
    const auto [begin, end] = index_.equal_range(leaf.gethash());
    for (auto it = begin; it != end; ++it) {
      const Entry& entry = it->second;
      if (!entry.symbol.is_equal(leaf)) continue;
      switch (entry.kind) {
        case Kind::time: out.time = true; break;
        case Kind::q: out.q.push_back(entry.i); break;
        case Kind::v: out.v.push_back(entry.i); break;
        case Kind::a: out.a.push_back(entry.i); break;
      }
      return;
    }
  };
  for_each_leaf(e, record);
  sort_unique(out.q);
  sort_unique(out.v);
  sort_unique(out.a);
  return out;
}

}  // namespace nhdyn::symbolic
