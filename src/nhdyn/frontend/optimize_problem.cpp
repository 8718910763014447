// The [optimize] reader: TOML in, an OptimalControlProblem out. Expressions are parsed by a
// SpecBuilder whose coordinates are the model's followed by the controls (the control layout of
// optimize_problem.hpp) and whose parameters are the model's, so that an unknown name gets the
// builder's file:line:column message with the nearest known one, and the compiled tapes read
// [q; u] and [q'; 0] as their coordinates and velocities.
#include "nhdyn/frontend/optimize_problem.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include <toml++/toml.h>

#include "nhdyn/core/error.hpp"
#include "nhdyn/core/join.hpp"
#include "nhdyn/core/detail/suggest.hpp"
#include "nhdyn/model/contact_modes.hpp"
#include "nhdyn/symbolic/compile.hpp"
#include "nhdyn/symbolic/spec_builder.hpp"

namespace nhdyn {

const char* collocation_method_name(CollocationMethod method) {
  return method == CollocationMethod::trapezoidal ? "trapezoidal" : "hermite-simpson";
}

const char* constraint_level_name(OptimizeConstraintLevel level) {
  return level == OptimizeConstraintLevel::acceleration ? "acceleration" : "given";
}

namespace {

using symbolic::SourceLocation;

const std::vector<std::string> kOptimizeKeys = {"controls", "objective", "objective_final", "t_end",
                                                "nodes",    "method",    "constraint_level", "initial",
                                                "final",    "bounds",    "path",          "guess"};
const std::vector<std::string> kControlKeys = {"name", "actuator"};

class SectionReader {
 public:
  SectionReader(const ModelSource& source, const Model& model)
      : file_(source.file_name), text_(source.text), model_(model), layout_(model.name) {}

  OptimalControlProblem read() {
    toml::table root;
    try {
      root = toml::parse(text_, std::string_view(file_));
    } catch (const toml::parse_error& e) {
      throw ModelError(fmt::format("{}: TOML syntax error: {}", file_, e.description()));
    }
    const toml::node* node = root.get("optimize");
    if (node == nullptr)
      throw InputError(fmt::format("{} has no [optimize] section: add one (docs/optimize.md), e.g.\n"
                                   "  [optimize]\n  controls = [{{ name = \"F\", actuator = \"{}\" }}]\n"
                                   "  objective = \"F^2\"\n  t_end = 1\n  nodes = 21",
                                   file_, model_.coordinates.front()));
    const toml::table* section = node->as_table();
    if (section == nullptr) fail(*node, "[optimize] must be a table");
    check_keys(*section, kOptimizeKeys, "in [optimize]");

    OptimalControlProblem p;
    p.model = model_;
    p.t0 = model_.t0;
    const int n = model_.n();
    if (model_.m() > 0)
      fail(*node, "the model has [[programs]]; optimize finds the program itself: leave the [[programs]] out of "
                  "this model file");
    require_rolling_contacts();
    read_controls(*section, p);
    declare_layout();
    read_method(*section, p);
    read_time(*section, p);
    p.state_lower.assign(static_cast<std::size_t>(2 * n), -kNoBound);
    p.state_upper.assign(static_cast<std::size_t>(2 * n), kNoBound);
    p.state_bounds_where.assign(static_cast<std::size_t>(2 * n), "");
    if (const toml::node* b = section->get("bounds")) read_bounds(*b, p);
    if (const toml::node* v = section->get("initial")) p.initial = read_state(*v, "initial");
    // final = { ... } is the final state; final = "..." (the spelling of the Mayer term) is
    // the same as objective_final = "...".
    if (const toml::node* v = section->get("final"); v != nullptr && !v->is_string()) p.final = read_state(*v, "final");
    read_objective(*section, p);
    if (const toml::node* v = section->get("path")) read_path(*v, p);
    if (const toml::node* v = section->get("guess")) p.guess = read_guess(*v);
    compile_force(p);
    check_controls_seen(p);
    return p;
  }

 private:
  // ---- Locations and errors ----------------------------------------------------------------

  SourceLocation at(const toml::node& node) const {
    const auto& begin = node.source().begin;
    return {file_, static_cast<int>(begin.line), static_cast<int>(begin.column)};
  }
  // Where the text of a one-line string starts (after its quote): SpecBuilder counts columns
  // through the expression from there.
  SourceLocation content_at(const toml::node& node) const {
    SourceLocation where = at(node);
    if (node.is_string() && where.column > 0) where.column += 1;
    return where;
  }
  [[noreturn]] void fail(const toml::node& node, const std::string& message) const {
    const std::string place = at(node).describe();
    throw ModelError(place.empty() ? message : place + ": " + message);
  }
  void check_keys(const toml::table& table, const std::vector<std::string>& keys, const std::string& where) const {
    for (auto&& [key, value] : table) {
      const std::string name(key.str());
      if (std::find(keys.begin(), keys.end(), name) != keys.end()) continue;
      const std::string nearest = nearest_name(name, keys);
      fail(value, fmt::format("unknown key '{}' {}; {}the keys are: {}", name, where,
                              nearest.empty() ? "" : fmt::format("did you mean '{}'? ", nearest), join(keys)));
    }
  }

  // The transcription imposes every contact's constraints at every point, as rolling and
  // bilateral; a contact that may slide or lift off (friction, unilateral, restitution, mode:
  // docs/contact-modes.md) would be optimized under another law than the model's, silently.
  void require_rolling_contacts() const {
    if (!model_.contact_modes) return;
    for (const ContactModeContact& c : model_.contact_modes->contacts) {
      std::vector<std::string> keys;
      if (c.friction) keys.emplace_back("friction");
      if (c.unilateral) keys.emplace_back("unilateral");
      if (c.initial >= 0) keys.emplace_back("mode");
      throw InputError(fmt::format(
          "{}{}contact '{}' has {}: optimize takes contacts as rolling, bilateral constraints (it cannot let one "
          "slide, lift off or bounce), so it would optimize another motion than the model's; for an optimization, "
          "remove friction, unilateral, restitution and mode from the contact (docs/optimize.md)",
          c.where, c.where.empty() ? "" : ": ", c.name,
          keys.empty() ? std::string("contact-mode keys") : join(keys, " and ")));
    }
  }

  // guess = "FILE.csv": relative to the model file's folder (a model given as text: to the
  // working directory); it must exist, so that a typo is caught before the solve.
  std::string read_guess(const toml::node& node) const {
    const std::optional<std::string> name = node.value<std::string>();
    if (!name || name->empty() || !node.is_string())
      fail(node, "guess must be the path of a CSV in quotes, e.g. guess = \"parking_guess.csv\" (relative to the "
                 "model file's folder)");
    std::filesystem::path path(*name);
    const std::filesystem::path file(file_);
    if (path.is_relative() && file_ != "<string>" && file.has_parent_path()) path = file.parent_path() / path;
    std::error_code ec;
    if (std::filesystem::is_directory(path, ec))
      fail(node, fmt::format("the guess file {} is a directory: write the path of a CSV in it", path.string()));
    if (!std::filesystem::is_regular_file(path, ec))
      fail(node, fmt::format("the guess file {} does not exist (guess is relative to the model file's folder); "
                             "write its path, or leave guess out and give --guess FILE.csv",
                             path.string()));
    return path.string();
  }

  // A number, or an expression in quotes, as text for the parser.
  std::string text_of(const toml::node& node, const std::string& what) const {
    if (const auto* s = node.as_string()) return s->get();
    if (const auto* i = node.as_integer()) return fmt::format("{}", i->get());
    if (const auto* f = node.as_floating_point()) {
      if (!std::isfinite(f->get())) fail(node, fmt::format("{} must be finite", what));
      return fmt::format("{:.17g}", f->get());
    }
    fail(node, fmt::format("{} must be a number or an expression in quotes", what));
  }

  // ---- The layout: coordinates, then controls; the model's parameters ---------------------

  void read_controls(const toml::table& section, OptimalControlProblem& p) {
    const toml::node* node = section.get("controls");
    if (node == nullptr)
      fail(section, fmt::format("[optimize] has no controls: give each a name and the coordinate its force acts on, "
                       "controls = [{{ name = \"F\", actuator = \"{}\" }}]",
                       model_.coordinates.front()));
    const toml::array* array = node->as_array();
    if (array == nullptr || array->empty())
      fail(*node, "controls must be a non-empty array of tables, controls = [{ name = \"F\", actuator = \"x\" }]");
    std::vector<std::string> taken = model_.coordinates;
    for (const Parameter& q : model_.parameters) taken.push_back(q.name);
    for (const toml::node& element : *array) {
      const toml::table* table = element.as_table();
      if (table == nullptr) fail(element, "each control is a table { name = \"F\", actuator = \"x\" }");
      check_keys(*table, kControlKeys, "in a control");
      const toml::node* name = table->get("name");
      const toml::node* actuator = table->get("actuator");
      if (name == nullptr || !name->is_string()) fail(element, "a control needs a name, name = \"F\"");
      if (actuator == nullptr)
        fail(element, fmt::format("control '{}' has no actuator: name the coordinate its force or torque acts on, "
                                  "actuator = \"{}\", or give a direction with one entry per coordinate, "
                                  "actuator = [...]",
                                  name->as_string()->get(), model_.coordinates.front()));
      OptimizeControl control;
      control.name = name->as_string()->get();
      if (std::find(taken.begin(), taken.end(), control.name) != taken.end())
        fail(*name, fmt::format("the control '{}' is named like a coordinate, parameter or earlier control: give it "
                                "a new name",
                                control.name));
      taken.push_back(control.name);
      actuator_nodes_.push_back(actuator);
      name_nodes_.push_back(name);
      control.where = at(*actuator).describe();
      if (const auto* s = actuator->as_string()) {
        control.actuator = s->get();
      } else if (const auto* entries = actuator->as_array()) {
        std::vector<std::string> texts;
        for (const toml::node& e : *entries) texts.push_back(text_of(e, "an actuator entry"));
        control.actuator = "[" + join(texts) + "]";
      } else {
        fail(*actuator, "actuator must be a coordinate's name or an array with one entry per coordinate");
      }
      p.controls.push_back(std::move(control));
    }
    controls_ = p.controls;
  }

  void declare_layout() {
    for (const std::string& c : model_.coordinates) layout_.coordinate(c);
    for (std::size_t j = 0; j < controls_.size(); ++j) {
      try {
        layout_.coordinate(controls_[j].name);
      } catch (const ModelError& e) {
        // The layout declares a control as a coordinate, and SpecBuilder's refusal of its name
        // ("coordinate 't': 't' is the time ...") says so: said again of the control, at its name.
        const std::string text = e.what();
        const std::size_t quote = text.find("coordinate '"), end = text.find("': ", quote);
        if (quote == std::string::npos || end == std::string::npos) throw;
        fail(*name_nodes_[j], "control " + text.substr(quote + 11, end + 1 - quote - 11) + ": " + text.substr(end + 3));
      }
    }
    for (const Parameter& q : model_.parameters) layout_.parameter(q.name, q.value);
  }

  int n() const { return model_.n(); }
  int m() const { return static_cast<int>(controls_.size()); }
  const symbolic::SymbolTable& symbols() const { return layout_.current().symbols; }

  // Parses the expression of `node` against the layout, refusing accelerations, the velocities of
  // controls and (unless allowed) the controls and the state.
  GiNaC::ex parse(const toml::node& node, const std::string& what, bool state, bool controls) const {
    const std::string text = text_of(node, what);
    const GiNaC::ex e = layout_.parse(text, content_at(node));
    for (int i = 0; i < n() + m(); ++i) {
      if (e.has(symbols().acceleration(i)))
        fail(node, fmt::format("{} may not contain accelerations (found {}'')", what, name_of(i)));
      if (i >= n() && e.has(symbols().velocity(i)))
        fail(node, fmt::format("{} reads {}', the rate of a control, which the problem does not have", what,
                               name_of(i)));
      if (i >= n() && !controls && e.has(symbols().coordinate(i)))
        fail(node, fmt::format("{} may not read the control {}", what, name_of(i)));
      if (i < n() && !state && (e.has(symbols().coordinate(i)) || e.has(symbols().velocity(i))))
        fail(node, fmt::format("{} must be a number or an expression in the parameters; it reads {}", what,
                               name_of(i)));
    }
    if (!state && e.has(symbols().time()))
      fail(node, fmt::format("{} must be a number or an expression in the parameters; it reads t", what));
    return e;
  }
  const std::string& name_of(int i) const {
    return i < n() ? model_.coordinates[static_cast<std::size_t>(i)] : controls_[static_cast<std::size_t>(i - n())].name;
  }

  // A number or an expression in the parameters, evaluated at their current values.
  double number(const toml::node& node, const std::string& what) const {
    const GiNaC::ex e = parse(node, what, false, false);
    GiNaC::exmap values;
    for (const Parameter& q : model_.parameters) values[symbols().parameter(q.name)] = q.value;
    const GiNaC::ex v = e.subs(values).evalf();
    if (!GiNaC::is_a<GiNaC::numeric>(v) || !GiNaC::ex_to<GiNaC::numeric>(v).is_real())
      fail(node, fmt::format("{} is not a real number", what));
    const double value = GiNaC::ex_to<GiNaC::numeric>(v).to_double();
    if (!std::isfinite(value)) fail(node, fmt::format("{} is not finite", what));
    return value;
  }

  Tape compile(const std::vector<GiNaC::ex>& expressions, const std::vector<std::string>& what) const {
    const Tape parametric = symbolic::compile_expressions(layout_.current(), expressions, what);
    std::vector<double> values;
    for (const Parameter& q : model_.parameters) values.push_back(q.value);
    return parametric.bind(values.data(), values.size());
  }

  // ---- The keys -------------------------------------------------------------------------------

  void read_method(const toml::table& section, OptimalControlProblem& p) const {
    if (const toml::node* node = section.get("method")) {
      const auto* s = node->as_string();
      const std::string name = s != nullptr ? s->get() : "";
      if (name == "trapezoidal")
        p.method = CollocationMethod::trapezoidal;
      else if (name == "hermite-simpson")
        p.method = CollocationMethod::hermite_simpson;
      else
        fail(*node, "method must be \"trapezoidal\" or \"hermite-simpson\"");
    }
    if (const toml::node* node = section.get("constraint_level")) {
      const auto* s = node->as_string();
      const std::string name = s != nullptr ? s->get() : "";
      if (name == "acceleration")
        p.level = OptimizeConstraintLevel::acceleration;
      else if (name == "given")
        p.level = OptimizeConstraintLevel::given;
      else
        fail(*node, "constraint_level must be \"acceleration\" or \"given\"");
      if (p.level == OptimizeConstraintLevel::given)
        for (const Constraint& c : model_.constraints)
          if (c.level != ConstraintLevel::velocity)
            fail(*node, fmt::format("constraint_level = \"given\" takes velocity-level constraints only; '{}' is "
                                    "given at {} level: leave constraint_level out",
                                    c.name, c.level == ConstraintLevel::position ? "position" : "acceleration"));
    }
    const toml::node* nodes = section.get("nodes");
    if (nodes == nullptr) fail(section, "[optimize] has no nodes: give the number of nodes, e.g. nodes = 51");
    const double count = number(*nodes, "nodes");
    if (count != std::floor(count) || count < 3 || count > 1e6)
      fail(*nodes, fmt::format("nodes must be an integer from 3 to 1000000, not {}", count));
    p.nodes = static_cast<int>(count);
  }

  void read_time(const toml::table& section, OptimalControlProblem& p) const {
    const toml::node* node = section.get("t_end");
    if (node == nullptr) fail(section, "[optimize] has no t_end: give the final time, t_end = 2, or t_end = { free = [1, 5] }");
    if (const toml::table* table = node->as_table()) {
      check_keys(*table, {"free"}, "in t_end");
      const toml::node* free = table->get("free");
      const toml::array* range = free != nullptr ? free->as_array() : nullptr;
      if (range == nullptr || range->size() != 2)
        fail(*node, "a free final time is t_end = { free = [earliest, latest] }");
      const double lo = number(*range->get(0), "the earliest t_end");
      const double hi = number(*range->get(1), "the latest t_end");
      if (!(lo > p.t0) || !(hi >= lo))
        fail(*node, fmt::format("t_end = {{ free = [{}, {}] }} needs t0 = {} < earliest <= latest", lo, hi, p.t0));
      p.free_time = true;
      p.duration_min = lo - p.t0;
      p.duration_max = hi - p.t0;
      p.t_end = p.t0 + 0.5 * (p.duration_min + p.duration_max);
      return;
    }
    p.t_end = number(*node, "t_end");
    if (!(p.t_end > p.t0)) fail(*node, fmt::format("t_end = {} must be later than t0 = {}", p.t_end, p.t0));
  }

  // "x" -> (index, false), "x'" -> (index, true); -1 when not a coordinate.
  std::pair<int, bool> state_index(const std::string& key) const {
    const bool velocity = !key.empty() && key.back() == '\'';
    const std::string name = velocity ? key.substr(0, key.size() - 1) : key;
    const auto it = std::find(model_.coordinates.begin(), model_.coordinates.end(), name);
    return {it == model_.coordinates.end() ? -1 : static_cast<int>(it - model_.coordinates.begin()), velocity};
  }

  std::string unknown_state(const std::string& key, const std::string& what) const {
    std::vector<std::string> known = model_.coordinates;
    for (const std::string& c : model_.coordinates) known.push_back(c + "'");
    const std::string nearest = nearest_name(key, known);
    return fmt::format("'{}' in {} is not a coordinate or a velocity ({}){}", key, what, join(model_.coordinates),
                       nearest.empty() ? "" : fmt::format("; did you mean '{}'?", nearest));
  }

  // initial / final: { position = { x = 0 }, velocity = { x = 0 } } or { x = 0, "x'" = 0 }.
  std::vector<BoundaryValue> read_state(const toml::node& node, const std::string& what) const {
    const toml::table* table = node.as_table();
    if (table == nullptr)
      fail(node, fmt::format("{} must be a table, {} = {{ position = {{ x = 0 }}, velocity = {{ x = 0 }} }}", what, what));
    std::vector<BoundaryValue> values;
    std::vector<std::pair<int, bool>> seen;
    const auto add = [&](const std::string& key, const toml::node& value, bool velocity_table) {
      auto [index, velocity] = state_index(key);
      if (index < 0 || (velocity_table && velocity)) fail(value, unknown_state(key, what));
      velocity = velocity || velocity_table;
      if (std::find(seen.begin(), seen.end(), std::pair{index, velocity}) != seen.end())
        fail(value, fmt::format("{} gives {}{} twice", what, model_.coordinates[static_cast<std::size_t>(index)],
                                velocity ? "'" : ""));
      seen.emplace_back(index, velocity);
      values.push_back({index, velocity, number(value, fmt::format("{}.{}", what, key)), at(value).describe()});
    };
    for (auto&& [key, value] : *table) {
      const std::string name(key.str());
      if ((name == "position" || name == "velocity") && value.is_table()) {
        for (auto&& [k, v] : *value.as_table()) add(std::string(k.str()), v, name == "velocity");
      } else {
        add(name, value, false);
      }
    }
    return values;
  }

  void read_bounds(const toml::node& node, OptimalControlProblem& p) const {
    const toml::table* table = node.as_table();
    if (table == nullptr) fail(node, "bounds must be a table, bounds = { F = [-1, 1], x = [0, 2] }");
    for (auto&& [key, value] : *table) {
      const std::string name(key.str());
      const toml::array* range = value.as_array();
      if (range == nullptr || range->size() != 2)
        fail(value, fmt::format("the bounds of {} are [lower, upper] (numbers or expressions in quotes)", name));
      // A bound on one side only is written with the other far beyond the motion: inf is not a number here.
      for (const toml::node& side : *range)
        if (const auto* f = side.as_floating_point(); f != nullptr && !std::isfinite(f->get()))
          fail(side, fmt::format("the bounds of {} are finite numbers: for a bound on one side only, give the other "
                                 "a value far beyond the motion, e.g. {} = [-1e6, 10]",
                                 name, name));
      const double lo = number(*range->get(0), fmt::format("the lower bound of {}", name));
      const double hi = number(*range->get(1), fmt::format("the upper bound of {}", name));
      if (lo > hi)
        fail(value, fmt::format("the bounds of {} have lower {} > upper {}: write [lower, upper] with lower <= upper",
                                name, lo, hi));
      const auto control = std::find_if(p.controls.begin(), p.controls.end(),
                                        [&](const OptimizeControl& c) { return c.name == name; });
      if (control != p.controls.end()) {
        control->lower = lo;
        control->upper = hi;
        continue;
      }
      const auto [index, velocity] = state_index(name);
      if (index < 0) {
        std::vector<std::string> known;
        for (const OptimizeControl& c : p.controls) known.push_back(c.name);
        for (const std::string& c : model_.coordinates) known.insert(known.end(), {c, c + "'"});
        const std::string nearest = nearest_name(name, known);
        fail(value, fmt::format("'{}' in bounds is not a control, coordinate or velocity ({}){}", name, join(known),
                                nearest.empty() ? "" : fmt::format("; did you mean '{}'?", nearest)));
      }
      const std::size_t slot = static_cast<std::size_t>(index + (velocity ? n() : 0));
      p.state_lower[slot] = lo;
      p.state_upper[slot] = hi;
      p.state_bounds_where[slot] = at(value).describe();
    }
  }

  void read_objective(const toml::table& section, OptimalControlProblem& p) {
    const toml::node* node = section.get("objective");
    if (node == nullptr)
      fail(section, "[optimize] has no objective: give the integrand, objective = \"F^2\", or objective = \"time\"");
    const auto* s = node->as_string();
    p.objective_text = s != nullptr ? s->get() : text_of(*node, "objective");
    p.objective_where = at(*node).describe();
    if (s != nullptr && s->get() == "time" && !symbols().has("time")) {
      if (!p.free_time)
        fail(*node, "objective = \"time\" needs a free final time, t_end = { free = [earliest, latest] }");
      p.minimum_time = true;
      p.integrand = compile({GiNaC::ex(0)}, {"objective"});
    } else {
      objective_ = parse(*node, "the objective", true, true);
      p.integrand = compile({objective_}, {"objective"});
    }
    const toml::node* f = section.get("objective_final");
    if (const toml::node* mayer = section.get("final"); mayer != nullptr && mayer->is_string()) {
      if (f != nullptr)
        fail(*mayer, "final = \"...\" and objective_final both give the term at t_end: keep one (and write the final "
                     "state as final = { position = {...}, velocity = {...} })");
      f = mayer;
    }
    if (f != nullptr) {
      const GiNaC::ex e = parse(*f, "objective_final", true, false);
      p.final_term = compile({e}, {"objective_final"});
      p.final_term_where = at(*f).describe();
      objective_ += e;
    }
  }

  void read_path(const toml::node& node, OptimalControlProblem& p) {
    const toml::array* array = node.as_array();
    if (array == nullptr) fail(node, "path must be an array of conditions, path = [\"x^2 + y^2 >= 1\"]");
    std::vector<GiNaC::ex> expressions;
    std::vector<std::string> what;
    for (const toml::node& element : *array) {
      const auto* s = element.as_string();
      if (s == nullptr) fail(element, "a path constraint is a condition in quotes, \"x^2 + y^2 >= 1\"");
      const std::string text = s->get();
      // One comparison: LHS >= RHS or LHS <= RHS (> and < read the same).
      std::size_t at_op = std::string::npos, width = 1;
      bool greater = true;
      for (std::size_t i = 0; i < text.size(); ++i)
        if (text[i] == '>' || text[i] == '<') {
          if (at_op != std::string::npos) fail(element, "a path constraint has one comparison, LHS >= RHS or LHS <= RHS");
          at_op = i;
          greater = text[i] == '>';
          width = i + 1 < text.size() && text[i + 1] == '=' ? 2 : 1;
        }
      if (at_op == std::string::npos)
        fail(element, fmt::format("the path constraint \"{}\" has no comparison: write LHS >= RHS or LHS <= RHS", text));
      SourceLocation where = content_at(element);
      const GiNaC::ex lhs = layout_.parse(text.substr(0, at_op), where);
      where.column += static_cast<int>(at_op + width);
      const GiNaC::ex rhs = layout_.parse(text.substr(at_op + width), where);
      for (int i = 0; i < n() + m(); ++i)
        if ((lhs - rhs).has(symbols().acceleration(i)) || (i >= n() && (lhs - rhs).has(symbols().velocity(i))))
          fail(element, "a path constraint reads t, the coordinates, their velocities, the controls and the parameters");
      expressions.push_back(lhs - rhs);
      what.push_back(fmt::format("path constraint \"{}\"", text));
      PathConstraint c;
      c.text = text;
      c.where = at(element).describe();
      (greater ? c.lower : c.upper) = 0.0;
      const GiNaC::ex g = lhs - rhs;
      for (int i = 0; i < n(); ++i) c.reads.push_back(g.has(symbols().coordinate(i)) ? 1 : 0);
      for (int i = 0; i < n(); ++i) c.reads.push_back(g.has(symbols().velocity(i)) ? 1 : 0);
      for (int j = 0; j < m(); ++j) c.reads.push_back(g.has(symbols().coordinate(n() + j)) ? 1 : 0);
      c.reads_time = g.has(symbols().time());
      p.path_constraints.push_back(c);
      path_.push_back(lhs - rhs);
    }
    p.path = compile(expressions, what);
  }

  // B u from the actuators: a coordinate (a unit column) or a direction with one entry per coordinate.
  void compile_force(OptimalControlProblem& p) const {
    std::vector<GiNaC::ex> force(static_cast<std::size_t>(n()), GiNaC::ex(0)), columns;
    std::vector<std::string> entries_what;
    for (int j = 0; j < m(); ++j) {
      const toml::node& node = *actuator_nodes_[static_cast<std::size_t>(j)];
      const GiNaC::symbol& u = symbols().coordinate(n() + j);
      std::vector<GiNaC::ex> column(static_cast<std::size_t>(n()), GiNaC::ex(0));
      if (const auto* s = node.as_string()) {
        const auto [index, velocity] = state_index(s->get());
        if (index < 0 || velocity) {
          const std::string nearest = nearest_name(s->get(), model_.coordinates);
          fail(node, fmt::format("the actuator '{}' of control '{}' is not a coordinate: name the coordinate the "
                                 "force or torque acts on (one of {}){}, or give a direction with one entry per "
                                 "coordinate",
                                 s->get(), name_of(n() + j), join(model_.coordinates),
                                 nearest.empty() ? "" : fmt::format("; did you mean '{}'?", nearest)));
        }
        column[static_cast<std::size_t>(index)] = 1;
      } else {
        const toml::array& entries = *node.as_array();
        if (static_cast<int>(entries.size()) != n())
          fail(node, fmt::format("the actuator of control '{}' has {} entries for {} coordinates ({})", name_of(n() + j),
                                 entries.size(), n(), join(model_.coordinates)));
        for (int i = 0; i < n(); ++i) {
          const GiNaC::ex e = parse(*entries.get(static_cast<std::size_t>(i)),
                                    fmt::format("the actuator of control '{}'", name_of(n() + j)), true, false);
          column[static_cast<std::size_t>(i)] = e;
        }
      }
      bool zero = true;
      for (const GiNaC::ex& e : column) zero = zero && e.expand().is_zero();
      if (zero)
        fail(node, fmt::format("control '{}' acts on nothing: its actuator direction is zero; give the coordinate its "
                               "force acts on or a nonzero direction",
                               name_of(n() + j)));
      for (int i = 0; i < n(); ++i) {
        force[static_cast<std::size_t>(i)] += column[static_cast<std::size_t>(i)] * u;
        columns.push_back(column[static_cast<std::size_t>(i)]);
        entries_what.push_back(fmt::format("the actuator of control '{}' on {}", name_of(n() + j), name_of(i)));
      }
    }
    p.actuators = compile(columns, entries_what);
    std::vector<std::string> what;
    for (int i = 0; i < n(); ++i) what.push_back(fmt::format("actuator force on {}", name_of(i)));
    p.force = compile(force, what);
  }

  // A control that neither the objective nor a bound nor a path constraint sees leaves a free mode
  // (docs/derivations/optimal-programs.md, section 5, item 2): say so.
  void check_controls_seen(OptimalControlProblem& p) const {
    for (int j = 0; j < m(); ++j) {
      const OptimizeControl& c = p.controls[static_cast<std::size_t>(j)];
      const GiNaC::symbol& u = symbols().coordinate(n() + j);
      bool seen = objective_.has(u) || std::isfinite(c.lower) || std::isfinite(c.upper);
      for (const GiNaC::ex& g : path_) seen = seen || g.has(u);
      if (!seen)
        p.warnings.push_back(fmt::format("the control '{}' costs nothing and has no bound: the problem may have no "
                                         "isolated optimum (docs/derivations/optimal-programs.md, section 5); add it "
                                         "to the objective or bound it",
                                         c.name));
    }
  }

  std::string file_;
  std::string text_;
  const Model& model_;
  symbolic::SpecBuilder layout_;
  std::vector<OptimizeControl> controls_;
  std::vector<const toml::node*> actuator_nodes_, name_nodes_;
  GiNaC::ex objective_ = 0;
  std::vector<GiNaC::ex> path_;
};

}  // namespace

OptimalControlProblem load_optimal_control_problem(const ModelSource& source, const LoadedModel& loaded) {
  if (source.is_builtin())
    throw InputError(fmt::format("'{}' is a built-in model: optimize reads an [optimize] section from a model file "
                                 "(docs/optimize.md)",
                                 source.builtin));
  if (dynamic_cast<const TapeEvaluator*>(loaded.model.evaluator.get()) == nullptr)
    throw InputError("optimize needs the model's compiled tapes (the interpreted evaluator): load it without "
                     "--compiled");
  SectionReader reader(source, loaded.model);
  return reader.read();
}

}  // namespace nhdyn
