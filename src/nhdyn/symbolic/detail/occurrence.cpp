#include "nhdyn/symbolic/detail/occurrence.hpp"

#include <algorithm>

namespace nhdyn::symbolic {
namespace {

void collect(const GiNaC::ex& e, SymbolSet& out) {
  if (GiNaC::is_a<GiNaC::symbol>(e)) {
    out.insert(e);
    return;
  }
  for (std::size_t i = 0; i < e.nops(); ++i) collect(e.op(i), out);
}

void sort_unique(std::vector<int>& indices) {
  std::sort(indices.begin(), indices.end());
  indices.erase(std::unique(indices.begin(), indices.end()), indices.end());
}

}  // namespace

SymbolSet symbols_of(const GiNaC::ex& e) {
  SymbolSet out;
  collect(e, out);
  return out;
}

SymbolIndex::SymbolIndex(const SymbolTable& symbols) {
  index_.emplace(symbols.time(), std::make_pair(Kind::time, 0));
  for (int i = 0; i < symbols.coordinates(); ++i) {
    index_.emplace(symbols.coordinate(i), std::make_pair(Kind::q, i));
    index_.emplace(symbols.velocity(i), std::make_pair(Kind::v, i));
    index_.emplace(symbols.acceleration(i), std::make_pair(Kind::a, i));
  }
}

Contained SymbolIndex::find(const GiNaC::ex& e) const {
  Contained out;
  for (const GiNaC::ex& symbol : symbols_of(e)) {
    const auto found = index_.find(symbol);
    if (found == index_.end()) continue;
    const auto [kind, i] = found->second;
    switch (kind) {
      case Kind::time: out.time = true; break;
      case Kind::q: out.q.push_back(i); break;
      case Kind::v: out.v.push_back(i); break;
      case Kind::a: out.a.push_back(i); break;
    }
  }
  sort_unique(out.q);
  sort_unique(out.v);
  sort_unique(out.a);
  return out;
}

}  // namespace nhdyn::symbolic
