// The chain rule as GiNaC's explicit derivative of the elementary functions (chain_rule.hpp).
#include "nhdyn/symbolic/detail/chain_rule.hpp"

#include <ginac/ginac.h>

#include <mutex>
#include <vector>

#include "nhdyn/symbolic/detail/derivative.hpp"

namespace nhdyn::symbolic::detail {
namespace {

using GiNaC::ex;

// GiNaC's table of functions and its partial derivative of a call are protected members of its
// class function: a derived class may name them.
struct FunctionTable : GiNaC::function {
  using GiNaC::function::registered_functions;
  static ex partial(const GiNaC::function& f, unsigned i) { return (f.*&FunctionTable::pderivative)(i); }
};

// The partial derivatives, as GiNaC 1.8's inifcns_trans.cpp writes them (its derivative_func of
// each function); chain_rule_test.cpp checks that they are the same expressions.
ex d_sin(const ex& x) { return GiNaC::cos(x); }
ex d_cos(const ex& x) { return -GiNaC::sin(x); }
ex d_tan(const ex& x) { return 1 + GiNaC::pow(GiNaC::tan(x), 2); }
ex d_exp(const ex& x) { return GiNaC::exp(x); }
ex d_log(const ex& x) { return GiNaC::pow(x, -1); }
ex d_asin(const ex& x) { return GiNaC::pow(1 - GiNaC::pow(x, 2), GiNaC::numeric(-1, 2)); }
ex d_acos(const ex& x) { return -GiNaC::pow(1 - GiNaC::pow(x, 2), GiNaC::numeric(-1, 2)); }
ex d_atan(const ex& x) { return GiNaC::pow(1 + GiNaC::pow(x, 2), -1); }
ex d_sinh(const ex& x) { return GiNaC::cosh(x); }
ex d_cosh(const ex& x) { return GiNaC::sinh(x); }
ex d_tanh(const ex& x) { return 1 - GiNaC::pow(GiNaC::tanh(x), 2); }

// f(u)' = f'(u) u', and 0 (not f'(u) 0) when u does not depend on s, as GiNaC's own chain rule.
// u' by derivative() (derivative.hpp): u.diff(s), the same expression, with less work.
template <ex (*Partial)(const ex&)>
ex chain_rule(const ex& u, const GiNaC::symbol& s) {
  const ex du = derivative(u, s);
  if (du.is_zero()) return ex();
  return Partial(u) * du;
}

// atan2(y, x)' = atan2_y y' + atan2_x x', with GiNaC's own partial derivatives of the call (atan2 is
// rare: the call is built again to ask for them).
ex atan2_chain_rule(const ex& y, const ex& x, const GiNaC::symbol& s) {
  const ex call = GiNaC::atan2(y, x);
  // The call was evaluated when it was made: built again from its arguments it is the same call.
  if (!GiNaC::is_exactly_a<GiNaC::function>(call)) return call.diff(s);
  ex result;
  for (unsigned i = 0; i < 2; ++i) {
    const ex d = derivative(i == 0 ? y : x, s);
    if (!d.is_zero()) result += FunctionTable::partial(GiNaC::ex_to<GiNaC::function>(call), i) * d;
  }
  return result;
}

}  // namespace

void install_chain_rule() {
  static std::once_flag once;
  std::call_once(once, [] {
    std::vector<GiNaC::function_options>& table = FunctionTable::registered_functions();
    table[GiNaC::sin_SERIAL::serial].expl_derivative_func(&chain_rule<d_sin>);
    table[GiNaC::cos_SERIAL::serial].expl_derivative_func(&chain_rule<d_cos>);
    table[GiNaC::tan_SERIAL::serial].expl_derivative_func(&chain_rule<d_tan>);
    table[GiNaC::exp_SERIAL::serial].expl_derivative_func(&chain_rule<d_exp>);
    table[GiNaC::log_SERIAL::serial].expl_derivative_func(&chain_rule<d_log>);
    table[GiNaC::asin_SERIAL::serial].expl_derivative_func(&chain_rule<d_asin>);
    table[GiNaC::acos_SERIAL::serial].expl_derivative_func(&chain_rule<d_acos>);
    table[GiNaC::atan_SERIAL::serial].expl_derivative_func(&chain_rule<d_atan>);
    table[GiNaC::atan2_SERIAL::serial].expl_derivative_func(&atan2_chain_rule);
    table[GiNaC::sinh_SERIAL::serial].expl_derivative_func(&chain_rule<d_sinh>);
    table[GiNaC::cosh_SERIAL::serial].expl_derivative_func(&chain_rule<d_cosh>);
    table[GiNaC::tanh_SERIAL::serial].expl_derivative_func(&chain_rule<d_tanh>);
  });
}

}  // namespace nhdyn::symbolic::detail
