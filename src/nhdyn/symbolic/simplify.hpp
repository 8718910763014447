// Deterministic simplification of the expressions of mechanics, used by derive() on every term it
// returns, by `nhdyn equations` for display, and by the tests to decide that two expressions agree
// (docs/design.md, "Rules the code follows": compare by simplifying the difference to zero, never by
// printed strings).
//
// simplify() rewrites tan and tanh through sin/cos and sinh/cosh, brings the expression to one
// fraction with expanded, coprime numerator and denominator (GiNaC's normal()), and reduces
// sin(u)^2 + cos(u)^2 = 1 (and cosh(u)^2 - sinh(u)^2 = 1) for every argument u. The reduction that
// eliminates sin(u)^2 is a canonical form for polynomials in sin(u), cos(u), so every identity
// built from these relations (for one argument at a time, e.g. not sin(2 x) = 2 sin(x) cos(x))
// simplifies to exactly 0. Of the candidate forms (no reduction, sin^2 eliminated, cos^2
// eliminated) the smallest is returned; a fraction whose denominator is a single product is
// distributed over the terms of the numerator (m g sin(alpha) + m a phi'^2/cos(phi)).
// The result depends only on the value of the input, never on GiNaC's internal term order.
#pragma once

#include <ginac/ginac.h>

#include <cstddef>
#include <string>
#include <utility>

namespace nhdyn::symbolic {

GiNaC::ex simplify(const GiNaC::ex& e);
// Entry by entry.
GiNaC::matrix simplify(const GiNaC::matrix& m);

// simplify() for expressions of at most kSimplifyLimit tree nodes; larger ones are returned as
// they are. normal() and the trigonometric reduction grow steeply with size (the Whipple
// bicycle's terms, built from a multibody description, took tens of seconds), while the compiler
// shares the common subexpressions of unsimplified terms anyway. The hand-written models of the
// gallery stay below the limit. Used by derive() on the terms and by the multibody front end.
inline constexpr std::size_t kSimplifyLimit = 1000;
GiNaC::ex simplify_moderate(const GiNaC::ex& e);

// simplify_moderate(e), or e as it is where that is smaller, counted in the symbols and functions
// written (numbers not; the powers of one base in a product counting it once): the rows of a
// rolling contact and their derivatives, which normal() would multiply out (a ball's rolling rows
// on a sphere: 3.6 times the operations). GiNaC writes an unsimplified expression by its term
// order, which changes from process to process, in two ways that matter: the sign of a sum (x - y
// in one process, -(y - x) in another; the -1 is a number) and, through it, whether S^(1/2) (-S) is
// merged into -S^(3/2). The count sees neither, and the compiler undoes both (compile.cpp), so the
// choice and the tape are the same in every process.
GiNaC::ex smaller_form(const GiNaC::ex& e);

// True when simplify(e) is 0; false when it is not or when simplify() cannot tell. Call it as
// symbolic::is_zero: argument-dependent lookup also finds GiNaC::is_zero, which only tests whether
// the expression is literally the number 0.
bool is_zero(const GiNaC::ex& e);
// True when every entry is zero in the sense above.
bool is_zero(const GiNaC::matrix& m);

// A serialization of `e` that does not depend on the order in which GiNaC keeps the terms of sums
// and the factors of products (which follows symbol creation order): operands are sorted by their
// own keys. Two expressions of the same structure have the same key; used to order terms for
// display and to make choices in simplify() reproducible.
std::string canonical_key(const GiNaC::ex& e);

// A term of a sum split into its numeric coefficient and the rest: 3 x y -> (3, x y).
std::pair<GiNaC::numeric, GiNaC::ex> split_coefficient(const GiNaC::ex& term);

}  // namespace nhdyn::symbolic
