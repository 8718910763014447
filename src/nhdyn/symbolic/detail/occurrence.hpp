// Which symbols an expression contains, found in one walk of the expression. The derivation of a
// large model (a chain of a thousand bodies) must differentiate each term only by the symbols it
// contains: asking GiNaC's has() once per coordinate is a walk per coordinate, quadratic in the
// size of the model.
// Internal: a helper of the derivation, not part of the public API (nhdyn/nhdyn.hpp).
#pragma once

#include <ginac/ginac.h>

#include <set>
#include <unordered_map>
#include <vector>

#include "nhdyn/symbolic/spec.hpp"

namespace nhdyn::symbolic {

using SymbolSet = std::set<GiNaC::ex, GiNaC::ex_is_less>;

// Every symbol that `e` contains.
SymbolSet symbols_of(const GiNaC::ex& e);

// The time, coordinates, velocities and accelerations of `e`, as indices into the coordinates.
struct Contained {
  bool time = false;
  std::vector<int> q, v, a;  // ascending, without repetition
};

// Finds the mechanical symbols of expressions of one spec by the symbol table's indices.
class SymbolIndex {
 public:
  explicit SymbolIndex(const SymbolTable& symbols);
  Contained find(const GiNaC::ex& e) const;
  // True when `e` is one of the velocities.
  bool is_velocity(const GiNaC::ex& e) const;

 private:
  enum class Kind { time, q, v, a };
  struct Entry {
    GiNaC::ex symbol;
    Kind kind;
    int i;
  };
  std::unordered_multimap<unsigned, Entry> index_;  // by the symbol's GiNaC hash
  const Entry* lookup(const GiNaC::ex& leaf) const;
};

}  // namespace nhdyn::symbolic
