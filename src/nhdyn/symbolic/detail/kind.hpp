// The class of a GiNaC object, found with one look-up where a chain of is_exactly_a<T> and is_a<T>
// would compare type names. A failed type test of GiNaC (typeid(*p) == typeid(T), or the
// dynamic_cast of is_a<T>) compares the two classes' mangled names with strcmp, and a walk over
// a large model's terms asks "a sum? a product? a power?" of every node on its way: a chain of
// failed tests per leaf. Here the answer is the chain's own, computed by GiNaC's tests the first
// time an object of a class is seen on this thread and then read back by the address of the
// class's type_info, an exact key (one type_info object is one class; should a class have two,
// each is looked up once).
// Internal: a helper of the symbolic front end, not part of the public API (nhdyn/nhdyn.hpp).
#pragma once

#include <ginac/ginac.h>

#include <array>
#include <cstddef>
#include <cstdint>
#include <typeinfo>

namespace nhdyn::symbolic::detail {

enum class ExKind : std::uint8_t {
  numeric,   // is_exactly_a<numeric>
  add,       // is_exactly_a<add>
  mul,       // is_exactly_a<mul>
  power,     // is_exactly_a<power>
  symbol,    // is_exactly_a<symbol>
  function,  // is_exactly_a<function>
  constant,  // is_exactly_a<constant>
  other,     // none of these (a subclass of symbol or function among them: ask is_a<> of it)
};

// The chain of is_exactly_a<> above, the first time a class is seen on this thread.
ExKind tested_kind_of(const GiNaC::ex& e);

// The classes seen on this thread, by their type_info's address: a model's expressions hold a
// handful of classes. Past the table's size a class is tested each time.
struct SeenKinds {
  std::array<const std::type_info*, 16> type{};
  std::array<ExKind, 16> kind{};
  std::size_t size = 0;
};
inline thread_local SeenKinds seen_kinds;

// The kind of `e` (the chain of is_exactly_a<> above, answered by one look-up).
inline ExKind kind_of(const GiNaC::ex& e) {
  const std::type_info* const type = &typeid(GiNaC::ex_to<GiNaC::basic>(e));
  for (std::size_t i = 0; i < seen_kinds.size; ++i)
    if (seen_kinds.type[i] == type) return seen_kinds.kind[i];
  return tested_kind_of(e);
}

}  // namespace nhdyn::symbolic::detail
