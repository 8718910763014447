// nhdyn._nhdyn: where a model comes from (Source), loading it (load, load_variants) and what a
// loaded Model shows (names, parameters, initial state, run options). GiNaC is used under load_*
// while the GIL is held, so two Python threads never compile at once (GiNaC is not thread-safe).
#include <pybind11/stl.h>

#include <cmath>

#include "bindings.hpp"
#include "nhdyn/core/error.hpp"
#include "nhdyn/io/results.hpp"
#include "nhdyn/model/builtin.hpp"
#include "nhdyn/model/parameters.hpp"

namespace nhdyn::python {

py::array_t<double> take_array(std::vector<double>&& values, std::vector<py::ssize_t> shape) {
  auto* owned = new std::vector<double>(std::move(values));
  py::capsule free_when_done(owned, [](void* p) { delete static_cast<std::vector<double>*>(p); });
  return py::array_t<double>(shape, owned->data(), free_when_done);
}

ParameterOverrides to_overrides(const py::iterable& pairs) {
  ParameterOverrides out;
  for (const py::handle item : pairs) {
    const auto pair = item.cast<py::tuple>();
    if (pair.size() != 2) throw InputError("a parameter override is a pair (name, value)");
    const auto name = pair[0].cast<std::string>();
    const py::handle value = pair[1];
    if (py::isinstance<py::str>(value))
      out.emplace_back(name, value.cast<std::string>());
    else if (py::isinstance<py::bool_>(value))
      throw InputError(fmt::format("parameter {} = {}: give a number, not a bool", name, py::str(value).cast<std::string>()));
    else {
      double number = 0.0;
      try {
        number = value.cast<double>();
      } catch (const py::cast_error&) {
        throw InputError(fmt::format("parameter {} = {}: give a number or the text of one", name,
                                     py::repr(value).cast<std::string>()));
      }
      // Named here: as text, float('nan') read as an unknown parameter 'nan'.
      if (!std::isfinite(number))
        throw InputError(fmt::format("parameter {} = {}: the value is not a finite number", name, number));
      out.emplace_back(name, number);
    }
  }
  return out;
}

namespace {

py::array_t<double> vector_array(const Vector& v) {
  return take_array(std::vector<double>(v.data(), v.data() + v.size()), {v.size()});
}

py::dict run_options_dict(const RunOptions& run) {
  py::dict d;
  d["t_end"] = run.t_end;
  d["output_step"] = run.output_step;
  d["method"] = run.method;
  d["complement"] = run.complement;
  d["integrator"] = run.integrator;
  d["rtol"] = run.rtol;
  d["atol"] = run.atol;
  return d;
}

}  // namespace

void bind_model(py::module_& m) {
  py::class_<ModelSource>(m, "Source", "Where a model comes from: a built-in name or a model file's text")
      .def_readonly("builtin", &ModelSource::builtin)
      .def_readonly("text", &ModelSource::text)
      .def_readonly("file_name", &ModelSource::file_name)
      .def_property_readonly("is_builtin", &ModelSource::is_builtin)
      .def(py::pickle([](const ModelSource& s) { return py::make_tuple(s.builtin, s.text, s.file_name); },
                      [](const py::tuple& t) {
                        return ModelSource{t[0].cast<std::string>(), t[1].cast<std::string>(),
                                           t[2].cast<std::string>()};
                      }));
  m.def("read_source", &read_model_source, py::arg("source"),
        "A built-in model's name or a model file's path -> Source (the file's text is read now)");
  m.def("source_from_text", &model_source_from_text, py::arg("text"), py::arg("file_name") = "<string>");
  m.def("builtin_models", [] {
    std::vector<std::pair<std::string, std::string>> out;
    for (const BuiltinModelInfo& info : list_builtin_models()) out.emplace_back(info.name, info.description);
    return out;
  });

  py::class_<Model, ModelPtr>(m, "Model", "A compiled model (numeric, read-only)")
      .def_readonly("name", &Model::name)
      .def_readonly("description", &Model::description)
      .def_readonly("coordinates", &Model::coordinates)
      .def_property_readonly("constraints",
                             [](const Model& model) {
                               std::vector<std::string> names;
                               for (const Constraint& c : model.constraints) names.push_back(c.name);
                               return names;
                             })
      .def_property_readonly("parameters",
                             [](const Model& model) {
                               std::vector<std::pair<std::string, double>> out;
                               for (const Parameter& p : model.parameters) out.emplace_back(p.name, p.value);
                               return out;
                             })
      .def_readonly("t0", &Model::t0)
      .def_property_readonly("q0", [](const Model& model) { return vector_array(model.q0); })
      .def_property_readonly("v0", [](const Model& model) { return vector_array(model.v0); })
      .def_property_readonly("n", &Model::n)
      .def_property_readonly("s", &Model::s)
      .def_property_readonly("run_options", [](const Model& model) { return run_options_dict(model.defaults); })
      .def_property_readonly("has_energy", [](const Model& model) { return model.evaluator->has_energy(); })
      .def_property_readonly("columns", [](const Model& model) {
        const ResultColumns c = make_result_columns(model);
        py::dict d;
        d["all"] = c.all;
        d["coordinates"] = c.coordinates;
        d["reactions"] = c.reactions;
        // The programs' residual columns come last in c.residuals; they are kept apart here, as
        // Result.residuals and Result.program_residuals are.
        std::size_t program_residuals = 0;
        for (const ProgramConstraint& p : model.program_constraints)
          program_residuals += p.level == ConstraintLevel::position ? 3 : p.level == ConstraintLevel::velocity ? 2 : 1;
        const auto split = c.residuals.end() - static_cast<std::ptrdiff_t>(program_residuals);
        d["residuals"] = std::vector<std::string>(c.residuals.begin(), split);
        d["program_residuals"] = std::vector<std::string>(split, c.residuals.end());
        d["actuators"] = c.actuators;
        d["energy"] = c.energy;
        d["contact_forces"] = c.contact_forces;
        d["outputs"] = c.outputs;
        return d;
      });

  m.def(
      "load",
      [](const ModelSource& source, const py::iterable& overrides) {
        return std::make_shared<Model>(load_model(source, to_overrides(overrides)));
      },
      py::arg("source"), py::arg("overrides") = py::list());
  // A copy of `model` with parameters set (numbers, or expressions in the others): no
  // recompilation, the copy computes what a model loaded with those values computes.
  m.def(
      "with_parameters",
      [](const Model& model, const py::iterable& values) {
        auto out = std::make_shared<Model>(model);
        for (const auto& [name, value] : to_overrides(values)) {
          if (const double* number = std::get_if<double>(&value))
            set_parameter(*out, name, *number);
          else
            set_parameter_expression(*out, name, std::get<std::string>(value));
        }
        return out;
      },
      py::arg("model"), py::arg("values"));
  m.def(
      "load_variants",
      [](const ModelSource& source, const py::iterable& overrides, const std::vector<std::string>& names,
         const py::array_t<double, py::array::c_style | py::array::forcecast>& values) {
        if (values.ndim() != 2 || values.shape(1) != static_cast<py::ssize_t>(names.size()))
          throw InputError(fmt::format("parameter values: expected an array of shape (runs, {}), got {} dimensions",
                                       names.size(), values.ndim()));
        std::vector<std::vector<double>> rows(static_cast<std::size_t>(values.shape(0)));
        for (py::ssize_t i = 0; i < values.shape(0); ++i)
          rows[static_cast<std::size_t>(i)].assign(values.data(i, 0), values.data(i, 0) + values.shape(1));
        std::vector<ModelPtr> out;
        for (Model& model : load_model_variants(source, to_overrides(overrides), names, rows))
          out.push_back(std::make_shared<Model>(std::move(model)));
        return out;
      },
      py::arg("source"), py::arg("overrides"), py::arg("names"), py::arg("values"));
  m.def(
      "parameters",
      [](const ModelSource& source, const py::iterable& overrides) {
        return model_parameters(source, to_overrides(overrides));
      },
      py::arg("source"), py::arg("overrides") = py::list());
}

}  // namespace nhdyn::python
