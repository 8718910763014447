// The error relation (docs/notation.md section 4, docs/studies/error-relation.md): does the residual
// of the velocity and position constraints along a numerical solution measure that solution's
// global error? For a list of tolerances, every formulation and integrator runs the model and is
// measured against the model's exact solution (Evaluator::solution); the study reports, per run,
// the largest global error and the largest residual at each constraint level. A model without an
// exact solution is measured against a run at rtol 1e-13 instead (the study then says so).
#pragma once

#include <string>
#include <vector>

#include "nhdyn/analysis/comparison.hpp"

namespace nhdyn {

// One formulation: the method, and for sanh where its complement D comes from.
struct StudyFormulation {
  Formulation method = Formulation::sanh;
  Complement complement = Complement::qr;
};

// "sanh-qr", "sanh-partition", "sanh-analytic", "lagrange", ...
std::string formulation_label(const StudyFormulation& formulation);

// Every formulation `model` allows: sanh with D from qr and partition (and analytic when the
// model gives D), lagrange, udwadia-kalaba, nullspace.
std::vector<StudyFormulation> calc_study_formulations(const Model& model);

struct ErrorRelationOptions {
  std::vector<double> tolerances;          // rtol of each run (atol = atol_factor * rtol); > 0
  double atol_factor = 1.0;
  std::vector<StudyFormulation> formulations;  // empty: every formulation the model allows
  std::vector<IntegratorKind> integrators{IntegratorKind::dopri5, IntegratorKind::cvode_bdf,
                                          IntegratorKind::cvode_adams};
  double t_end = 0.0;        // 0: the model's default; else after t0
  double output_step = 0.0;  // 0: the model's default; else > 0
};

// One run: a formulation, an integrator and a tolerance.
struct ErrorRelationRun {
  StudyFormulation formulation;
  IntegratorKind integrator = IntegratorKind::dopri5;
  double tolerance = 0.0;
  SimulationSummary summary;
  double max_error_q = 0.0;  // max over outputs of max_i |q_i - q_exact,i|
  double max_error_v = 0.0;  // ... of the velocities
  double max_residual_pos = 0.0;  // max over outputs of max |phi| (0 without position constraints)
  double max_residual_vel = 0.0;  // max over outputs of max |f| (velocity level, docs/notation.md (2.14))
};

struct ErrorRelation {
  bool analytic = false;  // measured against the exact solution (else against a tight run)
  std::vector<double> tolerances;
  std::vector<StudyFormulation> formulations;
  std::vector<IntegratorKind> integrators;
  // For each formulation, each integrator, each tolerance (in that nesting order).
  std::vector<ErrorRelationRun> runs;
  const ErrorRelationRun& run(std::size_t formulation, std::size_t integrator, std::size_t tolerance) const {
    return runs[(formulation * integrators.size() + integrator) * tolerances.size() + tolerance];
  }
};

// Throws InputError for a model without constraints (there is no residual to study), an empty,
// non-positive or repeated tolerance, a repeated formulation or integrator, rk4 (a fixed step: its
// runs do not depend on the tolerance), an analytic complement for a model without one, a negative
// t_end or output_step, or bad run options (as simulate does); ModelError for an exact solution
// that fails analysis/exact_solution.hpp's checks. Each (formulation, tolerance) runs its
// integrators in one compare_formulations call, so without an exact solution the tight reference is
// computed once per formulation and tolerance.
ErrorRelation study_error_relation(const Model& model, const ErrorRelationOptions& options);

}  // namespace nhdyn
