// Where the MODEL argument of a command comes from: a built-in example's name today; the same
// argument will accept a model file's path, so every command resolves it through this one place.
#pragma once

#include <string>

#include "nhdyn/model/model.hpp"

namespace nhdyn::cli {

// Throws InputError listing the available models when `source` names none.
Model resolve_model(const std::string& source);

}  // namespace nhdyn::cli
