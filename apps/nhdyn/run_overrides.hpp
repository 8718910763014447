// The run options of a command that runs a model: the model's own, with the command line's
// overrides. One place for simulate and batch, whose option structs share these fields.
#pragma once

#include "nhdyn/model/model.hpp"

namespace nhdyn::cli {

// The model's run options (its file's [simulation], else the defaults of RunOptions) with what the
// command line overrides: `args` has the optional t_end, output_step, method, complement,
// integrator, rtol and atol of the commands that run a model.
template <class Args>
RunOptions run_options_with(const Model& model, const Args& args) {
  RunOptions run = model.defaults;
  run.t_end = args.t_end.value_or(run.t_end);
  run.output_step = args.output_step.value_or(run.output_step);
  run.method = args.method.value_or(run.method);
  run.complement = args.complement.value_or(run.complement);
  run.integrator = args.integrator.value_or(run.integrator);
  run.rtol = args.rtol.value_or(run.rtol);
  run.atol = args.atol.value_or(run.atol);
  return run;
}

}  // namespace nhdyn::cli
