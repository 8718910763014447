// The entry point of nhdyn._nhdyn: the exceptions, then each bound module (bindings.hpp).
#include <pybind11/pybind11.h>

#include "bindings.hpp"
#include "nhdyn/core/error.hpp"
#include "nhdyn/core/shown_text.hpp"
#include "nhdyn/core/version.hpp"

namespace py = pybind11;

PYBIND11_MODULE(_nhdyn, m) {
  m.doc() = "nhdyn: equations of motion of constrained mechanical systems (C++ core; use the package nhdyn)";
  m.attr("__version__") = NHDYN_VERSION;
  m.attr("__git_commit__") = NHDYN_GIT_COMMIT;
  // nhdyn::Error and its subclasses keep their C++ names and messages; InputError and ModelError
  // are also ValueErrors and FileError an OSError, so generic Python handlers catch them.
  static py::exception<nhdyn::Error> error(m, "Error", PyExc_Exception);
  py::tuple input_bases = py::make_tuple(error, py::handle(PyExc_ValueError));
  py::tuple file_bases = py::make_tuple(error, py::handle(PyExc_OSError));
  static py::object input_error = py::reinterpret_steal<py::object>(
      PyErr_NewException("nhdyn._nhdyn.InputError", input_bases.ptr(), nullptr));
  static py::object model_error = py::reinterpret_steal<py::object>(
      PyErr_NewException("nhdyn._nhdyn.ModelError", input_bases.ptr(), nullptr));
  static py::object file_error = py::reinterpret_steal<py::object>(
      PyErr_NewException("nhdyn._nhdyn.FileError", file_bases.ptr(), nullptr));
  static py::object simulation_error = py::reinterpret_steal<py::object>(
      PyErr_NewException("nhdyn._nhdyn.SimulationError", error.ptr(), nullptr));
  m.attr("InputError") = input_error;
  m.attr("ModelError") = model_error;
  m.attr("FileError") = file_error;
  m.attr("SimulationError") = simulation_error;
  // The messages show an invisible character of what they echo by its code (core/shown_text.hpp),
  // as the CLI's do; a byte that is not UTF-8 would not even become a Python str.
  py::register_exception_translator([](std::exception_ptr p) {
    try {
      if (p) std::rethrow_exception(p);
    } catch (const nhdyn::InputError& e) {
      PyErr_SetString(input_error.ptr(), nhdyn::shown_text(e.what(), true).c_str());
    } catch (const nhdyn::ModelError& e) {
      PyErr_SetString(model_error.ptr(), nhdyn::shown_text(e.what(), true).c_str());
    } catch (const nhdyn::FileError& e) {
      PyErr_SetString(file_error.ptr(), nhdyn::shown_text(e.what(), true).c_str());
    } catch (const nhdyn::SimulationError& e) {
      PyErr_SetString(simulation_error.ptr(), nhdyn::shown_text(e.what(), true).c_str());
    } catch (const nhdyn::Error& e) {
      PyErr_SetString(error.ptr(), nhdyn::shown_text(e.what(), true).c_str());
    }
  });
  nhdyn::python::bind_model(m);
  nhdyn::python::bind_simulation(m);
  nhdyn::python::bind_batch(m);
  nhdyn::python::bind_analysis(m);
  nhdyn::python::bind_report(m);
  nhdyn::python::bind_optimize(m);
}
