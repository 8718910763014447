#include "nhdyn/analysis/simulation.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstring>
#include <limits>

#include "nhdyn/analysis/detail/contact_switches.hpp"
#include "nhdyn/analysis/detail/contact_watches.hpp"
#include "nhdyn/analysis/residuals.hpp"
#include "nhdyn/core/error.hpp"
#include "nhdyn/formulation/diagnosis.hpp"
#include "nhdyn/formulation/program_motion.hpp"

namespace nhdyn {
namespace {

// The rule for a derived output or an event that is NaN or infinite during a run (docs/cli.md):
// the run ends there, as a numerical failure, with this message; the rows before are kept.
std::string non_finite_message(const std::string& kind, const std::string& where, const std::string& name,
                               const std::string& expression, double value, double t, const std::string& state) {
  const std::string text = std::isnan(value) ? "NaN" : fmt::format("{}", value);  // not "-nan"
  return fmt::format("{}{} '{}' ({}) is {} at t = {:.6g}, where {}: it is not defined on this motion; write it in a "
                     "form defined along the motion, or end the run before (--t-end, a stop event)",
                     where.empty() ? "" : where + ": ", kind, name, expression, text, t, state);
}

// The first constraint residual of a row that is NaN or infinite (a terrain with a pole, its
// slope infinite where the contact point reaches it), as non_finite_message words it; "" when all
// are finite. The residuals are the columns residual_pos_, residual_vel_, residual_acc_ (Data's
// phi, f and e, in the constraints' order).
std::string non_finite_residual(const Model& model, const Data& data, double t) {
  Eigen::Index position = 0, velocity = 0;
  for (std::size_t i = 0; i < model.constraints.size(); ++i) {
    const Constraint& c = model.constraints[i];
    double value = 0.0;
    const char* level = nullptr;
    if (c.level == ConstraintLevel::position && !std::isfinite(value = data.phi(position++))) level = "position";
    else if (c.level != ConstraintLevel::acceleration && !std::isfinite(value = data.f(velocity++))) level = "velocity";
    else if (!std::isfinite(value = data.e(static_cast<Eigen::Index>(i)))) level = "acceleration";
    if (level)
      return non_finite_message(fmt::format("the {} residual of constraint", level), c.where, c.name, c.expression,
                                value, t, describe_state(model, data.q.data(), data.v.data()));
  }
  return "";
}

// A run whose explicit integrator spent a large share of its steps held by stability, not accuracy
// (IntegratorStats::stiff_steps, Hairer's test): at least 1000 steps and a quarter of all. "" when
// not, or for the other integrators. The friction's sentence only where a contact with friction
// has a single coefficient (mu_k = mu_s, the last values `data` holds).
std::string stiffness_warning(const Model& model, const Data& data, const IntegratorOptions& integrator,
                              const IntegratorStats& stats, bool projection) {
  if (stats.stiff_steps < std::max(1000L, stats.steps / 4)) return "";
  bool single = false;
  if (model.contact_modes)
    for (std::size_t c = 0; c < model.contact_modes->contacts.size(); ++c)
      single = single || (model.contact_modes->contacts[c].friction && c < data.modes.mu_s.size() &&
                          data.modes.mu_s[c] == data.modes.mu_k[c]);
  // A run of many short segments (contact modes switching) may never hold 15 stiff steps in a row.
  const std::string from = std::isnan(stats.stiff_from) ? "" : fmt::format(" from t = {:.6g}", stats.stiff_from);
  return fmt::format(
      "the run is stiff{}: {} of its {} steps were as short as the stability of {} requires, not as its accuracy "
      "does; {}{}",
      from, stats.stiff_steps, stats.steps, integrator_name(integrator.kind),
      // CVODE starts again from every projected state, so that an implicit integrator under
      // projection takes as many steps and drifts more (docs/stabilization.md).
      projection ? "with --stabilize projection keep the explicit integrator (an implicit one restarts at every "
                   "projection and takes as many steps); without projection, --integrator cvode-bdf takes far fewer"
                 : "an implicit integrator takes far fewer steps there: --integrator cvode-bdf",
      single ? ". A contact that starts to slide with a single friction coefficient makes such a stretch (its slip "
               "grows from 0 as t^2, and its direction is stiff while the slip is small); friction = [mu_s, mu_k] "
               "with mu_k < mu_s does not"
             : "");
}

// Outputs beyond this many rows are refused: at ~100 bytes a row that is a 10 GB file.
constexpr double kMaxOutputs = 1e8;

StepEnd project(const Model& model, Data& data, const ProjectionOptions& options, double t, double* y,
                SimulationSummary& summary) {
  ProjectionResult result;
  const Status status = compute_projection(model, data, t, y, y + model.n(), options, result);
  if (status != Status::ok) return {status, false};
  if (result.changed()) {
    ++summary.projection.count;
    summary.projection.iterations += result.position_iterations + result.velocity_iterations;
    summary.projection.max_position_correction = std::max(summary.projection.max_position_correction, result.position_change);
    summary.projection.max_velocity_correction = std::max(summary.projection.max_velocity_correction, result.velocity_change);
  }
  return {Status::ok, result.changed()};
}

// y = [q; q'], y' = [q'; q'']; with an energy balance also the work of the forces, of the
// reactions and of the explicit time dependence, W' = P (docs/derivations/energy-balance.md
// section 3), outside the error norm (OdeSystem::error_size).
class MechanicalOde final : public OdeSystem {
 public:
  MechanicalOde(const Model& model, Data& data, const FormulationOptions& options, const SimulationOptions& run,
                SimulationSummary& summary, ConstraintWatch* watch, WatchedEvents& watched)
      : model_(model), data_(data), options_(options), run_(run), summary_(summary), watch_(watch), watched_(watched),
        n_(model.n()), balance_(model.evaluator->has_energy_balance()),
        friction_(balance_ && model.contact_modes != nullptr) {}

  // The works: of the forces, the reactions, the explicit time dependence, and with contact modes
  // the friction's and the impacts' loss (model/contact_modes.hpp; the loss changes only at
  // touchdowns, analysis/detail/contact_switches.cpp).
  int size() const override { return 2 * n_ + (balance_ ? kWorks : 0) + (friction_ ? 2 : 0); }
  int error_size() const override { return 2 * n_; }

  Status rhs(double t, const double* y, double* ydot) override {
    // The stages want q'' alone: contact values wait for the switches and rows that read them.
    data_.modes.defer_forces = true;
    const Status status = compute_dynamics(model_, data_, options_, t, y, y + n_);
    data_.modes.defer_forces = false;
    if (status != Status::ok) return status;
    // One loop, not two calls of memcpy: n is small where a right-hand side is cheap.
    const double* qdd = data_.qdd.data();
    for (int i = 0; i < n_; ++i) {
      ydot[i] = y[n_ + i];
      ydot[n_ + i] = qdd[i];
    }
    if (balance_) {
      compute_power(model_, data_);
      ydot[2 * n_] = data_.power_forces;
      ydot[2 * n_ + 1] = data_.power_reactions;
      ydot[2 * n_ + 2] = data_.power_time;
      if (friction_) {
        ydot[2 * n_ + 3] = data_.power_friction;
        ydot[2 * n_ + 4] = 0.0;
      }
    }
    return Status::ok;
  }
  static constexpr int kWorks = 3;

  StepEnd after_step(double t, double* y) override {
    // A contact whose equations stay regular where it is not defined (a surface's tangents
    // vanishing): located as an event where the integrator can, else ended at the step that
    // reaches it, with the state for the message (WatchedEvents).
    if (const Status status = watched_.check(t, y); status != Status::ok) return {status, false};
    // The watch reads the terms Data holds, when they are those of the step's end (the last stage
    // of dopri5, evaluated there); b depends on t, q and, for constraints nonlinear in the
    // velocities, q'.
    if (watch_ && watch_->started && data_.stage == Stage::acceleration && data_.t == t &&
        std::equal(y, y + n_, data_.q.data()) && std::equal(y + n_, y + 2 * n_, data_.v.data()))
      compute_constraint_watch(model_, data_, *watch_);
    // A sliding contact carries its slip direction from step to step (formulation/contact_modes.hpp).
    if (data_.modes.active && data_.stage == Stage::acceleration && data_.t == t &&
        std::equal(y, y + n_, data_.q.data()) && std::equal(y + n_, y + 2 * n_, data_.v.data()))
      for (std::size_t i = 0; i < data_.modes.mode.size(); ++i)
        if (data_.modes.mode[i] == ContactMode::sliding) data_.modes.direction[i] = data_.modes.sliding_direction[i];
    if (run_.stabilization != Stabilization::projection) return {};
    return project(model_, data_, run_.projection, t, y, summary_);
  }

 private:
  const Model& model_;
  Data& data_;
  const FormulationOptions& options_;
  const SimulationOptions& run_;
  SimulationSummary& summary_;
  ConstraintWatch* watch_;  // null when the run does not watch
  WatchedEvents& watched_;
  int n_;
  bool balance_;
  bool friction_;
};

// At an output, after compute_dynamics and compute_energy: the power, the integrated work (the
// states past [q; q']) and the balance h - h(t0) - W (docs/derivations/energy-balance.md section 3).
void record_balance(const Model& model, Data& data, const double* work, SimulationSummary& summary) {
  compute_power(model, data);
  data.work_forces = work[0];
  data.work_reactions = work[1];
  data.work_time = work[2];
  data.work_friction = model.contact_modes ? work[3] : 0.0;
  data.impact_loss = model.contact_modes ? work[4] : 0.0;
  const double W = work[0] + work[1] + work[2] + data.work_friction - data.impact_loss;
  data.balance_error = data.energy_function - summary.energy.function_initial - W;
  summary.energy.balance_error = std::max(summary.energy.balance_error, std::abs(data.balance_error));
  summary.energy.work_forces = work[0];
  summary.energy.work_reactions = work[1];
  summary.energy.work_time = work[2];
  summary.energy.work_friction = data.work_friction;
  summary.energy.impact_loss = data.impact_loss;
  summary.energy.change = data.energy - summary.energy.initial;
  summary.energy.function_change = data.energy_function - summary.energy.function_initial;
}

// The dynamics that events reading q'' or R (or the contact forces) need
// (ModelEventFunctions::Dynamics): the run's own solve, on the run's Data (the right-hand side
// recomputes what it needs at every call).
ModelEventFunctions::Dynamics event_dynamics(const Model& model, Data& data, const FormulationOptions& formulation) {
  return [&model, &data, &formulation](double t, const double* y, const double** qdd, const double** R,
                                       const double** F) {
    const Status status = compute_dynamics(model, data, formulation, t, y, y + model.n());
    *qdd = data.qdd.data();
    *R = data.R.data();
    if (status == Status::ok && F != nullptr) {
      compute_contact_forces(model, data);
      *F = data.contact.values.data();
    }
    return status;
  };
}

}  // namespace

std::string_view stabilization_name(Stabilization stabilization) { return name_of(kStabilizations, stabilization); }

Stabilization parse_stabilization(std::string_view name) {
  if (const StabilizationInfo* info = find_named(kStabilizations, name)) return info->value;
  throw InputError("unknown stabilization '" + std::string(name) + "'; choose one of: " + list_names(kStabilizations));
}

namespace {

// Two times closer than this are one row (simulate's row callback below): the resolution of time
// near a and b, 64 units of round-off of the larger.
double time_resolution(double a, double b) {
  return 64.0 * std::numeric_limits<double>::epsilon() * std::max({1.0, std::abs(a), std::abs(b)});
}

}  // namespace

std::vector<double> make_output_times(double t0, double t_end, double output_step) {
  if (!std::isfinite(t_end) || !(t_end > t0))
    throw InputError(fmt::format("the end time t_end = {} must be a finite time after the start time {}",
                                 t_end, t0));
  // A run shorter than the times nhdyn tells apart (--t-end 5e-324) failed as a step size underflow.
  if (!(t_end - t0 > time_resolution(t0, t_end)))
    throw InputError(fmt::format("the end time t_end = {} is within {:.3g} of the start time {}, closer than nhdyn tells "
                                 "times apart; choose a later end time",
                                 t_end, time_resolution(t0, t_end), t0));
  if (!std::isfinite(output_step) || !(output_step > 0.0))
    throw InputError(fmt::format("the output step {} must be a positive, finite time", output_step));
  if (!(output_step > time_resolution(t0, t_end)))
    throw InputError(fmt::format("the output step {} is below {:.3g}, closer than nhdyn tells rows apart over "
                                 "[{}, {}]: its rows would be one; choose a larger output step",
                                 output_step, time_resolution(t0, t_end), t0, t_end));
  const double count = std::floor((t_end - t0) / output_step + 1e-9);
  if (count > kMaxOutputs)
    throw InputError(fmt::format("an output step of {} over [{}, {}] gives {:.3g} rows, more than the "
                                 "limit of {:.0g}; choose a larger output step",
                                 output_step, t0, t_end, count, kMaxOutputs));
  std::vector<double> times;
  times.reserve(static_cast<std::size_t>(count) + 2);
  for (long i = 0; i <= static_cast<long>(count); ++i) times.push_back(t0 + static_cast<double>(i) * output_step);
  // The last output is t_end itself, whether or not the step divides the interval.
  // (A last grid time within the resolution of t_end would be merged with its row: it becomes t_end.)
  // (Relative to the run's span too: with --t-end 1e-13 and a step of 0.01, 1e-9 of the step merged
  // the row of t0 into t_end's.)
  if (t_end - times.back() >
      std::max(1e-9 * std::min(output_step, t_end - t0), time_resolution(times.back(), t_end)))
    times.push_back(t_end);
  else times.back() = t_end;
  return times;
}

namespace {

// The times the integrator reports at: output_step's grid, or the given output times with t0 in
// front (the run's start state is computed there, for E0 and h0, and not handed on as a row).
std::vector<double> calc_run_times(const Model& model, const SimulationOptions& options) {
  if (options.output_times.empty()) return make_output_times(model.t0, options.t_end, options.output_step);
  std::vector<double> times;
  times.reserve(options.output_times.size() + 1);
  if (options.output_times.front() != model.t0) times.push_back(model.t0);
  for (std::size_t i = 0; i < options.output_times.size(); ++i) {
    const double t = options.output_times[i];
    if (!std::isfinite(t) || t < model.t0 || t > options.t_end)
      throw InputError(fmt::format("the output time {} (index {}) is {}; output times lie in [t0, t_end] = [{}, {}]",
                                   t, i, std::isfinite(t) ? "outside the run" : "not finite", model.t0, options.t_end));
    if (i > 0 && !(t > options.output_times[i - 1]))
      throw InputError(fmt::format("the output times must increase: {} (index {}) follows {}", t, i,
                                   options.output_times[i - 1]));
    // (The start, when it is not an output time, is no row: a first time near it merges with nothing.)
    const double before = i > 0 ? options.output_times[i - 1] : model.t0;
    if (i > 0 && !(t - before > time_resolution(t, before)))
      throw InputError(fmt::format("the output time {} (index {}) is within {:.3g} of {}, closer than nhdyn tells "
                                   "rows apart, so the two would be one row; leave one out",
                                   t, i, time_resolution(t, before), before));
    times.push_back(t);
  }
  if (options.output_times.size() > static_cast<std::size_t>(kMaxOutputs))
    throw InputError(fmt::format("{} output times, more than the limit of {:.0g}", options.output_times.size(),
                                 kMaxOutputs));
  // A run needs an interval: output times that all sit on the start leave nothing to integrate.
  if (!(times.back() > model.t0))
    throw InputError(fmt::format("the last output time {} must be after the model's start time t0 = {}",
                                 times.back(), model.t0));
  return times;
}

}  // namespace

void check_simulation_options(const Model& model, const SimulationOptions& options) {
  calc_run_times(model, options);
  const IntegratorOptions& io = options.integrator;
  if (io.kind != IntegratorKind::rk4) {
    if (!std::isfinite(io.rtol) || !(io.rtol > 0.0))
      throw InputError(fmt::format("the relative tolerance rtol = {} must be positive and finite (e.g. 1e-8)", io.rtol));
    if (!std::isfinite(io.atol) || !(io.atol > 0.0))
      throw InputError(fmt::format("the absolute tolerance atol = {} must be positive and finite (e.g. 1e-10)", io.atol));
    if (io.rtol < 1e-15)
      throw InputError(fmt::format("the relative tolerance rtol = {} is below what double precision can "
                                   "deliver; use 1e-14 or more", io.rtol));
    // A relative error of 100 % or more bounds nothing: the steps grew until the state overflowed,
    // and the run ended blaming the model.
    if (io.rtol >= 1.0)
      throw InputError(fmt::format("the relative tolerance rtol = {} must be below 1 (a relative error of 100 %); "
                                   "the default is 1e-8",
                                   io.rtol));
  }
  // The one check of the step budget, for the command line and Python alike.
  if (io.max_steps < 1)
    throw InputError(fmt::format("the step budget max_steps (--max-steps) = {} must be at least 1: it counts the "
                                 "accepted and rejected steps of the whole run (default {})",
                                 io.max_steps, IntegratorOptions{}.max_steps));
  if (!options.events.empty() && !supports_events(io.kind))
    throw InputError(fmt::format("events need an integrator that can locate them; {} has no continuous extension: "
                                 "choose dopri5, dop853, cvode-bdf or cvode-adams",
                                 integrator_name(io.kind)));
  if (!std::isfinite(io.step) || io.step < 0.0)
    throw InputError(fmt::format("the step {} must be positive (or 0 for the default)", io.step));
  if (options.stabilization == Stabilization::baumgarte) check_baumgarte_gains(options.formulation.baumgarte);
  if (options.stabilization == Stabilization::projection) {
    if (!std::isfinite(options.projection.tolerance) || !(options.projection.tolerance > 0.0))
      throw InputError(fmt::format("the projection tolerance {} must be positive and finite (e.g. 1e-13)",
                                   options.projection.tolerance));
    if (options.projection.max_iterations < 1)
      throw InputError(fmt::format("the projection needs at least one Newton iteration, not {}",
                                   options.projection.max_iterations));
  }
  // Events are told apart by name in the CSV, FILE-events.csv and the summary.
  for (std::size_t i = 0; i < options.events.size(); ++i) {
    const Event& e = options.events[i];
    if (e.name.empty())
      throw InputError(fmt::format("the event {} ({}) has an empty name; give it one (--event NAME=EXPR)", i + 1,
                                   e.where.empty() ? e.expression : e.where));
    for (std::size_t j = 0; j < i; ++j)
      if (options.events[j].name == e.name)
        throw InputError(fmt::format("two events are named '{}' ({} and {}); give each its own name", e.name,
                                     options.events[j].where.empty() ? options.events[j].expression
                                                                      : options.events[j].where,
                                     e.where.empty() ? e.expression : e.where));
  }
  if (model.m() > 0 && options.formulation.method != Formulation::sanh)
    throw InputError(fmt::format("model '{}' has programs ([[programs]]), which only the sanh formulation solves "
                                 "(docs/derivations/program-motion.md); choose --method sanh",
                                 model.name));
  if (options.formulation.program_feedback.enabled) {
    if (model.m() == 0)
      throw InputError(fmt::format("--program-feedback needs programs, and model '{}' has none ([[programs]] in "
                                   "docs/model-format.md)",
                                   model.name));
    check_program_feedback(options.formulation.program_feedback);
  }
  if (options.watch_constraints && (!std::isfinite(options.watch_factor) || !(options.watch_factor > 1.0)))
    throw InputError(fmt::format("the constraint watch's factor {} must be a finite number above 1 (the default is "
                                 "{:g}, three orders of magnitude)",
                                 options.watch_factor, kConstraintWatchFactor));
  if (model.contact_modes) {
    // The modes are solved by their own sanh kernel (formulation/contact_modes.hpp) and switch at events.
    // A sliding contact's friction is a reaction along a direction that is not a constraint row:
    // only the Do Sanh form takes it (D annihilates that direction), so another method is refused
    // by name, with the one to use.
    if (options.formulation.method != Formulation::sanh)
      throw InputError(fmt::format(
          "model '{}' has contacts that may slide or lift off (friction or unilateral, docs/contact-modes.md): "
          "--method {} cannot solve them (a sliding contact's friction is a reaction the Do Sanh form alone "
          "takes); use --method sanh (the default; method=\"sanh\" from Python), or remove friction and "
          "unilateral (and restitution, mode) from the [[contacts]] and [[wheels]] entries to run --method {}",
          model.name, formulation_name(options.formulation.method), formulation_name(options.formulation.method)));
    const char* why = options.stabilization == Stabilization::projection
                          ? "no projection (the projection would hold a sliding contact's slip at zero)"
                      : !supports_events(io.kind) ? "an integrator that locates events (dopri5, dop853, cvode-bdf, cvode-adams)"
                      : options.path == Path::sparse ? "the dense path"
                                                     : nullptr;
    if (why)
      throw InputError(fmt::format("model '{}' has contacts that may slide or lift off (friction or unilateral, "
                                   "docs/contact-modes.md); they need {}",
                                   model.name, why));
  }
  if (options.formulation.complement == Complement::analytic && !model.evaluator->has_complement())
    throw InputError(fmt::format("model '{}' has no analytic D; choose --complement qr or partition", model.name));
}

namespace {

// The run's start state: the model's q0 and v0 with the contact points' coordinates the model
// added found from the rest of the start (its parameters or initial values may have changed since
// it was made), fixed when asked, checked against the constraints and the programs; and the mode
// each contact starts in.
void prepare_start_state(const Model& model, Data& data, const SimulationOptions& options, SimulationSummary& summary,
                         Vector& q0, Vector& v0) {
  complete_initial_state(model, data, model.t0, q0, v0);
  check_state_or_throw(model, data, model.t0, q0.data(), v0.data());
  if (options.fix_initial) {
    summary.initial_fix = fix_free_initial_values(model, data, model.t0, q0, v0);
    q0 = summary.initial_fix->q;
    v0 = summary.initial_fix->v;
    check_state_or_throw(model, data, model.t0, q0.data(), v0.data());
  }
  // The mode each contact starts in, before the check: a sliding contact's slip is no violation.
  choose_initial_contact_modes(model, data, options.formulation, model.t0, q0, v0);
  // A contact point not defined at the start (a disk lying flat) is a bad start, as a singular
  // system there is: its watch would end the run only after the first step.
  if (const std::string singular = singular_contact_message(model, data, model.t0, q0.data(), v0.data(),
                                                            "start it where the contact point is defined");
      !singular.empty())
    throw ModelError(fmt::format("model '{}': at the initial state: {}", model.name, singular));
  if (!options.fix_initial) check_initial_state(model, data, model.t0, q0, v0, options.initial_tolerance);
  check_programs_at_initial_state(model, data, options.formulation, model.t0, q0, v0, options.initial_tolerance);
}

// What simulate does at each output time (and at each event, before its record): the state
// (projected, with projection), the dynamics and every quantity of a row computed in Data, the
// summary's maxima updated, and the row handed to the caller unless it is a hidden start or the
// same time as the last row.
class RowRecorder {
 public:
  RowRecorder(const Model& model, Data& data, const SimulationOptions& options, const FormulationOptions& formulation,
              ConstraintWatch& watch, SimulationSummary& summary, const RowFn& row, std::size_t states)
      : model_(model), data_(data), options_(options), formulation_(formulation), watch_(watch), summary_(summary),
        row_(row), states_(states), y_out_(states),
        // With given output times that do not start at t0, the start is computed but not a row.
        hide_start_(!options.output_times.empty() && options.output_times.front() != model.t0) {}

  Status record(double t, const double* y) {
    const int n = model_.n();
    if (options_.stabilization == Stabilization::projection) {
      // Between step ends the integrator interpolates; the solution it reports is the projected one.
      std::copy(y, y + states_, y_out_.begin());
      y = y_out_.data();
      const StepEnd end = project(model_, data_, options_.projection, t, y_out_.data(), summary_);
      if (end.status != Status::ok) {
        failure_ = end.status;
        return Status::stopped;
      }
    }
    const Status status = compute_dynamics(model_, data_, formulation_, t, y, y + n);
    if (status != Status::ok) {
      failure_ = status;
      return Status::stopped;
    }
    if (options_.watch_constraints) compute_constraint_watch(model_, data_, watch_);
    compute_residuals(model_, data_);
    if (std::string bad = non_finite_residual(model_, data_, t); !bad.empty()) {
      message_ = std::move(bad);
      failure_ = Status::non_finite;
      return Status::stopped;
    }
    record_contact_gaps(model_, data_);  // nothing without contact modes
    compute_energy(model_, data_);
    compute_contact_forces(model_, data_);  // nothing for a model without contacts
    compute_outputs(model_, data_);
    for (int i = 0; i < model_.outputs.count(); ++i)
      if (!std::isfinite(data_.outputs.values(i))) {
        const DerivedOutput& o = model_.outputs.list[static_cast<std::size_t>(i)];
        message_ = non_finite_message("derived output", o.where, o.name, o.expression, data_.outputs.values(i), t,
                                      describe_state(model_, data_.q.data(), data_.v.data()));
        failure_ = Status::non_finite;
        return Status::stopped;
      }
    update_summary(y);
    if (hide_start_) {
      hide_start_ = false;
      return Status::ok;
    }
    // An event at an output time (or two events at one time) is one row (docs/cli.md, "Events"):
    // the first written at that t, to round-off, stands for them all; each event keeps its record.
    if (summary_.outputs > 0 && std::abs(t - last_row_t_) <= time_resolution(t, last_row_t_)) return Status::ok;
    last_row_t_ = t;
    ++summary_.outputs;
    row_(data_);
    return Status::ok;
  }

  // Why a row stopped the run (ok when none did), and the message when it is not the dynamics' own failure.
  Status failure() const { return failure_; }
  const std::string& message() const { return message_; }

 private:
  // The summary's energies and largest residuals, with the row's Data computed.
  void update_summary(const double* y) {
    const int n = model_.n();
    if (first_output_) {
      summary_.energy.initial = data_.energy;
      summary_.energy.function_initial = data_.energy_function;
      first_output_ = false;
    }
    if (summary_.energy.has_balance) record_balance(model_, data_, y + 2 * n, summary_);
    summary_.residuals.position = std::max(summary_.residuals.position, max_abs(data_.phi));
    summary_.residuals.velocity = std::max(summary_.residuals.velocity, max_abs(data_.f));
    summary_.residuals.acceleration = std::max(summary_.residuals.acceleration, max_abs(data_.e));
    if (model_.m() > 0) {
      compute_program_residuals(model_, data_);
      summary_.program.position = std::max(summary_.program.position, max_abs(data_.motion.phi));
      summary_.program.velocity = std::max(summary_.program.velocity, max_abs(data_.motion.f));
      summary_.program.acceleration = std::max(summary_.program.acceleration, max_abs(data_.motion.e));
    }
    if (summary_.energy.has_energy)
      summary_.energy.drift = std::max(summary_.energy.drift, std::abs(data_.energy - summary_.energy.initial));
  }

  const Model& model_;
  Data& data_;
  const SimulationOptions& options_;
  const FormulationOptions& formulation_;
  ConstraintWatch& watch_;
  SimulationSummary& summary_;
  const RowFn& row_;
  std::size_t states_;
  std::vector<double> y_out_;
  bool hide_start_;
  bool first_output_ = true;
  double last_row_t_ = 0.0;  // the time of the last row written, once summary.outputs > 0
  Status failure_ = Status::ok;
  std::string message_;  // why failure_, when it is not the dynamics' own failure
};

// An event's record, with the state as written (projected, if so), after its row.
void record_crossing(const Model& model, const Data& data, int index, const std::string& name, double t,
                     SimulationSummary& summary) {
  EventRecord record;
  record.index = index;
  record.name = name;
  record.t = t;
  record.q.assign(data.q.data(), data.q.data() + model.n());
  record.v.assign(data.v.data(), data.v.data() + model.n());
  summary.events.crossings.push_back(std::move(record));
}

// A stop condition that never held: most likely a sign or threshold that cannot be met.
void note_unmet_stops(const Model& model, const std::vector<const Event*>& events, double t_reached,
                      SimulationSummary& summary) {
  for (std::size_t i = 0; i < events.size(); ++i) {
    const Event& e = *events[i];
    if (e.action != EventAction::stop) continue;
    if (std::any_of(summary.events.crossings.begin(), summary.events.crossings.end(),
                    [&](const EventRecord& r) { return r.index == static_cast<int>(i) && r.name == e.name; }))
      continue;
    // An option quotes its own text ("--stop-when \"x > 2\""); a file's event is named at its place.
    const bool option = e.where.starts_with("--") && e.where.find(e.expression) != std::string::npos;
    const std::string what = option ? "the stop condition " + e.where
                                    : fmt::format("{}the stop event '{}' ({})", e.where.empty() ? "" : e.where + ": ",
                                                  e.name, e.expression);
    summary.events.unmet_stops.push_back(fmt::format(
        "{} never {} between t = {:g} and t = {:g}: the run went to the end; check its sign, direction or threshold",
        what, e.condition ? "became true" : "crossed zero in its direction", model.t0, t_reached));
  }
}

// The largest |q|, |q'| of a start state.
double largest_state(const Vector& q0, const Vector& v0) {
  return std::max(q0.size() ? q0.cwiseAbs().maxCoeff() : 0.0, v0.size() ? v0.cwiseAbs().maxCoeff() : 0.0);
}

// An absolute tolerance at least the size of every state at the start (and not below 1e-3, for a
// state that starts at rest at the origin): the error test of an adaptive integrator accepts any
// step, whatever the model.
bool atol_bounds_nothing(const IntegratorOptions& integrator, double largest) {
  return integrator.kind != IntegratorKind::rk4 && integrator.atol >= std::max(largest, 1e-3);
}

// What the integrator's options may have done to a run that failed, said after the failure's own
// words (which blame the model); "" otherwise. An adaptive run that blew up or stalled under an
// absolute tolerance at least the size of every state at the start: its error test bounded
// nothing, and the steps grew until the integrator went unstable.
std::string integrator_hint(const IntegratorOptions& integrator, Status status, const Vector& q0,
                                 const Vector& v0) {
  // rk4's steps do not follow the tolerances: a stage that overflows is most often a step too long
  // for the motion (its time is the stage's, inside the step from the time the run reached).
  if (integrator.kind == IntegratorKind::rk4)
    return status != Status::non_finite
               ? ""
               : fmt::format(". Note rk4's fixed step ({}): a step too long for the motion makes its stages overflow "
                             "whatever the model, and the time above is that of the stage that did; try a smaller "
                             "--step, or an adaptive integrator (dopri5)",
                             integrator.step > 0.0 ? fmt::format("--step {:g}", integrator.step)
                                                   : std::string("a tenth of the output step"));
  if (status != Status::non_finite && status != Status::too_many_steps && status != Status::step_size_underflow)
    return "";
  const double largest = largest_state(q0, v0);
  if (!atol_bounds_nothing(integrator, largest)) return "";
  return fmt::format(
      ". Note the absolute tolerance atol = {:g}: at least the size of every state at the start (largest |q|, |q'| "
      "{:g}), so the error test bounds nothing and the steps grow until the integrator is unstable, whatever the "
      "model; give an atol well below the states' size (the default is 1e-10)",
      integrator.atol, largest);
}

// The message of a run that failed, in the most telling words there are.
std::string explain_run_failure(const Model& model, const Data& data, const ModelEventFunctions& event_functions,
                                const WatchedEvents& watched, const IntegrationResult& result,
                                const std::string& output_message, Status status) {
  // The kernels recorded the details of a failed evaluation in data; prefer those words.
  std::string message = data.status != Status::ok ? explain_failure(model, data) : result.message;
  // An event not finite at its latest evaluation ended the run, unless the dynamics failed after it.
  const ModelEventFunctions::NonFinite& bad_event = event_functions.non_finite();
  if (status == Status::non_finite && bad_event.index >= 0 &&
      (data.status == Status::ok || !(data.failed_t > bad_event.t))) {
    const Event& e = event_functions.event(bad_event.index);
    message = non_finite_message("event", e.where, e.name, e.expression, bad_event.g, bad_event.t,
                                 describe_state(model, bad_event.y.data(), bad_event.y.data() + model.n()));
  }
  if (!output_message.empty()) message = output_message;
  // A contact watch that ended the run (located at its threshold, or at the step past it).
  if (watched.fired() >= 0 && status == Status::singular_system) {
    const ContactWatch& w = model.contact_watches[static_cast<std::size_t>(watched.fired())];
    const double t = watched.fired_t(), *q = watched.fired_y(), *v = watched.fired_y() + model.n();
    return watch_message(model, w, calc_watch_measure(model, w, t, q, v), t, q, v);
  }
  // A contact point that is not defined there says so, rather than the equations' symptom of it.
  if (const std::string singular = singular_contact_message(model, data, data.t, data.q.data(), data.v.data());
      !singular.empty())
    message = singular;
  if (message.empty()) message = fmt::format("{} at t = {:.6g}", describe(status), result.t_reached);
  return message;
}

}  // namespace

SimulationSummary simulate(const Model& model, const SimulationOptions& options, const RowFn& row) {
  check_simulation_options(model, options);
  const std::vector<double> times = calc_run_times(model, options);
  // The Data of the chosen formulation only, on the path the model takes (model/data.hpp).
  DataOptions data_options;
  data_options.path = options.path;
  data_options.method = options.formulation.method;
  data_options.projection = options.fix_initial || options.stabilization == Stabilization::projection;
  Data data = make_data(model, data_options);
  // rk4 takes no smaller step near a singular S, and could step across it (model/data.hpp).
  data.motion.watch_sign = options.integrator.kind == IntegratorKind::rk4;
  SimulationSummary summary;
  Vector q0 = model.q0, v0 = model.v0;
  prepare_start_state(model, data, options, summary, q0, v0);

  const int n = model.n();
  summary.energy.has_energy = model.evaluator->has_energy();
  summary.energy.has_balance = model.evaluator->has_energy_balance();
  FormulationOptions formulation = options.formulation;
  formulation.baumgarte.enabled = options.stabilization == Stabilization::baumgarte;
  ConstraintWatch watch = make_constraint_watch(model, data, options.formulation.method, options.watch_factor);
  WatchedEvents watched(model, data);
  MechanicalOde ode(model, data, formulation, options, summary, options.watch_constraints ? &watch : nullptr, watched);
  const auto states = static_cast<std::size_t>(ode.size());
  std::vector<double> y0(states, 0.0);  // the work starts at 0
  std::copy(q0.data(), q0.data() + n, y0.begin());
  std::copy(v0.data(), v0.data() + n, y0.begin() + n);
  RowRecorder recorder(model, data, options, formulation, watch, summary, row, states);
  const OutputFn output = [&recorder](double t, const double* y) { return recorder.record(t, y); };

  std::vector<const Event*> events;
  for (const Event& e : options.events) events.push_back(&e);
  for (const Event* e : events) summary.events.names.push_back(e->name);
  ModelEventFunctions event_functions(model, events, [&](int i, double t, const double* y) -> Status {
    // The row at the crossing, then its record with the state as written (projected, if so).
    if (output(t, y) == Status::stopped) return recorder.failure();
    record_crossing(model, data, i, events[static_cast<std::size_t>(i)]->name, t, summary);
    return Status::ok;
  }, event_dynamics(model, data, formulation));
  event_functions.require_valid_start(model.t0, y0.data());
  // What the integrator locates: the run's events, and the contact watches where it can.
  EventFunctions* located = events.empty() ? nullptr : &event_functions;
  if (!watched.empty() && supports_events(options.integrator.kind)) {
    watched.set_user(located);
    located = &watched;
  }

  const auto start = std::chrono::steady_clock::now();
  // Contacts that may slide or lift off: the run goes on through their switches (contact_switches.hpp).
  ContactSwitches switches(model, data, formulation, static_cast<int>(states), located,
                           [&](const std::string& name, double t, const double* y) -> Status {
                             if (output(t, y) == Status::stopped) return recorder.failure();
                             auto at = std::find(summary.events.names.begin(), summary.events.names.end(), name);
                             if (at == summary.events.names.end()) at = summary.events.names.insert(at, name);
                             record_crossing(model, data, static_cast<int>(at - summary.events.names.begin()), name, t,
                                             summary);
                             return Status::ok;
                           },
                           times.back() - model.t0);
  const IntegrationResult result =
      model.contact_modes ? integrate_contact_modes(ode, options.integrator, model.t0, y0.data(), times, output, switches)
                          : integrate(ode, options.integrator, model.t0, y0.data(), times, output,
                                      located);
  summary.wall_time = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  summary.status = recorder.failure() != Status::ok ? recorder.failure() : result.status;
  summary.events.stopped_by = event_functions.stopped_by();
  // A stop event ends the run as planned.
  if (summary.status == Status::stopped && summary.events.stopped_by >= 0) summary.status = Status::ok;
  if (summary.status == Status::ok && summary.events.stopped_by < 0)
    note_unmet_stops(model, events, result.t_reached, summary);
  summary.t_reached = result.t_reached;
  summary.sparse = data.sparse;
  summary.partition_changes = data.partition_changes;
  summary.stats = result.stats;
  summary.energy.function_differs = summary.energy.has_balance && !model.evaluator->energy_function_is_energy();
  summary.watch.warnings = watch.warnings;
  for (const ConstraintWarning& w : watch.warnings) summary.warnings.push_back(format_constraint_warning(model, w));
  summary.warnings.insert(summary.warnings.end(), switches.warnings().begin(), switches.warnings().end());
  summary.stiffness = stiffness_warning(model, data, options.integrator, summary.stats,
                                        options.stabilization == Stabilization::projection);
  summary.watch.largest_row_factor = watch.largest_row_factor;
  summary.watch.largest_condition_factor = watch.largest_condition_factor;
  summary.watch.watched_states = watch.states;
  // A run that got through with such an atol took steps as long as its outputs allowed: its
  // numbers are the integrator's, not the model's, and nothing else would say so.
  // The largest state at the start or at the end: a run from rest at the origin may move far.
  if (const double largest = std::max(largest_state(q0, v0), largest_state(data.q, data.v));
      summary.status == Status::ok && atol_bounds_nothing(options.integrator, largest))
    summary.warnings.push_back(fmt::format(
        "the absolute tolerance atol = {:g} is at least the size of every state at the start and at the end "
        "(largest |q|, |q'| {:g}): the error test bounded nothing, the steps were not chosen for accuracy, and the motion may "
        "be far from the model's (its residuals and energy balance say how far); give an atol well below the "
        "states' size (the default is 1e-10)",
        options.integrator.atol, largest));
  if (summary.status != Status::ok)
    summary.message = explain_run_failure(model, data, event_functions, watched, result, recorder.message(),
                                          summary.status) +
                      integrator_hint(options.integrator, summary.status, q0, v0);
  return summary;
}

}  // namespace nhdyn
