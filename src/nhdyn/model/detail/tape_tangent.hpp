// Forward-mode (tangent) differentiation of straight-line tapes (tape.hpp): one pass over a
// Tape's instructions carries, next to each register's value, its directional derivative along
// a direction (dt, dq, dq') of the inputs, so the outputs' derivatives come out exact to
// round-off (no step size), at about twice the cost of a run. The linearization about steady
// motions (analysis/linearization.hpp) differentiates the terms A, Q, G, b, b0 and the residuals
// of a compiled model with it; docs/linearization.md gives the derivation it serves.
// Also here: which inputs the outputs of a tape depend on at all (structurally), which
// tells cyclic coordinates and explicit time dependence apart without evaluating anything.
// Internal: used by analysis/linearization and optimize/transcription, not part of the public API (nhdyn/nhdyn.hpp).
#pragma once

#include <vector>

#include "nhdyn/model/tape.hpp"

namespace nhdyn {

// Directional derivative of the outputs of `tape`. `values` holds the registers after
// tape.execute(t, q, v, values) at the point; `dq`, `dv` hold coordinates() entries (dv may be
// null when the tape reads no velocity). `tangents` is workspace of registers() doubles;
// `doutputs` receives outputs() derivatives (0 for a constant output). Allocates nothing.
void run_tangent(const Tape& tape, const double* values, double dt, const double* dq, const double* dv,
                 double* tangents, double* doutputs);

// For each input register (t, q_0..q_{n-1}, q'_0..q'_{n-1}: inputs() flags), whether some output
// of `tape` is computed from it. Structural: an output such as sin(x)^2 + cos(x)^2 counts as
// depending on x.
std::vector<char> calc_input_dependence(const Tape& tape);

}  // namespace nhdyn
