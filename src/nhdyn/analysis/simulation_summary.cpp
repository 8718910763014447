#include "nhdyn/analysis/simulation_summary.hpp"

#include <fmt/format.h>

#include <iterator>

#include "nhdyn/analysis/simulation.hpp"
#include "nhdyn/model/contact_forces.hpp"

namespace nhdyn {
namespace {

std::string format_residual(double value, bool defined) { return defined ? fmt::format("{:.3g}", value) : "-"; }

}  // namespace

std::string format_status(const SimulationSummary& summary) {
  return summary.status == Status::ok ? "ok" : std::string(describe(summary.status));
}

std::string format_failure_note(const SimulationSummary& summary) {
  if (summary.status == Status::ok) return {};
  return fmt::format("  FAILED at t = {:.4g}: {}", summary.t_reached, summary.message);
}

std::string format_steps(const SimulationSummary& summary) {
  return fmt::format("  steps {} (rejected {}), right-hand-side evaluations {}, wall time {:.3g} ms\n",
                     summary.stats.steps, summary.stats.rejected_steps, summary.stats.rhs_evaluations,
                     summary.wall_time * 1e3);
}

std::string format_residuals(const Model& model, const ResidualMaxima& residuals) {
  return fmt::format("  max residual: position {}, velocity {}, acceleration {}\n",
                     format_residual(residuals.position, model.position_constraints() > 0),
                     format_residual(residuals.velocity, model.velocity_constraints() > 0),
                     format_residual(residuals.acceleration, model.s() > 0));
}

std::string format_program(const Model& model, const ResidualMaxima& program, const ProgramFeedback& feedback) {
  if (model.m() == 0) return {};
  return fmt::format("  programs: {}, max residual: position {}, velocity {}, acceleration {}{}\n", model.m(),
                     format_residual(program.position, model.position_programs() > 0),
                     format_residual(program.velocity, model.velocity_programs() > 0),
                     format_residual(program.acceleration, true),
                     feedback.enabled
                         ? fmt::format(" (feedback alpha {:g} 1/s, beta {:g} 1/s)", feedback.alpha, feedback.beta)
                         : "");
}

std::string format_energy(const Model& model, const EnergySummary& energy) {
  const EnergySummary& e = energy;
  if (!e.has_balance) {
    if (e.has_energy && model.m() > 0)
      return fmt::format("  energy change: {:.3g} (E0 = {:.10g}; the actuators do work, so E is not conserved)\n",
                         e.drift, e.initial);
    if (e.has_energy) return fmt::format("  energy drift: {:.3g} (E0 = {:.10g})\n", e.drift, e.initial);
    return {};
  }
  // docs/derivations/energy-balance.md section 3: the balance is the error; the work and the change
  // of the energy are physics.
  std::string out = fmt::format("  energy balance error: {:.3g} (max |h - h0 - W|)\n", e.balance_error);
  if (model.contact_modes)  // contacts that slide (docs/contact-modes.md)
    out += fmt::format("  work W: {:.10g} (forces {:.6g}, reactions {:.6g}, explicit time {:.6g}, friction {:.6g}{})\n",
                       e.work_forces + e.work_reactions + e.work_time + e.work_friction - e.impact_loss, e.work_forces,
                       e.work_reactions, e.work_time, e.work_friction,
                       e.impact_loss != 0.0 ? fmt::format(", minus impact loss {:.6g}", e.impact_loss) : "");
  else
    out += fmt::format("  work W: {:.10g} (forces {:.6g}, reactions {:.6g}, explicit time {:.6g})\n",
                       e.work_forces + e.work_reactions + e.work_time, e.work_forces, e.work_reactions, e.work_time);
  out += fmt::format("  energy change: E - E0 = {:.10g} (E0 = {:.10g})\n", e.change, e.initial);
  if (e.function_differs)
    out += fmt::format("  energy function change: h - h0 = {:.10g} (h0 = {:.10g})\n", e.function_change,
                       e.function_initial);
  return out;
}

std::string format_stabilization(const SimulationOptions& options, const ProjectionSummary& projection) {
  if (options.stabilization == Stabilization::baumgarte)
    return fmt::format("  stabilization: baumgarte (alpha {:g} 1/s, beta {:g} 1/s)\n",
                       options.formulation.baumgarte.alpha, options.formulation.baumgarte.beta);
  if (options.stabilization == Stabilization::projection)
    return fmt::format("  stabilization: projection, {} projections ({} Newton iterations), largest correction "
                       "{:.3g} in a coordinate, {:.3g} in a velocity\n",
                       projection.count, projection.iterations, projection.max_position_correction,
                       projection.max_velocity_correction);
  return {};
}

std::string format_events(const EventSummary& events, const std::string& file) {
  if (events.names.empty()) return {};
  std::string out = fmt::format("  events: {} located{}\n", events.crossings.size(),
                                file.empty() ? std::string() : fmt::format(" -> {}", file));
  constexpr std::size_t shown = 10;
  for (std::size_t i = 0; i < events.crossings.size() && i < shown; ++i)
    fmt::format_to(std::back_inserter(out), "    {} at t = {:.12g}\n", events.crossings[i].name, events.crossings[i].t);
  if (events.crossings.size() > shown)
    fmt::format_to(std::back_inserter(out), "    ... and {} more\n", events.crossings.size() - shown);
  return out;
}

std::string format_constraint_watch(const Model& model, const ConstraintWatchSummary& watch, std::size_t warnings,
                                    bool sparse) {
  // The warnings themselves go to stderr as they are; here their count and the largest degradation
  // seen, so that a clean run says the watch had nothing to report.
  if (model.s() == 0) return {};
  return fmt::format("  constraint watch: {}; largest change of a row of b x{:.3g}{}\n",
                     warnings == 0 ? std::string("no warning")
                                   : fmt::format("{} warning{} on stderr", warnings, warnings == 1 ? "" : "s"),
                     watch.largest_row_factor,
                     sparse ? std::string() : fmt::format(", of the conditioning x{:.3g}", watch.largest_condition_factor));
}

std::string format_initial_fix(const Model& model, const InitialFix& fix) {
  std::string out = "  initial state moved onto the constraints (--fix-initial):\n";
  for (int i = 0; i < model.n(); ++i) {
    const std::string& c = model.coordinates[static_cast<std::size_t>(i)];
    if (fix.dq(i) != 0.0)
      fmt::format_to(std::back_inserter(out), "    {} = {:.12g} (changed by {:+.3g}), was {:.12g}\n", c, fix.q(i),
                     fix.dq(i), fix.q(i) - fix.dq(i));
    if (fix.dv(i) != 0.0)
      fmt::format_to(std::back_inserter(out), "    {}' = {:.12g} (changed by {:+.3g}), was {:.12g}\n", c, fix.v(i),
                     fix.dv(i), fix.v(i) - fix.dv(i));
  }
  return out;
}

std::string format_contact_force_notes(const Model& model) {
  std::string out;
  if (model.contact_forces)
    for (const std::string& note : model.contact_forces->notes) out += "note: contact forces: " + note + "\n";
  return out;
}

}  // namespace nhdyn
