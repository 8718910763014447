#include "model_source.hpp"

#include <fmt/format.h>

#include <filesystem>

#include "nhdyn/core/error.hpp"
#include "nhdyn/frontend/model_file.hpp"
#include "nhdyn/model/builtin.hpp"
#include "nhdyn/model/parameters.hpp"
#include "nhdyn/symbolic/compile.hpp"

namespace nhdyn::cli {
namespace {

bool looks_like_file(const std::string& source) {
  return source.find('/') != std::string::npos || source.ends_with(".toml") || std::filesystem::exists(source);
}

}  // namespace

symbolic::Spec resolve_spec(const std::string& source, const std::vector<std::string>& sets) {
  if (is_builtin_model(source) && !looks_like_file(source)) {
    const std::string file = source == "sled-paper" ? "sled_paper" : source;
    throw InputError(fmt::format("'{}' is a built-in model written in C++, with no symbolic form; use its "
                                 "model file instead: examples/{}.toml",
                                 source, file));
  }
  if (!looks_like_file(source)) make_builtin_model(source);  // throws, listing the built-in models
  symbolic::Spec spec = load_model_file(source);
  spec.apply_parameter_sets(sets);
  return spec;
}

ResolvedModel resolve_model(const std::string& source, const std::vector<std::string>& sets) {
  if (is_builtin_model(source) && !looks_like_file(source)) {
    Model model = make_builtin_model(source);
    apply_parameter_sets(model, sets);  // parameters are data: no recompilation
    return {std::move(model), std::nullopt};
  }
  symbolic::Spec spec = resolve_spec(source, sets);
  Model model = symbolic::compile_model(spec);
  return {std::move(model), std::move(spec)};
}

}  // namespace nhdyn::cli
