#include "model_source.hpp"

#include <fmt/format.h>

#include <cerrno>
#include <cmath>
#include <cstdlib>
#include <filesystem>

#include "nhdyn/core/error.hpp"
#include "nhdyn/io/model_file.hpp"
#include "nhdyn/model/builtin.hpp"
#include "nhdyn/symbolic/compile.hpp"

namespace nhdyn::cli {
namespace {

bool looks_like_file(const std::string& source) {
  return source.find('/') != std::string::npos || source.ends_with(".toml") || std::filesystem::exists(source);
}

void apply_sets(symbolic::Spec& spec, const std::vector<std::string>& sets) {
  for (const std::string& set : sets) {
    const std::size_t eq = set.find('=');
    if (eq == std::string::npos || eq == 0)
      throw InputError(fmt::format("--set '{}': write it as NAME=VALUE, e.g. --set a=0.3", set));
    const std::string name = set.substr(0, eq);
    const std::string text = set.substr(eq + 1);
    char* end = nullptr;
    errno = 0;
    const double value = std::strtod(text.c_str(), &end);
    if (text.empty() || *end != '\0' || errno == ERANGE || !std::isfinite(value))
      throw InputError(fmt::format("--set {}: '{}' is not a finite number", name, text));
    spec.set_parameter(name, value);
  }
}

}  // namespace

symbolic::Spec resolve_spec(const std::string& source, const std::vector<std::string>& sets) {
  if (is_builtin_model(source) && !looks_like_file(source)) {
    const std::string file = source == "sled-paper" ? "sled_paper" : source;
    throw InputError(fmt::format("'{}' is a built-in model written in C++, with fixed parameters and no "
                                 "symbolic form; use its model file instead: examples/{}.toml",
                                 source, file));
  }
  if (!looks_like_file(source)) make_builtin_model(source);  // throws, listing the built-in models
  symbolic::Spec spec = load_model_file(source);
  apply_sets(spec, sets);
  return spec;
}

ResolvedModel resolve_model(const std::string& source, const std::vector<std::string>& sets) {
  if (is_builtin_model(source) && !looks_like_file(source)) {
    if (!sets.empty()) resolve_spec(source, sets);  // throws: built-in parameters are fixed
    return {make_builtin_model(source), std::nullopt};
  }
  symbolic::Spec spec = resolve_spec(source, sets);
  Model model = symbolic::compile_model(spec);
  return {std::move(model), std::move(spec)};
}

}  // namespace nhdyn::cli
