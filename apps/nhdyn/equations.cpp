// `nhdyn equations MODEL.toml [--format text|latex]`: the derived equations of motion as the paper
// writes them — T, V, A, Q, G, b, b0, D, A0 = D A, C = D (Q + G) and the resulting equations.
#include <fmt/format.h>

#include <memory>

#include "commands.hpp"
#include "nhdyn/core/error.hpp"
#include "nhdyn/frontend/describe.hpp"

namespace nhdyn::cli {

std::function<int()> add_equations_command(CLI::App& app) {
  struct Args {
    std::string model;
    std::string format = "text";
    std::vector<std::string> sets;
  };
  auto args = std::make_shared<Args>();
  CLI::App* cmd = app.add_subcommand("equations", "Derive and print the equations of motion of a model file");
  cmd->add_option("MODEL", args->model, "A model file (.toml)")->required();
  cmd->add_option("--format", args->format, "text | latex")->capture_default_str();
  cmd->add_option("--set", args->sets, "Set a parameter, NAME=EXPR: a number or an expression in numbers, pi, e and the other parameters (repeatable)");
  return [args] {
    EquationsFormat format = EquationsFormat::text;
    if (args->format == "latex") format = EquationsFormat::latex;
    else if (args->format != "text")
      throw InputError(fmt::format("unknown format '{}'; choose text or latex", args->format));
    const auto description = load_description(read_model_source(args->model), parse_parameter_sets(args->sets));
    const int n = description_coordinates(*description);
    // A, D and D A are printed in full, n^2 entries each: 10000 coordinates made 600 MB of text
    // from 7 GB of memory. Refused before the derivation, with the way out.
    constexpr int largest = 1000;
    if (n > largest)
      throw InputError(fmt::format(
          "'{}' has {} coordinates: `nhdyn equations` prints the matrices A, D and D A in full, about {:.2g} "
          "entries here; it prints models of up to {} coordinates. For a large model use `nhdyn codegen` "
          "(straight-line C++) or `nhdyn simulate`",
          description_name(*description), n, 3.0 * n * n, largest));
    fmt::print("{}", format_model_equations(*description, format));
    return 0;
  };
}

}  // namespace nhdyn::cli
