// Where the MODEL argument of a command comes from: the name of a built-in model, or the path
// of a model file (TOML, docs/model-format.md). Every command resolves it through this one
// place, together with the `--set NAME=EXPR` overrides of its parameters.
#pragma once

#include <optional>
#include <string>
#include <vector>

#include "nhdyn/model/model.hpp"
#include "nhdyn/symbolic/spec.hpp"

namespace nhdyn::cli {

struct ResolvedModel {
  Model model;
  std::optional<symbolic::Spec> spec;  // set for model files
};

// Throws InputError listing the built-in models when `source` is neither one nor a file, and
// for a --set of an unknown parameter, a bad expression or a cyclic definition. The --set
// NAME=EXPR overrides apply to model files and built-in models alike (model/parameters.hpp).
ResolvedModel resolve_model(const std::string& source, const std::vector<std::string>& sets = {});

// A model file's Spec with the --set overrides applied; a built-in name is refused with the
// path of its model file in examples/.
symbolic::Spec resolve_spec(const std::string& source, const std::vector<std::string>& sets = {});

}  // namespace nhdyn::cli
