// From symbols to numbers: compile a Spec and its Derivation into a frozen numeric Model whose
// Evaluator runs straight-line code (tapes, model/tape.hpp) — all the terms A, Q, G, b, b0 in one
// tape with common subexpressions shared, and D, the residuals and the energy in their own —
// evaluated on doubles without allocation. The tapes read the parameters, whose values the
// Model holds: set_parameter (model/parameters.hpp) changes them without recompiling.
#pragma once

#include <string>
#include <vector>

#include "nhdyn/model/model.hpp"
#include "nhdyn/symbolic/derivation.hpp"
#include "nhdyn/symbolic/spec.hpp"

namespace nhdyn::symbolic {

// How the terms tape writes A and b: every entry (dense), or only the entries that are not
// identically zero (sparse; the evaluator then also offers sparse_terms() for the sparse
// formulations, formulation/sparse_sanh.hpp). `automatic` compiles sparse from kSparseFrom
// coordinates on when at most a quarter of the entries of A and b are nonzero: a chain of a
// thousand bodies would otherwise write 18 million entries per call, nearly all of them zero.
enum class TermsLayout { automatic, dense, sparse };
inline constexpr int kSparseFrom = 64;

struct CompileOptions {
  TermsLayout layout = TermsLayout::automatic;
};

// Throws ModelError when an initial value or term cannot be compiled (an unknown symbol, an
// unsupported function, an initial value that is not a number once the parameters are set), and
// InputError for a cyclic or unknown definition of a derived parameter.
Model compile_model(const Spec& spec, const Derivation& derivation, const CompileOptions& options = {});

// One expression of t, q, q' and the parameters of `spec` as a tape with one output (events,
// symbolic/events.hpp); `what` names it in errors. Throws ModelError as compile_model does.
Tape compile_expression(const Spec& spec, const GiNaC::ex& expression, const std::string& what);
// Several expressions as one tape, one output each, common subexpressions computed once
// (outputs, contact forces); what[i] names expression i in messages.
Tape compile_expressions(const Spec& spec, const std::vector<GiNaC::ex>& expressions,
                            const std::vector<std::string>& what);

// derive() then compile_model().
Model compile_model(const Spec& spec, const CompileOptions& options = {});

}  // namespace nhdyn::symbolic
