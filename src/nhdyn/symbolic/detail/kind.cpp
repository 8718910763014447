// The class of a GiNaC object by one look-up (kind.hpp).
#include "nhdyn/symbolic/detail/kind.hpp"

namespace nhdyn::symbolic::detail {
namespace {

ExKind tested(const GiNaC::ex& e) {
  if (GiNaC::is_exactly_a<GiNaC::numeric>(e)) return ExKind::numeric;
  if (GiNaC::is_exactly_a<GiNaC::add>(e)) return ExKind::add;
  if (GiNaC::is_exactly_a<GiNaC::mul>(e)) return ExKind::mul;
  if (GiNaC::is_exactly_a<GiNaC::power>(e)) return ExKind::power;
  if (GiNaC::is_exactly_a<GiNaC::symbol>(e)) return ExKind::symbol;
  if (GiNaC::is_exactly_a<GiNaC::function>(e)) return ExKind::function;
  if (GiNaC::is_exactly_a<GiNaC::constant>(e)) return ExKind::constant;
  return ExKind::other;
}

}  // namespace

ExKind tested_kind_of(const GiNaC::ex& e) {
  const ExKind k = tested(e);
  SeenKinds& seen = seen_kinds;
  if (seen.size < seen.type.size()) {
    seen.type[seen.size] = &typeid(GiNaC::ex_to<GiNaC::basic>(e));
    seen.kind[seen.size] = k;
    ++seen.size;
  }
  return k;
}

}  // namespace nhdyn::symbolic::detail
