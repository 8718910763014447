#include "nhdyn/model/builtin.hpp"

#include <fmt/format.h>

#include "nhdyn/core/error.hpp"
#include "nhdyn/model/appell.hpp"
#include "nhdyn/model/sled.hpp"

namespace nhdyn {

namespace {
Model make_by_name(std::string_view name) {
  if (name == "appell") return make_appell_model();
  if (name == "sled") return make_sled_model(SledVariant::centre_of_mass);
  if (name == "sled-paper") return make_sled_model(SledVariant::paper);
  return {};
}
}  // namespace

std::vector<BuiltinModelInfo> list_builtin_models() {
  std::vector<BuiltinModelInfo> out;
  for (const char* name : {"appell", "sled", "sled-paper"}) {
    Model m = make_by_name(name);
    out.push_back({m.name, m.description});
  }
  return out;
}

bool is_builtin_model(std::string_view name) {
  return name == "appell" || name == "sled" || name == "sled-paper";
}

Model make_builtin_model(std::string_view name) {
  if (!is_builtin_model(name)) {
    std::string names;
    for (const BuiltinModelInfo& info : list_builtin_models())
      names += fmt::format("\n  {:<12} {}", info.name, info.description);
    throw InputError(fmt::format("unknown model '{}'; the built-in models are:{}", name, names));
  }
  return make_by_name(name);
}

}  // namespace nhdyn
