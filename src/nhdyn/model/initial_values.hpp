// Initial values from the command line: `nhdyn simulate --initial "phi'=0.5"` replaces one entry
// of a Model's initial state (q0 or v0) before the run, as `batch` does with its x(0) and x'(0)
// columns. The value is an expression like a parameter's (model/parameters.hpp): numbers,
// constants, functions and the model's parameters, so `--initial "phi'=omega/2"` follows --set.
// Whether the new state satisfies the constraints is the run's check (analysis/initial_state.hpp:
// refused with the residuals, or moved onto them with --fix-initial).
#pragma once

#include <string>
#include <string_view>
#include <vector>

#include "nhdyn/model/model.hpp"

namespace nhdyn {

// One "NAME=EXPR" on `model`: NAME a coordinate (its initial value, q0) or a coordinate with a
// prime (its initial velocity, v0, "phi'"); "x(0)" and "x'(0)" as batch writes them are the same.
// Throws InputError, naming `option` and the text, for one without '=', a NAME that is not a
// coordinate (listing the model's, with the nearest), an expression that does not evaluate, or a
// value that is not finite. The model is unchanged when it throws.
void set_initial_value(Model& model, std::string_view set, std::string_view option = "--initial");

// Each of `sets` in turn (a later one for the same entry wins).
void apply_initial_values(Model& model, const std::vector<std::string>& sets, std::string_view option = "--initial");

}  // namespace nhdyn
