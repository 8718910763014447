// RunOptions: what a run of a model does when the user says nothing else — the times, the
// formulation, the integrator and its tolerances — read from a model file's [simulation] table
// (docs/model-format.md) or set by a built-in model, and kept in the Model (model.hpp). Every
// command, the Python package and the batch runner start from these values, so each default is
// written here and nowhere else.
//
// The formulation, complement and integrator are kept by name: their enums live in formulation/
// and integrators/, above this module, and parse_formulation / parse_complement / parse_integrator turn
// the names into them (make_simulation_options in analysis/simulation.hpp). A model file's names
// are checked when it is loaded (frontend/load_model.hpp), so a bad name is reported with its file.
#pragma once

#include <string>

namespace nhdyn {

struct RunOptions {
  double t_end = 10.0;             // end time [s]
  double output_step = 0.01;       // time between output rows [s]
  std::string method = "sanh";     // formulation: sanh | lagrange | udwadia-kalaba | nullspace
  std::string complement = "qr";   // where D comes from (sanh, nullspace): qr | partition | analytic
  std::string integrator = "dopri5";
  double rtol = 1e-8;              // relative tolerance of the adaptive integrators
  double atol = 1e-10;             // absolute tolerance of the adaptive integrators
};

}  // namespace nhdyn
