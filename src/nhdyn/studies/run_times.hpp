// The check both tolerance studies make of the end time and output step they are given (0 means
// the model's own), so that a bad value is refused with one wording before any run starts.
#pragma once

#include <fmt/format.h>

#include <cmath>

#include "nhdyn/core/error.hpp"
#include "nhdyn/model/model.hpp"

namespace nhdyn {

inline void check_study_run_times(const Model& model, double t_end, double output_step) {
  if (t_end < 0.0 || !std::isfinite(t_end))
    throw InputError(fmt::format("t_end {} is not a valid end time; give a time after t0 = {}, or 0 for the model's",
                                 t_end, model.t0));
  if (output_step < 0.0 || !std::isfinite(output_step))
    throw InputError(fmt::format("output_step {} is not a valid step; give a positive step, or 0 for the model's",
                                 output_step));
}

}  // namespace nhdyn
