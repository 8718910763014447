// The explicit Runge-Kutta integrators: one stepper (explicit_rk.cpp) driven by Butcher tableaus
// given as data (integrators/tableaus.hpp). rk4 is the classic fixed-step method whose steps land exactly on the
// output times; dopri5 is Dormand-Prince 5(4) with FSAL, Hairer's PI step-size control and the
// 4th-order continuous extension for output times inside a step (Hairer, Norsett, Wanner,
// "Solving Ordinary Differential Equations I", II.4-II.6, and their code DOPRI5); dop853 is
// Dormand-Prince 8(5,3) with the 7th-order continuous extension of Hairer's DOP853 (II.10), the
// choice for tight tolerances. The adaptive pairs share one driver; what differs (error
// estimate, continuous extension, controller constants) is in the tableau. integrate()
// (ode.hpp) checks its input and dispatches here; call that rather than these entry points.
// Internal: integrate() is the public entry point (nhdyn/nhdyn.hpp).
#pragma once

#include <span>

#include "nhdyn/integrators/ode.hpp"
#include "nhdyn/integrators/tableaus.hpp"

namespace nhdyn {

// Classic RK4 with fixed steps: h = options.step, or (mean spacing of the output times) / 10 when
// options.step is 0; each interval between consecutive output times (t0 included) is split into
// ceil(interval / h) equal steps, so outputs are step ends. 4 rhs evaluations per step.
IntegrationResult integrate_rk4(OdeSystem& system, const IntegratorOptions& options, double t0,
                                const double* y0, std::span<const double> output_times,
                                const OutputFn& output);

// Dormand-Prince 5(4), 6 rhs evaluations per step (FSAL), plus 1 after each step whose state
// after_step changed. Error test on the RMS norm of the error estimate weighted by
// atol + rtol max(|y0|, |y1|); outputs inside a step come from the continuous extension and never
// shorten a step; only the last step is shortened to end on the last output time, so the rhs is
// never evaluated beyond it. With `events`, a step whose ends differ in the sign of some event
// function is interpolated (as for an output) and each crossing located on it (events.hpp).
IntegrationResult integrate_dopri5(OdeSystem& system, const IntegratorOptions& options, double t0,
                                   const double* y0, std::span<const double> output_times,
                                   const OutputFn& output, EventFunctions* events = nullptr);

// Dormand-Prince 8(5,3) as in Hairer's DOP853: 12 rhs evaluations per accepted step (11 for a
// rejected one, whose FSAL stage is never needed), plus 3 in each step that holds an output time
// strictly inside it (the stages of the 7th-order continuous extension), plus 1 after a step whose
// state after_step changed while the step also held an output. Same error weights, output and
// last-step rules as dopri5.
IntegrationResult integrate_dop853(OdeSystem& system, const IntegratorOptions& options, double t0,
                                   const double* y0, std::span<const double> output_times,
                                   const OutputFn& output, EventFunctions* events = nullptr);

}  // namespace nhdyn
