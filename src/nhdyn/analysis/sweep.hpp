// Eigenvalues of the linearization (linearization.hpp) against one parameter, and the values
// where the motion changes stability: where the real part of an eigenvalue crosses zero — a
// complex pair (a Hopf crossing, the bicycle's weave speed) or a real eigenvalue (a divergence,
// the capsize speed). The crossings are bracketed on the grid by a change in the number of
// eigenvalues with positive real part and then found by bisection on that number to round-off
// (docs/linearization.md, "Stability crossings"). The model at a parameter value comes from the
// caller (the CLI recompiles the model file's derivation with the new value), so that this
// module needs no symbolic layer.
#pragma once

#include <complex>
#include <functional>
#include <string>
#include <vector>

#include "nhdyn/analysis/linearization.hpp"
#include "nhdyn/model/model.hpp"

namespace nhdyn {

struct SweepOptions {
  std::string parameter;  // its name, for messages
  double from = 0.0;
  double to = 1.0;
  int steps = 101;        // grid points, both ends included: from + (to - from) i / (steps - 1)
  bool find_crossings = true;
  LinearizationOptions linearization;
};

struct SweepPoint {
  double value = 0.0;
  std::vector<std::complex<double>> eigenvalues;  // sorted as Linearization::eigenvalues
};

struct StabilityCrossing {
  double value = 0.0;       // the parameter where a real part crosses zero
  bool oscillatory = false; // a complex pair (Hopf) rather than a real eigenvalue (divergence)
  double frequency = 0.0;   // |Im| of the crossing pair [rad/s] (0 for a real eigenvalue)
  int unstable_before = 0;  // eigenvalues with positive real part just below `value`
  int unstable_after = 0;   // and just above
  double bracket = 0.0;     // width of the final bisection interval
};

struct Sweep {
  std::vector<std::string> state;  // the state's names at the first point (kept for all points)
  std::vector<SweepPoint> points;
  std::vector<StabilityCrossing> crossings;
};

// The model with the parameter set to a value; may throw (ModelError, InputError).
using ModelAtValue = std::function<Model(double)>;

// Throws InputError naming the bad value when steps < 2 or > 1000000, from or to is not finite,
// or from >= to. Linearizes at every grid point with the state chosen at the first one (the
// independent coordinates and speeds named from it), so that every row has the same columns;
// a point where the linearization fails rethrows its error with the parameter value in front.
Sweep calc_eigenvalue_sweep(const ModelAtValue& model_at, const SweepOptions& options);

// Checks `options` as sweep_eigenvalues does (for callers that must refuse bad input before they
// open files).
void check_sweep_options(const SweepOptions& options);

}  // namespace nhdyn
