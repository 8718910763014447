// nhdyn._nhdyn.simulate_batch: many runs on the C++ thread pool (analysis/batch.hpp) with the GIL
// released, the results stacked into arrays of shape (runs, rows, ...). A run that ended early
// keeps its rows and has NaN after them; its ok flag is False and its message says why.
#include <pybind11/stl.h>

#include <chrono>
#include <cmath>
#include <limits>

#include "bindings.hpp"
#include "nhdyn/core/error.hpp"
#include "nhdyn/io/results.hpp"
#include "nhdyn/model/data.hpp"

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

// Stacks one quantity of every run into (runs, rows, width), NaN after a run's last row; a
// quantity with one value per row (`per_row`: t, energy) into (runs, rows). A model with one
// coordinate still gets (runs, rows, 1) for q: the shape does not depend on n.
py::array_t<double> stack(const std::vector<BatchResult>& results, std::size_t rows, std::size_t width,
                          const std::vector<double> Trajectory::*column, bool per_row = false) {
  std::vector<double> out(results.size() * rows * width, std::numeric_limits<double>::quiet_NaN());
  for (std::size_t r = 0; r < results.size(); ++r) {
    const std::vector<double>& values = results[r].trajectory.*column;
    std::copy(values.begin(), values.begin() + static_cast<std::ptrdiff_t>(std::min(values.size(), rows * width)),
              out.begin() + static_cast<std::ptrdiff_t>(r * rows * width));
  }
  if (per_row)
    return take_array(std::move(out), {static_cast<py::ssize_t>(results.size()), static_cast<py::ssize_t>(rows)});
  return take_array(std::move(out), {static_cast<py::ssize_t>(results.size()), static_cast<py::ssize_t>(rows),
                                     static_cast<py::ssize_t>(width)});
}

// threads=: an int (not a bool, a float or a string), brought within what a C int holds.
int thread_count(const py::object& value) {
  if (!py::isinstance<py::int_>(value) || py::isinstance<py::bool_>(value))
    throw InputError(fmt::format("threads = {}: give a whole number (0: every core)", std::string(py::repr(value))));
  const auto big = value.cast<py::int_>();
  // A negative count is refused by simulate_batch (check_batch_threads), in the library's words.
  if (big < py::int_(0)) return big < py::int_(-(1 << 20)) ? -(1 << 20) : big.cast<int>();
  if (big > py::int_(1 << 20)) return 1 << 20;  // capped by batch_threads anyway
  return big.cast<int>();
}

// The batch's results are held whole, each run's rows then the stacked arrays: refused before any
// run when they would not fit in this machine's memory (the runs went on until the system ended
// Python). The rows are the output times (the events' rows apart), each of the CSV's columns.
void check_batch_memory(const Model& model, const SimulationOptions& options, std::size_t runs) {
  const double rows = options.output_times.empty()
                          ? std::floor((options.t_end - model.t0) / options.output_step) + 2.0
                          : static_cast<double>(options.output_times.size());
  const double columns = static_cast<double>(make_result_columns(model).all.size());
  const double needed = 2.0 * 8.0 * static_cast<double>(runs) * rows * columns;
  const double available = physical_memory_bytes();
  if (available > 0.0 && needed > available)
    throw InputError(fmt::format("simulate_batch: {} runs of {:.0f} rows of {:.0f} values need about {:.3g} GB held at "
                                 "once, more than this machine's {:.3g} GB; give fewer runs or a larger output_step, or "
                                 "run them with the command `nhdyn batch`, which writes each run's rows as it ends",
                                 runs, rows, columns, needed / 1e9, available / 1e9));
}

}  // namespace

void bind_batch(py::module_& m) {
  // The batch's stop conditions that never held, each once with its runs (as `nhdyn batch` warns).
  m.def("format_batch_unmet_stops", &format_batch_unmet_stops, py::arg("unmet_stops"));
  m.def(
      "simulate_batch",
      [](const std::vector<ModelPtr>& models, const py::object& q0, const py::object& v0, const py::object& threads_arg,
         bool keep_trajectories, const py::kwargs& kwargs) {
        const int threads = thread_count(threads_arg);
        check_batch_threads(threads);  // before any work, in the library's words
        if (models.empty()) throw InputError("simulate_batch: no runs (give at least one parameter value or initial state)");
        const int n = models.front()->n();
        for (const ModelPtr& model : models)
          if (!model || model->n() != n) throw InputError("simulate_batch: every run needs a model with the same coordinates");
        BatchOptions options;
        options.simulation = make_options(*models.front(), kwargs);
        options.threads = threads;
        options.keep_trajectories = keep_trajectories;
        if (keep_trajectories) check_batch_memory(*models.front(), options.simulation, models.size());
        const std::vector<std::optional<Vector>> q = initial_states(q0, "q", models.size(), n);
        const std::vector<std::optional<Vector>> v = initial_states(v0, "qd", models.size(), n);
        std::vector<BatchRun> runs(models.size());
        for (std::size_t i = 0; i < runs.size(); ++i) runs[i] = BatchRun{models[i], q[i], v[i]};
        std::vector<BatchResult> results;
        double seconds = 0.0;
        // Ctrl-C: the calling thread polls Python's signals between the workers' runs and stops
        // the batch (the running runs finish), then KeyboardInterrupt is raised.
        bool interrupted = false;
        options.keep_going = [&interrupted] {
          py::gil_scoped_acquire acquire;
          if (PyErr_CheckSignals() == 0) return true;
          interrupted = true;
          return false;
        };
        {
          py::gil_scoped_release release;
          const auto start = std::chrono::steady_clock::now();
          results = simulate_batch(runs, options);
          seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
        }
        if (interrupted) throw py::error_already_set();
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
        // One time vector when every run has the same times (each run's rows a prefix of the
        // longest's); with events or a stop condition the runs' rows differ, and t is per run.
        bool shared_times = true;
        for (const BatchResult& res : results)
          if (!std::equal(res.trajectory.t.begin(), res.trajectory.t.end(), shape.t.begin())) shared_times = false;
        out["t"] = shared_times ? take_array(std::vector<double>(shape.t), {static_cast<py::ssize_t>(longest)})
                                : stack(results, longest, 1, &Trajectory::t, true);
        out["q"] = stack(results, longest, un, &Trajectory::q);
        out["qd"] = stack(results, longest, un, &Trajectory::v);
        out["qdd"] = stack(results, longest, un, &Trajectory::qdd);
        out["R"] = stack(results, longest, un, &Trajectory::R);
        out["residuals"] = stack(results, longest, static_cast<std::size_t>(models.front()->position_constraints() +
                                                                             models.front()->velocity_constraints() +
                                                                             models.front()->s()),
                                 &Trajectory::residuals);
        // A multibody model's contact forces and, for contacts with modes, NAME_mode, the slip,
        // NAME_gap and work_friction (columns["contact_forces"], as in one run's Result).
        const int contact_columns = shape.contact_columns;
        out["contact_forces"] = contact_columns > 0
                                    ? py::object(stack(results, longest, static_cast<std::size_t>(contact_columns),
                                                       &Trajectory::contact_forces))
                                    : py::object(py::none());
        out["energy"] = models.front()->evaluator->has_energy() ? py::object(stack(results, longest, 1, &Trajectory::energy, true))
                                                                : py::object(py::none());
        std::vector<double> q_end(results.size() * un, std::numeric_limits<double>::quiet_NaN());
        std::vector<double> v_end(results.size() * un, std::numeric_limits<double>::quiet_NaN());
        std::vector<double> max_residual(results.size(), std::numeric_limits<double>::quiet_NaN());
        py::list ok, messages, summaries, events;
        for (std::size_t r = 0; r < results.size(); ++r) {
          const BatchResult& res = results[r];
          if (res.q_end.size() == n) {
            std::copy(res.q_end.data(), res.q_end.data() + n, q_end.begin() + static_cast<std::ptrdiff_t>(r * un));
            std::copy(res.v_end.data(), res.v_end.data() + n, v_end.begin() + static_cast<std::ptrdiff_t>(r * un));
            max_residual[r] = std::max({res.summary.residuals.position, res.summary.residuals.velocity,
                                        res.summary.residuals.acceleration});
          }
          ok.append(res.ok);
          messages.append(res.message);
          py::list run_events;
          for (const EventRecord& e : res.summary.events.crossings) {
            py::dict event;
            event["name"] = e.name;
            event["t"] = e.t;
            event["q"] = py::array_t<double>(static_cast<py::ssize_t>(e.q.size()), e.q.data());
            event["qd"] = py::array_t<double>(static_cast<py::ssize_t>(e.v.size()), e.v.data());
            run_events.append(event);
          }
          events.append(run_events);
          summaries.append(summary_dict(res.summary));
        }
        out["q_end"] = take_array(std::move(q_end), {static_cast<py::ssize_t>(results.size()), n});
        out["qd_end"] = take_array(std::move(v_end), {static_cast<py::ssize_t>(results.size()), n});
        out["max_residual"] = take_array(std::move(max_residual), {static_cast<py::ssize_t>(results.size())});
        out["ok"] = ok;
        out["messages"] = messages;
        out["summaries"] = summaries;
        out["events"] = events;
        out["threads"] = batch_threads(threads, results.size());
        out["cpp_seconds"] = seconds;
        return out;
      },
      py::arg("models"), py::arg("q0") = py::none(), py::arg("v0") = py::none(), py::arg("threads") = 0,
      py::arg("keep_trajectories") = true);
}

}  // namespace nhdyn::python
