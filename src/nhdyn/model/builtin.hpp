// The registry of models built into nhdyn, by name: what `nhdyn list` shows and what
// `nhdyn simulate NAME` finds.
#pragma once

#include <string>
#include <string_view>
#include <vector>

#include "nhdyn/model/model.hpp"

namespace nhdyn {

struct BuiltinModelInfo {
  std::string name;
  std::string description;
};

std::vector<BuiltinModelInfo> list_builtin_models();
bool is_builtin_model(std::string_view name);
// Throws InputError listing the available names when `name` is unknown.
Model make_builtin_model(std::string_view name);

}  // namespace nhdyn
