// The tracking study (docs/studies/tracking.md): program motion (docs/derivations/program-motion.md)
// solves the programs at acceleration level, so along a numerical solution the programs'
// position- and velocity-level residuals are what the realized motion misses of its program: the
// paper's error relation read for control. Does that residual measure the error of the solution
// (the distance from the exact programmed motion)? For a list of feedback gains (section 5,
// alpha = beta = gain; 0 is no feedback) and tolerances, the model runs with dopri5 and is
// measured against its exact solution (Evaluator::solution, a [solution] table): per run the
// largest error of q and q' beside the largest program residual at each level.
#pragma once

#include <vector>

#include "nhdyn/analysis/simulation.hpp"

namespace nhdyn {

struct TrackingOptions {
  std::vector<double> tolerances;  // rtol of each run (atol = atol_factor * rtol); > 0, distinct
  double atol_factor = 1e-2;
  std::vector<double> gains{0.0};  // alpha = beta [1/s] of --program-feedback; 0: none; >= 0, distinct
  IntegratorKind integrator = IntegratorKind::dopri5;
  double t_end = 0.0;        // 0: the model's default; else after t0
  double output_step = 0.0;  // 0: the model's default; else > 0
};

// One run: a gain and a tolerance.
struct TrackingRun {
  double gain = 0.0;
  double tolerance = 0.0;
  SimulationSummary summary;
  double max_error_q = 0.0;       // max over outputs of max_i |q_i - q_exact,i|
  double max_error_v = 0.0;       // ... of the velocities
  double max_residual_pos = 0.0;  // max over outputs of max |phi_p| (position-level programs)
  double max_residual_vel = 0.0;  // max over outputs of max |f_p| (position- and velocity-level programs)
  double max_residual_acc = 0.0;  // max over outputs of max |b_p q'' + b_p0| (the feedback terms, with feedback)
};

struct Tracking {
  std::vector<double> gains;
  std::vector<double> tolerances;
  std::vector<TrackingRun> runs;  // gain by gain, tolerance by tolerance
  const TrackingRun& run(std::size_t gain, std::size_t tolerance) const {
    return runs[gain * tolerances.size() + tolerance];
  }
};

// Throws InputError for a model without programs or without an exact solution (saying how to give
// one), an empty, non-positive or repeated tolerance or gain, rk4 (its fixed step does not depend on
// the tolerance), bad times, or bad run options (as simulate does); ModelError for an exact
// solution that fails analysis/exact_solution.hpp's checks. A run that fails keeps its status in
// its summary, its maxima over the outputs it reached.
Tracking study_tracking(const Model& model, const TrackingOptions& options);

}  // namespace nhdyn
