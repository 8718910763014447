// `nhdyn list`: the built-in models with a line of description each.
#include <fmt/format.h>

#include "commands.hpp"
#include "nhdyn/model/builtin.hpp"

namespace nhdyn::cli {

std::function<int()> add_list_command(CLI::App& app) {
  app.add_subcommand("list", "List the built-in models");
  return [] {
    for (const BuiltinModelInfo& info : list_builtin_models()) fmt::print("{:<12} {}\n", info.name, info.description);
    return 0;
  };
}

}  // namespace nhdyn::cli
