// Events from their expressions: a model file's [[events]] (compile_events, called by
// compile_model) and the command line's --stop-when CONDITION and --event NAME=EXPR for any model,
// built-in ones included (their expressions are read against the model's names: t, the
// coordinates, their velocities x', the parameters, the outputs and, for a multibody model, the
// contact-force columns NAME_N ... of its wheels and knife edges; one the model does not determine,
// NaN by design, is refused here, before any run). A model file's are read against its own Spec,
// the one kept in its description (frontend/events.hpp chooses); a model without one (built in,
// or a Model alone) gives its names from the Model. The result is a model/event.hpp Event whose
// tape g reads the parameters, so --set applies to it. Errors are ModelError (a model file's,
// with file:line:column) or InputError (the command line's, naming the option, the column and the
// nearest known name).
#pragma once

#include <string>

#include "nhdyn/model/event.hpp"
#include "nhdyn/model/model.hpp"

namespace nhdyn::symbolic {

struct Spec;  // spec.hpp: this header includes no GiNaC, for the CLI and the Python module

// Appends an Event to model.events for each of spec.events, in order.
void compile_events(const Spec& spec, Model& model);

// `--stop-when CONDITION`: "LHS > RHS", "LHS >= RHS", "LHS < RHS" or "LHS <= RHS" (one comparison
// outside parentheses). The event is g = LHS - RHS (RHS - LHS for < and <=), rising, action stop,
// a condition (a run that starts with it true is refused); its name is the condition as written.
// Read against the names of `model` (a SpecBuilder declaring them).
Event make_stop_condition(const Model& model, const std::string& condition);
// The same read against `spec`, the Spec `model` was compiled from (a model file's description).
Event make_stop_condition(const Spec& spec, const Model& model, const std::string& condition);

// `--event NAME=EXPR`: g = EXPR, both directions, action record.
Event make_record_event(const Model& model, const std::string& definition);
Event make_record_event(const Spec& spec, const Model& model, const std::string& definition);

}  // namespace nhdyn::symbolic
