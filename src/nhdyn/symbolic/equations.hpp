// The display of a derivation for `nhdyn equations MODEL [--format text|latex]`: the terms of the
// equations of motion in the paper's names and order — T, V, A, Q, G, b and b0 per constraint, D,
// A0 = D A, C = D (Q + G) — and the equations A0 q'' = C, b q'' + b0 = 0 written out row by row
// (docs/notation.md sections 1-3); with programs also b_p, b_p0, the actuator matrix B, D B and the
// equations of program motion A0 q'' - D B u = C, b_p q'' + b_p0 = 0 (docs/derivations/program-motion.md). Every expression goes through simplify() and a printer of its own
// that orders terms and factors by names (parameters, coordinates, functions, velocities,
// accelerations), never by GiNaC's internal order, so the output is reproducible.
// Text uses the symbols' own names (x' and x'' for velocities and accelerations); LaTeX uses
// \dot x, \ddot x, Greek letters for Greek names (\varphi for phi) and pmatrix, inside one align*
// environment (needs amsmath) that can be pasted into a document.
#pragma once

#include <string>

#include "nhdyn/symbolic/derivation.hpp"
#include "nhdyn/symbolic/spec.hpp"

namespace nhdyn::symbolic {

enum class EquationFormat { text, latex };

// The whole display. Without a D in the derivation (no independent coordinates, no analytic D)
// it says so and shows, when one exists, the partitioned D for the first choice of independent
// coordinates whose block of b is not singular, with A0 and C for it; otherwise A0 and C are
// reported unavailable with a hint to add `independent = [...]`.
std::string format_equations(const Spec& spec, const Derivation& derivation, EquationFormat format);

// One expression, simplified, in the notation of format_equations.
std::string format_expression(const Spec& spec, const GiNaC::ex& e, EquationFormat format);

}  // namespace nhdyn::symbolic
