// The events a run is given beside a model's own [[events]]: the command line's
// `--stop-when CONDITION` and `--event NAME=EXPR`, and the Python package's stop_when= and
// events=. A model file's are read against the Spec its compile produced, kept in its description
// (load_model.hpp, LoadedModel), so that no name is declared twice; a built-in model (no
// description), or a Model alone, gives its names from the Model. Either way the expression is
// compiled by symbolic/events.hpp, whose syntax, names and messages these are (InputError naming
// the option, the column and the nearest known name). This header includes no GiNaC.
//
//     "abs(phi) > 1.2" --make_stop_condition(loaded)--> Event (model/event.hpp) --> SimulationOptions::events
#pragma once

#include <string>

#include "nhdyn/frontend/load_model.hpp"
#include "nhdyn/model/event.hpp"
#include "nhdyn/model/model.hpp"

namespace nhdyn {

// `--stop-when CONDITION`: "LHS > RHS", "LHS >= RHS", "LHS < RHS" or "LHS <= RHS"; the event
// g = LHS - RHS (RHS - LHS for < and <=), rising, action stop, a condition (a run that starts
// with it true is refused), named as written.
Event make_stop_condition(const LoadedModel& loaded, const std::string& condition);
// The same for a Model without its description (its names from the Model).
Event make_stop_condition(const Model& model, const std::string& condition);

// `--event NAME=EXPR`: g = EXPR, both directions, action record.
Event make_record_event(const LoadedModel& loaded, const std::string& definition);
Event make_record_event(const Model& model, const std::string& definition);

}  // namespace nhdyn
