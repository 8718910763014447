// `nhdyn codegen MODEL.toml -o FILE.hpp`: standalone C++ that implements the model's Evaluator
// with straight-line code and needs no GiNaC; written whole or not at all.
#include <fmt/format.h>

#include <memory>

#include "commands.hpp"
#include "model_source.hpp"
#include "outputs.hpp"
#include "nhdyn/io/atomic_file.hpp"
#include "nhdyn/symbolic/codegen.hpp"
#include "nhdyn/symbolic/derivation.hpp"

namespace nhdyn::cli {

std::function<int()> add_codegen_command(CLI::App& app) {
  struct Args {
    std::string model;
    std::string output;
    std::string namespace_name = "nhdyn::generated";
    std::vector<std::string> sets;
  };
  auto args = std::make_shared<Args>();
  CLI::App* cmd = app.add_subcommand("codegen", "Generate standalone C++ for a model file");
  cmd->add_option("MODEL", args->model, "A model file (.toml)")->required();
  cmd->add_option("-o,--output", args->output, "Header to write")->required();
  cmd->add_option("--namespace", args->namespace_name, "C++ namespace of the generated code")->capture_default_str();
  cmd->add_option("--set", args->sets, "Set a parameter, NAME=EXPR: a number or an expression in numbers, pi, e and the other parameters (repeatable)");
  return [args] {
    protect_model_file(args->model);
    AtomicFile file(args->output);  // refuses an unwritable path before deriving
    const symbolic::Spec spec = resolve_spec(args->model, args->sets);
    symbolic::CodegenOptions options;
    options.namespace_name = args->namespace_name;
    file.write(symbolic::generate_code(spec, symbolic::derive(spec), options));
    file.commit();
    fmt::print("nhdyn codegen {}: wrote {} (make_{}_model())\n", spec.name, args->output,
               symbolic::make_identifier(spec.name));
    return 0;
  };
}

}  // namespace nhdyn::cli
