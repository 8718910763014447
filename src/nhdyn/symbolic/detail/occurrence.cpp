#include "nhdyn/symbolic/detail/occurrence.hpp"

#include <algorithm>

#include "nhdyn/symbolic/detail/kind.hpp"
#include "nhdyn/symbolic/detail/pairs.hpp"

namespace nhdyn::symbolic {
namespace {

// Calls f on every leaf of e (symbols, numbers, constants), shared ones as often as they occur.
// The pairs of sums and products are walked as GiNaC keeps them (detail/pairs.hpp): their
// coefficients and exponents are numbers, so the symbols are in the rests.
template <class F>
void for_each_leaf(const GiNaC::ex& e, F& f) {
  const detail::ExKind kind = detail::kind_of(e);
  if (kind == detail::ExKind::add || kind == detail::ExKind::mul) {
    for (const GiNaC::expair& p : detail::Pairs::of(e)) for_each_leaf(p.rest, f);
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
    const detail::ExKind kind = detail::kind_of(leaf);
    if (kind == detail::ExKind::symbol || (kind == detail::ExKind::other && GiNaC::is_a<GiNaC::symbol>(leaf)))
      out.insert(leaf);
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

// By GiNaC's hash of a symbol (from its serial number, the same in every copy), then equality.
const SymbolIndex::Entry* SymbolIndex::lookup(const GiNaC::ex& leaf) const {
  const auto [begin, end] = index_.equal_range(leaf.gethash());
  for (auto it = begin; it != end; ++it)
    if (it->second.symbol.is_equal(leaf)) return &it->second;
  return nullptr;
}

bool SymbolIndex::is_velocity(const GiNaC::ex& e) const {
  const Entry* entry = lookup(e);
  return entry != nullptr && entry->kind == Kind::v;
}

Contained SymbolIndex::find(const GiNaC::ex& e) const {
  Contained out;
  const auto record = [&](const GiNaC::ex& leaf) {
    if (detail::kind_of(leaf) == detail::ExKind::numeric) return;  // equal to no symbol of the index
    const Entry* entry = lookup(leaf);
    if (entry == nullptr) return;
    switch (entry->kind) {
      case Kind::time: out.time = true; break;
      case Kind::q: out.q.push_back(entry->i); break;
      case Kind::v: out.v.push_back(entry->i); break;
      case Kind::a: out.a.push_back(entry->i); break;
    }
  };
  for_each_leaf(e, record);
  sort_unique(out.q);
  sort_unique(out.v);
  sort_unique(out.a);
  return out;
}

}  // namespace nhdyn::symbolic
