// The equations' sections of a model file (model_file_sections.hpp): coordinates, parameters,
// forces, constraints, programs, the complement, initial values, the exact solution, the run's
// defaults ([simulation], [plot]), outputs and events, each translated into SpecBuilder calls.
#include <fmt/format.h>

#include <algorithm>
#include <array>
#include <optional>
#include <set>
#include <string>
#include <string_view>
#include <unordered_map>
#include <utility>
#include <vector>

#include "nhdyn/core/error.hpp"
#include "nhdyn/core/join.hpp"
#include "nhdyn/core/detail/suggest.hpp"
#include "nhdyn/formulation/formulation.hpp"
#include "nhdyn/frontend/detail/model_file_sections.hpp"
#include "nhdyn/integrators/ode.hpp"
#include "nhdyn/model/parameters.hpp"
#include "nhdyn/symbolic/spec_builder.hpp"

namespace nhdyn::model_file {
namespace {

// The keys of each table of these sections (docs/model-format.md), in the order the doc lists them.
const std::vector<std::string> parameter_keys = {"value", "unit"};
const std::vector<std::string> constraint_keys = {"name", "position", "velocity", "acceleration"};
const std::vector<std::string> program_keys = {"name", "position", "velocity", "acceleration", "actuator"};
const std::vector<std::string> initial_keys = {"t0", "position", "velocity"};
const std::vector<std::string> simulation_keys = {"t_end", "output_step", "integrator", "method", "rtol", "atol"};
const std::vector<std::string> plot_keys = {"path"};
const std::vector<std::string> event_keys = {"name", "when", "direction", "action"};

// The names parse_formulation and parse_integrator accept, from their tables (formulation.hpp, ode.hpp).
const std::vector<std::string> method_names = names_of(kFormulations);
const std::vector<std::string> integrator_names = names_of(kIntegrators);

// The one level key of a constraint or program table (position, velocity or acceleration, the
// expression = 0): its node, the key and the level. `what` names the table in the messages.
struct LevelEntry {
  const toml::node* node;
  std::string key;
  ConstraintLevel level;
};

struct InitialValue {
  std::string text = "0";
  SourceLocation where;
  const toml::node* node = nullptr;
  bool given = false;
};

// A number, or an expression in numbers, pi, e and the parameters above ("pi/6", "2*a"),
// evaluated as --set evaluates one (model/parameters.hpp, no GiNaC), so that a value computed
// here and one re-evaluated after a --set agree to the bit. Returns the value and, for an
// expression that uses parameters (a derived parameter), its text.
std::pair<double, std::string> parameter_value(LoadContext& cx, const toml::node& node, const std::string& name) {
  const Cursor& c = cx.cursor;
  if (const std::optional<double> number = c.number_value(node, name)) {
    try {
      check_parameter_value(name, *number);
    } catch (const InputError& e) {
      c.fail(c.at(node), e.what());
    }
    return {*number, ""};
  }
  if (!node.is_string())
    c.fail(c.at(node), fmt::format("parameter '{}' must be a number, an expression in pi and the parameters above it "
                                   "(e.g. \"pi/6\"), or {{ value = ..., unit = \"...\" }}; it is {}",
                                   name, type_name(node)));
  const std::string& text = node.as_string()->get();
  const SourceLocation where = c.content_at(node);
  std::vector<std::string> names;
  try {
    names = calc_expression_names(text, cx.parameter_values);
  } catch (const InputError& e) {
    c.fail(where, fmt::format("the value of parameter '{}', \"{}\", cannot be evaluated: {}", name, text, e.what()));
  }
  bool derived = false;
  for (const std::string& symbol : names) {
    const auto known = std::find_if(cx.parameter_values.begin(), cx.parameter_values.end(),
                                    [&](const Parameter& p) { return p.name == symbol; });
    if (known == cx.parameter_values.end())
      c.fail(where, fmt::format("the value of parameter '{}' uses '{}'; a parameter's value may use only numbers, "
                                "pi and the parameters above it",
                                name, symbol));
    derived = true;
  }
  try {
    const double value = calc_parameter_expression(text, cx.parameter_values);
    check_parameter_value(name, value);
    return {value, derived ? text : std::string()};
  } catch (const InputError& e) {
    c.fail(where, fmt::format("the value of parameter '{}', \"{}\": {}", name, text, e.what()));
  }
}

LevelEntry level_of(const Cursor& c, const toml::table& table, const toml::node& element, std::string_view what,
                    const std::string& name) {
  LevelEntry out{nullptr, {}, ConstraintLevel::velocity};
  for (const Entry& entry : in_file_order(table)) {
    const std::string key(entry.key->str());
    ConstraintLevel level;
    if (key == "position") level = ConstraintLevel::position;
    else if (key == "velocity") level = ConstraintLevel::velocity;
    else if (key == "acceleration") level = ConstraintLevel::acceleration;
    else continue;
    if (out.node != nullptr)
      c.fail(c.at(*entry.key), fmt::format("{} '{}' is given both as {} and as {}; give exactly one of "
                                           "position, velocity, acceleration",
                                           what, name, out.key, key));
    out = {entry.value, key, level};
  }
  if (out.node == nullptr)
    c.fail(c.at(element), fmt::format("{} '{}' has no expression: give exactly one of position = \"...\", "
                                      "velocity = \"...\" or acceleration = \"...\" (the {} is expression = 0)",
                                      what, name, what));
  return out;
}

void load_initial_values(LoadContext& cx, const toml::node& node, std::string_view which,
                         std::vector<InitialValue>& values) {
  const Cursor& c = cx.cursor;
  const std::string what = fmt::format("initial.{}", which);
  const toml::table& table = c.table_of(node, what, fmt::format("{} = {{ x = 0, phi = \"pi/4\" }}", which));
  for (const Entry& entry : in_file_order(table)) {
    const std::string coordinate(entry.key->str());
    const int i = cx.coordinate_index(coordinate, c.at(*entry.key), fmt::format("in [{}]", what));
    InitialValue& value = values[static_cast<std::size_t>(i)];
    value.text = c.number_or_expression(*entry.value, fmt::format("{}.{}", what, coordinate), "1.5 or \"a/2\"");
    value.where = c.content_at(*entry.value);
    value.node = entry.value;
    value.given = true;
  }
}

}  // namespace

void load_coordinates(LoadContext& cx, const toml::table& root, SpecBuilder& builder) {
  const Cursor& c = cx.cursor;
  const toml::node* node = c.required(
      root, "coordinates", "the generalized coordinates in order, e.g. coordinates = [\"x\", \"y\", \"phi\"]");
  const toml::array& array = c.array_of(*node, "coordinates", "coordinates = [\"x\", \"y\", \"phi\"]");
  if (array.empty())
    c.fail(c.at(*node), "'coordinates' is empty: list the generalized coordinates, e.g. coordinates = [\"x\", \"y\"]");
  for (std::size_t i = 0; i < array.size(); ++i) {
    const toml::node& element = *array.get(i);
    const std::string name =
        c.string_of(element, fmt::format("coordinates[{}]", i + 1), "coordinates = [\"x\", \"y\", \"phi\"]");
    builder.coordinate(name, c.at(element));
    cx.coordinate_by_name.emplace(name, static_cast<int>(cx.coordinates.size()));
    cx.coordinates.push_back(name);
  }
}

void load_parameters(LoadContext& cx, const toml::node& node, SpecBuilder& builder) {
  const Cursor& c = cx.cursor;
  const toml::table& table = c.table_of(node, "parameters", "[parameters] followed by m = 1.0");
  for (const Entry& entry : in_file_order(table)) {
    c.check_not_misplaced(*entry.key, "in [parameters]");
    const std::string name(entry.key->str());
    const toml::node* value = entry.value;
    std::string unit;
    if (const toml::table* full = value->as_table()) {
      c.check_keys(*full, parameter_keys, fmt::format("in parameter '{}'", name));
      value = full->get("value");
      if (value == nullptr)
        c.fail(c.at(*entry.value, *entry.key),
               fmt::format("parameter '{}' has no value: write {} = {{ value = 0.5, unit = \"m\" }}", name, name));
      if (const toml::node* unit_node = full->get("unit"))
        unit = c.string_of(*unit_node, fmt::format("{}.unit", name), "unit = \"m\"");
    }
    const auto [number, expression] = parameter_value(cx, *value, name);
    builder.parameter(name, number, unit, c.at(*entry.key));
    cx.parameter_values.push_back(Parameter{name, number, unit, expression});
  }
}

// [outputs]: NAME = "expression" in t, q, q', q'', the reactions R_x, the parameters and the
// outputs above it; one result column each, in file order (symbolic/outputs.hpp).
void load_outputs(LoadContext& cx, const toml::node& node, SpecBuilder& builder) {
  const Cursor& c = cx.cursor;
  const toml::table& table = c.table_of(node, "outputs", "[outputs] followed by energy = \"m/2*x'^2 + m*g*y\"");
  std::vector<std::pair<std::string, SourceLocation>> names;  // for the message of a forward reference
  for (const Entry& entry : in_file_order(table)) names.emplace_back(std::string(entry.key->str()), c.at(*entry.key));
  builder.announce_outputs(names);
  for (const Entry& entry : in_file_order(table)) {
    c.check_not_misplaced(*entry.key, "in [outputs]");
    const std::string name(entry.key->str());
    const std::string text =
        c.expression_string(*entry.value, fmt::format("outputs.{}", name), "energy = \"m/2*x'^2 + m*g*y\"");
    const GiNaC::ex expression =
        c.located(*entry.value, [&] { return builder.parse_derived(text, c.content_at(*entry.value), name); });
    builder.output(name, expression, text, c.at(*entry.key));
  }
}

void load_forces(LoadContext& cx, const toml::node& node, SpecBuilder& builder) {
  const Cursor& c = cx.cursor;
  const toml::table& table = c.table_of(node, "forces", "[forces] followed by x = \"-c * x'\"");
  for (const Entry& entry : in_file_order(table)) {
    c.check_not_misplaced(*entry.key, "in [forces]");
    const std::string coordinate(entry.key->str());
    cx.coordinate_index(coordinate, c.at(*entry.key), "in [forces]");
    const std::string what = fmt::format("forces.{}", coordinate);
    const std::string text = c.expression_string(*entry.value, what, "x = \"-c * x'\"");
    c.located(*entry.value, [&] { builder.force(coordinate, text, c.content_at(*entry.value)); });
  }
}

void load_constraints(LoadContext& cx, const toml::node& node, SpecBuilder& builder) {
  const Cursor& c = cx.cursor;
  const toml::array& array =
      c.array_of(node, "constraints", "[[constraints]] followed by name = \"blade\" and velocity = \"...\"");
  std::unordered_map<std::string, SourceLocation> names;  // a search of a list is quadratic in their number
  int number = 0;
  for (const toml::node& element : array) {
    ++number;
    const std::string context = fmt::format("in constraint {}", number);
    const toml::table* table = element.as_table();
    if (table == nullptr)
      c.fail(c.at(element), fmt::format("constraint {} must be a table with a name and one of position, velocity, "
                                        "acceleration (write it as [[constraints]]); it is {}",
                                        number, type_name(element)));
    c.check_keys(*table, constraint_keys, context);

    std::string name = fmt::format("c{}", number);
    SourceLocation name_at = c.at(element);
    if (const toml::node* name_node = table->get("name")) {
      name = c.string_of(*name_node, "name", "name = \"blade\"");
      name_at = c.at(*name_node);
    }
    if (const auto other = names.find(name); other != names.end())
      c.fail(name_at, fmt::format("constraint name '{}' is used twice (first at line {}); give each constraint "
                                  "its own name",
                                  name, other->second.line));
    names.emplace(name, name_at);

    const LevelEntry found = level_of(c, *table, element, "constraint", name);
    const toml::node* level_node = found.node;
    const std::string& level_key = found.key;
    const ConstraintLevel level = found.level;
    const std::string text =
        c.expression_string(*level_node, fmt::format("{}.{}", name, level_key), "velocity = \"y' - tan(phi) * x'\"");
    c.located(*level_node, [&] { builder.constraint(name, level, text, c.content_at(*level_node)); });
  }
}

// [[events]]: name, when = "g" (crossing zero), direction = rising | falling | both (default
// both), action = stop | record (default record). The expression is read against the model's
// symbols here, so that its errors carry their file position.
std::vector<symbolic::SpecEvent> load_events(LoadContext& cx, const toml::node& node, const SpecBuilder& builder) {
  const Cursor& c = cx.cursor;
  const toml::array& array =
      c.array_of(node, "events", "[[events]] followed by name = \"fallen\" and when = \"abs(phi) - 1\"");
  std::vector<symbolic::SpecEvent> events;
  int number = 0;
  for (const toml::node& element : array) {
    ++number;
    const std::string context = fmt::format("in event {}", number);
    const toml::table* table = element.as_table();
    if (table == nullptr)
      c.fail(c.at(element), fmt::format("event {} must be a table with a name and when = \"...\" (write it as "
                                        "[[events]]); it is {}",
                                        number, type_name(element)));
    c.check_keys(*table, event_keys, context);
    symbolic::SpecEvent event;
    event.name = fmt::format("event{}", number);
    SourceLocation name_at = c.at(element);
    if (const toml::node* name_node = table->get("name")) {
      event.name = c.string_of(*name_node, "name", "name = \"fallen\"");
      name_at = c.at(*name_node);
    }
    for (const symbolic::SpecEvent& other : events)
      if (other.name == event.name)
        c.fail(name_at, fmt::format("event name '{}' is used twice (first at line {}); give each event its own name",
                                    event.name, other.where.line));
    const toml::node* when = table->get("when");
    if (when == nullptr)
      c.fail(c.at(element), fmt::format("event '{}' has no when = \"...\": give the expression whose crossing of zero "
                                        "is the event, e.g. when = \"abs(phi) - 1\"",
                                        event.name));
    event.text = c.expression_string(*when, "when", "when = \"abs(phi) - 1\"");
    event.where = c.content_at(*when);
    event.expression = c.located(*when, [&] { return builder.parse_derived(event.text, c.content_at(*when)); });
    if (const toml::node* direction = table->get("direction")) {
      const std::string value = c.string_of(*direction, "direction", "direction = \"rising\"");
      if (value == "rising") event.direction = EventDirection::rising;
      else if (value == "falling") event.direction = EventDirection::falling;
      else if (value == "both") event.direction = EventDirection::both;
      else
        c.fail(
            c.at(*direction),
            fmt::format("event '{}': direction '{}' is not one of rising, falling, both{}", event.name, value,
                        nearest_name(value, {"rising", "falling", "both"}).empty()
                            ? ""
                            : fmt::format("; did you mean '{}'?", nearest_name(value, {"rising", "falling", "both"}))));
    }
    if (const toml::node* action = table->get("action")) {
      const std::string value = c.string_of(*action, "action", "action = \"stop\"");
      if (value == "stop") event.action = EventAction::stop;
      else if (value == "record") event.action = EventAction::record;
      else
        c.fail(c.at(*action),
               fmt::format("event '{}': action '{}' is not one of stop, record{}", event.name, value,
                           nearest_name(value, {"stop", "record"}).empty()
                               ? ""
                               : fmt::format("; did you mean '{}'?", nearest_name(value, {"stop", "record"}))));
    }
    events.push_back(std::move(event));
  }
  return events;
}

// [[programs]] (docs/model-format.md, docs/derivations/program-motion.md): each a constraint the
// motion must follow, with the actuator that realizes it.
void load_programs(LoadContext& cx, const toml::node& node, SpecBuilder& builder) {
  const Cursor& c = cx.cursor;
  constexpr std::string_view example =
      "[[programs]] followed by name = \"heading\", position = \"phi - omega*t\" "
      "and actuator = \"phi\"";
  const toml::array& array = c.array_of(node, "programs", example);
  int number = 0;
  for (const toml::node& element : array) {
    ++number;
    const toml::table* table = element.as_table();
    if (table == nullptr)
      c.fail(c.at(element), fmt::format("program {} must be a table with a name, one of position, velocity, "
                                        "acceleration, and an actuator (write it as [[programs]]); it is {}",
                                        number, type_name(element)));
    c.check_keys(*table, program_keys, fmt::format("in program {}", number));
    std::string name = fmt::format("p{}", number);
    if (const toml::node* name_node = table->get("name")) name = c.string_of(*name_node, "name", "name = \"heading\"");
    const LevelEntry found = level_of(c, *table, element, "program", name);
    const toml::node* level_node = found.node;
    const std::string& level_key = found.key;
    const ConstraintLevel level = found.level;
    const toml::node* actuator = table->get("actuator");
    if (actuator == nullptr)
      c.fail(c.at(element), fmt::format("program '{}' has no actuator: name the coordinate its force or torque acts "
                                        "on, actuator = \"{}\", or give a generalized force direction with one entry "
                                        "per coordinate, actuator = [...]",
                                        name, cx.coordinates.empty() ? "x" : cx.coordinates.back()));
    const std::string text =
        c.expression_string(*level_node, fmt::format("{}.{}", name, level_key), "position = \"phi - omega*t\"");
    if (actuator->is_string()) {
      const std::string coordinate = actuator->as_string()->get();
      c.located(*level_node,
                [&] { builder.program(name, level, text, coordinate, c.content_at(*level_node), c.at(*actuator)); });
      continue;
    }
    const std::string what = fmt::format("{}.actuator", name);
    const toml::array& entries = c.array_of(*actuator, what, "actuator = \"phi\" or actuator = [0, 0, 1]");
    std::vector<std::string> direction;
    for (const toml::node& entry : entries)
      direction.push_back(c.number_or_expression(entry, what, "\"cos(q1)\" or 0"));
    c.located(*level_node,
              [&] { builder.program(name, level, text, direction, c.content_at(*level_node), c.at(*actuator)); });
  }
}

void load_complement(LoadContext& cx, const toml::table& root, SpecBuilder& builder) {
  const Cursor& c = cx.cursor;
  const toml::node* independent = root.get("independent");
  const toml::node* complement = root.get("complement");
  if (independent != nullptr && complement != nullptr)
    c.fail(c.at(*complement),
           "give either 'independent' or 'complement', not both: 'independent' chooses the "
           "coordinates kept independent, 'complement' writes D itself");
  if (independent != nullptr) {
    const toml::array& array = c.array_of(*independent, "independent", "independent = [\"x\", \"phi\"]");
    std::vector<std::string> names;
    for (std::size_t i = 0; i < array.size(); ++i) {
      const toml::node& element = *array.get(i);
      const std::string name =
          c.string_of(element, fmt::format("independent[{}]", i + 1), "independent = [\"x\", \"phi\"]");
      cx.coordinate_index(name, c.at(element), "in 'independent'");
      names.push_back(name);
    }
    builder.independent(names, c.at(*independent));
  }
  if (complement != nullptr) {
    constexpr std::string_view example = "complement = [[\"1\", \"tan(phi)\", \"0\"], [0, 0, 1]]";
    const toml::array& rows = c.array_of(*complement, "complement", example);
    std::vector<std::vector<std::string>> texts;
    for (const toml::node& row_node : rows) {
      const std::string row_what = fmt::format("complement row {}", texts.size() + 1);
      const toml::array& row = c.array_of(row_node, row_what, "[\"1\", \"tan(phi)\", \"0\"]");
      if (row.size() != cx.coordinates.size())
        c.fail(c.at(row_node), fmt::format("{} has {} entries; D needs one column per coordinate ({}): {}", row_what,
                                           row.size(), cx.coordinates.size(), join(cx.coordinates)));
      std::vector<std::string>& out = texts.emplace_back();
      for (const toml::node& entry : row) {
        const std::string text = c.number_or_expression(entry, row_what, "\"tan(phi)\" or 0");
        // SpecBuilder locates errors in D from the one location it is given. To point at the
        // entry, each expression is first given in a D of zeros that ends with it, so that the
        // builder names its row and column (complement() sets D: the call for the whole matrix
        // below replaces these probes).
        if (entry.is_string()) {
          std::vector<std::vector<std::string>> probe(texts.size(), std::vector<std::string>(out.size() + 1, "0"));
          probe.back().back() = text;
          c.located(entry, [&] { builder.complement(probe, c.content_at(entry)); });
        }
        out.push_back(text);
      }
    }
    builder.complement(texts, c.at(*complement));
  }
}

void load_initial(LoadContext& cx, const toml::node& node, SpecBuilder& builder) {
  const Cursor& c = cx.cursor;
  const toml::table& table = c.table_of(node, "initial", "[initial] followed by velocity = { x = 1 }");
  c.check_keys(table, initial_keys, "in [initial]");
  if (const toml::node* t0 = table.get("t0")) {
    cx.t0 = c.number_of(*t0, "initial.t0", "t0 = 0");
    builder.initial_time(cx.t0);
  }
  std::vector<InitialValue> q0(cx.coordinates.size()), v0(cx.coordinates.size());
  if (const toml::node* position = table.get("position")) load_initial_values(cx, *position, "position", q0);
  if (const toml::node* velocity = table.get("velocity")) load_initial_values(cx, *velocity, "velocity", v0);
  const bool any = std::any_of(q0.begin(), q0.end(), [](const InitialValue& v) { return v.given; }) ||
                   std::any_of(v0.begin(), v0.end(), [](const InitialValue& v) { return v.given; });
  if (!any) return;
  for (std::size_t i = 0; i < cx.coordinates.size(); ++i) {
    cx.q0_written.push_back(q0[i].given);
    cx.v0_written.push_back(v0[i].given);
  }
  // SpecBuilder::initial takes a coordinate's value and velocity with one location. To point at
  // the faulty one, the value is checked first with velocity 0; the second call, which sets both,
  // can then fail only on the velocity (initial() sets, so the second call replaces the first).
  for (std::size_t i = 0; i < cx.coordinates.size(); ++i) {
    const std::string& coordinate = cx.coordinates[i];
    if (q0[i].given) c.located(*q0[i].node, [&] { builder.initial(coordinate, q0[i].text, "0", q0[i].where); });
    if (v0[i].given)
      c.located(*v0[i].node, [&] { builder.initial(coordinate, q0[i].text, v0[i].text, v0[i].where); });
    else if (!q0[i].given) builder.initial(coordinate, "0", "0", c.at(node));
  }
}

// [solution]: q(t) per coordinate, expressions in t and the parameters.
void load_solution(LoadContext& cx, const toml::node& node, SpecBuilder& builder) {
  const Cursor& c = cx.cursor;
  const toml::table& table = c.table_of(node, "solution", "[solution] followed by x = \"x0 + v0*t\"");
  for (const Entry& entry : in_file_order(table)) {
    const std::string coordinate(entry.key->str());
    cx.coordinate_index(coordinate, c.at(*entry.key), "in [solution]");
    const std::string text =
        c.number_or_expression(*entry.value, fmt::format("solution.{}", coordinate), "\"x0 + v0*t\"");
    c.located(*entry.value, [&] { builder.solution(coordinate, text, c.content_at(*entry.value)); });
  }
}

void load_simulation(LoadContext& cx, const toml::node& node, SpecBuilder& builder) {
  const Cursor& c = cx.cursor;
  const toml::table& table = c.table_of(node, "simulation", "[simulation] followed by t_end = 10");
  c.check_keys(table, simulation_keys, "in [simulation]");
  SimulationDefaults defaults;
  if (const toml::node* t_end = table.get("t_end")) {
    defaults.t_end = c.number_of(*t_end, "simulation.t_end", "t_end = 10");
    if (!(defaults.t_end > cx.t0))
      c.fail(c.at(*t_end),
             fmt::format("simulation.t_end = {} must be after the initial time t0 = {}", defaults.t_end, cx.t0));
  }
  if (const toml::node* step = table.get("output_step")) {
    defaults.output_step = c.number_of(*step, "simulation.output_step", "output_step = 0.01");
    if (!(defaults.output_step > 0.0))
      c.fail(c.at(*step), fmt::format("simulation.output_step = {} must be positive", defaults.output_step));
  }
  builder.defaults(defaults);
  if (const toml::node* integrator = table.get("integrator"))
    builder.integrator(c.one_of(*integrator, "simulation.integrator", integrator_names));
  if (const toml::node* method = table.get("method"))
    builder.method(c.one_of(*method, "simulation.method", method_names));
  std::optional<double> rtol, atol;
  if (const toml::node* node_rtol = table.get("rtol")) {
    rtol = c.number_of(*node_rtol, "simulation.rtol", "rtol = 1e-8");
    if (!(*rtol > 0.0)) c.fail(c.at(*node_rtol), fmt::format("simulation.rtol = {} must be positive", *rtol));
  }
  if (const toml::node* node_atol = table.get("atol")) {
    atol = c.number_of(*node_atol, "simulation.atol", "atol = 1e-10");
    if (!(*atol > 0.0))
      c.fail(c.at(*node_atol), fmt::format("simulation.atol = {} must be positive (pure relative error control fails "
                                           "where a state crosses zero)",
                                           *atol));
  }
  if (rtol || atol) builder.tolerances(rtol, atol);
}

void load_plot(LoadContext& cx, const toml::node& node, SpecBuilder& builder) {
  const Cursor& c = cx.cursor;
  const toml::table& table = c.table_of(node, "plot", "[plot] followed by path = [\"x\", \"y\"]");
  c.check_keys(table, plot_keys, "in [plot]");
  if (const toml::node* path = table.get("path")) {
    const toml::array& array = c.array_of(*path, "plot.path", "path = [\"x\", \"y\"]");
    if (array.size() != 2)
      c.fail(c.at(*path), fmt::format("plot.path must name two coordinates, the horizontal and the vertical axis, "
                                      "e.g. path = [\"x\", \"y\"]; it has {}",
                                      array.size()));
    std::array<std::string, 2> axes;
    for (std::size_t i = 0; i < 2; ++i) {
      axes[i] = c.string_of(*array.get(i), fmt::format("plot.path[{}]", i + 1), "path = [\"x\", \"y\"]");
      cx.coordinate_index(axes[i], c.at(*array.get(i)), "in plot.path");
    }
    builder.path(axes[0], axes[1]);
  }
}

}  // namespace nhdyn::model_file
