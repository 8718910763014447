// The public surface of the nhdyn library in one include, for programs that use it:
//
//     #include "nhdyn/nhdyn.hpp"
//     nhdyn::Model model = nhdyn::load_model("examples/sled.toml", {{"a", 0.3}});
//     nhdyn::SimulationSummary run = nhdyn::simulate(model, nhdyn::make_simulation_options(model), row);
//
// It includes no GiNaC and no SUNDIALS (tests/layering checks it): models come from the front door
// (frontend/load_model.hpp) or from the built-in C++ models, and everything after is numeric. The
// other headers of a module folder are public too and go deeper (one formulation's kernel,
// formulation/sanh.hpp; the symbolic front end, symbolic/, for programs that build a Spec in C++:
// examples/appell_builder.cpp). The headers of a module's detail/ folder are the library's own
// (formulation/detail/small_dense.hpp, model/detail/tape_tangent.hpp, ...): not installed, and
// refused in an application by tests/layering. docs/design.md, "Architecture", shows where each
// part sits.
#pragma once

#include "nhdyn/core/error.hpp"             // InputError, FileError, ModelError
#include "nhdyn/core/status.hpp"            // Status of a kernel or a run
#include "nhdyn/core/shown_text.hpp"        // a text as a message shows it (invisible characters by code)
#include "nhdyn/model/model.hpp"            // Model: frozen, numeric
#include "nhdyn/model/data.hpp"             // Data: the workspace of one thread; Formulation
#include "nhdyn/model/parameters.hpp"       // set_parameter: parameters are data
#include "nhdyn/model/builtin.hpp"          // the built-in C++ models
#include "nhdyn/formulation/formulation.hpp"  // compute_acceleration, compute_dynamics; kFormulations
#include "nhdyn/integrators/ode.hpp"        // IntegratorOptions; kIntegrators
#include "nhdyn/analysis/simulation.hpp"    // simulate
#include "nhdyn/analysis/run_options.hpp"   // make_simulation_options
#include "nhdyn/analysis/batch.hpp"         // simulate_batch
#include "nhdyn/analysis/linearization.hpp"  // calc_linearization
#include "nhdyn/analysis/sweep.hpp"         // calc_parameter_sweep
#include "nhdyn/io/results.hpp"             // the CSV columns of a run
#include "nhdyn/io/csv.hpp"                 // CsvWriter, load_csv
#include "nhdyn/frontend/load_model.hpp"    // load_model: the one way from a source to a Model
#include "nhdyn/frontend/describe.hpp"      // equations and generated code of a model file
