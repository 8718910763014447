#include "nhdyn/analysis/run_options.hpp"

namespace nhdyn {

SimulationOptions make_simulation_options(const RunOptions& run) {
  SimulationOptions options;
  options.t_end = run.t_end;
  options.output_step = run.output_step;
  options.formulation.method = parse_formulation(run.method);
  options.formulation.complement = parse_complement(run.complement);
  options.integrator.kind = parse_integrator(run.integrator);
  options.integrator.rtol = run.rtol;
  options.integrator.atol = run.atol;
  return options;
}

SimulationOptions make_simulation_options(const Model& model) { return make_simulation_options(model.defaults); }

}  // namespace nhdyn
