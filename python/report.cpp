// nhdyn._nhdyn.provenance, write_report and write_file: a Python run's provenance header
// (io/provenance.hpp), the same lines `nhdyn simulate` writes into its CSV; the HTML report of a
// Python Result (io/report.hpp), the page `nhdyn simulate --html` writes, with that provenance at
// its top; and a text written by the command line's rules (io/atomic_file.hpp).
#include <pybind11/stl.h>

#include <string>
#include <vector>

#include "bindings.hpp"
#include "nhdyn/core/error.hpp"
#include "nhdyn/frontend/provenance.hpp"
#include "nhdyn/io/atomic_file.hpp"
#include "nhdyn/io/csv.hpp"
#include "nhdyn/io/report.hpp"

namespace nhdyn::python {

void bind_report(py::module_& m) {
  m.def(
      "provenance",
      [](const ModelPtr& model_ptr, const ModelSource& source, const py::kwargs& kwargs) {
        Model model = *model_ptr;
        // q0 and v0 as simulate takes them (already checked by the run this describes).
        for (const char* key : {"q0", "v0"}) {
          if (!kwargs.contains(key) || py::object(kwargs[key]).is_none()) continue;
          const auto values = py::object(kwargs[key]).cast<std::vector<double>>();
          Vector& target = std::string(key) == "q0" ? model.q0 : model.v0;
          for (std::size_t i = 0; i < values.size() && i < static_cast<std::size_t>(target.size()); ++i)
            target(static_cast<Eigen::Index>(i)) = values[i];
        }
        py::dict options(kwargs);
        if (options.contains("q0")) PyDict_DelItemString(options.ptr(), "q0");
        if (options.contains("v0")) PyDict_DelItemString(options.ptr(), "v0");
        return format_provenance(make_provenance(model, source, make_options(model, options), "interpreted"));
      },
      py::arg("model"), py::arg("source"),
      "provenance(model, source, **simulate options) -> the provenance header of that run ('# key: value' lines)");
  m.def(
      "write_report",
      [](const ModelSource& source, const py::iterable& overrides, const std::vector<std::string>& names,
         const py::array_t<double, py::array::c_style | py::array::forcecast>& rows,
         const std::vector<std::string>& comments, const std::string& path, const std::string& title,
         const std::vector<std::pair<std::string, std::string>>& extra, int max_frames) {
        if (rows.ndim() != 2 || rows.shape(1) != static_cast<py::ssize_t>(names.size()))
          throw InputError(fmt::format("report: expected rows x {} values, got {} dimensions", names.size(),
                                       rows.ndim()));
        ReportOptions options;
        options.max_frames = max_frames;
        check_report_options(options);  // before the model is loaded, in the library's words
        const LoadedModel loaded = load_model_described(source, to_overrides(overrides));
        CsvTable table;
        table.header = names;
        table.comments = comments;
        table.rows.resize(static_cast<std::size_t>(rows.shape(0)));
        for (py::ssize_t i = 0; i < rows.shape(0); ++i)
          table.rows[static_cast<std::size_t>(i)].assign(rows.data(i, 0), rows.data(i, 0) + rows.shape(1));
        py::gil_scoped_release release;
        return write_model_report(loaded.model, loaded.description.get(), table, title, extra, path, options);
      },
      py::arg("source"), py::arg("overrides"), py::arg("names"), py::arg("rows"), py::arg("comments"),
      py::arg("path"), py::arg("title"), py::arg("extra") = std::vector<std::pair<std::string, std::string>>{},
      py::arg("max_frames") = ReportOptions{}.max_frames,
      "write_report(source, overrides, names, rows, comments, path, title, extra) -> the page's notice; extra: "
      "(label, value) pairs shown first in the summary");
  // The tables of Result.to_csv and Optimum.to_csv: whole or not at all, a device or pipe written
  // straight, a symbolic link written through, a replaced file's mode kept, a full disk a FileError.
  m.def(
      "write_file",
      [](const std::string& path, const std::string& text) {
        py::gil_scoped_release release;
        AtomicFile file(path);
        file.write(text);
        file.commit();
      },
      py::arg("path"), py::arg("text"), "write_file(path, text): text written whole to path, as the CLI writes");
}

}  // namespace nhdyn::python
