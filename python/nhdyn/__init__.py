"""nhdyn in Python: load a constrained mechanical system, simulate it, look at its equations,
linearize it, sweep a parameter and run batches on every core.

    import nhdyn
    m = nhdyn.load("examples/sled.toml")          # a model file, a built-in name, or nhdyn.loads(text)
    m.parameters["m"] = 2.0                       # no recompilation
    r = m.simulate(t_end=5, rtol=1e-10)           # Result: NumPy arrays r.t, r.q, r.qd, ...
    r.to_pandas()                                 # a DataFrame with the CSV's column names

The numbers come from the C++ library (nhdyn._nhdyn); its errors arrive as nhdyn.Error (and the
subclasses InputError, ModelError, FileError) with the library's message (file:line: ...).
See docs/python.md.
"""

import os
import sys
import sysconfig
import warnings
from collections.abc import MutableMapping

from . import _build_info


def _wrong_interpreter(reason):
    """The ImportError for an interpreter other than the one nhdyn was built for: which one it was
    built for, which one this is, and the two ways out."""
    here = "Python {}.{} ({}, extension suffix {})".format(
        sys.version_info[0], sys.version_info[1], sys.executable, sysconfig.get_config_var("EXT_SUFFIX"))
    return ImportError(
        "nhdyn {v} was built for Python {bv} ({bexe}, extension suffix {bs}) but is imported by {here}: {reason}. "
        "Run it with {bexe} (or a venv made from it with --system-site-packages), or build nhdyn for this "
        "interpreter (pip install . with it, or cmake -DPYTHON_EXECUTABLE={exe}); docs/python.md".format(
            v=_build_info.version, bv=_build_info.python_version, bexe=_build_info.python_executable,
            bs=_build_info.extension_suffix, here=here, reason=reason, exe=sys.executable))


def _is_built_for_interpreter():
    """This is the very interpreter nhdyn was built for (not a venv or a pyenv beside it)."""
    built = os.path.realpath(_build_info.python_executable)
    return os.path.realpath(sys.executable) == built and sys.prefix == sys.base_prefix


if sysconfig.get_config_var("EXT_SUFFIX") != _build_info.extension_suffix:
    raise _wrong_interpreter("its compiled module nhdyn/_nhdyn{} cannot be loaded by this interpreter".format(
        _build_info.extension_suffix))
try:
    import numpy as np

    from . import _nhdyn
except ImportError as error:
    if _is_built_for_interpreter():
        raise
    # The same ABI but another installation (a pyenv or a venv without the system's packages):
    # the missing piece is usually NumPy, which Debian installs for its own interpreter only.
    raise _wrong_interpreter(str(error)) from error
from ._nhdyn import Error, FileError, InputError, ModelError, SimulationError

__version__ = _nhdyn.__version__

__all__ = [
    "__version__", "Error", "InputError", "ModelError", "FileError", "SimulationError", "ConstraintWarning",
    "load", "loads", "builtin_models", "Model", "Result", "Equations", "Linearization", "Sweep",
    "BatchResult", "simulate_batch",
]


class ConstraintWarning(UserWarning):
    """A constraint whose row of b, or the conditioning of the stacked matrix [D A; b], degraded
    by three orders of magnitude during a run (a form singular along the path, such as
    y' - tan(phi) x' at phi = pi/2): the motion past that time may be wrong. The library's
    constraint watch (docs/cli.md, "Warnings"); Result.summary["constraint_warnings"] has the
    numbers. Filter with warnings.simplefilter("error", nhdyn.ConstraintWarning) to make it fatal."""


def _warn_constraints(model_name, summary, stacklevel, run=None):
    where = "" if run is None else " (run {})".format(run)
    for text in summary.get("warnings", []):
        warnings.warn("nhdyn: {}{}: {}".format(model_name, where, text), ConstraintWarning, stacklevel=stacklevel + 1)


def builtin_models():
    """The built-in models as a dict name -> description (what `nhdyn list` shows)."""
    return dict(_nhdyn.builtin_models())


def load(source, **parameters):
    """A model from a model file's path or a built-in model's name; keyword arguments override
    the file's parameters (numbers, or the text of one)."""
    return Model(_nhdyn.read_source(str(source)), parameters)


def loads(text, file_name="<string>", **parameters):
    """A model from the text of a model file; `file_name` appears in error messages."""
    return Model(_nhdyn.source_from_text(text, file_name), parameters)


class Parameters(MutableMapping):
    """The parameters of a model by name. Setting one (a number, or an expression in the others such
    as "2*m") changes the value in place, without recompiling: the model then computes what a model
    loaded with that value computes.
    Unknown names raise nhdyn.InputError naming the nearest parameter."""

    def __init__(self, model):
        self._model = model

    def __getitem__(self, name):
        for key, value in self._model._compiled().parameters:
            if key == name:
                return value
        raise KeyError(name)

    def __setitem__(self, name, value):
        self._model._set_parameters({name: value})

    def __delitem__(self, name):
        raise TypeError("a model's parameters cannot be deleted; set another value")

    def __iter__(self):
        return iter([key for key, _ in self._model._compiled().parameters])

    def __len__(self):
        return len(self._model._compiled().parameters)

    def __repr__(self):
        return repr(dict(self.items()))


class Model:
    """A model and where it came from: its source (a built-in name or a model file's text) and
    the parameter overrides, from which it can be compiled again (here, or on a Dask worker)."""

    def __init__(self, source, overrides=None):
        self.source = source
        self.overrides = dict(overrides or {})
        self._cpp = _nhdyn.load(source, list(self.overrides.items()))

    def _compiled(self):
        return self._cpp

    def _set_parameters(self, values):
        overrides = dict(self.overrides)
        overrides.update(values)
        # A copy with the values set, no recompilation; raises before anything changes.
        cpp = _nhdyn.with_parameters(self._cpp, list(values.items()))
        self.overrides, self._cpp = overrides, cpp

    def copy(self):
        """An independent model with the same source and parameters."""
        other = Model.__new__(Model)
        other.source, other.overrides, other._cpp = self.source, dict(self.overrides), self._cpp
        return other

    # --- what the model is ---------------------------------------------------------------------
    @property
    def name(self):
        return self._cpp.name

    @property
    def coordinates(self):
        return list(self._cpp.coordinates)

    @property
    def constraints(self):
        return list(self._cpp.constraints)

    @property
    def n(self):
        return self._cpp.n

    @property
    def s(self):
        return self._cpp.s

    @property
    def t0(self):
        return self._cpp.t0

    @property
    def q0(self):
        return self._cpp.q0

    @property
    def qd0(self):
        return self._cpp.v0

    @property
    def parameters(self):
        return Parameters(self)

    @property
    def run_options(self):
        """The model's run options ([simulation] of its file, else the library's defaults)."""
        return self._cpp.run_options

    @property
    def text(self):
        """The model file's text (None for a built-in model)."""
        return None if self.source.is_builtin else self.source.text

    def __repr__(self):
        return "<nhdyn.Model {!r}: n = {}, s = {}>".format(self.name, self.n, self.s)

    # --- runs and analyses ---------------------------------------------------------------------
    def simulate(self, t_end=None, *, rtol=None, atol=None, method=None, integrator=None, output_step=None,
                 complement=None, step=None, fix_initial=None, stabilize=None, q0=None, qd0=None,
                 stop_when=None, events=None, max_steps=None, program_feedback=None):
        """One run from the model's initial state (or q0, qd0) with the model's run options, any of
        them overridden here. Events: the model file's [[events]], plus stop_when (a condition such
        as "abs(phi) > 1", or a list of them: the run ends when one becomes true) and events (a
        dict of names to expressions whose zero crossings are recorded); they are located exactly
        and listed in Result.events, each also a row of the outputs. For a model with programs,
        program_feedback=(alpha, beta) adds PD feedback on the programs' residuals (rates in 1/s, as
        `nhdyn simulate --program-feedback alpha,beta`; docs/derivations/program-motion.md section 5).
        Returns a Result; a run that fails numerically raises nhdyn.SimulationError with the
        library's message."""
        out = _nhdyn.simulate(self._cpp, t_end=t_end, rtol=rtol, atol=atol, method=method, integrator=integrator,
                              output_step=output_step, complement=complement, step=step, fix_initial=fix_initial,
                              stabilize=stabilize, q0=q0, v0=qd0, stop_when=stop_when, events=events,
                              max_steps=max_steps, program_feedback=program_feedback)
        _warn_constraints(self.name, out["summary"], stacklevel=2)
        if not out["ok"]:
            summary = out["summary"]
            raise SimulationError("simulation of '{}' failed at t = {:.6g}: {}".format(
                self.name, summary["t_reached"], summary["message"]))
        return Result(self, out)

    def equations(self, format="latex"):
        """The equations of motion (T, V, A, Q, G, b, b0, D, A0 = D A, C = D (Q + G)) as
        `nhdyn equations` shows them; displayed as LaTeX in Jupyter."""
        return Equations(_nhdyn.equations(self.source, list(self.overrides.items()), "text"),
                         _nhdyn.equations(self.source, list(self.overrides.items()), "latex"))

    def linearize(self, cyclic=(), independent=(), speeds=(), detect_cyclic=True):
        """The linearization about the model's steady motion (its initial state): state names,
        state matrix and eigenvalues (docs/linearization.md)."""
        return Linearization(_nhdyn.linearize(self._cpp, list(cyclic), list(independent), list(speeds),
                                              detect_cyclic))

    def sweep(self, parameter, values, cyclic=(), independent=(), speeds=(), detect_cyclic=True,
              find_crossings=True):
        """The eigenvalues of the linearization at each of `values` (evenly spaced, increasing) of
        a parameter, and the values where a real part crosses zero (located by bisection)."""
        values = np.asarray(values, dtype=float)
        if values.ndim != 1 or values.size < 2:
            raise InputError("sweep values: give at least two values in a 1-D array")
        first, last = float(values[0]), float(values[-1])
        grid = np.linspace(first, last, values.size)
        if not np.allclose(values, grid, rtol=0, atol=1e-12 * max(1.0, abs(first), abs(last))):
            raise InputError("sweep values: give evenly spaced increasing values, e.g. np.linspace(0, 10, 101)")
        return Sweep(_nhdyn.sweep(self.source, list(self.overrides.items()), parameter, first, last, values.size,
                                  list(cyclic), list(independent), list(speeds), detect_cyclic, find_crossings))


class Result:
    """The outputs of one run, one row per output time: t (rows), q, qd, qdd, R (rows x n),
    residuals (rows x residual columns: position, velocity, acceleration level) and energy (rows,
    or None); for a model with programs, u (rows x m, the actuator forces) and program_residuals
    (rows x the programs' residual columns, position, velocity, acceleration level), both with no
    columns otherwise; outputs (name -> rows, the derived outputs of docs/model-format.md [outputs]).
    `columns` holds the names, the same as the CSV written by `nhdyn simulate`."""

    def __init__(self, model, out):
        self.model_name = model.name
        self.coordinates = model.coordinates
        self.t, self.q, self.qd, self.qdd = out["t"], out["q"], out["qd"], out["qdd"]
        self.R, self.residuals, self.energy = out["R"], out["residuals"], out["energy"]
        # h, P, W_forces, W_reactions, W_time, W, h - h0 - W (docs/derivations/energy-balance.md), or None
        self.energy_balance = out.get("energy_balance")
        # Program motion (docs/derivations/program-motion.md): rows x m and rows x residual columns.
        self.u, self.program_residuals = out["u"], out["program_residuals"]
        # A multibody model's contact forces (docs/multibody.md): rows x columns, named by
        # columns["contact_forces"] (NAME_Fx ... NAME_Flat per wheel or knife edge, then
        # contact_residual), or None.
        self.contact_forces = out.get("contact_forces")
        self.summary = out["summary"]
        # The located events in time order: dicts with name, t, q and qd at the crossing.
        self.events = out["events"]
        self.cpp_seconds = out["cpp_seconds"]
        self.columns = model._cpp.columns
        # The derived outputs ([outputs] of the model file, a multibody model's points): name -> rows.
        values = out.get("outputs")
        self.outputs = {name: values[:, i] for i, name in enumerate(self.columns["outputs"])}

    def table(self):
        """Every column side by side, in the CSV's order: (names, rows x columns array)."""
        parts = [self.t[:, None], self.q, self.qd, self.qdd, self.R, self.residuals]
        if self.energy is not None:
            parts.append(self.energy[:, None])
        if self.energy_balance is not None:
            parts.append(self.energy_balance)
        parts += [self.u, self.program_residuals]
        if self.contact_forces is not None:
            parts.append(self.contact_forces)
        if self.outputs:
            parts.append(np.column_stack(list(self.outputs.values())))
        return list(self.columns["all"]), np.hstack(parts)

    def to_pandas(self):
        """A pandas DataFrame with the CSV's column names (needs pandas)."""
        import pandas as pd

        names, values = self.table()
        return pd.DataFrame(values, columns=names)

    def __repr__(self):
        return "<nhdyn.Result {!r}: {} rows, t = {:g} .. {:g}>".format(
            self.model_name, len(self.t), self.t[0], self.t[-1])


class Equations:
    """The equations of motion; `text` and `latex` hold both forms. Jupyter shows the LaTeX."""

    def __init__(self, text, latex):
        self.text, self.latex = text, latex

    def _repr_latex_(self):
        # MathJax renders align* inside $$ ... $$.
        return "$$" + self.latex + "$$"

    def __str__(self):
        return self.text

    def __repr__(self):
        return self.text


class Linearization:
    """state (names), state_matrix, eigenvalues (sorted), cyclic, independent, speeds."""

    def __init__(self, out):
        self.__dict__.update(out)

    def __repr__(self):
        return "<nhdyn.Linearization: state {}, {} eigenvalues>".format(self.state, len(self.eigenvalues))


class Sweep:
    """values (the grid), eigenvalues (values x state), crossings (list of dicts: value,
    oscillatory, frequency, unstable_before, unstable_after, bracket), state (names)."""

    def __init__(self, out):
        self.__dict__.update(out)

    def __repr__(self):
        return "<nhdyn.Sweep: {} points, crossings at {}>".format(
            len(self.values), [round(c["value"], 6) for c in self.crossings])


class BatchResult:
    """The runs of simulate_batch stacked: t (rows), q, qd, qdd, R (runs x rows x n), residuals
    (runs x rows x columns), energy (runs x rows or None), q_end, qd_end (runs x n), max_residual
    (runs), ok (runs, bool), messages (runs: empty, or why the run failed), parameters (name ->
    runs values). Rows after a failed run's end are NaN."""

    def __init__(self, out, parameters, coordinates):
        self.t, self.q, self.qd, self.qdd = out["t"], out["q"], out["qd"], out["qdd"]
        self.R, self.residuals, self.energy = out["R"], out["residuals"], out["energy"]
        self.q_end, self.qd_end, self.max_residual = out["q_end"], out["qd_end"], out["max_residual"]
        self.ok = np.asarray(out["ok"], dtype=bool)
        self.messages = list(out["messages"])
        self.summaries = out["summaries"]
        self.threads = out["threads"]
        self.cpp_seconds = out["cpp_seconds"]
        self.parameters = parameters
        self.coordinates = coordinates

    def __len__(self):
        return len(self.ok)

    def summary(self):
        """One row per run: the parameters, the final state, the largest residual, the status
        (a pandas DataFrame)."""
        import pandas as pd

        frame = pd.DataFrame({name: values for name, values in self.parameters.items()})
        for i, c in enumerate(self.coordinates):
            frame[c] = self.q_end[:, i]
        for i, c in enumerate(self.coordinates):
            frame[c + "'"] = self.qd_end[:, i]
        frame["max_residual"] = self.max_residual
        frame["status"] = ["ok" if ok else "failed" for ok in self.ok]
        frame["message"] = self.messages
        return frame

    def __repr__(self):
        return "<nhdyn.BatchResult: {} runs, {} failed, {} threads>".format(
            len(self.ok), int((~self.ok).sum()), self.threads)


def _batch_runs(model, parameters, initial):
    """Checks the shapes of a batch's inputs; returns (names, values runs x p, q0, qd0, runs)."""
    parameters = dict(parameters or {})
    initial = dict(initial or {})
    unknown = set(initial) - {"q", "qd"}
    if unknown:
        raise InputError("initial: unknown key(s) {}; give 'q' and/or 'qd', arrays of shape (runs, n)".format(
            ", ".join(sorted(map(str, unknown)))))
    names = list(parameters)
    columns = []
    runs = None
    for name in names:
        values = np.asarray(parameters[name], dtype=float)
        if values.ndim != 1:
            raise InputError("parameters[{!r}]: expected a 1-D array of values, got shape {}".format(
                name, values.shape))
        if runs is not None and values.size != runs:
            raise InputError("parameters[{!r}]: {} values, but other inputs give {} runs".format(
                name, values.size, runs))
        runs = values.size
        columns.append(values)
    q0 = initial.get("q")
    qd0 = initial.get("qd")
    for key, value in (("q", q0), ("qd", qd0)):
        if value is None:
            continue
        value = np.asarray(value, dtype=float)
        if value.ndim != 2 or value.shape[1] != model.n or (runs is not None and value.shape[0] != runs):
            raise InputError("initial[{!r}]: expected an array of shape (runs, n) = ({}, {}), got {}".format(
                key, "runs" if runs is None else runs, model.n, value.shape))
        runs = value.shape[0]
    if runs is None:
        raise InputError("simulate_batch: give parameters={name: values} and/or initial={'q': ..., 'qd': ...}")
    values = np.column_stack(columns) if columns else np.zeros((runs, 0))
    return names, values, q0, qd0, runs


def _batch_models(model, names, values, runs):
    if not names:
        return [model._cpp] * runs
    return _nhdyn.load_variants(model.source, list(model.overrides.items()), names, values)


def simulate_batch(model, parameters=None, initial=None, t_end=None, threads=0, keep_trajectories=True, **options):
    """Many runs of one model on a pool of C++ threads (threads=0: every core), the GIL released.

    parameters: {name: 1-D array of values}, one run per index (all of the same length);
    initial: {"q": (runs, n) array, "qd": (runs, n) array}, initial states replacing the model's.
    Other keyword arguments are those of Model.simulate (rtol, method, output_step, ...).
    A run that fails keeps its rows up to the failure and says why in messages; the others are
    unaffected. Returns a BatchResult.
    """
    names, values, q0, qd0, runs = _batch_runs(model, parameters, initial)
    models = _batch_models(model, names, values, runs)
    out = _nhdyn.simulate_batch(models, q0=q0, v0=qd0, threads=int(threads), keep_trajectories=keep_trajectories,
                                t_end=t_end, **options)
    for run, summary in enumerate(out["summaries"]):
        _warn_constraints(model.name, summary, stacklevel=2, run=run)
    return BatchResult(out, {name: values[:, j] for j, name in enumerate(names)}, model.coordinates)
