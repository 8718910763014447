// One table per list of names. A kind of thing users choose by name (an integrator, a formulation,
// a choice of D, a stabilization, an evaluator) is listed once, as a constexpr array of entries
// {value, name, ...properties}, next to its enum; parsing, printing, the valid names of an error
// message, the model-file keys and the CLI's help are derived from that array by the functions
// below, so that adding a value touches its table and nothing that lists names.
//
//     constexpr std::array<IntegratorInfo, 5> kIntegrators{{{IntegratorKind::rk4, "rk4", ...}, ...}};
//     integrator_name(kind) == name_of(kIntegrators, kind)
//     parse_integrator(name) == find_named(kIntegrators, name), else an error listing list_names(kIntegrators)
//
// An entry is any struct with members `value` (the enum) and `name` (std::string_view).
#pragma once

#include <cstddef>
#include <string>
#include <string_view>
#include <vector>

namespace nhdyn {

// The entry for `value`, or null (a value cast from a bad integer).
template <class Table, class Value>
constexpr auto find_value(const Table& table, Value value) -> decltype(&table[0]) {
  for (const auto& entry : table)
    if (entry.value == value) return &entry;
  return nullptr;
}

// The entry called `name`, or null.
template <class Table>
constexpr auto find_named(const Table& table, std::string_view name) -> decltype(&table[0]) {
  for (const auto& entry : table)
    if (entry.name == name) return &entry;
  return nullptr;
}

// The entry's name for `value`; "?" for a value not in the table.
template <class Table, class Value>
constexpr std::string_view name_of(const Table& table, Value value) {
  const auto* entry = find_value(table, value);
  return entry ? entry->name : std::string_view("?");
}

// The names, in table order, for lists of valid values (a model file's keys).
template <class Table>
std::vector<std::string> names_of(const Table& table) {
  std::vector<std::string> out;
  for (const auto& entry : table) out.emplace_back(entry.name);
  return out;
}

// The names of the entries that satisfy `keep`, in table order, separated by `separator`, the last
// two by `last` ("a, b, c" or, with last = " or ", "a, b or c").
template <class Table, class Keep>
std::string list_names_if(const Table& table, Keep keep, std::string_view separator = ", ",
                          std::string_view last = ", ") {
  std::string out;
  std::size_t count = 0, total = 0;
  for (const auto& entry : table) total += keep(entry) ? 1 : 0;
  for (const auto& entry : table) {
    if (!keep(entry)) continue;
    if (count > 0) out += count + 1 == total ? last : separator;
    out += entry.name;
    ++count;
  }
  return out;
}

template <class Table>
std::string list_names(const Table& table, std::string_view separator = ", ", std::string_view last = ", ") {
  return list_names_if(table, [](const auto&) { return true; }, separator, last);
}

// The choices as the CLI's help writes them: "a | b (default) | c".
template <class Table, class Value>
std::string help_choices(const Table& table, Value default_value) {
  std::string out;
  for (const auto& entry : table) {
    if (!out.empty()) out += " | ";
    out += entry.name;
    if (entry.value == default_value) out += " (default)";
  }
  return out;
}

}  // namespace nhdyn
