// `nhdyn equations MODEL.toml [--format text|latex]`: the derived equations of motion as the paper
// writes them — T, V, A, Q, G, b, b0, D, A0 = D A, C = D (Q + G) and the resulting equations.
#include <fmt/format.h>

#include <memory>

#include "commands.hpp"
#include "model_source.hpp"
#include "nhdyn/core/error.hpp"
#include "nhdyn/symbolic/derivation.hpp"
#include "nhdyn/symbolic/equations.hpp"

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
    symbolic::EquationFormat format = symbolic::EquationFormat::text;
    if (args->format == "latex") format = symbolic::EquationFormat::latex;
    else if (args->format != "text")
      throw InputError(fmt::format("unknown format '{}'; choose text or latex", args->format));
    const symbolic::Spec spec = resolve_spec(args->model, args->sets);
    // A, D and D A are printed in full, n^2 entries each: 10000 coordinates made 600 MB of text
    // from 7 GB of memory. Refused before the derivation, with the way out.
    constexpr int largest = 1000;
    if (spec.n() > largest)
      throw InputError(fmt::format(
          "'{}' has {} coordinates: `nhdyn equations` prints the matrices A, D and D A in full, about {:.2g} "
          "entries here; it prints models of up to {} coordinates. For a large model use `nhdyn codegen` "
          "(straight-line C++) or `nhdyn simulate`",
          spec.name, spec.n(), 3.0 * spec.n() * spec.n(), largest));
    const symbolic::Derivation derivation = symbolic::derive(spec);
    fmt::print("{}", symbolic::format_equations(spec, derivation, format));
    return 0;
  };
}

}  // namespace nhdyn::cli
