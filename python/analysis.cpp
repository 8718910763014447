// nhdyn._nhdyn: the equations of motion as text or LaTeX, the linearization about a steady motion
// and the eigenvalue sweep against a parameter (analysis/linearization.hpp, analysis/sweep.hpp).
#include <pybind11/complex.h>
#include <pybind11/stl.h>

#include "bindings.hpp"
#include "nhdyn/analysis/linearization.hpp"
#include "nhdyn/analysis/sweep.hpp"
#include "nhdyn/core/error.hpp"

namespace nhdyn::python {
namespace {

py::array_t<double> matrix_array(const Matrix& a) {
  std::vector<double> values(static_cast<std::size_t>(a.size()));
  for (Eigen::Index i = 0; i < a.rows(); ++i)
    for (Eigen::Index j = 0; j < a.cols(); ++j) values[static_cast<std::size_t>(i * a.cols() + j)] = a(i, j);
  return take_array(std::move(values), {a.rows(), a.cols()});
}

py::array_t<std::complex<double>> complex_array(const std::vector<std::complex<double>>& values) {
  py::array_t<std::complex<double>> out(static_cast<py::ssize_t>(values.size()));
  auto view = out.mutable_unchecked<1>();
  for (std::size_t i = 0; i < values.size(); ++i) view(static_cast<py::ssize_t>(i)) = values[i];
  return out;
}

LinearizationOptions linearization_options(const std::vector<std::string>& cyclic,
                                           const std::vector<std::string>& independent,
                                           const std::vector<std::string>& speeds, bool detect_cyclic) {
  LinearizationOptions options;
  options.cyclic = cyclic;
  options.independent = independent;
  options.speeds = speeds;
  options.detect_cyclic = detect_cyclic;
  return options;
}

}  // namespace

void bind_analysis(py::module_& m) {
  m.def(
      "equations",
      [](const ModelSource& source, const py::iterable& overrides, const std::string& format) {
        if (format != "text" && format != "latex")
          throw InputError(fmt::format("equations format '{}': choose text or latex", format));
        return model_equations(source, to_overrides(overrides),
                               format == "latex" ? EquationsFormat::latex : EquationsFormat::text);
      },
      py::arg("source"), py::arg("overrides"), py::arg("format") = "text");
  m.def(
      "linearize",
      [](const ModelPtr& model, const std::vector<std::string>& cyclic, const std::vector<std::string>& independent,
         const std::vector<std::string>& speeds, bool detect_cyclic) {
        const Linearization lin =
            calc_linearization(*model, linearization_options(cyclic, independent, speeds, detect_cyclic));
        py::dict d;
        d["cyclic"] = lin.cyclic;
        d["independent"] = lin.independent;
        d["speeds"] = lin.speeds;
        d["state"] = lin.state;
        d["state_matrix"] = matrix_array(lin.state_matrix);
        d["eigenvalues"] = complex_array(lin.eigenvalues);
        d["derivatives"] = std::string(derivative_method_name(lin.derivatives));
        d["steady_residual"] = lin.steady_residual;
        return d;
      },
      py::arg("model"), py::arg("cyclic") = std::vector<std::string>{},
      py::arg("independent") = std::vector<std::string>{}, py::arg("speeds") = std::vector<std::string>{},
      py::arg("detect_cyclic") = true);
  m.def(
      "sweep",
      [](const ModelSource& source, const py::iterable& overrides, const std::string& parameter, double from, double to,
         int steps, const std::vector<std::string>& cyclic, const std::vector<std::string>& independent,
         const std::vector<std::string>& speeds, bool detect_cyclic, bool find_crossings) {
        SweepOptions options;
        options.parameter = parameter;
        options.from = from;
        options.to = to;
        options.steps = steps;
        options.find_crossings = find_crossings;
        options.linearization = linearization_options(cyclic, independent, speeds, detect_cyclic);
        const Sweep sweep = sweep_model_parameter(source, to_overrides(overrides), options);
        std::vector<double> values;
        std::vector<std::complex<double>> eigenvalues;
        std::size_t width = sweep.points.empty() ? 0 : sweep.points.front().eigenvalues.size();
        for (const SweepPoint& p : sweep.points) {
          values.push_back(p.value);
          if (p.eigenvalues.size() != width) throw InputError("sweep: the number of eigenvalues changed along the sweep");
          eigenvalues.insert(eigenvalues.end(), p.eigenvalues.begin(), p.eigenvalues.end());
        }
        py::array_t<std::complex<double>> eig = complex_array(eigenvalues);
        eig.resize({static_cast<py::ssize_t>(values.size()), static_cast<py::ssize_t>(width)});
        py::list crossings;
        for (const StabilityCrossing& c : sweep.crossings) {
          py::dict d;
          d["value"] = c.value;
          d["oscillatory"] = c.oscillatory;
          d["frequency"] = c.frequency;
          d["unstable_before"] = c.unstable_before;
          d["unstable_after"] = c.unstable_after;
          d["bracket"] = c.bracket;
          crossings.append(d);
        }
        py::dict d;
        d["state"] = sweep.state;
        d["values"] = take_array(std::move(values), {static_cast<py::ssize_t>(sweep.points.size())});
        d["eigenvalues"] = eig;
        d["crossings"] = crossings;
        return d;
      },
      py::arg("source"), py::arg("overrides"), py::arg("parameter"), py::arg("from_"), py::arg("to"), py::arg("steps"),
      py::arg("cyclic") = std::vector<std::string>{}, py::arg("independent") = std::vector<std::string>{},
      py::arg("speeds") = std::vector<std::string>{}, py::arg("detect_cyclic") = true,
      py::arg("find_crossings") = true);
}

}  // namespace nhdyn::python
