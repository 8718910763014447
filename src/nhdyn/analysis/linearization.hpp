// Linearization about a steady motion (docs/linearization.md): the equations of motion
// q'' = F(t, q, q') on the constraint manifold, linearized about the model's initial state
// (q0, q0'), which must be a steady motion — the non-cyclic coordinates at rest, every velocity
// constant. Cyclic coordinates (found automatically when no term or residual depends on them, or
// named) leave the state; the perturbations of the others obey the linearized constraints, from
// which independent coordinates and speeds are chosen (pivoted QR, or named); the result is the
// state matrix of (dq_ind, dq'_ind) and its eigenvalues. Derivatives are exact (tangent mode,
// model/detail/tape_tangent.hpp) for compiled models and Richardson-extrapolated central differences
// for hand-written ones. sweep.hpp repeats it over a parameter.
#pragma once

#include <complex>
#include <string>
#include <vector>

#include "nhdyn/core/types.hpp"
#include "nhdyn/model/model.hpp"

namespace nhdyn {

struct LinearizationOptions {
  // Coordinates to treat as cyclic besides those found (a heading that enters the constraints
  // but, by symmetry, not the reduced dynamics). Unknown names are an InputError.
  std::vector<std::string> cyclic;
  bool detect_cyclic = true;
  // Independent coordinates and speeds of the state, by coordinate name (a speed "x" means x');
  // empty: chosen by pivoted QR on the constraint Jacobians (cyclic velocities preferred as
  // dependent). When given, their number must be the number of degrees of freedom.
  std::vector<std::string> independent;
  std::vector<std::string> speeds;
  // The steady-motion test: every non-cyclic velocity and every acceleration within
  // tolerance * scale (scale: 1 for velocities, max(1, |A^-1 (Q + G)|) for accelerations), and
  // the constraints within tolerance.
  double steady_tolerance = 1e-9;
};

enum class DerivativeMethod { tangent, richardson };
// "exact (tangent mode of the compiled tapes)" or "Richardson-extrapolated central differences".
const char* derivative_method_name(DerivativeMethod method);

struct Linearization {
  std::vector<std::string> cyclic;       // cyclic coordinates (found and named), in coordinate order
  std::vector<std::string> independent;  // independent coordinates (non-cyclic), in coordinate order
  std::vector<std::string> speeds;       // coordinates whose velocity is an independent speed
  std::vector<std::string> state;        // the state's names: independent, then "x'" per speed
  Matrix state_matrix;                   // d/dt (dq_ind, dv_ind) = state_matrix (dq_ind, dv_ind)
  // Eigenvalues of state_matrix, by decreasing real part, then decreasing imaginary part.
  std::vector<std::complex<double>> eigenvalues;
  DerivativeMethod derivatives = DerivativeMethod::tangent;
  double steady_residual = 0.0;  // the largest scaled violation of the steady-motion conditions
  Vector qdd;                    // n, q'' at the steady state (zero within the tolerance)
  Matrix Fq, Fv;                 // n x n, dq''/dq and dq''/dq' at the steady state (full, all coordinates)
};

// Linearizes `model` about its initial state (t0, q0, q0'). Throws InputError for unknown or
// ill-chosen names (a cyclic coordinate named independent, the wrong number of independent ones,
// dependent ones that the constraints cannot express) and ModelError when the model depends on
// time explicitly, when the state violates a constraint, or when it is not a steady motion (the
// message names the largest violation: which velocity or acceleration, how large). Cost: 2n
// tangent (or 8n finite-difference) evaluations of the terms and n^3-size dense algebra.
Linearization calc_linearization(const Model& model, const LinearizationOptions& options = {});

// Sorted as in Linearization::eigenvalues: decreasing real part, then decreasing imaginary part.
void sort_eigenvalues(std::vector<std::complex<double>>& eigenvalues);

}  // namespace nhdyn
