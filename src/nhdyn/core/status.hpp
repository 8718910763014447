// Status codes returned by kernels and integrators when the numbers go wrong inside the time
// loop. The caller chooses the policy; describe() gives the words for a user.
#pragma once

#include <string_view>

namespace nhdyn {

enum class Status {
  ok = 0,
  dependent_constraints,          // rank of b below s: constraints dependent or conflicting
  inertia_not_positive_definite,  // A(q) has a non-positive eigenvalue
  singular_system,                // the stacked / KKT / reduced system could not be solved
  non_finite,                     // a NaN or infinity in a term or result
  step_size_underflow,            // the adaptive step fell below its floor
  too_many_steps,                 // the step budget of the run was used up
  integrator_failure,             // any other failure reported by an integrator
  stopped,                        // an observer asked to stop
  projection_failed,              // Newton's method did not bring the state onto the constraints
};

// A short name for the status, e.g. "dependent constraints".
std::string_view describe(Status status);

}  // namespace nhdyn
