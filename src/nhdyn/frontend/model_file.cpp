// The model-file loader: TOML (toml++) in, SpecBuilder calls out. The format is documented in
// docs/model-format.md; this file checks only what TOML cannot (which keys exist, their types, the
// shape of each section) and leaves every question about the mechanics to SpecBuilder, passing it
// the source location of each node. Every toml++ node is reached through a type-checked accessor
// (as_string, as_table, ...), so no input can make the loader dereference a missing node.
#include "nhdyn/core/join.hpp"
#include "nhdyn/frontend/model_file.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <array>
#include <cerrno>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <fstream>
#include <iterator>
#include <optional>
#include <set>
#include <sstream>
#include <string>
#include <string_view>
#include <system_error>
#include <unordered_map>
#include <utility>
#include <vector>

#include <toml++/toml.h>

#include "nhdyn/core/error.hpp"
#include "nhdyn/formulation/formulation.hpp"
#include "nhdyn/frontend/contacts_file.hpp"
#include "nhdyn/integrators/ode.hpp"
#include "nhdyn/model/parameters.hpp"
#include "nhdyn/symbolic/multibody.hpp"
#include "nhdyn/symbolic/outputs.hpp"
#include "nhdyn/symbolic/spec_builder.hpp"
#include "nhdyn/core/suggest.hpp"

namespace nhdyn {
namespace {

using symbolic::SourceLocation;
using symbolic::SpecBuilder;

// The keys of each table of the format (docs/model-format.md), in the order the doc lists them.
const std::vector<std::string> top_level_keys = {
    "name",           "description", "coordinates", "parameters",  "kinetic_energy",
    "potential_energy", "forces",    "constraints", "programs", "independent", "complement",
    "initial",        "solution",    "simulation",  "plot",        "visual",
    "events",  // [[events]]: zero crossings located during a run
    "outputs",  // [outputs]: derived result columns
    "optimize",  // [optimize]: an optimal control problem, read by `nhdyn optimize` (frontend/optimize_problem.hpp)
    // The multibody description (docs/multibody.md).
    "gravity", "frames", "points", "bodies", "wheels", "knife_edges", "surfaces", "curves", "contacts"};
const std::vector<std::string> frame_keys = {"name", "parent", "translation", "rotations", "quaternion"};
const std::vector<std::string> point_keys = {"name", "frame", "position"};
const std::vector<std::string> body_keys = {"name", "frame", "mass", "com", "inertia"};
// A wheel's mode keys (contact_mode_keys(): friction, ...) make it the [[contacts]] disk it is
// (contacts_file.hpp).
const std::vector<std::string> wheel_keys = [] {
  std::vector<std::string> keys = {"name", "body", "axis", "radius", "normal"};
  keys.insert(keys.end(), contact_mode_keys().begin(), contact_mode_keys().end());
  return keys;
}();
const std::vector<std::string> knife_edge_keys = {"name", "point", "axis", "normal"};
const std::vector<std::string> surface_keys = {"name", "point", "surface"};
const std::vector<std::string> curve_keys = {"name", "point", "surfaces"};
const std::vector<std::string> parameter_keys = {"value", "unit"};
const std::vector<std::string> constraint_keys = {"name", "position", "velocity", "acceleration"};
const std::vector<std::string> program_keys = {"name", "position", "velocity", "acceleration", "actuator"};
const std::vector<std::string> initial_keys = {"t0", "position", "velocity"};
const std::vector<std::string> simulation_keys = {"t_end", "output_step", "integrator", "method", "rtol", "atol"};
const std::vector<std::string> plot_keys = {"path"};
const std::vector<std::string> event_keys = {"name", "when", "direction", "action"};
const std::vector<std::string> visual_keys = {"points", "segments"};
const std::vector<std::string> visual_point_keys = {"name", "position", "radius"};
const std::vector<std::string> visual_segment_keys = {"name", "from", "to"};

// The names parse_formulation and parse_integrator accept, from their tables (formulation.hpp, ode.hpp).
const std::vector<std::string> method_names = names_of(kFormulations);
const std::vector<std::string> integrator_names = names_of(kIntegrators);

std::string_view type_name(const toml::node& node) {
  switch (node.type()) {
    case toml::node_type::string: return "a string";
    case toml::node_type::integer: return "an integer";
    case toml::node_type::floating_point: return "a floating-point number";
    case toml::node_type::boolean: return "a boolean";
    case toml::node_type::date: return "a date";
    case toml::node_type::time: return "a time";
    case toml::node_type::date_time: return "a date-time";
    case toml::node_type::table: return "a table";
    case toml::node_type::array: return "an array";
    case toml::node_type::none: break;
  }
  return "nothing";
}

// One key = value of a table, in the order of the file.
struct Entry {
  const toml::key* key;
  const toml::node* value;
};

bool before(const toml::source_position& a, const toml::source_position& b) {
  return a.line != b.line ? a.line < b.line : a.column < b.column;
}

// toml++ keeps a table's keys sorted by name; errors and parameters follow the file's order.
std::vector<Entry> in_file_order(const toml::table& table) {
  std::vector<Entry> entries;
  for (auto&& [key, value] : table) entries.push_back({&key, &value});
  std::stable_sort(entries.begin(), entries.end(), [](const Entry& a, const Entry& b) {
    return before(a.key->source().begin, b.key->source().begin);
  });
  return entries;
}

// A double as text that GiNaC's parser reads back to the same value ("0.5", "1e-05", "3").
std::string number_text(double value) {
  if (value == std::floor(value) && std::fabs(value) < 1e15) return fmt::format("{}", static_cast<long long>(value));
  return fmt::format("{}", value);
}

// The cursor every section of the file is read through: the text and the name of the file, where
// each line starts, and the type-checked accessors that turn a node of the wrong kind into a
// ModelError naming file:line:column and what to write instead.
class Cursor {
 public:
  Cursor(std::string_view text, std::string file) : text_(text), file_(std::move(file)) {
    // Where each line starts, so that a position costs a lookup, not a walk from the top of the
    // file: a generated model has thousands of expressions, each located once (N-trailer chain,
    // docs/performance.md).
    line_starts_.push_back(0);
    for (std::size_t p = text_.find('\n'); p != std::string_view::npos; p = text_.find('\n', p + 1))
      line_starts_.push_back(p + 1);
  }

  std::string_view text() const { return text_; }
  const std::string& file() const { return file_; }

  // ---- Locations and errors ----------------------------------------------------------------

  SourceLocation at(const toml::source_region& region) const {
    return {file_, static_cast<int>(region.begin.line), static_cast<int>(region.begin.column)};
  }
  SourceLocation at(const toml::node& node) const { return at(node.source()); }
  SourceLocation at(const toml::key& key) const { return at(key.source()); }
  // Where a table is: its header, or for a table that has none (made implicit by [a.b] or a
  // dotted key) the key that names it.
  SourceLocation at(const toml::node& table, const toml::key& key) const {
    return table.source().begin.line > 0 ? at(table) : at(key);
  }

  [[noreturn]] void fail(const SourceLocation& where, const std::string& message) const {
    const std::string place = where.describe();
    throw ModelError(place.empty() ? message : place + ": " + message);
  }

  // Byte offset in text_ of a 1-based (line, column), toml++ counting columns in code points.
  std::optional<std::size_t> offset_of(const toml::source_position& position) const {
    if (position.line == 0 || position.column == 0) return std::nullopt;
    if (position.line > line_starts_.size()) return std::nullopt;
    std::size_t p = line_starts_[position.line - 1];
    for (toml::source_index column = 1; column < position.column; ++column) {
      if (p >= text_.size()) return std::nullopt;
      ++p;
      while (p < text_.size() && (static_cast<unsigned char>(text_[p]) & 0xC0u) == 0x80u) ++p;
    }
    return p;
  }

  // The (line, column) of byte offset p of text_.
  SourceLocation location_of(std::size_t p) const {
    p = std::min(p, text_.size());
    // The last line starting at or before p (a '\n' at p - 1 starts the line at p).
    const auto next = std::upper_bound(line_starts_.begin(), line_starts_.end(), p);
    const int line = static_cast<int>(next - line_starts_.begin());
    const std::size_t line_start = *(next - 1);
    int column = 1;
    for (std::size_t i = line_start; i < p; ++i)
      if ((static_cast<unsigned char>(text_[i]) & 0xC0u) != 0x80u) ++column;
    return {file_, line, column};
  }

  // Where byte `offset` of the content of a string value sits in the file, following the quotes,
  // escapes and line continuations of TOML's four kinds of string. Falls back to the node itself.
  SourceLocation string_position(const toml::node& node, std::size_t offset) const {
    const std::optional<std::size_t> start = offset_of(node.source().begin);
    if (!start || !node.is_string()) return at(node);
    std::size_t p = *start;
    const std::string_view rest = text_.substr(p);
    const bool multiline = rest.starts_with("\"\"\"") || rest.starts_with("'''");
    const bool basic = rest.starts_with('"');
    if (!basic && !rest.starts_with('\'')) return at(node);
    p += multiline ? 3 : 1;
    if (multiline) {
      if (text_.substr(p).starts_with('\n')) p += 1;
      else if (text_.substr(p).starts_with("\r\n")) p += 2;
    }
    const auto is_space = [](char c) { return c == ' ' || c == '\t' || c == '\n' || c == '\r'; };
    const auto continuation = [&](std::size_t at) {
      return basic && multiline && at + 1 < text_.size() && text_[at] == '\\' && is_space(text_[at + 1]);
    };
    std::size_t decoded = 0;
    // Up to the character at `offset`, and past a line continuation that ends there.
    while ((decoded < offset || continuation(p)) && p < text_.size()) {
      const char c = text_[p];
      const char next = p + 1 < text_.size() ? text_[p + 1] : '\0';
      if (basic && c == '\\') {
        if (next == 'u' || next == 'U') {
          const std::size_t digits = next == 'u' ? 4 : 8;
          unsigned long code = 0;
          for (std::size_t i = 0; i < digits && p + 2 + i < text_.size(); ++i) {
            const char h = text_[p + 2 + i];
            const int v = h >= '0' && h <= '9' ? h - '0' : (h | 0x20) >= 'a' && (h | 0x20) <= 'f' ? (h | 0x20) - 'a' + 10 : 0;
            code = code * 16 + static_cast<unsigned long>(v);
          }
          p += 2 + digits;
          decoded += code < 0x80 ? 1 : code < 0x800 ? 2 : code < 0x10000 ? 3 : 4;
        } else if (multiline && is_space(next)) {
          // A line-ending backslash: the newline and the whitespace after it vanish.
          ++p;
          while (p < text_.size() && is_space(text_[p])) ++p;
        } else {
          p += 2;
          decoded += 1;
        }
      } else if (c == '\r' && next == '\n') {
        p += 2;  // read as one '\n'
        decoded += 1;
      } else {
        p += 1;
        decoded += 1;
      }
    }
    return location_of(p);
  }

  // Where the text of a value starts: inside the quotes for a string.
  SourceLocation content_at(const toml::node& node) const { return string_position(node, 0); }

  // Runs a SpecBuilder call that was given content_at(node) and moves the position of its error
  // to the file. SpecBuilder counts from content_at(node) through the text as TOML delivers it
  // (escapes decoded, line continuations removed); string_position follows the raw file instead.
  template <class Call>
  auto located(const toml::node& node, Call&& call) const -> decltype(call()) {
    try {
      return call();
    } catch (const ModelError& e) {
      std::optional<std::string> moved = move_into_file(node, e.what());
      if (!moved) throw;
      throw ModelError(*moved);
    }
  }

  // The message with its leading "file:line:column" replaced by the file position of the same
  // character, when that position lies inside the string value `node`; nullopt otherwise.
  std::optional<std::string> move_into_file(const toml::node& node, std::string_view message) const {
    const toml::value<std::string>* value = node.as_string();
    if (value == nullptr || !message.starts_with(file_ + ":")) return std::nullopt;
    std::size_t p = file_.size() + 1;
    const auto read_number = [&]() -> long {
      long number = 0;
      const std::size_t first = p;
      while (p < message.size() && message[p] >= '0' && message[p] <= '9' && p - first < 9)
        number = number * 10 + (message[p++] - '0');
      return p > first ? number : -1;
    };
    const long line = read_number();
    if (line < 0 || p >= message.size() || message[p] != ':') return std::nullopt;
    ++p;
    const long column = read_number();
    if (column < 0 || !message.substr(p).starts_with(": ")) return std::nullopt;
    const SourceLocation start = content_at(node);
    const toml::source_region& region = node.source();
    if (line < start.line || line > static_cast<long>(region.end.line) || (line == start.line && column < start.column))
      return std::nullopt;
    // The same (line, column) counted in the decoded text, from `start`, as SpecBuilder counts.
    const std::string& text = value->get();
    long text_line = line - start.line;
    long text_column = text_line == 0 ? column - start.column + 1 : column;
    std::size_t offset = 0;
    while (text_line > 0 && offset < text.size())
      if (text[offset++] == '\n') --text_line;
    while (text_column > 1 && offset < text.size() && text[offset] != '\n') {
      ++offset;
      while (offset < text.size() && (static_cast<unsigned char>(text[offset]) & 0xC0u) == 0x80u) ++offset;
      --text_column;
    }
    if (text_line > 0 || text_column > 1) return std::nullopt;  // not inside this string
    return string_position(node, offset).describe() + std::string(message.substr(p));
  }

  // ---- Type-checked access -------------------------------------------------------------------

  // A top-level key found inside a section was written below that section's header: say so.
  void check_not_misplaced(const toml::key& key, std::string_view context) const {
    const std::string name(key.str());
    if (std::find(top_level_keys.begin(), top_level_keys.end(), name) == top_level_keys.end()) return;
    fail(at(key), fmt::format("'{}' is {}, because it comes after that section's header; TOML puts every key "
                              "below a [section] header into that section: move '{}' above the first [section]",
                              name, context, name));
  }

  // Every key of `table` must be one of `allowed`; `context` says where we are ("in [plot]").
  void check_keys(const toml::table& table, const std::vector<std::string>& allowed, std::string_view context) const {
    for (const Entry& entry : in_file_order(table)) {
      const std::string key(entry.key->str());
      if (std::find(allowed.begin(), allowed.end(), key) != allowed.end()) continue;
      if (&allowed != &top_level_keys) check_not_misplaced(*entry.key, context);
      const std::string nearest = nearest_name(key, allowed);
      fail(at(*entry.key), nearest.empty()
                               ? fmt::format("unknown key '{}' {}; the keys here are: {}", key, context, join(allowed))
                               : fmt::format("unknown key '{}' {}; did you mean '{}'?", key, context, nearest));
    }
  }

  const toml::node* required(const toml::table& root, std::string_view key, std::string_view what) const {
    const toml::node* node = root.get(key);
    if (node == nullptr)
      fail({file_, 1, 1}, fmt::format("missing key '{}' at the top level: give {}", key, what));
    return node;
  }

  const toml::table& table_of(const toml::node& node, std::string_view what, std::string_view example) const {
    const toml::table* table = node.as_table();
    if (table == nullptr)
      fail(at(node), fmt::format("'{}' must be a table, e.g. {}; it is {}", what, example, type_name(node)));
    return *table;
  }

  const toml::array& array_of(const toml::node& node, std::string_view what, std::string_view example) const {
    const toml::array* array = node.as_array();
    if (array == nullptr)
      fail(at(node), fmt::format("'{}' must be an array, e.g. {}; it is {}", what, example, type_name(node)));
    return *array;
  }

  std::string string_of(const toml::node& node, std::string_view what, std::string_view example) const {
    const toml::value<std::string>* value = node.as_string();
    if (value == nullptr)
      fail(at(node), fmt::format("'{}' must be a string, e.g. {}; it is {}", what, example, type_name(node)));
    return value->get();
  }

  // An expression must be written as a string (in double or single quotes).
  std::string expression_string(const toml::node& node, std::string_view what, std::string_view example) const {
    const toml::value<std::string>* value = node.as_string();
    if (value == nullptr)
      fail(at(node), fmt::format("'{}' must be an expression written as a string, e.g. {}; it is {}", what,
                                 example, type_name(node)));
    return value->get();
  }

  // A number (integer or floating point), finite.
  std::optional<double> number_value(const toml::node& node, std::string_view what) const {
    double value = 0.0;
    if (const toml::value<std::int64_t>* integer = node.as_integer()) value = static_cast<double>(integer->get());
    else if (const toml::value<double>* real = node.as_floating_point()) value = real->get();
    else return std::nullopt;
    if (!std::isfinite(value)) fail(at(node), fmt::format("'{}' must be a finite number, not {}", what, value));
    return value;
  }

  double number_of(const toml::node& node, std::string_view what, std::string_view example) const {
    const std::optional<double> value = number_value(node, what);
    if (!value) fail(at(node), fmt::format("'{}' must be a number, e.g. {}; it is {}", what, example, type_name(node)));
    return *value;
  }

  // A number or an expression string, as text for SpecBuilder (initial values, entries of D).
  std::string number_or_expression(const toml::node& node, std::string_view what, std::string_view example) const {
    if (node.is_string()) return node.as_string()->get();
    const std::optional<double> value = number_value(node, what);
    if (!value)
      fail(at(node), fmt::format("'{}' must be a number or an expression written as a string, e.g. {}; it is {}",
                                 what, example, type_name(node)));
    return number_text(*value);
  }

  // ---- Entries of the arrays of tables (the multibody sections, [visual]) --------------------

  // The tables of an array of tables such as [[frames]]; `example` shows one.
  std::vector<const toml::table*> tables_of(const toml::node& node, const std::string& key,
                                            const std::vector<std::string>& keys) const {
    const toml::array& array = array_of(node, key, fmt::format("[[{}]] followed by name = \"...\"", key));
    std::vector<const toml::table*> out;
    for (const toml::node& element : array) {
      const toml::table* table = element.as_table();
      if (table == nullptr)
        fail(at(element), fmt::format("each entry of '{}' must be a table (write it as [[{}]]); entry {} is {}", key,
                                      key, out.size() + 1, type_name(element)));
      check_keys(*table, keys, fmt::format("in [[{}]] entry {}", key, out.size() + 1));
      out.push_back(table);
    }
    return out;
  }

  const toml::node& member(const toml::table& table, const std::string& section, std::string_view key,
                           std::string_view example) const {
    const toml::node* node = table.get(key);
    if (node == nullptr)
      fail(at(table), fmt::format("[[{}]] entry has no '{}': give it, e.g. {}", section, key, example));
    return *node;
  }

  std::string name_of(const toml::table& table, const std::string& section) const {
    return string_of(member(table, section, "name", "name = \"wheel\""), section + ".name", "name = \"wheel\"");
  }

  // Three numbers or expressions, e.g. translation = ["x", "y", 0].
  symbolic::Triple triple_of(const toml::node& node, const std::string& what, std::string_view example) const {
    const toml::array& array = array_of(node, what, example);
    if (array.size() != 3)
      fail(at(node), fmt::format("'{}' must have 3 components (x, y, z), e.g. {}; it has {}", what, example,
                                 array.size()));
    symbolic::Triple out;
    for (std::size_t i = 0; i < 3; ++i)
      out[i] = number_or_expression(*array.get(i), fmt::format("{}[{}]", what, i + 1), example);
    return out;
  }

  std::optional<symbolic::Triple> optional_triple(const toml::table& table, std::string_view key,
                                                  const std::string& what) const {
    const toml::node* node = table.get(key);
    if (node == nullptr) return std::nullopt;
    return triple_of(*node, what, "[0, 0, 1]");
  }

  std::string one_of(const toml::node& node, std::string_view what, const std::vector<std::string>& names) const {
    const std::string name = string_of(node, what, fmt::format("\"{}\"", names.front()));
    if (std::find(names.begin(), names.end(), name) == names.end()) {
      const std::string nearest = nearest_name(name, names);
      fail(at(node), fmt::format("unknown {} '{}'; {}choose one of: {}", what, name,
                                 nearest.empty() ? "" : fmt::format("did you mean '{}'? ", nearest), join(names)));
    }
    return name;
  }

 private:
  std::string_view text_;
  std::vector<std::size_t> line_starts_;  // byte offset of the start of each line, line 1 first
  std::string file_;
};

// What the sections share: the cursor, and what earlier sections found that later ones read.
struct LoadContext {
  LoadContext(std::string_view text, std::string file) : cursor(text, std::move(file)) {}

  Cursor cursor;
  std::vector<std::string> coordinates;  // in the order `coordinates` lists them
  std::unordered_map<std::string, int> coordinate_by_name;  // index into coordinates (first of a name)
  std::vector<Parameter> parameter_values;  // as loaded so far, in file order
  std::vector<bool> q0_written, v0_written;  // per coordinate: [initial] wrote its value, its velocity
  std::vector<std::string> quaternion_coordinates;  // the quaternion frames' components, from [[frames]]
  double t0 = 0.0;  // [initial] t0, which [simulation] t_end must follow

  // A coordinate named by a key or a string; returns its index.
  int coordinate_index(const std::string& name, const SourceLocation& where, std::string_view context) const {
    if (const auto it = coordinate_by_name.find(name); it != coordinate_by_name.end()) return it->second;
    const std::string nearest = nearest_name(name, coordinates);
    cursor.fail(where, fmt::format("'{}' {} is not a coordinate; {}", name, context,
                            nearest.empty() ? fmt::format("the coordinates are: {}", join(coordinates))
                                            : fmt::format("did you mean '{}'?", nearest)));
  }
};

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

// What the multibody sections build together: the builder, the scene, and the names the
// automatic outputs and the wheels' scene need.
struct MultibodySections {
  symbolic::MultibodyBuilder& mb;
  symbolic::SpecVisual& visual;
  std::vector<std::string> frame_names, point_names;                     // for the automatic outputs
  std::vector<std::pair<std::string, symbolic::PlacedFrame>> body_frames;  // for the wheels' scene
};

// The sections and their helpers, each a function over the shared context (defined below in the
// order the file format lists them).
symbolic::Spec load_sections(LoadContext& cx);
void load_coordinates(LoadContext& cx, const toml::table& root, SpecBuilder& builder);
void load_parameters(LoadContext& cx, const toml::node& node, SpecBuilder& builder);
std::pair<double, std::string> parameter_value(LoadContext& cx, const toml::node& node, const std::string& name);
void load_outputs(LoadContext& cx, const toml::node& node, SpecBuilder& builder);
void load_forces(LoadContext& cx, const toml::node& node, SpecBuilder& builder);
void load_constraints(LoadContext& cx, const toml::node& node, SpecBuilder& builder);
LevelEntry level_of(const Cursor& c, const toml::table& table, const toml::node& element, std::string_view what,
                    const std::string& name);
std::vector<symbolic::SpecEvent> load_events(LoadContext& cx, const toml::node& node, const SpecBuilder& builder);
void load_programs(LoadContext& cx, const toml::node& node, SpecBuilder& builder);
void load_complement(LoadContext& cx, const toml::table& root, SpecBuilder& builder);
void load_initial_values(LoadContext& cx, const toml::node& node, std::string_view which,
                         std::vector<InitialValue>& values);
void load_initial(LoadContext& cx, const toml::node& node, SpecBuilder& builder);
void load_solution(LoadContext& cx, const toml::node& node, SpecBuilder& builder);
void load_simulation(LoadContext& cx, const toml::node& node, SpecBuilder& builder);
void load_multibody(LoadContext& cx, const toml::table& root, SpecBuilder& builder, symbolic::SpecVisual& visual);
void load_frames(LoadContext& cx, const toml::table& root, MultibodySections& scene);
void load_points(LoadContext& cx, const toml::table& root, MultibodySections& scene);
void load_bodies(LoadContext& cx, const toml::table& root, SpecBuilder& builder, MultibodySections& scene);
void load_wheels(LoadContext& cx, const toml::table& root, SpecBuilder& builder, MultibodySections& scene);
void load_knife_edges(LoadContext& cx, const toml::table& root, MultibodySections& scene);
void load_surfaces(LoadContext& cx, const toml::table& root, MultibodySections& scene);
void load_curves(LoadContext& cx, const toml::table& root, MultibodySections& scene);
std::optional<std::array<std::string, 4>> quaternion_of(const Cursor& c, const toml::table& table,
                                                        const std::string& frame);
symbolic::InertiaText inertia_of(const Cursor& c, const toml::node& node, const std::string& body);
void load_plot(LoadContext& cx, const toml::node& node, SpecBuilder& builder);
symbolic::VisualItem frame_item(const symbolic::PlacedFrame& frame, symbolic::VisualKind kind,
                                const SourceLocation& where);
std::vector<GiNaC::ex> position_of(const Cursor& c, const toml::node& node, const std::string& what,
                                   SpecBuilder& builder, std::size_t& components);
void load_visual(LoadContext& cx, const toml::node& node, SpecBuilder& builder, symbolic::SpecVisual& visual);

symbolic::Spec load_sections(LoadContext& cx) {
  const Cursor& c = cx.cursor;
  toml::table root;
  try {
    root = toml::parse(c.text(), std::string_view(c.file()));
  } catch (const toml::parse_error& e) {
    c.fail(c.at(e.source()),
           fmt::format("TOML syntax error: {} (docs/model-format.md describes the format)", e.description()));
  }
  c.check_keys(root, top_level_keys, "at the top level");

  const toml::node* name = c.required(root, "name", "the model's name, e.g. name = \"sled\"");
  SpecBuilder builder(c.string_of(*name, "name", "name = \"sled\""), c.at(*name));
  if (const toml::node* description = root.get("description"))
    builder.description(c.string_of(*description, "description", "description = \"A sled on an inclined plane\""));

  load_coordinates(cx, root, builder);
  if (const toml::node* parameters = root.get("parameters")) load_parameters(cx, *parameters, builder);

  // With [[bodies]], T comes from them; a kinetic_energy given as well is added to theirs.
  const toml::node* kinetic = root.get("bodies") != nullptr
                                  ? root.get("kinetic_energy")
                                  : c.required(root, "kinetic_energy",
                                               "the kinetic energy in the velocities x', e.g. "
                                               "kinetic_energy = \"m/2 * (x'^2 + y'^2)\" (or [[bodies]], "
                                               "docs/multibody.md)");
  if (kinetic != nullptr) {
    const std::string kinetic_text = c.expression_string(*kinetic, "kinetic_energy", "kinetic_energy = \"m/2 * x'^2\"");
    c.located(*kinetic, [&] { builder.kinetic_energy(kinetic_text, c.content_at(*kinetic)); });
  }
  if (const toml::node* potential = root.get("potential_energy")) {
    const std::string potential_text =
        c.expression_string(*potential, "potential_energy", "potential_energy = \"-m * g * z\"");
    c.located(*potential, [&] { builder.potential_energy(potential_text, c.content_at(*potential)); });
  }

  if (const toml::node* forces = root.get("forces")) load_forces(cx, *forces, builder);
  if (const toml::node* constraints = root.get("constraints")) load_constraints(cx, *constraints, builder);
  if (const toml::node* programs = root.get("programs")) load_programs(cx, *programs, builder);
  symbolic::SpecVisual visual;
  load_multibody(cx, root, builder, visual);
  if (const toml::node* node = root.get("visual")) load_visual(cx, *node, builder, visual);
  load_complement(cx, root, builder);
  if (const toml::node* initial = root.get("initial")) load_initial(cx, *initial, builder);
  if (const toml::node* solution = root.get("solution")) load_solution(cx, *solution, builder);
  if (const toml::node* simulation = root.get("simulation")) load_simulation(cx, *simulation, builder);
  if (const toml::node* plot = root.get("plot")) load_plot(cx, *plot, builder);
  if (const toml::node* node = root.get("outputs")) load_outputs(cx, *node, builder);
  std::vector<symbolic::SpecEvent> events;
  if (const toml::node* node = root.get("events")) events = load_events(cx, *node, builder);
  symbolic::Spec spec = builder.build();
  spec.events = std::move(events);
  spec.visual = std::move(visual);
  // The definitions of derived parameters, which a --set of a parameter they use re-evaluates.
  for (symbolic::SpecParameter& p : spec.parameters)
    for (const Parameter& loaded : cx.parameter_values)
      if (loaded.name == p.name) p.expression = loaded.expression;
  spec.q0_written = std::move(cx.q0_written);
  spec.v0_written = std::move(cx.v0_written);
  spec.q0_written.resize(spec.coordinates.size(), false);
  spec.v0_written.resize(spec.coordinates.size(), false);
  // A quaternion's components, written or not, are free for --fix-initial: its norm is a gauge,
  // and the smallest change onto the unit sphere is along e itself (e/|e|, the same direction;
  // e' loses its part along e), docs/derivations/quaternion-frame.md.
  for (const std::string& name : cx.quaternion_coordinates)
    for (std::size_t i = 0; i < spec.coordinates.size(); ++i)
      if (spec.coordinates[i] == name) spec.q0_written[i] = spec.v0_written[i] = false;
  // The contact points' coordinates nhdyn added (rolling_contact.hpp): found from the rest.
  symbolic::solve_contact_coordinates(spec);
  return spec;
}

// ---- Sections ------------------------------------------------------------------------------

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
  std::vector<std::pair<std::string, SourceLocation>> names;
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
    for (const auto& [other, other_at] : names)
      if (other == name)
        c.fail(name_at, fmt::format("constraint name '{}' is used twice (first at line {}); give each constraint "
                                    "its own name",
                                    name, other_at.line));
    names.emplace_back(name, name_at);

    const LevelEntry found = level_of(c, *table, element, "constraint", name);
    const toml::node* level_node = found.node;
    const std::string& level_key = found.key;
    const ConstraintLevel level = found.level;
    const std::string text =
        c.expression_string(*level_node, fmt::format("{}.{}", name, level_key), "velocity = \"y' - tan(phi) * x'\"");
    c.located(*level_node, [&] { builder.constraint(name, level, text, c.content_at(*level_node)); });
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

// ---- The multibody description (docs/multibody.md) ------------------------------------------

void load_multibody(LoadContext& cx, const toml::table& root, SpecBuilder& builder, symbolic::SpecVisual& visual) {
  const Cursor& c = cx.cursor;
  bool any = false;
  for (const char* key :
       {"gravity", "frames", "points", "bodies", "wheels", "knife_edges", "surfaces", "curves", "contacts"})
    any = any || root.get(key) != nullptr;
  if (!any) return;
  symbolic::MultibodyBuilder mb(builder);
  visual.ground = true;
  MultibodySections scene{mb, visual, {}, {}, {}};
  if (const toml::node* gravity = root.get("gravity"))
    mb.gravity(c.triple_of(*gravity, "gravity", "gravity = [0, 0, \"-g\"]"), c.at(*gravity));
  load_frames(cx, root, scene);
  load_points(cx, root, scene);
  load_bodies(cx, root, builder, scene);
  load_wheels(cx, root, builder, scene);
  load_knife_edges(cx, root, scene);
  load_surfaces(cx, root, scene);
  load_curves(cx, root, scene);
  if (const toml::node* contacts = root.get("contacts"))
    load_contacts(*contacts, mb, visual, scene.body_frames, [&c](const toml::node& node) { return c.at(node); });
  mb.apply();
  // Every point's and frame origin's world position and velocity as result columns.
  symbolic::add_multibody_outputs(builder, mb, scene.frame_names, scene.point_names);
}

// [[frames]]: each turned by angles or by a quaternion, placed in its parent.
void load_frames(LoadContext& cx, const toml::table& root, MultibodySections& scene) {
  const Cursor& c = cx.cursor;
  if (const toml::node* frames = root.get("frames"))
    for (const toml::table* table : c.tables_of(*frames, "frames", frame_keys)) {
      const std::string name = c.name_of(*table, "frames");
      std::string parent = "ground";
      if (const toml::node* node = table->get("parent"))
        parent = c.string_of(*node, fmt::format("frame '{}': parent", name), "parent = \"ground\"");
      symbolic::Triple translation{"0", "0", "0"};
      if (const toml::node* node = table->get("translation"))
        translation =
            c.triple_of(*node, fmt::format("frame '{}': translation", name), "translation = [\"x\", \"y\", 0]");
      if (std::optional<std::array<std::string, 4>> quaternion = quaternion_of(c, *table, name)) {
        scene.mb.quaternion_frame(name, parent, translation, *quaternion, c.at(*table->get("quaternion")));
        cx.quaternion_coordinates.insert(cx.quaternion_coordinates.end(), quaternion->begin(), quaternion->end());
        scene.frame_names.push_back(name);
        scene.visual.items.push_back(
            frame_item(scene.mb.placed_frame(name), symbolic::VisualKind::frame, c.at(*table)));
        continue;
      }
      std::vector<symbolic::FrameRotation> rotations;
      if (const toml::node* node = table->get("rotations")) {
        constexpr std::string_view example = "rotations = [[\"z\", \"psi\"], [\"x\", \"theta\"]]";
        const toml::array& array = c.array_of(*node, fmt::format("frame '{}': rotations", name), example);
        for (const toml::node& element : array) {
          const std::string what = fmt::format("frame '{}': rotation {}", name, rotations.size() + 1);
          const toml::array& pair = c.array_of(element, what, "[\"z\", \"psi\"] (an axis and an angle)");
          if (pair.size() != 2)
            c.fail(c.at(element), fmt::format("'{}' must be a pair [axis, angle], e.g. [\"z\", \"psi\"]; it has {} "
                                              "entries",
                                              what, pair.size()));
          rotations.push_back({c.string_of(*pair.get(0), what + " axis", "\"z\""),
                               c.number_or_expression(*pair.get(1), what + " angle", "\"psi\""), c.at(element)});
        }
      }
      scene.mb.frame(name, parent, translation, rotations, c.at(*table));
      scene.frame_names.push_back(name);
      scene.visual.items.push_back(frame_item(scene.mb.placed_frame(name), symbolic::VisualKind::frame, c.at(*table)));
    }
}

// [[points]]: fixed in a frame.
void load_points(LoadContext& cx, const toml::table& root, MultibodySections& scene) {
  const Cursor& c = cx.cursor;
  if (const toml::node* points = root.get("points"))
    for (const toml::table* table : c.tables_of(*points, "points", point_keys)) {
      const std::string name = c.name_of(*table, "points");
      const std::string frame = c.string_of(c.member(*table, "points", "frame", "frame = \"wheel\""),
                                            fmt::format("point '{}': frame", name), "frame = \"wheel\"");
      symbolic::Triple position{"0", "0", "0"};
      if (const toml::node* node = table->get("position"))
        position = c.triple_of(*node, fmt::format("point '{}': position", name), "position = [0, 0, \"-l\"]");
      scene.mb.point(name, frame, position, c.at(*table));
      scene.point_names.push_back(name);
    }
}

// [[bodies]]: a mass and inertia on a frame, drawn as its ellipsoid of inertia.
void load_bodies(LoadContext& cx, const toml::table& root, SpecBuilder& builder, MultibodySections& scene) {
  const Cursor& c = cx.cursor;
  if (const toml::node* bodies = root.get("bodies"))
    for (const toml::table* table : c.tables_of(*bodies, "bodies", body_keys)) {
      const std::string name = c.name_of(*table, "bodies");
      const std::string frame = c.string_of(c.member(*table, "bodies", "frame", "frame = \"wheel\""),
                                            fmt::format("body '{}': frame", name), "frame = \"wheel\"");
      const std::string mass = c.number_or_expression(c.member(*table, "bodies", "mass", "mass = \"m\""),
                                                      fmt::format("body '{}': mass", name), "mass = \"m\"");
      symbolic::Triple com{"0", "0", "0"};
      if (const toml::node* node = table->get("com"))
        com = c.triple_of(*node, fmt::format("body '{}': com", name), "com = [0, 0, \"-l/2\"]");
      const toml::node& inertia_node = c.member(
          *table, "bodies", "inertia", "inertia = [\"Ixx\", \"Iyy\", \"Izz\"] (principal moments) or a 3 x 3 array");
      const symbolic::InertiaText inertia = inertia_of(c, inertia_node, name);
      scene.mb.body(name, frame, mass, com, inertia, c.at(*table));
      // The scene's ellipsoid of the body: its centre of mass, moving with its frame.
      symbolic::VisualItem item = frame_item(scene.mb.placed_frame(frame), symbolic::VisualKind::body, c.at(*table));
      item.name = name;
      item.size = builder.parse(mass, c.at(*table));
      for (std::size_t i = 0; i < 3; ++i) {
        for (std::size_t j = 0; j < 3; ++j) {
          item.at[i] += item.other[3 * i + j] * builder.parse(com[j], c.at(*table));
          item.inertia.push_back(builder.parse(inertia[i][j], c.at(*table)));
        }
      }
      scene.body_frames.emplace_back(name, scene.mb.placed_frame(frame));
      scene.visual.items.push_back(std::move(item));
    }
}

// [[wheels]]: thin wheels rolling on the ground, drawn as disks about their axles.
void load_wheels(LoadContext& cx, const toml::table& root, SpecBuilder& builder, MultibodySections& scene) {
  const Cursor& c = cx.cursor;
  if (const toml::node* wheels = root.get("wheels"))
    for (const toml::table* table : c.tables_of(*wheels, "wheels", wheel_keys)) {
      const std::string name = c.name_of(*table, "wheels");
      const std::string what = fmt::format("wheel '{}'", name);
      const std::string body =
          c.string_of(c.member(*table, "wheels", "body", "body = \"disk\""), what + ": body", "body = \"disk\"");
      const std::string axis =
          c.string_of(c.member(*table, "wheels", "axis", "axis = \"y\""), what + ": axis", "axis = \"y\"");
      const std::string radius = c.number_or_expression(c.member(*table, "wheels", "radius", "radius = \"r\""),
                                                        what + ": radius", "radius = \"r\"");
      const std::optional<symbolic::Triple> normal = c.optional_triple(*table, "normal", what + ": normal");
      if (has_contact_mode_keys(*table))
        // A wheel that may slide or lift off: the contact modes are the [[contacts]] machinery's.
        load_wheel_contact(*table, {name, body, axis, radius, normal}, scene.mb, scene.visual,
                           [&c](const toml::node& node) { return c.at(node); });
      else
        scene.mb.rolling_wheel(name, body, axis, radius, normal, c.at(*table));
      // The scene draws the wheel's body as a disk of the wheel's radius about its axle.
      for (const auto& [body_name, placed] : scene.body_frames)
        if (body_name == body) {
          symbolic::VisualItem item = frame_item(placed, symbolic::VisualKind::wheel, c.at(*table));
          item.name = name;
          item.size = builder.parse(radius, c.at(*table));
          item.axis = axis == "x" ? 0 : axis == "y" ? 1 : 2;
          scene.visual.items.push_back(std::move(item));
        }
    }
}

// [[knife_edges]]: a point that moves only along its blade.
void load_knife_edges(LoadContext& cx, const toml::table& root, MultibodySections& scene) {
  const Cursor& c = cx.cursor;
  if (const toml::node* knives = root.get("knife_edges")) {
    refuse_knife_edge_modes(*knives, [&c](const toml::node& node) { return c.at(node); });
    for (const toml::table* table : c.tables_of(*knives, "knife_edges", knife_edge_keys)) {
      const std::string name = c.name_of(*table, "knife_edges");
      const std::string what = fmt::format("knife edge '{}'", name);
      scene.mb.knife_edge(
          name,
          c.string_of(c.member(*table, "knife_edges", "point", "point = \"blade\""), what + ": point",
                      "point = \"blade\""),
          c.string_of(c.member(*table, "knife_edges", "axis", "axis = \"x\""), what + ": axis", "axis = \"x\""),
          c.optional_triple(*table, "normal", what + ": normal"), c.at(*table));
    }
  }
}

// [[surfaces]]: a point held on a fixed surface.
void load_surfaces(LoadContext& cx, const toml::table& root, MultibodySections& scene) {
  const Cursor& c = cx.cursor;
  if (const toml::node* surfaces = root.get("surfaces"))
    for (const toml::table* table : c.tables_of(*surfaces, "surfaces", surface_keys)) {
      const std::string name = c.name_of(*table, "surfaces");
      const std::string what = fmt::format("surface '{}'", name);
      const toml::node& surface = c.member(*table, "surfaces", "surface", "surface = \"X^2 + Y^2 - R^2\"");
      const std::string text = c.expression_string(surface, what + ": surface", "surface = \"X^2 + Y^2 - R^2\"");
      scene.mb.point_on_surface(
          name,
          c.string_of(c.member(*table, "surfaces", "point", "point = \"bead\""), what + ": point", "point = \"bead\""),
          text, c.content_at(surface));
    }
}

// [[curves]]: a point held on the meeting of two fixed surfaces.
void load_curves(LoadContext& cx, const toml::table& root, MultibodySections& scene) {
  const Cursor& c = cx.cursor;
  if (const toml::node* curves = root.get("curves"))
    for (const toml::table* table : c.tables_of(*curves, "curves", curve_keys)) {
      const std::string name = c.name_of(*table, "curves");
      const std::string what = fmt::format("curve '{}'", name);
      constexpr std::string_view example = "surfaces = [\"X^2 + Y^2 - R^2\", \"Z\"]";
      const toml::node& node = c.member(*table, "curves", "surfaces", example);
      const toml::array& array = c.array_of(node, what + ": surfaces", example);
      if (array.size() != 2)
        c.fail(c.at(node), fmt::format("{}: a curve is the meeting of two surfaces, e.g. {}; {} are given", what,
                                       example, array.size()));
      scene.mb.point_on_curve(
          name,
          c.string_of(c.member(*table, "curves", "point", "point = \"bead\""), what + ": point", "point = \"bead\""),
          c.expression_string(*array.get(0), what + ": surfaces[1]", example),
          c.expression_string(*array.get(1), what + ": surfaces[2]", example), c.at(node));
    }
}

// A frame's `rotations = "quaternion"` with `quaternion = ["e0", "e1", "e2", "e3"]`: the four
// coordinates' names; nullopt for a frame turned by angles (docs/derivations/quaternion-frame.md).
std::optional<std::array<std::string, 4>> quaternion_of(const Cursor& c, const toml::table& table,
                                                        const std::string& frame) {
  constexpr std::string_view example = "quaternion = [\"e0\", \"e1\", \"e2\", \"e3\"]";
  const toml::node* rotations = table.get("rotations");
  const toml::node* names = table.get("quaternion");
  const bool by_quaternion = rotations != nullptr && rotations->is_string();
  if (by_quaternion && rotations->value<std::string>().value_or("") != "quaternion")
    c.fail(c.at(*rotations),
           fmt::format("frame '{}': rotations = \"{}\" is not known; write rotations = \"quaternion\" "
                       "(with {}) for a frame turned by a unit quaternion, or a list of [axis, angle] "
                       "pairs such as [[\"z\", \"psi\"], [\"x\", \"theta\"]]",
                       frame, rotations->value<std::string>().value_or(""), example));
  if (!by_quaternion) {
    if (names != nullptr)
      c.fail(c.at(*names), fmt::format("frame '{}': 'quaternion' is given but the frame is not turned by one; add "
                                       "rotations = \"quaternion\" (and no angles), or remove 'quaternion'",
                                       frame));
    return std::nullopt;
  }
  if (names == nullptr)
    c.fail(c.at(*rotations), fmt::format("frame '{}': rotations = \"quaternion\" needs the four coordinates that hold "
                                         "it, scalar first: {} (each listed in `coordinates`)",
                                         frame, example));
  const toml::array& array = c.array_of(*names, fmt::format("frame '{}': quaternion", frame), example);
  if (array.size() != 4)
    c.fail(c.at(*names), fmt::format("frame '{}': a quaternion has 4 components (scalar first), e.g. {}; {} {} given",
                                     frame, example, array.size(), array.size() == 1 ? "is" : "are"));
  std::array<std::string, 4> out;
  for (std::size_t k = 0; k < 4; ++k)
    out[k] = c.string_of(*array.get(k), fmt::format("frame '{}': quaternion[{}]", frame, k + 1), "\"e0\"");
  return out;
}

// [Ixx, Iyy, Izz] (principal axes along the frame's) or a 3 x 3 array.
symbolic::InertiaText inertia_of(const Cursor& c, const toml::node& node, const std::string& body) {
  const std::string what = fmt::format("body '{}': inertia", body);
  constexpr std::string_view example = "[\"Ixx\", \"Iyy\", \"Izz\"] or [[9.2, 0, 2.4], [0, 11, 0], [2.4, 0, 2.8]]";
  const toml::array& array = c.array_of(node, what, example);
  symbolic::InertiaText I;
  for (auto& row : I) row = {"0", "0", "0"};
  if (array.size() == 3 && !array.get(0)->is_array()) {
    for (std::size_t i = 0; i < 3; ++i)
      I[i][i] = c.number_or_expression(*array.get(i), fmt::format("{}[{}]", what, i + 1), example);
    return I;
  }
  if (array.size() != 3)
    c.fail(c.at(node), fmt::format("'{}' must be 3 principal moments or a 3 x 3 array, e.g. {}; it has {} entries",
                                   what, example, array.size()));
  for (std::size_t i = 0; i < 3; ++i) {
    const std::string row_what = fmt::format("{} row {}", what, i + 1);
    const toml::array& row = c.array_of(*array.get(i), row_what, "[9.2, 0, 2.4]");
    if (row.size() != 3)
      c.fail(c.at(*array.get(i)), fmt::format("'{}' must have 3 entries; it has {}", row_what, row.size()));
    for (std::size_t j = 0; j < 3; ++j)
      I[i][j] = c.number_or_expression(*row.get(j), fmt::format("{}[{}]", row_what, j + 1), example);
  }
  return I;
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

// ---- [visual]: what the report's scene draws of a hand-written model (docs/model-format.md) ----

// A multibody frame's origin and rotation as a scene item.
symbolic::VisualItem frame_item(const symbolic::PlacedFrame& frame, symbolic::VisualKind kind,
                                const SourceLocation& where) {
  symbolic::VisualItem item;
  item.kind = kind;
  item.name = frame.name;
  item.where = where.describe();
  item.at.assign(frame.origin.begin(), frame.origin.end());
  for (unsigned i = 0; i < 3; ++i)
    for (unsigned j = 0; j < 3; ++j) item.other.push_back(frame.rotation(i, j));
  return item;
}

// A position: two (x, y: a planar scene) or three components, expressions in t, q, q' and the
// parameters. `components` is set by the first position met; the others must agree.
std::vector<GiNaC::ex> position_of(const Cursor& c, const toml::node& node, const std::string& what,
                                   SpecBuilder& builder, std::size_t& components) {
  constexpr std::string_view example = "[\"x\", \"y\"] or [\"x\", \"y\", \"z\"]";
  const toml::array& array = c.array_of(node, what, example);
  if (array.size() != 2 && array.size() != 3)
    c.fail(c.at(node), fmt::format("'{}' must have 2 (x, y: a planar scene) or 3 components, e.g. {}; it has {}", what,
                                   example, array.size()));
  if (components == 0) components = array.size();
  if (array.size() != components)
    c.fail(c.at(node), fmt::format("'{}' has {} components but an earlier [visual] position has {}; give every "
                                   "position the same number (2 for a planar scene, 3 otherwise)",
                                   what, array.size(), components));
  std::vector<GiNaC::ex> out;
  for (std::size_t i = 0; i < array.size(); ++i) {
    const toml::node& element = *array.get(i);
    const std::string text = c.number_or_expression(element, fmt::format("{}[{}]", what, i + 1), example);
    out.push_back(c.located(element, [&] { return builder.parse(text, c.content_at(element)); }));
  }
  if (out.size() == 2) out.push_back(0);
  return out;
}

void load_visual(LoadContext& cx, const toml::node& node, SpecBuilder& builder, symbolic::SpecVisual& visual) {
  const Cursor& c = cx.cursor;
  const toml::table& table =
      c.table_of(node, "visual", "[visual] followed by points = [{ name = \"particle\", position = [\"x\", \"y\"] }]");
  c.check_keys(table, visual_keys, "in [visual]");
  std::size_t components = 0;
  if (const toml::node* points = table.get("points"))
    for (const toml::table* entry : c.tables_of(*points, "visual.points", visual_point_keys)) {
      symbolic::VisualItem item;
      item.kind = symbolic::VisualKind::sphere;
      item.name = c.name_of(*entry, "visual.points");
      item.where = c.at(*entry).describe();
      const std::string what = fmt::format("[visual] point '{}'", item.name);
      item.at = position_of(c, c.member(*entry, "visual.points", "position", "position = [\"x\", \"y\"]"),
                            what + ": position", builder, components);
      item.size = 0.05;
      if (const toml::node* radius = entry->get("radius")) {
        const std::string text = c.number_or_expression(*radius, what + ": radius", "radius = 0.05");
        item.size = c.located(*radius, [&] { return builder.parse(text, c.content_at(*radius)); });
      }
      visual.items.push_back(std::move(item));
    }
  if (const toml::node* segments = table.get("segments"))
    for (const toml::table* entry : c.tables_of(*segments, "visual.segments", visual_segment_keys)) {
      symbolic::VisualItem item;
      item.kind = symbolic::VisualKind::segment;
      item.name = c.name_of(*entry, "visual.segments");
      item.where = c.at(*entry).describe();
      const std::string what = fmt::format("[visual] segment '{}'", item.name);
      item.at = position_of(c, c.member(*entry, "visual.segments", "from", "from = [\"x\", \"y\"]"), what + ": from",
                            builder, components);
      item.other = position_of(c, c.member(*entry, "visual.segments", "to", "to = [\"x + l*cos(phi)\", \"y\"]"),
                               what + ": to", builder, components);
      visual.items.push_back(std::move(item));
    }
  visual.planar = components == 2 && !visual.ground;
}

}  // namespace

symbolic::Spec load_model_string(std::string_view text, std::string file_name) {
  LoadContext context(text, std::move(file_name));
  return load_sections(context);
}

std::string read_model_text(const std::filesystem::path& path) {
  std::error_code ec;
  const std::filesystem::file_status status = std::filesystem::status(path, ec);
  if (!std::filesystem::exists(status))
    throw FileError(fmt::format("{}: no such model file; check the path (model files end in .toml, e.g. "
                                "examples/sled.toml)",
                                path.string()));
  if (std::filesystem::is_directory(status))
    throw FileError(fmt::format("{}: is a directory, not a model file; give the path of a .toml file", path.string()));
  std::ifstream in(path, std::ios::binary);
  if (!in) {
    const int error = errno;
    throw FileError(fmt::format("{}: cannot open the model file: {}", path.string(),
                                error != 0 ? std::strerror(error) : "unknown error"));
  }
  std::ostringstream text;
  text << in.rdbuf();
  if (in.bad()) throw FileError(fmt::format("{}: cannot read the model file", path.string()));
  return text.str();
}

symbolic::Spec load_model_file(const std::filesystem::path& path) {
  return load_model_string(read_model_text(path), path.string());
}

}  // namespace nhdyn
