// Eigenvalues of the linearization (linearization.hpp) against one parameter, and the values
// where the motion changes stability: where the real part of an eigenvalue crosses zero — a
// complex pair (a Hopf crossing, the bicycle's weave speed) or a real eigenvalue (a divergence,
// the capsize speed). Each eigenvalue is known only to an uncertainty that reflects its
// conditioning (a multiple eigenvalue with a Jordan block of size l only to about eps^(1/l));
// a real part within it is "undecided", never counted unstable. The crossings are bracketed on the
// grid by a change in the number of eigenvalues whose real part is positive beyond that
// uncertainty, narrowed by bisection on that number, and then, for a simple eigenvalue, by
// bisection on the sign of its real part (docs/linearization.md, "Stability crossings"). The model at
// a parameter value is a copy of one loaded model with the parameter set (parameters are data,
// model/parameters.hpp: nothing is recompiled), so that this module needs no symbolic layer.
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
  // Per eigenvalue, how far the computed value may be from the exact one (calc_eigenvalue_uncertainty).
  std::vector<double> uncertainty;
  int unstable = 0;   // eigenvalues with real part > its uncertainty
  int undecided = 0;  // eigenvalues with |real part| <= its uncertainty (zero, imaginary, or a split multiple one)
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

// `base` with parameter `parameter` set to the value asked (set_parameter on a copy); the returned
// function keeps its own copy of `base`. Throws InputError, naming the nearest parameter, when
// called with a name `base` does not have.
ModelAtValue make_model_at_value(const Model& base, const std::string& parameter);

// The sweep of options.parameter on `base`: checks the options, then sets the parameter to
// options.from (InputError naming the nearest for an unknown name), then calc_eigenvalue_sweep
// over make_model_at_value.
Sweep calc_parameter_sweep(const Model& base, const SweepOptions& options);

// How far each computed eigenvalue of `state_matrix` may be from the exact one: with
// s = ||state_matrix||_F and e = 64 eps, r_l = 8 e^(1/l) s for an eigenvalue in a cluster of m
// eigenvalues (within 2 r_m of each other) whose largest Jordan block can be l = m - g + 1 long,
// g being the number of singular values of (state_matrix - centre I) below 2 r_m. A simple
// eigenvalue gets r_1 = 512 eps s; a double zero of a Jordan block (a roller racer going straight)
// about 1e-6 s; a semisimple multiple eigenvalue r_1. An eigenvalue split from its nearest
// neighbour by d gets at most max(r_1, 8 e s^2 / d) (first-order perturbation near a multiple one). docs/linearization.md, "Stability crossings".
std::vector<double> calc_eigenvalue_uncertainty(const Matrix& state_matrix,
                                                const std::vector<std::complex<double>>& eigenvalues);

// Checks `options` as sweep_eigenvalues does (for callers that must refuse bad input before they
// open files).
void check_sweep_options(const SweepOptions& options);

}  // namespace nhdyn
