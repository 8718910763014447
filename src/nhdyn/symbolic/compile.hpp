// From symbols to numbers: compile a Spec and its Derivation into a frozen numeric Model whose
// Evaluator runs straight-line programs (model/program.hpp) — all the terms A, Q, G, b, b0 in one
// program with common subexpressions shared, and D, the residuals and the energy in their own —
// evaluated on doubles without allocation. Parameters are replaced by their values here.
#pragma once

#include "nhdyn/model/model.hpp"
#include "nhdyn/symbolic/derivation.hpp"
#include "nhdyn/symbolic/spec.hpp"

namespace nhdyn::symbolic {

// Throws ModelError when an initial value or term is not a number once the parameters are set.
Model compile_model(const Spec& spec, const Derivation& derivation);

// derive() then compile_model().
Model compile_model(const Spec& spec);

}  // namespace nhdyn::symbolic
