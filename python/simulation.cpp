// nhdyn._nhdyn.simulate: one run of a Model with the model's run options and the caller's
// overrides; the outputs come back as NumPy arrays that take over the C++ vectors (no copy).
// The GIL is released during the run.
#include <pybind11/stl.h>

#include <chrono>
#include <map>
#include <string>
#include <type_traits>
#include <vector>

#include "bindings.hpp"
#include "nhdyn/analysis/batch.hpp"
#include "nhdyn/analysis/run_options.hpp"
#include "nhdyn/core/error.hpp"
#include "nhdyn/core/shown_text.hpp"
#include "nhdyn/frontend/events.hpp"

namespace nhdyn::python {
namespace {

template <typename T>
std::optional<T> get(const py::dict& kwargs, const char* key) {
  if (!kwargs.contains(key)) return std::nullopt;
  const py::object value = kwargs[key];
  if (value.is_none()) return std::nullopt;
  // A bool is an int to Python, and would run t_end=True as 1 s: only a flag takes one.
  if constexpr (!std::is_same_v<T, bool>)
    if (py::isinstance<py::bool_>(value))
      throw InputError(fmt::format("{}={}: give a number, not a bool", key, py::repr(value).cast<std::string>()));
  try {
    return value.cast<T>();
  } catch (const py::cast_error&) {
    throw InputError(fmt::format("{}={}: wrong type", key, py::repr(value).cast<std::string>()));
  }
}

const char* const known_options[] = {"t_end",     "output_step", "method",    "complement",
                                     "integrator", "rtol",        "atol",      "step",
                                     "fix_initial", "stabilize",  "q0",        "v0",
                                     "stop_when",  "events",      "max_steps", "program_feedback",
                                     "t_eval"};

// A string or a sequence of strings.
std::vector<std::string> strings(const py::dict& kwargs, const char* key) {
  if (!kwargs.contains(key) || py::object(kwargs[key]).is_none()) return {};
  const py::object value = kwargs[key];
  if (py::isinstance<py::str>(value)) return {value.cast<std::string>()};
  try {
    return value.cast<std::vector<std::string>>();
  } catch (const py::cast_error&) {
    throw InputError(fmt::format("{}={}: expected a string or a list of strings", key, py::repr(value).cast<std::string>()));
  }
}

}  // namespace

SimulationOptions make_options(const Model& model, const py::dict& kwargs) {
  for (const auto& item : kwargs) {
    const auto key = item.first.cast<std::string>();
    bool known = false;
    for (const char* name : known_options) known = known || key == name;
    if (!known)
      throw InputError(fmt::format("simulate: unknown option '{}'; the options are t_end, output_step, method, complement, "
                                   "integrator, rtol, atol, step, fix_initial, stabilize, q0, v0, stop_when, events, "
                                   "max_steps, program_feedback, t_eval",
                                   key));
  }
  RunOptions run = model.defaults;
  // t_eval: the output times (nhdyn/__init__.py has checked them: 1-D, finite, increasing); the
  // run ends at the last one unless t_end says otherwise.
  std::vector<double> t_eval;
  if (kwargs.contains("t_eval") && !py::object(kwargs["t_eval"]).is_none()) {
    try {
      t_eval = py::object(kwargs["t_eval"]).cast<std::vector<double>>();
    } catch (const py::cast_error&) {
      throw InputError("t_eval: expected a 1-D array of times");
    }
    if (t_eval.empty()) throw InputError("t_eval: give at least one time");
    run.t_end = t_eval.back();
  }
  run.t_end = get<double>(kwargs, "t_end").value_or(run.t_end);
  run.output_step = get<double>(kwargs, "output_step").value_or(run.output_step);
  run.method = get<std::string>(kwargs, "method").value_or(run.method);
  run.complement = get<std::string>(kwargs, "complement").value_or(run.complement);
  run.integrator = get<std::string>(kwargs, "integrator").value_or(run.integrator);
  run.rtol = get<double>(kwargs, "rtol").value_or(run.rtol);
  run.atol = get<double>(kwargs, "atol").value_or(run.atol);
  SimulationOptions options = make_simulation_options(run);
  options.output_times = std::move(t_eval);
  options.integrator.step = get<double>(kwargs, "step").value_or(0.0);
  options.fix_initial = get<bool>(kwargs, "fix_initial").value_or(false);
  options.stabilization = parse_stabilization(get<std::string>(kwargs, "stabilize").value_or("none"));
  // Checked with the other options by check_simulation_options below.
  if (const std::optional<long> max_steps = get<long>(kwargs, "max_steps")) options.integrator.max_steps = *max_steps;
  // program_feedback=(alpha, beta): the PD feedback of program motion (docs/derivations/program-motion.md
  // section 5), as --program-feedback alpha,beta.
  if (kwargs.contains("program_feedback") && !py::object(kwargs["program_feedback"]).is_none()) {
    const py::object value = kwargs["program_feedback"];
    std::vector<double> gains;
    try {
      gains = value.cast<std::vector<double>>();
    } catch (const py::cast_error&) {
      gains.clear();
    }
    if (gains.size() != 2)
      throw InputError(fmt::format("program_feedback={}: give two rates in 1/s as (alpha, beta), e.g. "
                                   "program_feedback=(10, 10)",
                                   py::repr(value).cast<std::string>()));
    options.formulation.program_feedback = {true, gains[0], gains[1]};
  }
  // The model's [[events]], then stop_when="abs(phi) > 1" (conditions) and events={"name": "expr"}.
  options.events = model.events;
  for (const std::string& condition : strings(kwargs, "stop_when"))
    options.events.push_back(make_stop_condition(model, condition));
  if (kwargs.contains("events") && !py::object(kwargs["events"]).is_none()) {
    std::map<std::string, std::string> events;
    try {
      events = py::object(kwargs["events"]).cast<std::map<std::string, std::string>>();
    } catch (const py::cast_error&) {
      throw InputError("events: expected a dict of names to expressions, e.g. events={\"bottom\": \"x\"}");
    }
    for (const auto& [name, expression] : events)
      options.events.push_back(make_record_event(model, name + "=" + expression));
  }
  check_simulation_options(model, options);
  return options;
}

namespace {

std::optional<Vector> state_vector(const py::dict& kwargs, const char* key, int n) {
  if (!kwargs.contains(key) || py::object(kwargs[key]).is_none()) return std::nullopt;
  const auto array = py::array_t<double, py::array::c_style | py::array::forcecast>::ensure(kwargs[key]);
  if (!array || array.ndim() != 1 || array.shape(0) != n)
    throw InputError(fmt::format("{}: expected {} values (one per coordinate), got an array of shape {}", key, n,
                                 array ? py::str(py::cast(std::vector<py::ssize_t>(array.shape(), array.shape() + array.ndim()))).cast<std::string>()
                                       : std::string("(not numeric)")));
  Vector v(n);
  for (int i = 0; i < n; ++i) v(i) = array.at(i);
  return v;
}

}  // namespace

namespace {

// The summary dict, group by group (analysis/simulation_summary.hpp); the keys are the package's
// interface (tests/python) and keep their order.

void add_run(py::dict& d, const SimulationSummary& s) {
  d["status"] = std::string(describe(s.status));
  d["message"] = shown_text(s.message, true);  // as the CLI shows it (core/shown_text.hpp)
  d["t_reached"] = s.t_reached;
  d["steps"] = s.stats.steps;
  d["rejected_steps"] = s.stats.rejected_steps;
  d["rhs_evaluations"] = s.stats.rhs_evaluations;
  d["stiff_steps"] = s.stats.stiff_steps;  // IntegratorStats: held by stability (dopri5, dop853)
  d["outputs"] = s.outputs;
  d["wall_time"] = s.wall_time;
}

void add_residuals(py::dict& d, const ResidualMaxima& r, const char* prefix) {
  d[py::str(fmt::format("max_{}position_residual", prefix))] = r.position;
  d[py::str(fmt::format("max_{}velocity_residual", prefix))] = r.velocity;
  d[py::str(fmt::format("max_{}acceleration_residual", prefix))] = r.acceleration;
}

// The constraint watch (analysis/constraint_watch.hpp): the run's warnings in words, and each
// watch warning's constraint, measure, time and factor; the Python package raises them as
// ConstraintWarning.
void add_watch_warnings(py::dict& d, const SimulationSummary& s) {
  py::list warnings;
  for (const std::string& w : s.warnings) warnings.append(w);
  d["warnings"] = warnings;
  d["stiffness"] = s.stiffness;  // raised as nhdyn.StiffnessWarning
  py::list watch;
  for (const ConstraintWarning& w : s.watch.warnings) {
    py::dict item;
    item["constraint"] = w.constraint;
    item["measure"] = w.measure == WatchMeasure::row_norm ? "row_norm" : "conditioning";
    item["t"] = w.t;
    item["initial"] = w.initial;
    item["value"] = w.value;
    item["factor"] = w.factor;
    watch.append(item);
  }
  d["constraint_warnings"] = watch;
}

// fix_initial=True: where the initial state was moved, and by how much (coordinate order).
py::object initial_fix_dict(const std::optional<InitialFix>& initial_fix) {
  if (!initial_fix) return py::none();
  py::dict fix;
  const auto array = [](const Vector& v) {
    return take_array(std::vector<double>(v.data(), v.data() + v.size()), {v.size()});
  };
  fix["q"] = array(initial_fix->q);
  fix["qd"] = array(initial_fix->v);
  fix["dq"] = array(initial_fix->dq);
  fix["dqd"] = array(initial_fix->dv);
  return fix;
}

// docs/derivations/energy-balance.md: the balance error (accuracy), the work by agent and the
// change of E (physics).
void add_energy_balance(py::dict& d, const EnergySummary& e) {
  if (!e.has_balance) return;
  d["energy_balance_error"] = e.balance_error;
  d["work_forces"] = e.work_forces;
  d["work_reactions"] = e.work_reactions;
  d["work_time"] = e.work_time;
  d["energy_change"] = e.change;
}

}  // namespace

py::dict summary_dict(const SimulationSummary& s) {
  py::dict d;
  add_run(d, s);
  add_residuals(d, s.residuals, "");
  d["energy_drift"] = s.energy.has_energy ? py::cast(s.energy.drift) : py::none();
  add_residuals(d, s.program, "program_");
  add_watch_warnings(d, s);
  // A stop condition that never held on a run that reached its end: simulate's sentences
  // (analysis/simulation.hpp); the Python package raises them as StopConditionWarning.
  d["unmet_stops"] = s.events.unmet_stops;
  d["largest_row_factor"] = s.watch.largest_row_factor;
  d["largest_condition_factor"] = s.watch.largest_condition_factor;
  const EventSummary& events = s.events;
  d["stopped_by"] =
      events.stopped_by >= 0 ? py::cast(events.names[static_cast<std::size_t>(events.stopped_by)]) : py::none();
  d["initial_fix"] = initial_fix_dict(s.initial_fix);
  add_energy_balance(d, s.energy);
  return d;
}

py::dict trajectory_dict(Trajectory&& tr) {
  const py::ssize_t rows = tr.rows();
  const py::ssize_t n = tr.n;
  py::dict d;
  d["t"] = take_array(std::move(tr.t), {rows});
  d["q"] = take_array(std::move(tr.q), {rows, n});
  d["qd"] = take_array(std::move(tr.v), {rows, n});
  d["qdd"] = take_array(std::move(tr.qdd), {rows, n});
  d["R"] = take_array(std::move(tr.R), {rows, n});
  d["residuals"] = take_array(std::move(tr.residuals), {rows, static_cast<py::ssize_t>(tr.residual_columns)});
  d["energy"] = tr.has_energy ? py::object(take_array(std::move(tr.energy), {rows})) : py::object(py::none());
  const auto b = static_cast<py::ssize_t>(tr.balance_columns);
  d["energy_balance"] = b > 0 ? py::object(take_array(std::move(tr.balance), {rows, b})) : py::object(py::none());
  // Program motion: the actuator forces and the programs' residuals (rows x 0 without programs).
  d["u"] = take_array(std::move(tr.u), {rows, static_cast<py::ssize_t>(tr.actuator_columns)});
  d["program_residuals"] =
      take_array(std::move(tr.program_residuals), {rows, static_cast<py::ssize_t>(tr.program_residual_columns)});
  // The contact forces of a multibody model, columns as model.columns["contact_forces"].
  const auto c = static_cast<py::ssize_t>(tr.contact_columns);
  d["contact_forces"] =
      c > 0 ? py::object(take_array(std::move(tr.contact_forces), {rows, c})) : py::object(py::none());
  // The derived outputs ([outputs], multibody points), rows x count in Model::outputs order.
  d["outputs"] = take_array(std::move(tr.outputs), {rows, static_cast<py::ssize_t>(tr.output_columns)});
  return d;
}

void bind_simulation(py::module_& m) {
  m.def(
      "simulate",
      [](const ModelPtr& model_ptr, const py::kwargs& kwargs) {
        const Model* model = model_ptr.get();
        std::optional<Model> changed;
        const std::optional<Vector> q0 = state_vector(kwargs, "q0", model->n());
        const std::optional<Vector> v0 = state_vector(kwargs, "v0", model->n());
        if (q0 || v0) {
          changed = *model;
          if (q0) changed->q0 = *q0;
          if (v0) changed->v0 = *v0;
          model = &*changed;
        }
        const SimulationOptions options = make_options(*model, kwargs);
        Trajectory trajectory;
        SimulationSummary summary;
        double seconds = 0.0;
        {
          py::gil_scoped_release release;
          const auto start = std::chrono::steady_clock::now();
          const std::size_t rows = options.output_times.empty()
                                       ? make_output_times(model->t0, options.t_end, options.output_step).size()
                                       : options.output_times.size();
          trajectory.reset(*model, static_cast<long>(rows));
          summary = simulate(*model, options, [&](const Data& data) { trajectory.append(data); });
          seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
        }
        py::dict out = trajectory_dict(std::move(trajectory));
        out["summary"] = summary_dict(summary);
        // The located crossings, in time order: name, t, q, qd at each.
        py::list events;
        for (const EventRecord& e : summary.events.crossings) {
          py::dict event;
          event["name"] = e.name;
          event["t"] = e.t;
          event["q"] = py::array_t<double>(static_cast<py::ssize_t>(e.q.size()), e.q.data());
          event["qd"] = py::array_t<double>(static_cast<py::ssize_t>(e.v.size()), e.v.data());
          events.append(event);
        }
        out["events"] = events;
        out["ok"] = summary.status == Status::ok;
        out["cpp_seconds"] = seconds;  // the whole C++ call, for the overhead benchmark
        return out;
      },
      "simulate(model, **options) -> dict of arrays (t, q, qd, qdd, R, residuals, energy, u, program_residuals) "
      "and summary");
}

}  // namespace nhdyn::python
