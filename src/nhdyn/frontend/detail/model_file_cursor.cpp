// The model-file loader's reader (model_file_cursor.hpp): where each position of the file is,
// and the type-checked accessors with their messages.
#include "nhdyn/frontend/detail/model_file_cursor.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <iterator>
#include <utility>

#include "nhdyn/core/join.hpp"
#include "nhdyn/core/detail/suggest.hpp"
#include "nhdyn/symbolic/multibody.hpp"
#include "nhdyn/symbolic/spec.hpp"

namespace nhdyn::model_file {

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

Cursor::Cursor(std::string_view text, std::string file) : text_(text), file_(std::move(file)) {
  // Where each line starts, so that a position costs a lookup, not a walk from the top of the
  // file: a generated model has thousands of expressions, each located once (N-trailer chain,
  // docs/performance.md).
  line_starts_.push_back(0);
  for (std::size_t p = text_.find('\n'); p != std::string_view::npos; p = text_.find('\n', p + 1))
    line_starts_.push_back(p + 1);
}

SourceLocation Cursor::at(const toml::source_region& region) const {
  return {file_, static_cast<int>(region.begin.line), static_cast<int>(region.begin.column)};
}

SourceLocation Cursor::at(const toml::node& node) const { return at(node.source()); }

SourceLocation Cursor::at(const toml::key& key) const { return at(key.source()); }

SourceLocation Cursor::at(const toml::node& table, const toml::key& key) const {
  return table.source().begin.line > 0 ? at(table) : at(key);
}

void Cursor::fail(const SourceLocation& where, const std::string& message) const {
  const std::string place = where.describe();
  throw ModelError(place.empty() ? message : place + ": " + message);
}

std::optional<std::size_t> Cursor::offset_of(const toml::source_position& position) const {
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

SourceLocation Cursor::location_of(std::size_t p) const {
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

SourceLocation Cursor::string_position(const toml::node& node, std::size_t offset) const {
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

SourceLocation Cursor::content_at(const toml::node& node) const { return string_position(node, 0); }

std::optional<std::string> Cursor::move_into_file(const toml::node& node, std::string_view message) const {
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

void Cursor::check_not_misplaced(const toml::key& key, std::string_view context) const {
  const std::string name(key.str());
  if (std::find(top_level_keys().begin(), top_level_keys().end(), name) == top_level_keys().end()) return;
  fail(at(key), fmt::format("'{}' is {}, because it comes after that section's header; TOML puts every key "
                            "below a [section] header into that section: move '{}' above the first [section]",
                            name, context, name));
}

void Cursor::check_keys(const toml::table& table, const std::vector<std::string>& allowed,
                        std::string_view context) const {
  for (const Entry& entry : in_file_order(table)) {
    const std::string key(entry.key->str());
    if (std::find(allowed.begin(), allowed.end(), key) != allowed.end()) continue;
    if (&allowed != &top_level_keys()) check_not_misplaced(*entry.key, context);
    const std::string nearest = nearest_name(key, allowed);
    fail(at(*entry.key), nearest.empty()
                             ? fmt::format("unknown key '{}' {}; the keys here are: {}", key, context, join(allowed))
                             : fmt::format("unknown key '{}' {}; did you mean '{}'?", key, context, nearest));
  }
}

const toml::node* Cursor::required(const toml::table& root, std::string_view key, std::string_view what) const {
  const toml::node* node = root.get(key);
  if (node == nullptr)
    fail({file_, 1, 1}, fmt::format("missing key '{}' at the top level: give {}", key, what));
  return node;
}

const toml::table& Cursor::table_of(const toml::node& node, std::string_view what, std::string_view example) const {
  const toml::table* table = node.as_table();
  if (table == nullptr)
    fail(at(node), fmt::format("'{}' must be a table, e.g. {}; it is {}", what, example, type_name(node)));
  return *table;
}

const toml::array& Cursor::array_of(const toml::node& node, std::string_view what, std::string_view example) const {
  const toml::array* array = node.as_array();
  if (array == nullptr)
    fail(at(node), fmt::format("'{}' must be an array, e.g. {}; it is {}", what, example, type_name(node)));
  return *array;
}

std::string Cursor::string_of(const toml::node& node, std::string_view what, std::string_view example) const {
  const toml::value<std::string>* value = node.as_string();
  if (value == nullptr)
    fail(at(node), fmt::format("'{}' must be a string, e.g. {}; it is {}", what, example, type_name(node)));
  return value->get();
}

std::string Cursor::expression_string(const toml::node& node, std::string_view what, std::string_view example) const {
  const toml::value<std::string>* value = node.as_string();
  if (value == nullptr)
    fail(at(node), fmt::format("'{}' must be an expression written as a string, e.g. {}; it is {}", what,
                               example, type_name(node)));
  return value->get();
}

std::optional<double> Cursor::number_value(const toml::node& node, std::string_view what) const {
  double value = 0.0;
  if (const toml::value<std::int64_t>* integer = node.as_integer()) value = static_cast<double>(integer->get());
  else if (const toml::value<double>* real = node.as_floating_point()) value = real->get();
  else return std::nullopt;
  if (!std::isfinite(value)) fail(at(node), fmt::format("'{}' must be a finite number, not {}", what, value));
  return value;
}

double Cursor::number_of(const toml::node& node, std::string_view what, std::string_view example) const {
  const std::optional<double> value = number_value(node, what);
  if (!value) fail(at(node), fmt::format("'{}' must be a number, e.g. {}; it is {}", what, example, type_name(node)));
  return *value;
}

std::string Cursor::number_or_expression(const toml::node& node, std::string_view what,
                                         std::string_view example) const {
  if (node.is_string()) return node.as_string()->get();
  const std::optional<double> value = number_value(node, what);
  if (!value)
    fail(at(node), fmt::format("'{}' must be a number or an expression written as a string, e.g. {}; it is {}",
                               what, example, type_name(node)));
  return number_text(*value);
}

std::vector<const toml::table*> Cursor::tables_of(const toml::node& node, const std::string& key,
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

const toml::node& Cursor::member(const toml::table& table, const std::string& section, std::string_view key,
                                 std::string_view example) const {
  const toml::node* node = table.get(key);
  if (node == nullptr)
    fail(at(table), fmt::format("[[{}]] entry has no '{}': give it, e.g. {}", section, key, example));
  return *node;
}

std::string Cursor::name_of(const toml::table& table, const std::string& section) const {
  return string_of(member(table, section, "name", "name = \"wheel\""), section + ".name", "name = \"wheel\"");
}

symbolic::Triple Cursor::triple_of(const toml::node& node, const std::string& what, std::string_view example) const {
  const toml::array& array = array_of(node, what, example);
  if (array.size() != 3)
    fail(at(node), fmt::format("'{}' must have 3 components (x, y, z), e.g. {}; it has {}", what, example,
                               array.size()));
  symbolic::Triple out;
  for (std::size_t i = 0; i < 3; ++i)
    out[i] = number_or_expression(*array.get(i), fmt::format("{}[{}]", what, i + 1), example);
  return out;
}

std::optional<symbolic::Triple> Cursor::optional_triple(const toml::table& table, std::string_view key,
                                                        const std::string& what) const {
  const toml::node* node = table.get(key);
  if (node == nullptr) return std::nullopt;
  return triple_of(*node, what, "[0, 0, 1]");
}

std::string Cursor::one_of(const toml::node& node, std::string_view what, const std::vector<std::string>& names) const {
  const std::string name = string_of(node, what, fmt::format("\"{}\"", names.front()));
  if (std::find(names.begin(), names.end(), name) == names.end()) {
    const std::string nearest = nearest_name(name, names);
    fail(at(node), fmt::format("unknown {} '{}'; {}choose one of: {}", what, name,
                               nearest.empty() ? "" : fmt::format("did you mean '{}'? ", nearest), join(names)));
  }
  return name;
}

int LoadContext::coordinate_index(const std::string& name, const SourceLocation& where,
                                  std::string_view context) const {
  if (const auto it = coordinate_by_name.find(name); it != coordinate_by_name.end()) return it->second;
  const std::string nearest = nearest_name(name, coordinates);
  cursor.fail(where, fmt::format("'{}' {} is not a coordinate; {}", name, context,
                          nearest.empty() ? fmt::format("the coordinates are: {}", join(coordinates))
                                          : fmt::format("did you mean '{}'?", nearest)));
}

}  // namespace nhdyn::model_file
