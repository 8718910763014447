// nhdyn._nhdyn.simulate_batch: many runs on the C++ thread pool (analysis/batch.hpp) with the GIL
// released, the results stacked into arrays of shape (runs, rows, ...). A run that ended early
// keeps its rows and has NaN after them; its ok flag is False and its message says why.
#include <pybind11/stl.h>

#include <chrono>
#include <limits>

#include "bindings.hpp"
#include "nhdyn/core/error.hpp"

namespace nhdyn::python {
namespace {

// Initial states: None, or an array (runs, n).
std::vector<std::optional<Vector>> initial_states(const py::object& value, const char* key, std::size_t runs, int n) {
  std::vector<std::optional<Vector>> out(runs);
  if (value.is_none()) return out;
  const auto array = py::array_t<double, py::array::c_style | py::array::forcecast>::ensure(value);
  if (!array || array.ndim() != 2 || array.shape(0) != static_cast<py::ssize_t>(runs) || array.shape(1) != n) {
    std::string shape = "not numeric";
    if (array) {
      shape = "(";
      for (py::ssize_t i = 0; i < array.ndim(); ++i) shape += (i ? ", " : "") + std::to_string(array.shape(i));
      shape += array.ndim() == 1 ? ",)" : ")";
    }
    throw InputError(fmt::format("initial {}: expected an array of shape (runs, n) = ({}, {}), got {}", key, runs, n, shape));
  }
  for (std::size_t r = 0; r < runs; ++r) {
    Vector v(n);
    for (int i = 0; i < n; ++i) v(i) = array.at(static_cast<py::ssize_t>(r), i);
    out[r] = v;
  }
  return out;
}

// Stacks one quantity of every run into (runs, rows, width), NaN after a run's last row.
py::array_t<double> stack(const std::vector<BatchResult>& results, std::size_t rows, std::size_t width,
                          const std::vector<double> Trajectory::*column) {
  std::vector<double> out(results.size() * rows * width, std::numeric_limits<double>::quiet_NaN());
  for (std::size_t r = 0; r < results.size(); ++r) {
    const std::vector<double>& values = results[r].trajectory.*column;
    std::copy(values.begin(), values.begin() + static_cast<std::ptrdiff_t>(std::min(values.size(), rows * width)),
              out.begin() + static_cast<std::ptrdiff_t>(r * rows * width));
  }
  if (width == 1)
    return take_array(std::move(out), {static_cast<py::ssize_t>(results.size()), static_cast<py::ssize_t>(rows)});
  return take_array(std::move(out), {static_cast<py::ssize_t>(results.size()), static_cast<py::ssize_t>(rows),
                                     static_cast<py::ssize_t>(width)});
}

}  // namespace

void bind_batch(py::module_& m) {
  m.def(
      "simulate_batch",
      [](const std::vector<ModelPtr>& models, const py::object& q0, const py::object& v0, int threads,
         bool keep_trajectories, const py::kwargs& kwargs) {
        if (models.empty()) throw InputError("simulate_batch: no runs (give at least one parameter value or initial state)");
        const int n = models.front()->n();
        for (const ModelPtr& model : models)
          if (!model || model->n() != n) throw InputError("simulate_batch: every run needs a model with the same coordinates");
        if (threads < 0) throw InputError(fmt::format("threads = {}: give 0 (every core) or a positive number", threads));
        BatchOptions options;
        options.simulation = make_options(*models.front(), kwargs);
        options.threads = threads;
        options.keep_trajectories = keep_trajectories;
        const std::vector<std::optional<Vector>> q = initial_states(q0, "q", models.size(), n);
        const std::vector<std::optional<Vector>> v = initial_states(v0, "qd", models.size(), n);
        std::vector<BatchRun> runs(models.size());
        for (std::size_t i = 0; i < runs.size(); ++i) runs[i] = BatchRun{models[i], q[i], v[i]};
        std::vector<BatchResult> results;
        double seconds = 0.0;
        {
          py::gil_scoped_release release;
          const auto start = std::chrono::steady_clock::now();
          results = simulate_batch(runs, options);
          seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
        }
        std::size_t longest = 0;
        std::size_t best = 0;
        for (std::size_t r = 0; r < results.size(); ++r)
          if (results[r].trajectory.t.size() > longest) {
            longest = results[r].trajectory.t.size();
            best = r;
          }
        const Trajectory& shape = results[best].trajectory;
        const auto un = static_cast<std::size_t>(n);
        py::dict out;
        out["t"] = take_array(std::vector<double>(shape.t), {static_cast<py::ssize_t>(longest)});
        out["q"] = stack(results, longest, un, &Trajectory::q);
        out["qd"] = stack(results, longest, un, &Trajectory::v);
        out["qdd"] = stack(results, longest, un, &Trajectory::qdd);
        out["R"] = stack(results, longest, un, &Trajectory::R);
        out["residuals"] = stack(results, longest, static_cast<std::size_t>(models.front()->position_constraints() +
                                                                             models.front()->velocity_constraints() +
                                                                             models.front()->s()),
                                 &Trajectory::residuals);
        out["energy"] = models.front()->evaluator->has_energy() ? py::object(stack(results, longest, 1, &Trajectory::energy))
                                                                : py::object(py::none());
        std::vector<double> q_end(results.size() * un, std::numeric_limits<double>::quiet_NaN());
        std::vector<double> v_end(results.size() * un, std::numeric_limits<double>::quiet_NaN());
        std::vector<double> max_residual(results.size(), std::numeric_limits<double>::quiet_NaN());
        py::list ok, messages, summaries;
        for (std::size_t r = 0; r < results.size(); ++r) {
          const BatchResult& res = results[r];
          if (res.q_end.size() == n) {
            std::copy(res.q_end.data(), res.q_end.data() + n, q_end.begin() + static_cast<std::ptrdiff_t>(r * un));
            std::copy(res.v_end.data(), res.v_end.data() + n, v_end.begin() + static_cast<std::ptrdiff_t>(r * un));
            max_residual[r] = std::max({res.summary.max_position_residual, res.summary.max_velocity_residual,
                                        res.summary.max_acceleration_residual});
          }
          ok.append(res.ok);
          messages.append(res.message);
          summaries.append(summary_dict(res.summary));
        }
        out["q_end"] = take_array(std::move(q_end), {static_cast<py::ssize_t>(results.size()), n});
        out["qd_end"] = take_array(std::move(v_end), {static_cast<py::ssize_t>(results.size()), n});
        out["max_residual"] = take_array(std::move(max_residual), {static_cast<py::ssize_t>(results.size())});
        out["ok"] = ok;
        out["messages"] = messages;
        out["summaries"] = summaries;
        out["threads"] = batch_threads(threads, results.size());
        out["cpp_seconds"] = seconds;
        return out;
      },
      py::arg("models"), py::arg("q0") = py::none(), py::arg("v0") = py::none(), py::arg("threads") = 0,
      py::arg("keep_trajectories") = true);
}

}  // namespace nhdyn::python
