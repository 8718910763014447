#include "nhdyn/analysis/events.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>

#include "nhdyn/core/error.hpp"
#include "nhdyn/model/contact_forces.hpp"
#include "nhdyn/model/output.hpp"

namespace nhdyn {

ModelEventFunctions::ModelEventFunctions(const Model& model, const std::vector<const Event*>& events,
                                         Handler handler, Dynamics dynamics)
    : n_(model.n()), events_(events), handler_(std::move(handler)), dynamics_(std::move(dynamics)) {
  std::vector<double> values;
  for (const Parameter& p : model.parameters) values.push_back(p.value);
  int registers = 0;
  contact_columns_ = model.contact_forces ? model.contact_forces->values() : 0;
  for (const Event* event : events_) {
    if (event->contact_forces && contact_columns_ == 0)
      throw InputError(fmt::format("event '{}' reads contact forces, but model '{}' has none (only the wheels and knife "
                                   "edges of a multibody model have them)",
                                   event->name, model.name));
    const int coordinates = event->contact_forces ? 2 * n_ + contact_columns_ : (event->dynamics ? 2 * n_ : n_);
    if (event->g.outputs() != 1 || event->g.coordinates() != coordinates)
      throw InputError(fmt::format("event '{}' was compiled for another model ({} coordinates, {} outputs); "
                                   "this one has {} coordinates",
                                   event->name, event->g.coordinates(), event->g.outputs(), n_));
    if (event->g.parameters() > static_cast<int>(values.size()))
      throw InputError(fmt::format("event '{}' reads {} parameters; model '{}' has {}", event->name,
                                   event->g.parameters(), model.name, values.size()));
    if (event->dynamics && !dynamics_)
      throw InputError(fmt::format("event '{}' reads q'' or the reactions R, which need the dynamics solved at the "
                                   "state; this caller evaluates events without them",
                                   event->name));
    needs_dynamics_ = needs_dynamics_ || event->dynamics || event->contact_forces;
    needs_contact_forces_ = needs_contact_forces_ || event->contact_forces;
    tapes_.push_back(event->g.bind(values.data(), values.size()));
    registers = std::max(registers, tapes_.back().registers());
  }
  registers_.assign(static_cast<std::size_t>(registers), 0.0);
  x_.assign(static_cast<std::size_t>(2 * n_ + contact_columns_), 0.0);
  xd_.assign(static_cast<std::size_t>(2 * n_ + contact_columns_), 0.0);
  g_.assign(events_.size(), 0.0);
  non_finite_.y.assign(static_cast<std::size_t>(2 * n_), 0.0);
}

CrossingDirection ModelEventFunctions::direction(int i) const {
  switch (event(i).direction) {
    case EventDirection::rising: return CrossingDirection::rising;
    case EventDirection::falling: return CrossingDirection::falling;
    case EventDirection::both: return CrossingDirection::both;
  }
  return CrossingDirection::both;
}

Status ModelEventFunctions::run_all(double t, const double* y, double* g) {
  if (needs_dynamics_) {
    const double* qdd = nullptr;
    const double* R = nullptr;
    const double* F = nullptr;
    const Status status = dynamics_(t, y, &qdd, &R, needs_contact_forces_ ? &F : nullptr);
    if (status != Status::ok) return status;
    pack_dynamics_inputs(n_, y, y + n_, qdd, R, x_.data(), xd_.data());
    if (needs_contact_forces_) std::copy(F, F + contact_columns_, x_.begin() + 2 * n_);
  }
  for (std::size_t i = 0; i < tapes_.size(); ++i) {
    if (events_[i]->dynamics)
      tapes_[i].run(t, x_.data(), xd_.data(), registers_.data(), g + i);
    else
      tapes_[i].run(t, y, y + n_, registers_.data(), g + i);
  }
  return Status::ok;
}

Status ModelEventFunctions::evaluate(double t, const double* y, double* g) {
  non_finite_.index = -1;
  const Status status = run_all(t, y, g);
  if (status != Status::ok) return status;
  for (std::size_t i = 0; i < tapes_.size(); ++i)
    if (!std::isfinite(g[i])) {
      non_finite_.index = static_cast<int>(i);
      non_finite_.t = t;
      non_finite_.g = g[i];
      std::copy(y, y + 2 * n_, non_finite_.y.begin());
      return Status::non_finite;
    }
  return Status::ok;
}

Status ModelEventFunctions::on_event(int i, double t, const double* y) {
  const Status status = handler_(i, t, y);
  if (status != Status::ok) return status;
  if (event(i).action == EventAction::stop) {
    stopped_by_ = i;
    return Status::stopped;
  }
  return Status::ok;
}

void ModelEventFunctions::require_valid_start(double t0, const double* y0) {
  if (tapes_.empty()) return;
  if (run_all(t0, y0, g_.data()) != Status::ok)
    throw InputError(fmt::format("the events cannot be evaluated at the start (t0 = {}): the dynamics there could "
                                 "not be solved",
                                 t0));
  for (std::size_t i = 0; i < tapes_.size(); ++i) {
    const Event& e = *events_[i];
    const std::string where = e.where.empty() ? "" : e.where + ": ";
    if (!std::isfinite(g_[i]))
      throw InputError(fmt::format("{}event '{}' ({}) is {} at the start (t0 = {}): it cannot be evaluated there; "
                                   "write it in a form defined at the initial state",
                                   where, e.name, e.expression, g_[i], t0));
    if (e.condition && g_[i] >= 0.0)
      throw InputError(fmt::format("{}the stop condition already holds at the start (t0 = {}, the difference of its "
                                   "sides is {:.6g}): the run would stop before its first step; give a condition "
                                   "that becomes true later",
                                   where, t0, g_[i]));
    // With a direction the start is not a crossing: the sign g takes after t0 decides, so that
    // "back on the start line" (g = 0 at t0, rising) is found where it comes back. Without one, a
    // zero at t0 is refused: which side the run starts on is then ambiguous to the reader.
    if (g_[i] == 0.0 && e.direction == EventDirection::both)
      throw InputError(fmt::format("{}event '{}' ({}) is already at zero at the start (t0 = {}): it would be found "
                                   "at the initial state, not where it crosses zero later; give it a direction "
                                   "(\"rising\" or \"falling\", which skips the start), or shift its expression or "
                                   "the initial state",
                                   where, e.name, e.expression, t0));
  }
}

}  // namespace nhdyn
