// `nhdyn compare`: one model run by several formulations and integrators side by side, each
// measured against one reference solution: a run at the tightest tolerances (sanh, dopri5,
// rtol 1e-13, atol 1e-15), or the model's exact motion where it has one (Evaluator::solution: the
// [solution] of a model file, docs/model-format.md; the built-in appell).
#pragma once

#include <string>
#include <vector>

#include "nhdyn/analysis/simulation.hpp"

namespace nhdyn {

struct ComparisonCase {
  Formulation method = Formulation::sanh;
  IntegratorKind integrator = IntegratorKind::dopri5;
};

enum class Reference {
  tight,     // a run of sanh with dopri5 at rtol 1e-13, atol 1e-15
  analytic,  // the model's exact solution
};

struct ComparisonOptions {
  Reference reference = Reference::tight;
  SimulationOptions run;                // times, tolerances, complement, stabilization of every case
  std::vector<ComparisonCase> cases;    // each formulation x integrator to run
  int cost_samples = 20000;             // acceleration solves timed per case (0: not timed, NaN)
};

// The result of one case.
struct ComparisonResult {
  ComparisonCase which;
  SimulationSummary summary;
  double solve_ns = 0.0;        // wall time of one compute_dynamics at the initial state [ns]
  double max_error_q = 0.0;     // max over outputs of max_i |q_i - q_ref,i|
  double max_error_v = 0.0;     // ... of the velocities
  std::vector<double> error;    // per output time: max(|q - q_ref|, |q' - q_ref'|)
  std::vector<double> position_residual;  // per output time: max |phi|
  std::vector<double> velocity_residual;  // per output time: max |f|
};

struct Comparison {
  std::vector<double> times;             // the output times
  SimulationSummary reference;           // the reference run (empty for an analytic reference)
  std::vector<ComparisonResult> results; // in the order of options.cases
};

// Runs the reference, then every case. Throws InputError for bad options (as simulate does) or
// an analytic reference for a model without a solution, and ModelError when the reference run
// itself fails (naming why). A case that fails keeps its
// summary's status and message; its error columns stop where it stopped (NaN after).
Comparison compare_formulations(const Model& model, const ComparisonOptions& options);

}  // namespace nhdyn
