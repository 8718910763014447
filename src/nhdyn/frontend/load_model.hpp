// The front door: the one way from a source (the name of a built-in model, the path of a model
// file or the text of one) to a numeric Model, with parameter overrides, for the CLI, the Python
// package, the benchmarks, the fuzzer and the tests. The symbolic front end (Spec, derivation,
// compilation; GiNaC) stays behind this header: it includes no GiNaC, so a program that only loads
// and runs models never sees the compiler's types.
//
//     "examples/sled.toml" | "sled" | text --load_model--> Model --make_data--> Data
//                                         \--load_model_described--> Model + ModelDescription
//
// What the compile of a model file produced (its Spec, derivation and scene) is kept, once, in a
// shared immutable symbolic::ModelDescription beside the Model (LoadedModel); the commands that
// show the equations, generate code or draw the report read it (frontend/describe.hpp) instead
// of deriving again.
//
// Overrides replace a model file's parameter values before compilation (a built-in model's are
// set on the Model: parameters are data, model/parameters.hpp). An override given as a string is
// an expression in numbers, constants and the other parameters, as `--set NAME=EXPR`.
#pragma once

#include <memory>
#include <string>
#include <string_view>
#include <utility>
#include <variant>
#include <vector>

#include "nhdyn/analysis/sweep.hpp"
#include "nhdyn/model/model.hpp"

namespace nhdyn::symbolic {
class ModelDescription;  // symbolic/description.hpp (GiNaC): read through frontend/describe.hpp
}

namespace nhdyn {

// A parameter's new value: a number, or the text of one ("0.3", "1e-2").
using ParameterValue = std::variant<double, std::string>;
// In the order they are applied; a later override of the same name wins.
using ParameterOverrides = std::vector<std::pair<std::string, ParameterValue>>;

// The command line's `--set NAME=EXPR`, each as an override whose value is the text of EXPR;
// throws InputError for one without '=' (model/parameters.hpp, split_parameter_set).
ParameterOverrides parse_parameter_sets(const std::vector<std::string>& sets);

// Where a model comes from, kept so that it can be loaded again (with other overrides, or on
// another machine: the Python package's Dask workers rebuild models from it).
struct ModelSource {
  std::string builtin;    // the name of a built-in model (nhdyn list), or empty
  std::string text;       // the model file's text (empty for a built-in model)
  std::string file_name;  // the path it was read from, for messages ("<string>" for text)
  bool is_builtin() const { return !builtin.empty(); }
};

// Resolves `source`: a built-in model's name (unless a file of that name exists, or it contains
// '/' or ends in .toml), else a model file, whose text is read. Throws InputError listing the
// built-in models when it is neither, FileError when the file cannot be read.
ModelSource read_model_source(const std::string& source);

// The text of a model file; `file_name` is used in the messages only.
ModelSource model_source_from_text(std::string text, std::string file_name = "<string>");

// Loads and compiles. Throws ModelError ("file:line:column: ...") for anything wrong in a model
// file, InputError for an unknown parameter (naming the nearest one) or a value that is not one.
// An override is a number or an expression in numbers, constants and the other parameters, as
// `--set NAME=EXPR` on the command line; built-in models take them too.
Model load_model(const ModelSource& source, const ParameterOverrides& overrides = {});
Model load_model(const std::string& source, const ParameterOverrides& overrides = {});
Model load_model_text(std::string_view text, const std::string& file_name = "<string>",
                      const ParameterOverrides& overrides = {});

// A model and what its compile produced.
struct LoadedModel {
  Model model;
  // The Spec, derivation and scene of a model file, shared and immutable (symbolic/
  // description.hpp, read through frontend/describe.hpp); null for a built-in model, which is
  // written in C++ and has no symbolic form.
  std::shared_ptr<const symbolic::ModelDescription> description;
};

// load_model, keeping the description: the derivation made for the compile is the one the
// equations, the generated code and the report read. Throws like load_model.
LoadedModel load_model_described(const ModelSource& source, const ParameterOverrides& overrides = {});

// A command's MODEL argument with its `--set NAME=EXPR` options: read_model_source,
// parse_parameter_sets, load_model_described.
LoadedModel load_model_argument(const std::string& source, const std::vector<std::string>& sets);

// The description of a model file alone, parsed with the overrides applied, nothing derived or
// compiled yet (for commands that need only the equations). A built-in model is refused with the
// path of its model file in examples/ (InputError).
std::shared_ptr<const symbolic::ModelDescription> load_description(const ModelSource& source,
                                                                   const ParameterOverrides& overrides = {});

// One model per row of `values` (each row one value per name in `names`), with `overrides`
// applied first; the model is loaded once and each row is a copy with its parameters set (no
// recompilation, model/parameters.hpp). Used by batch runs over parameters. Throws like load_model, the message naming the row.
std::vector<Model> load_model_variants(const ModelSource& source, const ParameterOverrides& overrides,
                                       const std::vector<std::string>& names,
                                       const std::vector<std::vector<double>>& values);

// The names of the parameters of a model (a model file's in file order), with their values after
// the overrides.
std::vector<std::pair<std::string, double>> model_parameters(const ModelSource& source,
                                                             const ParameterOverrides& overrides = {});

enum class EquationsFormat { text, latex };

// The equations of motion as `nhdyn equations` shows them (T, V, A, Q, G, b, b0, D, A0, C); the
// LaTeX form is one align* environment. A built-in model is refused (no symbolic form).
std::string model_equations(const ModelSource& source, const ParameterOverrides& overrides, EquationsFormat format);

// calc_parameter_sweep (analysis/sweep.hpp) of the model loaded once: the options are checked
// before the model is loaded.
Sweep sweep_model_parameter(const ModelSource& source, const ParameterOverrides& overrides,
                            const SweepOptions& options);

}  // namespace nhdyn
