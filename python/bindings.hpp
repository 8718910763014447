// The pybind11 module nhdyn._nhdyn, one file per bound module of the library: model.cpp (loading,
// the Model), simulation.cpp (one run, results as NumPy arrays), batch.cpp (many runs on a thread
// pool), analysis.cpp (equations, linearization, sweep). The Python package nhdyn (python/nhdyn/)
// wraps these into the classes users see. The library's exceptions become nhdyn.Error and its
// subclasses with the same messages (module.cpp).
#pragma once

#include <fmt/format.h>
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>

#include <memory>
#include <utility>
#include <vector>

#include "nhdyn/analysis/batch.hpp"
#include "nhdyn/analysis/simulation.hpp"
#include "nhdyn/frontend/load_model.hpp"
#include "nhdyn/model/model.hpp"

namespace nhdyn::python {

namespace py = pybind11;

// A Model as Python holds it: shared, read-only, cheap to pass to many runs.
using ModelPtr = std::shared_ptr<Model>;  // pybind11 holders are non-const; nothing here writes it

void bind_model(py::module_& m);
void bind_simulation(py::module_& m);
void bind_batch(py::module_& m);
void bind_analysis(py::module_& m);
void bind_report(py::module_& m);  // report.cpp: provenance and the HTML report
void bind_optimize(py::module_& m);  // optimize.cpp: optimal programs (`nhdyn optimize`)

// A NumPy array that takes over `values` (no copy), with the given shape (C order).
py::array_t<double> take_array(std::vector<double>&& values, std::vector<py::ssize_t> shape);

// Overrides from a Python list of (name, float | str) pairs.
ParameterOverrides to_overrides(const py::iterable& pairs);

// SimulationOptions from the model's run options and the keyword arguments of a simulate call
// (None keeps the model's value). Throws InputError for a bad name or value.
SimulationOptions make_options(const Model& model, const py::dict& kwargs);

// A run's outputs as NumPy arrays t, q, qd, qdd, R, residuals, energy (taking over the vectors).
py::dict trajectory_dict(Trajectory&& trajectory);

// A run's summary (status, steps, residuals, wall time) as a dict.
py::dict summary_dict(const SimulationSummary& summary);

}  // namespace nhdyn::python
