// The simulation driver: adapts a Model and a formulation to a first-order ODE y = [q; q'],
// integrates it, and at every output time evaluates the accelerations, reactions, residuals and
// energy, hands them to the caller (who writes CSV rows), and keeps the summary a user reads:
// steps, right-hand-side evaluations, wall time, maximum residual per level, the energy balance
// (docs/derivations/energy-balance.md: the work W' = P is integrated with the state).
#pragma once

#include <array>
#include <functional>
#include <optional>
#include <string>
#include <vector>

#include "nhdyn/analysis/constraint_watch.hpp"
#include "nhdyn/analysis/events.hpp"
#include "nhdyn/analysis/initial_state.hpp"
#include "nhdyn/analysis/projection.hpp"
#include "nhdyn/analysis/simulation_summary.hpp"
#include "nhdyn/formulation/formulation.hpp"
#include "nhdyn/integrators/ode.hpp"
#include "nhdyn/model/data.hpp"
#include "nhdyn/model/model.hpp"

namespace nhdyn {

// How a run keeps the solution on the constraints (docs/stabilization.md).
enum class Stabilization {
  none,        // the paper's form as it stands: the residuals measure the integration error
  baumgarte,   // the acceleration constraint with the gains of formulation.baumgarte
  projection,  // after every accepted step, and at every output, onto phi = 0 and then f = 0
};

// The stabilizations, once (core/names.hpp): "none", "baumgarte", "projection".
using StabilizationInfo = Named<Stabilization>;
inline constexpr std::array<StabilizationInfo, 3> kStabilizations{
    {{Stabilization::none, "none"}, {Stabilization::baumgarte, "baumgarte"}, {Stabilization::projection, "projection"}}};

std::string_view stabilization_name(Stabilization stabilization);
Stabilization parse_stabilization(std::string_view name);  // throws InputError listing valid names

struct SimulationOptions {
  double t_end = 10.0;        // end time [s], > t0
  double output_step = 0.01;  // spacing of output times [s], > 0
  // When not empty, the output times instead of output_step's grid (Python's t_eval): finite,
  // strictly increasing, within [t0, t_end]; the run ends at the last one. The rows are at these
  // times exactly (the integrator's dense output; rk4 steps to each), plus the events' rows.
  std::vector<double> output_times;
  FormulationOptions formulation;
  IntegratorOptions integrator;
  // The initial state must satisfy the position and velocity constraints to this tolerance, or
  // the run is refused with each residual listed ...
  double initial_tolerance = 1e-9;
  // ... unless it is moved onto them first (analysis/initial_state.hpp).
  bool fix_initial = false;
  // Baumgarte's gains are formulation.baumgarte.{alpha, beta}; `baumgarte` switches them on.
  Stabilization stabilization = Stabilization::none;
  ProjectionOptions projection;
  // Dense or sparse kernels (model/data.hpp): `automatic` takes the sparse path for a model
  // compiled sparse and a formulation with sparse kernels (sanh, lagrange), the dense path
  // otherwise (udwadia-kalaba and nullspace on a sparse model: dense, if it fits in memory).
  Path path = Path::automatic;
  // Events located during the run (analysis/events.hpp; a model file's [[events]] are in
  // Model::events: copy them here to locate them). Each crossing writes a row at its time (the
  // exact event state, between the output rows) and is listed in SimulationSummary::events
  // (analysis/simulation_summary.hpp); a stop event ends the run there with status ok. rk4 cannot
  // locate events: check_simulation_options refuses them.
  std::vector<Event> events;
  // The constraint watch (analysis/constraint_watch.hpp): warns when a constraint's row of b or the
  // conditioning of the stacked matrix degrades by watch_factor or more during the run. Checked at
  // every output and at every accepted step whose end state the right-hand side last evaluated.
  bool watch_constraints = true;
  double watch_factor = kConstraintWatchFactor;
};

// Called at every output time, and at every event (its row is the state at the crossing), with
// Data holding t, q, q', q'', R, residuals and energy (and for a model with programs data.motion:
// the actuator forces u and the programs' residuals).
using RowFn = std::function<void(const Data&)>;

// The output times t0, t0 + h, ..., ending exactly at t_end. Throws InputError on t_end <= t0
// or output_step <= 0 (or too many outputs to store), naming the value.
std::vector<double> make_output_times(double t0, double t_end, double output_step);

// Throws InputError for options that cannot make a run (times, tolerances, step budget, analytic
// D missing, events with an integrator that cannot locate them), naming the value and what to do.
void check_simulation_options(const Model& model, const SimulationOptions& options);

// Checks the options, the initial state and the events at it (throws InputError / ModelError
// before any step), then integrates. Numerical trouble during the run ends it with summary.status and message set.
SimulationSummary simulate(const Model& model, const SimulationOptions& options, const RowFn& row);

}  // namespace nhdyn
