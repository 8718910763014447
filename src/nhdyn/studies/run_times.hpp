// The check both tolerance studies make of the end time and output step they are given (0 means
// the model's own), so that a bad value is refused with one wording, from the command line or a
// C++ caller, before any run starts.
#pragma once

#include <fmt/format.h>

#include <cmath>
#include <optional>

#include "nhdyn/core/error.hpp"
#include "nhdyn/model/model.hpp"

namespace nhdyn {

// The one check of a tolerance study's run length, for the command line and the library alike:
// an end time given must be finite and after the model's initial time, an output step given
// positive and finite. Messages name the command line's options (--t-end, --output-step).
inline void check_study_run_times(const Model& model, std::optional<double> t_end, std::optional<double> output_step) {
  if (t_end && !(std::isfinite(*t_end) && *t_end > model.t0))
    throw InputError(fmt::format("--t-end {} must be after the initial time {}", *t_end, model.t0));
  if (output_step && !(std::isfinite(*output_step) && *output_step > 0.0))
    throw InputError(fmt::format("--output-step {} must be positive", *output_step));
}

// The same for a study's options, where 0 means the model's own value.
inline void check_study_run_times(const Model& model, double t_end, double output_step) {
  check_study_run_times(model, t_end == 0.0 ? std::nullopt : std::optional<double>(t_end),
                        output_step == 0.0 ? std::nullopt : std::optional<double>(output_step));
}

}  // namespace nhdyn
