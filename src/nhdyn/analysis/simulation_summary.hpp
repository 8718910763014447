// What a run reports once it is over (analysis/simulation.hpp fills it): the outcome and the cost,
// then one group per subject, residuals, energy balance, projection, events, constraint watch,
// programs. Each group has a `format_*` that writes the lines `nhdyn simulate` prints for it, so
// that the CLI, the Python package and any other front end print one text and keep no copy of it.
#pragma once

#include <cstddef>
#include <optional>
#include <string>
#include <vector>

#include "nhdyn/analysis/constraint_watch.hpp"
#include "nhdyn/analysis/events.hpp"
#include "nhdyn/analysis/initial_state.hpp"
#include "nhdyn/core/status.hpp"
#include "nhdyn/formulation/program_feedback.hpp"
#include "nhdyn/integrators/ode.hpp"
#include "nhdyn/model/model.hpp"

namespace nhdyn {

struct SimulationOptions;

// The largest residual of each level over the outputs: max |phi|, max |f| and max |b q'' + b0| for
// the constraints; for the programs (model.m() > 0) the tracking error of the realized motion
// (docs/derivations/program-motion.md section 5).
struct ResidualMaxima {
  double position = 0.0;
  double velocity = 0.0;
  double acceleration = 0.0;
};

// The energy E = T + V and its balance (docs/derivations/energy-balance.md), when the model has
// them. `drift` is max |E(t) - E(t0)| over outputs: an error only when no agent does work. With a
// balance, `balance_error` is the largest |h - h(t0) - W| over outputs (the accuracy figure), and as
// physics the work W done up to the last output by each agent and the change of E and of h (which
// differs from E when T has parts of degree 1 or 0 in the velocities).
struct EnergySummary {
  bool has_energy = false;
  double initial = 0.0;  // E(t0)
  double drift = 0.0;
  bool has_balance = false;
  bool function_differs = false;  // h is not E for this model
  double function_initial = 0.0;  // h(t0)
  double balance_error = 0.0;
  double work_forces = 0.0, work_reactions = 0.0, work_time = 0.0;
  double work_friction = 0.0;     // contacts that slide (model/contact_modes.hpp); in W
  double impact_loss = 0.0;       // energy taken by touchdowns (model/contact_modes.hpp); W has -impact_loss
  double change = 0.0;            // E(t_last) - E(t0)
  double function_change = 0.0;   // h(t_last) - h(t0)
};

// Stabilization::projection: projections that changed the state (after steps and at outputs),
// their Newton iterations, and the largest change of a coordinate and of a velocity.
struct ProjectionSummary {
  long count = 0;
  long iterations = 0;
  double max_position_correction = 0.0;
  double max_velocity_correction = 0.0;
};

// The crossings located, in time order, and the stop event that ended the run (its index in
// `names`), or -1 when the run reached t_end.
struct EventSummary {
  std::vector<std::string> names;  // the run's events, those of SimulationOptions::events
  std::vector<EventRecord> crossings;
  int stopped_by = -1;
  // A stop condition (--stop-when, an event with action "stop") that never held on a run that
  // reached its end: one sentence each, naming it (docs/cli.md, "Events").
  std::vector<std::string> unmet_stops;
};

// The constraint watch (SimulationOptions::watch_constraints): at most one warning per constraint,
// in time order (in words in SimulationSummary::warnings); the largest degradation factor of the
// row norms and of the conditioning seen (1 when nothing changed) and the number of states watched.
struct ConstraintWatchSummary {
  std::vector<ConstraintWarning> warnings;
  double largest_row_factor = 1.0;
  double largest_condition_factor = 1.0;
  long watched_states = 0;
};

struct SimulationSummary {
  Status status = Status::ok;
  std::string message;              // empty when ok: what went wrong, where
  double t_reached = 0.0;
  IntegratorStats stats;
  long outputs = 0;                 // rows handed to the caller
  double wall_time = 0.0;           // [s], integration and output evaluation
  bool sparse = false;              // whether the run took the sparse kernels (model/data.hpp)
  long partition_changes = 0;       // sparse sanh: times the dependent coordinates were chosen anew
  ResidualMaxima residuals;         // the constraints'
  ResidualMaxima program;           // the programs' (model.m() > 0)
  EnergySummary energy;
  std::optional<InitialFix> initial_fix;  // set when options.fix_initial moved the initial state
  ProjectionSummary projection;
  EventSummary events;
  ConstraintWatchSummary watch;
  // The run's warnings in words, in time order: the constraint watch's (format_constraint_warning)
  // and those of the contacts' mode switches (analysis/detail/contact_switches.hpp).
  std::vector<std::string> warnings;
  // A stiff stretch of an explicit integrator's run in words (IntegratorStats::stiff_steps, with
  // the integrator to take instead); "" when the run had none. Kept apart from `warnings`: the
  // result is right, only slow.
  std::string stiffness;
};

// The lines `nhdyn simulate` prints after a run, one function per group, each line indented by two
// spaces and ended by a newline; an empty string when the group has nothing to say for this model
// and these options.

// The outcome in a table's cell: "ok", or the status in words (describe, core/status.hpp).
std::string format_status(const SimulationSummary& summary);

// What ends a table's row of a run that failed: "  FAILED at t = T: MESSAGE"; empty when it succeeded.
std::string format_failure_note(const SimulationSummary& summary);

// "  steps S (rejected R), right-hand-side evaluations N, wall time T ms"
std::string format_steps(const SimulationSummary& summary);

// "  max residual: position P, velocity V, acceleration A" ("-" for a level without constraints).
std::string format_residuals(const Model& model, const ResidualMaxima& residuals);

// "  programs: M, max residual: ...", with the feedback's gains when it is on; empty when model.m() == 0.
std::string format_program(const Model& model, const ResidualMaxima& program, const ProgramFeedback& feedback);

// The energy balance's error, the work by agent and the change of E (and of h when it differs), or
// the drift of E; empty when the model has no energy.
std::string format_energy(const Model& model, const EnergySummary& energy);

// The stabilization in use: Baumgarte's gains, or the projections made and their largest
// corrections; empty without stabilization.
std::string format_stabilization(const SimulationOptions& options, const ProjectionSummary& projection);

// "  events: N located[ -> FILE]" and the first ten crossings; empty when the run had no events.
// `file` is where the crossings were written (empty: nowhere).
std::string format_events(const EventSummary& events, const std::string& file);

// "  constraint watch: ...": how many warnings went to stderr (`warnings`, every warning of the run)
// and the largest degradation seen; empty for a model without constraints.
std::string format_constraint_watch(const Model& model, const ConstraintWatchSummary& watch, std::size_t warnings,
                                    bool sparse);

// Where --fix-initial moved the initial state: one line per coordinate or velocity changed.
std::string format_initial_fix(const Model& model, const InitialFix& fix);

// What loading found about the contact forces (docs/multibody.md): "note: contact forces: ..."
// lines, printed before the run; empty for a model without contact forces.
std::string format_contact_force_notes(const Model& model);

}  // namespace nhdyn
