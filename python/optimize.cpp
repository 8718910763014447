// nhdyn._nhdyn.optimize: `nhdyn optimize` for Python (docs/python.md, docs/optimize.md). The model
// is loaded again from its source with the overrides (the [optimize] section is read from the
// source's text, against the model as compiled with them), solved as optimize/solve.hpp does for
// the CLI, and returned as a dict: the summary's values, the CSV's columns and rows as one array,
// and the motion split into t, q, qd, qdd, u.
#include <pybind11/stl.h>

#include <string>
#include <utility>
#include <vector>

#include "bindings.hpp"
#include "nhdyn/core/error.hpp"
#include "nhdyn/frontend/optimize_problem.hpp"
#include "nhdyn/optimize/solve.hpp"

namespace nhdyn::python {

void bind_optimize(py::module_& m) {
  m.def(
      "optimize",
      [](const ModelSource& source, const py::iterable& overrides, const std::string& guess, double tolerance,
         int max_iterations) {
        const LoadedModel loaded = load_model_described(source, to_overrides(overrides));
        const OptimalControlProblem problem = load_optimal_control_problem(source, loaded);
        OptimizeOptions options;
        options.nlp.tolerance = tolerance;
        options.nlp.constraint_tolerance = tolerance;
        options.nlp.max_iterations = max_iterations;
        options.guess = guess;
        OptimizeResult result;
        {
          py::gil_scoped_release release;
          result = solve_optimal_control(problem, options);
        }
        if (result.solver.status == NlpStatus::unavailable) throw InputError(result.solver.message);
        const std::vector<std::string> columns = optimize_columns(problem);
        const std::vector<std::vector<double>> rows = optimize_rows(problem, result);
        std::vector<double> table;
        for (const std::vector<double>& row : rows) table.insert(table.end(), row.begin(), row.end());
        const auto P = static_cast<py::ssize_t>(result.points);
        const auto n = static_cast<py::ssize_t>(problem.n()), m_count = static_cast<py::ssize_t>(problem.m());
        py::dict d;
        d["summary_text"] = format_optimize_summary(problem, result);
        d["status"] = std::string(optimize_status_name(result));
        d["solver_message"] = result.solver.message;
        d["converged"] = result.solved();  // IPOPT converged and the replay confirms a motion (solve.hpp)
        d["replay_limit"] = result.replay_limit;
        d["interval_replay"] = result.local_difference;
        d["replay_coordinate"] = result.replay_coordinate;
        d["replay_verdict"] = result.replay_verdict;
        d["iterations"] = result.solver.iterations;
        d["objective"] = result.objective;
        d["t_end"] = result.t_end;
        d["free_time"] = problem.free_time;
        d["constraint_violation"] = result.constraint_violation;
        d["replay_difference"] = result.replayed ? py::object(py::float_(result.replay_difference)) : py::object(py::none());
        d["replay_message"] = result.replay_message;
        d["notes"] = result.notes;
        std::vector<std::string> controls;
        for (const OptimizeControl& c : problem.controls) controls.push_back(c.name);
        d["controls"] = controls;
        d["columns"] = columns;
        d["table"] = take_array(std::move(table), {P, static_cast<py::ssize_t>(columns.size())});
        d["t"] = take_array(std::move(result.times), {P});
        d["q"] = take_array(std::move(result.q), {P, n});
        d["qd"] = take_array(std::move(result.v), {P, n});
        d["qdd"] = take_array(std::move(result.a), {P, n});
        d["u"] = take_array(std::move(result.u), {P, m_count});
        return d;
      },
      py::arg("source"), py::arg("overrides"), py::arg("guess") = "", py::arg("tolerance") = 1e-8,
      py::arg("max_iterations") = 3000,
      "optimize(source, overrides, guess='', tolerance=1e-8, max_iterations=3000) -> dict: the optimal program of "
      "the model file's [optimize] section (direct collocation with IPOPT), as `nhdyn optimize`");
}

}  // namespace nhdyn::python
