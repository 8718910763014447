// The interface between a mechanical model and the time integrators: a first-order system
// y' = f(t, y) with y = [q; q'] (size 2n), output at user-chosen times independent of the steps,
// and a hook after each accepted step (used by constraint projection). Integrators know nothing
// of mechanics; the simulation driver (analysis/simulation.hpp) adapts a Model to OdeSystem.
#pragma once

#include <array>
#include <cmath>
#include <functional>
#include <limits>
#include <span>
#include <string_view>
#include <string>

#include "nhdyn/core/names.hpp"
#include "nhdyn/core/status.hpp"

namespace nhdyn {

// What OdeSystem::after_step did to the state.
struct StepEnd {
  Status status = Status::ok;
  bool changed = false;
};

class OdeSystem {
 public:
  virtual ~OdeSystem() = default;
  // Number of states.
  virtual int size() const = 0;
  // Number of leading states that the adaptive Runge-Kutta pairs' error norm and first-step
  // heuristic weigh (all by default). The states past it are quadratures no state depends on, not
  // even their own (the work of the forces, docs/derivations/energy-balance.md): rhs() never reads
  // them. Integrated by the same method on the same steps, they do not choose the steps, so the
  // other states are those of a run without them, to the bit; the explicit Runge-Kutta methods
  // form them only in the states they return (a stage's state holds the leading ones alone).
  // CVODE weighs every state.
  virtual int error_size() const { return size(); }
  // ydot = f(t, y). Returns Status::ok or the reason the right-hand side cannot be evaluated;
  // an integrator stops at the first non-ok status and reports it.
  virtual Status rhs(double t, const double* y, double* ydot) = 0;
  // Called after every accepted step with the new state; may change y in place (projection onto
  // the constraint manifold) and then says so, so that the integrator restarts from the changed
  // state (drops FSAL derivatives, re-initializes multistep history). A non-ok status ends the
  // run there, as a failed right-hand side does.
  virtual StepEnd after_step(double /*t*/, double* /*y*/) { return {}; }
};

enum class IntegratorKind { rk4, dopri5, dop853, cvode_bdf, cvode_adams };

// The integrators, once (core/names.hpp): their names in the CLI, model files and Python, and
// what each can do. A new integrator adds its kind above, its line here and its case in
// integrate().
struct IntegratorInfo {
  IntegratorKind value;
  std::string_view name;
  bool events;    // locates events (events.hpp): a continuous extension or root finding
  bool adaptive;  // chooses its steps to meet rtol and atol
};
inline constexpr std::array<IntegratorInfo, 5> kIntegrators{{
    {IntegratorKind::rk4, "rk4", false, false},
    {IntegratorKind::dopri5, "dopri5", true, true},
    {IntegratorKind::dop853, "dop853", true, true},
    {IntegratorKind::cvode_bdf, "cvode-bdf", true, true},
    {IntegratorKind::cvode_adams, "cvode-adams", true, true},
}};

// Its name in kIntegrators: "rk4", "dopri5", "dop853", "cvode-bdf", "cvode-adams".
std::string_view integrator_name(IntegratorKind kind);
// Inverse of integrator_name; throws InputError listing the valid names.
IntegratorKind parse_integrator(std::string_view name);
// Whether the integrator can locate events (events.hpp): all but rk4.
bool supports_events(IntegratorKind kind);
// The adaptive integrators' names, "dopri5, dop853, cvode-bdf or cvode-adams" (`last` between the
// last two), for the messages of the studies that vary the tolerance.
std::string adaptive_integrator_names(std::string_view last = " or ");

struct IntegratorOptions {
  IntegratorKind kind = IntegratorKind::dopri5;
  double rtol = 1e-8;        // relative tolerance (adaptive methods)
  double atol = 1e-10;       // absolute tolerance (adaptive methods)
  double step = 0.0;         // rk4: largest step; 0 = output step / 10. Adaptive: first step, 0 = automatic
  double max_step = 0.0;     // adaptive: largest step, 0 = unlimited
  long max_steps = 50'000'000;  // budget of accepted + rejected steps for the whole run
};

struct IntegratorStats {
  long steps = 0;             // accepted steps
  long rejected_steps = 0;    // rejected by the error test (adaptive) or failed (CVODE)
  long rhs_evaluations = 0;   // calls of OdeSystem::rhs, including those for Jacobians
  // dopri5, dop853: the accepted steps whose size the method's stability bounded rather than its
  // accuracy (Hairer's test: h |lambda| near the stability boundary, |lambda| estimated from two
  // stages at t + h), and the first t where 15 of them came nearly in a row (NaN if never): a stiff
  // stretch, which an implicit method (cvode-bdf) crosses in far fewer steps.
  long stiff_steps = 0;
  double stiff_from = std::numeric_limits<double>::quiet_NaN();

  // The counts of a run made of several integrations (contact modes' segments, restarts).
  void add(const IntegratorStats& later) {
    steps += later.steps;
    rejected_steps += later.rejected_steps;
    rhs_evaluations += later.rhs_evaluations;
    stiff_steps += later.stiff_steps;
    if (std::isnan(stiff_from)) stiff_from = later.stiff_from;
  }
};

struct IntegrationResult {
  Status status = Status::ok;
  double t_reached = 0.0;     // last time the solution is known at
  IntegratorStats stats;
  std::string message;        // empty when ok; otherwise what went wrong, with t
};

// Called at each output time with the interpolated state; return Status::stopped to end the run.
using OutputFn = std::function<Status(double t, const double* y)>;

class EventFunctions;  // events.hpp

// Integrates from (t0, y0) and calls `output` at every time of `output_times` (strictly increasing,
// all >= t0; the first may equal t0). Does not throw on numerical trouble: the result says.
// `events` (optional) are located during the run and reported through their on_event, in time
// order among the outputs (events.hpp); rk4, which has no continuous extension, refuses them
// (InputError).
IntegrationResult integrate(OdeSystem& system, const IntegratorOptions& options, double t0,
                            const double* y0, std::span<const double> output_times,
                            const OutputFn& output, EventFunctions* events = nullptr);

}  // namespace nhdyn
