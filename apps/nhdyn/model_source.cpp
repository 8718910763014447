#include "model_source.hpp"

#include <fmt/format.h>

#include <filesystem>

#include "nhdyn/core/error.hpp"
#include "nhdyn/model/builtin.hpp"

namespace nhdyn::cli {

Model resolve_model(const std::string& source) {
  if (is_builtin_model(source)) return make_builtin_model(source);
  const bool looks_like_file = source.find('/') != std::string::npos || source.ends_with(".toml") ||
                               std::filesystem::exists(source);
  if (looks_like_file) {
    std::string names;
    for (const BuiltinModelInfo& info : list_builtin_models()) names += " " + info.name;
    throw InputError(fmt::format("'{}': this version of nhdyn reads no model files yet; give the name of "
                                 "a built-in model:{}",
                                 source, names));
  }
  return make_builtin_model(source);  // throws, listing the built-in models
}

}  // namespace nhdyn::cli
