#include "nhdyn/model/model.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <set>

#include "nhdyn/core/error.hpp"
#include "nhdyn/model/contact_modes.hpp"

namespace nhdyn {

int Model::position_constraints() const {
  return static_cast<int>(std::count_if(constraints.begin(), constraints.end(), [](const Constraint& c) {
    return c.level == ConstraintLevel::position;
  }));
}

int Model::velocity_constraints() const {
  return static_cast<int>(std::count_if(constraints.begin(), constraints.end(), [](const Constraint& c) {
    return c.level != ConstraintLevel::acceleration;
  }));
}

int Model::position_programs() const {
  return static_cast<int>(std::count_if(program_constraints.begin(), program_constraints.end(),
                                        [](const ProgramConstraint& c) { return c.level == ConstraintLevel::position; }));
}

int Model::velocity_programs() const {
  return static_cast<int>(std::count_if(program_constraints.begin(), program_constraints.end(), [](const ProgramConstraint& c) {
    return c.level != ConstraintLevel::acceleration;
  }));
}

void require_fewer_constraints(const Model& model, const std::string& what) {
  if (model.s() < model.n()) return;
  throw InputError(fmt::format(
      "model '{}' has {} constraints on {} coordinates, which its contacts' modes never hold all at once "
      "(docs/contact-modes.md, \"More contacts than freedom\"); {} holds every constraint, which leaves no motion: "
      "simulate the model instead, or remove a contact",
      model.name, model.s(), model.n(), what));
}

void check_model_shape(const Model& model) {
  const std::string who = fmt::format("model '{}'", model.name);
  if (model.n() == 0) throw ModelError(who + ": it has no coordinates");
  if (const int held = constraints_always_held(model); held >= model.n())
    throw ModelError(held == model.s()
                         ? fmt::format("{}: {} constraints on {} coordinates leave no freedom of motion; "
                                       "a model needs fewer constraints than coordinates",
                                       who, model.s(), model.n())
                         : fmt::format("{}: {} constraints on {} coordinates, {} of them held whatever the contacts' "
                                       "modes, leave no freedom of motion; fewer than n must hold at any time",
                                       who, model.s(), model.n(), held));
  if (!model.evaluator) throw ModelError(who + ": it has no evaluator");
  if (model.q0.size() != model.n() || model.v0.size() != model.n())
    throw ModelError(fmt::format("{}: initial state has {} coordinates and {} velocities, expected {}",
                                 who, model.q0.size(), model.v0.size(), model.n()));
  std::set<std::string> seen;
  for (const std::string& c : model.coordinates)
    if (!seen.insert(c).second) throw ModelError(fmt::format("{}: coordinate '{}' appears twice", who, c));
  for (const Constraint& c : model.constraints)
    if (!seen.insert(c.name).second)
      throw ModelError(fmt::format("{}: the name '{}' is used twice (constraint names must differ "
                                   "from each other and from coordinate names)", who, c.name));
  for (const ProgramConstraint& c : model.program_constraints)
    if (!seen.insert(c.name).second)
      throw ModelError(fmt::format("{}: the name '{}' is used twice (program names must differ from each other and "
                                   "from coordinate and constraint names)", who, c.name));
  if (model.m() > model.k())
    throw ModelError(fmt::format("{}: {} programs for k = n - s = {} degrees of freedom: at most {} programs are "
                                 "possible", who, model.m(), model.k(), model.k()));
  if (model.m() > 0 && !model.evaluator->has_program_constraints())
    throw ModelError(fmt::format("{}: it has {} programs but its evaluator does not compute their terms", who,
                                 model.m()));
  if (model.path && (model.path->x >= model.n() || model.path->y >= model.n()))
    throw ModelError(who + ": the planar path names a coordinate that does not exist");
}

}  // namespace nhdyn
