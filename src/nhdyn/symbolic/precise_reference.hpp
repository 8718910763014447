// A high-precision reference for one evaluation of the equations of motion: given a Spec, its
// Derivation and a state (t, q, q'), the terms A, Q, G, b, b0 are evaluated with GiNaC at a chosen
// number of decimal digits (50 by default) and the accelerations q'', the multipliers and the
// reactions R = A q'' - Q - G (docs/notation.md (2.15)) are solved for at that precision. The
// studies (studies/spread_masses.hpp, docs/studies/spread-masses.md) measure the double-precision
// formulations against it.
//
// Every double that enters (state and parameter values) is first turned into the exact rational
// it stands for (mantissa times a power of two). GiNaC::numeric(double) would instead hold a
// double-precision float, and arithmetic on it stays in double precision whatever GiNaC::Digits
// says; with exact rationals the only rounding is that of evalf() at the requested digits and of
// the elimination. The reference thus answers: what are q'' and R, to 50 digits, for exactly the
// problem the double-precision model is given (the same parameter values and state)?
#pragma once

#include <ginac/ginac.h>

#include <span>
#include <vector>

#include "nhdyn/core/types.hpp"
#include "nhdyn/symbolic/derivation.hpp"
#include "nhdyn/symbolic/spec.hpp"

namespace nhdyn::symbolic {

// The exact rational value of a finite double (m 2^e with integer m). Throws InputError naming
// the value for NaN or infinity.
GiNaC::numeric exact_rational(double x);

struct PreciseAcceleration {
  int digits = 0;                        // decimal digits of the evaluation
  std::vector<GiNaC::numeric> qdd;       // n accelerations q''
  std::vector<GiNaC::numeric> R;         // n reactions A q'' - Q - G
  std::vector<GiNaC::numeric> lambda;    // s multipliers, R = b^T lambda
  // max over q'' and R of ||x_digits - x_(digits+20)|| / ||x_(digits+20)||: how many of the
  // digits the ill-conditioning of the problem left. Far below 1e-16 for the reference to be one.
  double estimated_error = 0.0;
};

// q'' and R at (t, q, v) (q, v of size n) from the Lagrange-multiplier system
//     [ A  b^T ] [ q''     ]   [ Q + G ]
//     [ b  0   ] [ -lambda ] = [ -b0   ]          (docs/notation.md section 5)
// which has the same unique solution as every other formulation in exact arithmetic; solved by
// Gaussian elimination with partial pivoting on `digits`-digit floats, twice (at `digits` and at
// digits + 20, for estimated_error). GiNaC::Digits is restored on return. The parameters take
// the values in spec.parameters. Throws InputError for a non-finite input or digits < 17,
// ModelError when a term is not a real number at this state or the system is singular.
// Cost: a few milliseconds for n = 4 (GiNaC's evalf dominates).
PreciseAcceleration calc_precise_acceleration(const Spec& spec, const Derivation& derivation, double t,
                                              std::span<const double> q, std::span<const double> v,
                                              int digits = 50);

// The same solve for terms given as doubles (A n x n, h = Q + G of size n, b s x n, b0 of size s),
// each taken as the exact rational it stands for: the exact solution of the problem exactly as a
// double-precision evaluation of the terms posed it. Against it, a formulation's error is that of
// its solve alone; against calc_precise_acceleration, it includes the rounding of the terms.
// Throws InputError for inconsistent sizes, non-finite terms or digits < 17, ModelError when singular.
PreciseAcceleration calc_precise_solution(const Matrix& A, const Vector& h, const Matrix& b, const Vector& b0,
                                          int digits = 50);

// ||x - reference||_2 / ||reference||_2 computed at the precision of `reference` (x exact, as
// rationals), rounded to double; ||x - reference||_2 when the reference is zero. Sizes must match.
double calc_relative_error(std::span<const double> x, const std::vector<GiNaC::numeric>& reference,
                           int digits = 50);

}  // namespace nhdyn::symbolic
