#include "nhdyn/analysis/events.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>

#include "nhdyn/core/error.hpp"

namespace nhdyn {

ModelEventFunctions::ModelEventFunctions(const Model& model, const std::vector<const Event*>& events,
                                         Handler handler)
    : n_(model.n()), events_(events), handler_(std::move(handler)) {
  std::vector<double> values;
  for (const Parameter& p : model.parameters) values.push_back(p.value);
  int registers = 0;
  for (const Event* event : events_) {
    if (event->g.outputs() != 1 || event->g.coordinates() != n_)
      throw InputError(fmt::format("event '{}' was compiled for another model ({} coordinates, {} outputs); "
                                   "this one has {} coordinates",
                                   event->name, event->g.coordinates(), event->g.outputs(), n_));
    if (event->g.parameters() > static_cast<int>(values.size()))
      throw InputError(fmt::format("event '{}' reads {} parameters; model '{}' has {}", event->name,
                                   event->g.parameters(), model.name, values.size()));
    programs_.push_back(event->g.reads_parameters() ? event->g.bind(values.data(), values.size()) : event->g);
    registers = std::max(registers, programs_.back().registers());
  }
  registers_.assign(static_cast<std::size_t>(registers), 0.0);
  g_.assign(events_.size(), 0.0);
}

CrossingDirection ModelEventFunctions::direction(int i) const {
  switch (event(i).direction) {
    case EventDirection::rising: return CrossingDirection::rising;
    case EventDirection::falling: return CrossingDirection::falling;
    case EventDirection::both: return CrossingDirection::both;
  }
  return CrossingDirection::both;
}

Status ModelEventFunctions::evaluate(double t, const double* y, double* g) {
  for (std::size_t i = 0; i < programs_.size(); ++i) {
    programs_[i].run(t, y, y + n_, registers_.data(), g + i);
    if (!std::isfinite(g[i])) return Status::non_finite;
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
  if (programs_.empty()) return;
  for (std::size_t i = 0; i < programs_.size(); ++i) programs_[i].run(t0, y0, y0 + n_, registers_.data(), &g_[i]);
  for (std::size_t i = 0; i < programs_.size(); ++i) {
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
    if (g_[i] == 0.0)
      throw InputError(fmt::format("{}event '{}' ({}) is already at zero at the start (t0 = {}): it would be found "
                                   "at the initial state, not where it crosses zero later; shift its expression or "
                                   "the initial state",
                                   where, e.name, e.expression, t0));
  }
}

}  // namespace nhdyn
