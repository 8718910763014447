// `nhdyn codegen MODEL.toml -o FILE.hpp`: standalone C++ that implements the model's Evaluator
// with straight-line code and needs no GiNaC; written whole or not at all.
#include <fmt/format.h>

#include <memory>

#include "commands.hpp"
#include "nhdyn/io/atomic_file.hpp"
#include "nhdyn/frontend/describe.hpp"
#include "run_files.hpp"

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
    RunFiles files(args->model);
    files.output(args->output, "-o");
    files.check();
    AtomicFile& file = files.open(args->output);  // refuses an unwritable path before deriving
    const auto description = load_description(read_model_source(args->model), parse_parameter_sets(args->sets));
    file.write(generate_model_code(*description, args->namespace_name));
    files.commit();
    fmt::print("nhdyn codegen {}: wrote {} (make_{}_model())\n", description_name(*description), args->output,
               model_code_identifier(*description));
    return 0;
  };
}

}  // namespace nhdyn::cli
