// The bridge from a Model's typed run options (model/run_options.hpp, read from [simulation]) to
// the SimulationOptions of one run: the names of the formulation, complement and integrator become
// their enums here, where those modules are visible. The CLI, the Python package and the batch
// runner all start from make_simulation_options and then apply what their user overrides.
#pragma once

#include "nhdyn/analysis/simulation.hpp"
#include "nhdyn/model/model.hpp"
#include "nhdyn/model/run_options.hpp"

namespace nhdyn {

// The options of a run with every value from `run`; throws InputError for an unknown method,
// complement or integrator name (listing the valid ones). Cost: three name lookups.
SimulationOptions make_simulation_options(const RunOptions& run);

// The same for the model's own defaults (model.defaults).
SimulationOptions make_simulation_options(const Model& model);

}  // namespace nhdyn
