#include "nhdyn/io/provenance.hpp"

#include <fmt/format.h>

#include <cstdint>
#include <cstdlib>
#include <iterator>

#include "nhdyn/core/error.hpp"
#include "nhdyn/core/version.hpp"

namespace nhdyn {
namespace {

constexpr std::string_view kFirst = "nhdyn version";
constexpr std::string_view kEnd = "end of provenance";
// Every key the header has, in order; a header missing one was cut short.
constexpr std::string_view kKeys[] = {"nhdyn version", "model",   "model file", "model hash",
                                      "parameters",    "initial", "run"};

std::string provenance_line(std::string text) {
  for (char& c : text)
    if (c == '\n' || c == '\r') c = ' ';
  return text;
}

std::string trim_field(std::string_view text) {
  while (!text.empty() && (text.front() == ' ' || text.front() == '\t')) text.remove_prefix(1);
  while (!text.empty() && (text.back() == ' ' || text.back() == '\t' || text.back() == '\r')) text.remove_suffix(1);
  return std::string(text);
}

// "a=1, b=2" -> pairs; the values as strings. "(none)" is the empty list.
std::vector<std::pair<std::string, std::string>> split_provenance_pairs(const std::string& text, const std::string& key,
                                                             const std::string& file) {
  std::vector<std::pair<std::string, std::string>> out;
  if (text == "(none)") return out;
  std::size_t start = 0;
  while (start <= text.size()) {
    std::size_t comma = text.find(", ", start);
    if (comma == std::string::npos) comma = text.size();
    const std::string item = trim_field(std::string_view(text).substr(start, comma - start));
    const std::size_t eq = item.find('=');
    if (eq == std::string::npos || eq == 0)
      throw InputError(fmt::format("{}: the provenance header's '{}' line has '{}', which is not NAME=VALUE; the "
                                   "header was altered: write the result again with nhdyn simulate",
                                   file, key, item));
    out.emplace_back(item.substr(0, eq), item.substr(eq + 1));
    start = comma + 2;
  }
  return out;
}

std::vector<std::pair<std::string, double>> provenance_numbers(const std::string& text, const std::string& key,
                                                    const std::string& file) {
  std::vector<std::pair<std::string, double>> out;
  for (const auto& [name, value] : split_provenance_pairs(text, key, file)) {
    char* end = nullptr;
    const double x = std::strtod(value.c_str(), &end);
    if (value.empty() || *end != '\0')
      throw InputError(fmt::format("{}: the provenance header's '{}' line gives {} = '{}', which is not a number; "
                                   "the header was altered: write the result again with nhdyn simulate",
                                   file, key, name, value));
    out.emplace_back(name, x);
  }
  return out;
}

std::string format_provenance_numbers(const std::vector<std::pair<std::string, double>>& values) {
  if (values.empty()) return "(none)";
  std::string out;
  for (const auto& [name, value] : values)
    fmt::format_to(std::back_inserter(out), "{}{}={}", out.empty() ? "" : ", ", name, value);
  return out;
}

}  // namespace

std::string calc_text_hash(std::string_view text) {
  std::uint64_t h = 0xcbf29ce484222325ULL;
  for (const char c : text) {
    h ^= static_cast<unsigned char>(c);
    h *= 0x100000001b3ULL;
  }
  return fmt::format("fnv1a64:{:016x}", h);
}

std::string nhdyn_version_text() { return fmt::format("{} (commit {})", NHDYN_VERSION, NHDYN_GIT_COMMIT); }

std::string format_provenance(const Provenance& p) {
  std::string out;
  const auto line = [&](std::string_view key, const std::string& value) {
    fmt::format_to(std::back_inserter(out), "# {}: {}\n", key, provenance_line(value));
  };
  line(kFirst, p.version);
  line("model", p.model);
  line("model file", p.model_file);
  line("model hash", p.model_hash);
  line("parameters", format_provenance_numbers(p.parameters));
  line("initial", format_provenance_numbers(p.initial));
  std::string run;
  for (const auto& [name, value] : p.run) {
    // ", " separates the options: one inside a value (an event's atan2(y, x)) loses its blank.
    std::string text = value;
    for (std::size_t at = text.find(", "); at != std::string::npos; at = text.find(", ", at)) text.erase(at + 1, 1);
    run += fmt::format("{}{}={}", run.empty() ? "" : ", ", name, text);
  }
  line("run", run.empty() ? "(none)" : run);
  out += fmt::format("# {}\n", kEnd);
  return out;
}

std::optional<Provenance> parse_provenance(const std::vector<std::string>& comments, const std::string& file) {
  std::size_t first = comments.size();
  for (std::size_t i = 0; i < comments.size(); ++i)
    if (trim_field(comments[i]).starts_with(std::string(kFirst) + ":")) {
      first = i;
      break;
    }
  if (first == comments.size()) return std::nullopt;
  const std::string what_to_do = "write the result again with nhdyn simulate (or remove the '#' lines to "
                                 "read it as a CSV without provenance, giving --set again)";
  std::vector<std::pair<std::string, std::string>> fields;
  bool ended = false;
  for (std::size_t i = first; i < comments.size(); ++i) {
    const std::string text = trim_field(comments[i]);
    if (text == kEnd) {
      ended = true;
      break;
    }
    const std::size_t colon = text.find(": ");
    if (colon == std::string::npos && !text.ends_with(":"))
      throw InputError(fmt::format("{}: the provenance header's line '# {}' is not '# key: value'; {}", file, text,
                                   what_to_do));
    const std::size_t cut = colon == std::string::npos ? text.size() - 1 : colon;
    fields.emplace_back(text.substr(0, cut), colon == std::string::npos ? "" : text.substr(colon + 2));
  }
  const auto value = [&](std::string_view key) -> const std::string* {
    for (const auto& [k, v] : fields)
      if (k == key) return &v;
    return nullptr;
  };
  for (std::string_view key : kKeys)
    if (!value(key))
      throw InputError(fmt::format("{}: the provenance header is truncated: it has no '{}' line; {}", file, key,
                                   what_to_do));
  if (!ended)
    throw InputError(fmt::format("{}: the provenance header is truncated: its last line '# {}' is missing; {}", file,
                                 kEnd, what_to_do));
  Provenance p;
  p.version = *value("nhdyn version");
  p.model = *value("model");
  p.model_file = *value("model file");
  p.model_hash = *value("model hash");
  p.parameters = provenance_numbers(*value("parameters"), "parameters", file);
  p.initial = provenance_numbers(*value("initial"), "initial", file);
  p.run = split_provenance_pairs(*value("run"), "run", file);
  return p;
}

}  // namespace nhdyn
