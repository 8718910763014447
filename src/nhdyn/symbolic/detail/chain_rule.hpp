// The chain rule for GiNaC's elementary functions, given to GiNaC as their explicit derivative.
// GiNaC 1.8 differentiates a call f(u) by asking for f's explicit derivative and, when f has none,
// catching the exception that says so and then applying the chain rule (function::derivative). None
// of the elementary functions has one, so every derivative of a sin or a cos in a derivation threw
// and caught an exception: about a tenth of the bicycle's load (docs/performance.md). The explicit
// derivative installed here is that same chain rule, sum_i f_i(u) u_i', with the partial derivatives
// f_i that GiNaC itself gives, so every derivative is the expression GiNaC built before, term for term
// (tests/symbolic/chain_rule_test.cpp compares each f_i with GiNaC's own).
// Internal: a helper of the symbolic front end, not part of the public API (nhdyn/nhdyn.hpp).
#pragma once

namespace nhdyn::symbolic::detail {

// Gives sin, cos, tan, exp, log, asin, acos, atan, atan2, sinh, cosh and tanh (the functions of a
// model's expressions, spec_builder.cpp, but abs, whose derivative GiNaC writes otherwise, and sqrt,
// a power) their explicit derivative. Once per process, thread-safe; SymbolTable's constructor calls
// it, so it is done before any expression of a model exists.
void install_chain_rule();

}  // namespace nhdyn::symbolic::detail
