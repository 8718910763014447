// How far a constraint's residual can be from 0 by round-off alone, at a state on the constraint:
// the rounding of each coordinate x_j moves the residual by about eps |b_ij x_j|, so the residual
// of a pendulum 1500 km long, x^2 + y^2 - l^2, lies near 1e-4 at points of its circle. A check
// that a state is on the constraints allows each row the larger of its own tolerance and a
// multiple of this, so that its verdict does not depend on the units the model is written in.
// Internal: used by analysis/initial_state and model/contact_forces, not part of the public API (nhdyn/nhdyn.hpp).
#pragma once

#include <cmath>
#include <limits>

namespace nhdyn {

// The multiple of the round-off of its terms that a residual is allowed: the rounding of the
// state alone leaves it within about one unit (the 1500 km pendulum's 4.9e-4 is half a unit of its
// terms, 4.5e12), the evaluation of an expression a few more; more would let a 1 m pendulum pivoted
// 1000 km from the origin start with its bob visibly off its circle.
inline constexpr double kResidualRoundOffUnits = 32.0;

// kResidualRoundOffUnits units of round-off of the residual r of one constraint row: its terms
// sum_j |b_j x_j| over the n entries of its row of b (x = q at the position level, q' at the
// velocity level), with, at the velocity level, its own term r - b x' (`own_term`). 0 when a
// term is not finite: no allowance, the residual alone decides.
template <class Row, class State>
double residual_round_off(const Row& b_row, const State& x, int n, double r, bool own_term) {
  double terms = 0.0, dot = 0.0;
  for (int j = 0; j < n; ++j) {
    terms += std::abs(b_row(j) * x(j));
    dot += b_row(j) * x(j);
  }
  if (own_term) terms += std::abs(r - dot);
  const double allowance = kResidualRoundOffUnits * std::numeric_limits<double>::epsilon() * terms;
  return std::isfinite(allowance) ? allowance : 0.0;
}

}  // namespace nhdyn
