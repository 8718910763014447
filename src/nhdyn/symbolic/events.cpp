#include "nhdyn/symbolic/events.hpp"

#include <fmt/format.h>

#include <cctype>
#include <memory>
#include <optional>
#include <utility>
#include <vector>

#include "nhdyn/core/error.hpp"
#include "nhdyn/symbolic/compile.hpp"
#include "nhdyn/symbolic/contact_forces.hpp"
#include "nhdyn/symbolic/outputs.hpp"
#include "nhdyn/symbolic/spec.hpp"
#include "nhdyn/symbolic/spec_builder.hpp"

namespace nhdyn::symbolic {
namespace {

// A SpecBuilder with the model's names and parameter values: the symbol table to read an event
// of a model that has no Spec at hand (built-in models, the command line).
SpecBuilder names_of(const Model& model) {
  SpecBuilder builder(model.name);
  for (const std::string& q : model.coordinates) builder.coordinate(q);
  for (const Parameter& p : model.parameters) builder.parameter(p.name, p.value, p.unit);
  // The model's outputs, read again from their text, so that an event may name them. An
  // automatic output whose text is not an expression (the multibody points') is left out: an
  // event naming it is then refused as an unknown symbol.
  for (const DerivedOutput& o : model.outputs.list) {
    try {
      builder.output(o.name, o.expression);
    } catch (const ModelError&) {
      if (!o.automatic) throw;
    }
  }
  // The contact-force columns of its wheels and knife edges, which an event may name too.
  if (model.contact_forces) {
    auto contact = std::make_shared<SpecContactForces>();
    std::vector<ReportedContact> reported;
    for (const ContactForceContact& c : model.contact_forces->contacts)
      if (c.reported) reported.emplace_back(c.name, c.components);
    contact->columns = make_contact_force_symbols(reported);
    builder.contact_forces(std::move(contact));
  }
  return builder;
}

// Reads `text` for the command-line option `option` (quoted in messages as `shown`): a parse error
// becomes an InputError naming the option and the text as the user wrote it. `text` may be
// `shown` with parts blanked out (so that columns stay those of `shown`).
GiNaC::ex read_option(const Spec& spec, const std::string& option, const std::string& shown,
                      const std::string& text) {
  try {
    return parse_derived(spec, text);
  } catch (const ModelError& e) {
    std::string message = e.what();
    const std::string blanked = fmt::format("\"{}\"", text);
    const std::size_t at = message.find(blanked);
    if (at != std::string::npos) message.replace(at, blanked.size(), fmt::format("\"{}\"", shown));
    throw InputError(fmt::format("{} \"{}\": {}", option, shown, message));
  }
}

Event finish(const Spec& spec, const Model& model, const GiNaC::ex& g, std::string name, std::string text,
             std::string where, EventDirection direction, EventAction action) {
  Event event;
  const std::string what = fmt::format("event '{}'", name);
  // An event that reads a contact force is refused before the run when the model does not
  // determine it (NaN by design); otherwise it is evaluated with the forces of each state.
  require_determined_contact_forces(spec, model, g, where, what);
  event.contact_forces = !contact_force_columns_in(spec, g).empty();
  // An event that reads q'' or R (through an output), or a contact force, is evaluated on the
  // solved dynamics.
  event.dynamics = event.contact_forces || reads_dynamics(spec, g);
  if (event.contact_forces)
    event.g = compile_dynamics_tape(spec, {g}, {what}, spec.contact_forces->columns);
  else
    event.g = event.dynamics ? compile_dynamics_tape(spec, {g}, {what}) : compile_expression(spec, g, what);
  event.name = std::move(name);
  event.expression = std::move(text);
  event.where = std::move(where);
  event.direction = direction;
  event.action = action;
  return event;
}

}  // namespace

void compile_events(const Spec& spec, Model& model) {
  for (const SpecEvent& e : spec.events)
    model.events.push_back(
        finish(spec, model, e.expression, e.name, e.text, e.where.describe(), e.direction, e.action));
}

namespace {

// A --stop-when condition split at its comparison (checked): the sides, each with the other blanked
// out so that columns stay those of the whole condition.
struct StopComparison {
  std::string lhs, rhs;
  bool greater = false;
};

StopComparison split_stop_condition(const std::string& condition) {
  const std::string option = "--stop-when";
  // The comparison: one '<' or '>' (optionally followed by '=') outside parentheses.
  std::vector<std::size_t> found;
  int depth = 0;
  for (std::size_t i = 0; i < condition.size(); ++i) {
    const char c = condition[i];
    if (c == '(') ++depth;
    if (c == ')') --depth;
    if ((c == '<' || c == '>') && depth == 0) found.push_back(i);
    if (c == '=' && !(i > 0 && (condition[i - 1] == '<' || condition[i - 1] == '>')))
      throw InputError(fmt::format("{} \"{}\": unexpected '=' at column {}; expected a condition that becomes true, "
                                   "LHS > RHS or LHS < RHS (>= and <= too), e.g. --stop-when \"abs(phi) > 1.2\"",
                                   option, condition, i + 1));
  }
  if (found.empty())
    throw InputError(fmt::format("{} \"{}\": expected a condition with a comparison, LHS > RHS or LHS < RHS (>= and "
                                 "<= too), e.g. --stop-when \"abs(phi) > 1.2\"; found no '<' or '>'",
                                 option, condition));
  if (found.size() > 1)
    throw InputError(fmt::format("{} \"{}\": expected one comparison, LHS > RHS or LHS < RHS; found {} (columns {} "
                                 "and {}): give one --stop-when per condition",
                                 option, condition, found.size(), found[0] + 1, found[1] + 1));
  const std::size_t op = found.front();
  const bool greater = condition[op] == '>';
  const std::size_t op_end = op + (op + 1 < condition.size() && condition[op + 1] == '=' ? 2 : 1);
  const auto blank = [&](std::size_t from, std::size_t to) {
    std::string text = condition;
    for (std::size_t i = from; i < to && i < text.size(); ++i) text[i] = ' ';
    return text;
  };
  const auto empty = [](const std::string& text) {
    for (char c : text)
      if (!std::isspace(static_cast<unsigned char>(c))) return false;
    return true;
  };
  const std::string lhs = blank(op, condition.size());
  const std::string rhs = blank(0, op_end);
  if (empty(lhs) || empty(rhs))
    throw InputError(fmt::format("{} \"{}\": the comparison '{}' needs an expression on each side, e.g. --stop-when "
                                 "\"abs(phi) > 1.2\"",
                                 option, condition, condition.substr(op, op_end - op)));
  return {lhs, rhs, greater};
}

Event stop_event(const Spec& spec, const Model& model, const std::string& condition, const StopComparison& c) {
  const std::string option = "--stop-when";
  const GiNaC::ex left = read_option(spec, option, condition, c.lhs);
  const GiNaC::ex right = read_option(spec, option, condition, c.rhs);
  try {
    Event event = finish(spec, model, c.greater ? left - right : right - left, condition, condition,
                         fmt::format("{} \"{}\"", option, condition), EventDirection::rising, EventAction::stop);
    event.condition = true;
    return event;
  } catch (const ModelError& e) {
    throw InputError(e.what());
  }
}

// A --event definition split at its '=' (checked): the name, and the text with the name and '='
// blanked (columns in messages are those of the whole option).
std::pair<std::string, std::string> split_event_definition(const std::string& definition) {
  const std::string option = "--event";
  const std::size_t eq = definition.find('=');
  const auto identifier = [](const std::string& name) {
    if (name.empty() || !(std::isalpha(static_cast<unsigned char>(name[0])) || name[0] == '_')) return false;
    for (char c : name)
      if (!(std::isalnum(static_cast<unsigned char>(c)) || c == '_' || c == '-')) return false;
    return true;
  };
  if (eq == std::string::npos || !identifier(definition.substr(0, eq)))
    throw InputError(fmt::format("{} \"{}\": expected NAME=EXPR, a name (letters, digits, _ and -) and the expression "
                                 "whose zero crossings to record, e.g. --event \"upright=phi\"",
                                 option, definition));
  std::string text = definition;
  for (std::size_t i = 0; i <= eq; ++i) text[i] = ' ';
  return {definition.substr(0, eq), text};
}

Event record_event_of(const Spec& spec, const Model& model, const std::string& definition, const std::string& name,
                   const std::string& text) {
  const std::string option = "--event";
  const GiNaC::ex g = read_option(spec, option, definition, text);
  try {
    return finish(spec, model, g, name, definition.substr(name.size() + 1),
                  fmt::format("{} \"{}\"", option, definition), EventDirection::both, EventAction::record);
  } catch (const ModelError& e) {
    throw InputError(e.what());
  }
}

}  // namespace

// The syntax is checked before the names are declared (a condition without a comparison is told
// so whatever the model).
Event make_stop_condition(const Model& model, const std::string& condition) {
  const StopComparison c = split_stop_condition(condition);
  const SpecBuilder builder = names_of(model);
  return stop_event(builder.current(), model, condition, c);
}

Event make_stop_condition(const Spec& spec, const Model& model, const std::string& condition) {
  return stop_event(spec, model, condition, split_stop_condition(condition));
}

Event make_record_event(const Model& model, const std::string& definition) {
  const auto [name, text] = split_event_definition(definition);
  const SpecBuilder builder = names_of(model);
  return record_event_of(builder.current(), model, definition, name, text);
}

Event make_record_event(const Spec& spec, const Model& model, const std::string& definition) {
  const auto [name, text] = split_event_definition(definition);
  return record_event_of(spec, model, definition, name, text);
}

}  // namespace nhdyn::symbolic
