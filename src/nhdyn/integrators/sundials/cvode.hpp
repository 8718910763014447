// CVODE (SUNDIALS) behind the integrator interface of ode.hpp: variable-order, variable-step BDF
// for stiff systems and Adams-Moulton for smooth non-stiff ones, both with Newton iteration on a
// dense direct linear solver and a difference-quotient Jacobian. This header includes no SUNDIALS
// header, so nothing outside integrators/sundials/ (target nhdyn_sundials) sees SUNDIALS.
// integrate() (ode.hpp) checks its input and dispatches here; call that rather than this.
#pragma once

#include <span>

#include "nhdyn/integrators/ode.hpp"

namespace nhdyn {

// options.kind selects the method (cvode_bdf or cvode_adams). CVODE takes one internal step per
// call (CV_ONE_STEP), so after_step sees every accepted step; when it changes the state CVODE is
// re-initialized there (order 1, fresh step size). Outputs inside a step come from CVODE's
// interpolating polynomial (CVodeGetDky); the last output time is CVODE's stop time, so the rhs
// is never evaluated beyond it. Stats sum CVODE's counters over re-initializations; rhs
// evaluations include those of the difference-quotient Jacobian. Cost per step: one LU of a dense
// n x n matrix when CVODE updates its Jacobian (n rhs evaluations), O(n^2) per Newton iteration.
// An exception thrown by OdeSystem::rhs is carried across CVODE and rethrown here. `events` are
// located by CVODE's root finding (CVodeRootInit) and reported at the roots it returns.
IntegrationResult integrate_cvode(OdeSystem& system, const IntegratorOptions& options, double t0,
                                  const double* y0, std::span<const double> output_times,
                                  const OutputFn& output, EventFunctions* events = nullptr);

}  // namespace nhdyn
