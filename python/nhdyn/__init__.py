"""nhdyn in Python: load a constrained mechanical system, simulate it, look at its equations,
linearize it, sweep a parameter and run batches on every core.

    import nhdyn
    m = nhdyn.load("examples/sled.toml")          # a model file, a built-in name, or nhdyn.loads(text)
    m.parameters["m"] = 2.0                       # no recompilation
    r = m.simulate(t_end=5, rtol=1e-10)           # Result: NumPy arrays r.t, r.q, r.qd, ...
    r["x"], r["phi'"]                             # a column by its CSV name
    r.to_pandas(index="t")                        # a DataFrame with the CSV's column names
    m.report(r, "run.html"); r.plot()             # the HTML report; matplotlib panels

The numbers come from the C++ library (nhdyn._nhdyn); its errors arrive as nhdyn.Error (and the
subclasses InputError, ModelError, FileError) with the library's message (file:line: ...).
See docs/python.md.
"""

import functools
import os
import re
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
from ._from_sympy import from_sympy, from_sympy_mechanics

__version__ = _nhdyn.__version__

# What the library's messages call a command-line option, in Python's terms (the keywords of
# Model.simulate, Model.linearize, Model.sweep, simulate_batch, nhdyn.load): a Python user gets
# "fix_initial=True", not "--fix-initial". Whole phrases first (an option with its value), then
# single options; an option the table lacks is left as it is.
_PYTHON_PHRASES = [
    # --event "NAME=EXPR" and --stop-when "COND", as the events dict and stop_when give them.
    (re.compile(r'--event "([^"=]*)=([^"]*)"'), lambda m: 'events={{"{}": "{}"}}'.format(m.group(1), m.group(2))),
    (re.compile(r'--stop-when "([^"]*)"'), r'stop_when="\1"'),
    # nhdyn.load(path, k="1/0") reaches the library as --set k=1/0.
    (re.compile(r"--set ([A-Za-z_][A-Za-z0-9_]*)="), r"\1="),
    (re.compile(r"--guess FILE\.csv"), 'guess="FILE.csv"'),
    # The integrator and the stabilization a warning advises, as the keywords take them.
    (re.compile(r"--(integrator|stabilize) ([a-z][a-z0-9-]*)"), r'\1="\2"'),
    (re.compile(r"--steps (\d+)"), r"len(values) = \1"),
    (re.compile(r"expected NAME=EXPR, a name"), "expected a name"),
    (re.compile(r"`nhdyn equations MODEL --format latex` prints them"), "Model.equations() gives them"),
    (re.compile(r"load it without --compiled"), "load it with the interpreted evaluator"),
]
_PYTHON_TERMS = {
    "--fix-initial": "fix_initial=True", "--t-end": "t_end", "--output-step": "output_step", "--rtol": "rtol",
    "--atol": "atol", "--step": "step", "--method": "method", "--integrator": "integrator",
    "--complement": "complement", "--stabilize": "stabilize", "--max-steps": "max_steps",
    "--stop-when": "stop_when", "--event": "events", "--program-feedback": "program_feedback",
    "--set": "m.parameters[NAME] = value", "--initial": "q0/qd0", "--threads": "threads",
    "--cyclic": "cyclic=[...]", "--independent": "independent=[...]", "--speeds": "speeds=[...]",
    "--from": "values[0]", "--to": "values[-1]", "--steps": "len(values)", "--guess": "guess",
    "--max-frames": "max_frames", "--tolerance": "tolerance", "--max-iterations": "max_iterations",
}
_OPTION = re.compile(r"--[a-z][a-z-]*[a-z]")
# "max_steps (--max-steps)" names the keyword twice once translated.
_TWICE = re.compile(r"\b(\w+) \(\1\)")


def _python_text(text):
    """`text` with the command line's options named as Python keywords."""
    for pattern, replacement in _PYTHON_PHRASES:
        text = pattern.sub(replacement, text)
    text = _OPTION.sub(lambda m: _PYTHON_TERMS.get(m.group(0), m.group(0)), text)
    return _TWICE.sub(r"\1", text)


def _in_python_terms(error):
    """The same exception (its type and attributes kept) with the command line's options named as
    Python keywords."""
    text = str(error)
    translated = _python_text(text)
    if translated == text:
        return error
    other = type(error)(translated)
    other.__dict__.update(error.__dict__)
    return other


def _python_errors(function):
    """`function` raising the library's errors in Python's terms (_in_python_terms)."""
    @functools.wraps(function)
    def wrapper(*args, **kwargs):
        try:
            return function(*args, **kwargs)
        except Error as error:
            raise _in_python_terms(error) from None
    return wrapper


def _real_numbers(values, what):
    """`values` as a float array, or InputError naming `what` for booleans, complex numbers or text
    (NumPy would read True as 1 and drop an imaginary part with a warning only)."""
    raw = np.asarray(values)
    if raw.dtype == bool or raw.dtype.kind not in "iuf":
        raise InputError("{}: expected real numbers, got {} values (dtype {}); booleans, complex numbers and text "
                         "are not accepted".format(what, raw.size, raw.dtype))
    if not isinstance(values, np.ndarray):  # a list mixing True with numbers becomes numbers
        for i, value in enumerate(np.asarray(values, dtype=object).ravel()):
            if isinstance(value, (bool, np.bool_)):
                raise InputError("{}: entry {} is {!r}, a boolean, not a number".format(what, i, value))
    return raw.astype(float)


def _check_t_eval(t_eval, t0, t_end):
    """t_eval as a 1-D float array of finite, strictly increasing times in [t0, t_end], or InputError."""
    times = _real_numbers(t_eval, "t_eval")
    if times.ndim != 1 or times.size == 0:
        raise InputError("t_eval: expected a non-empty 1-D array of times, got shape {}".format(times.shape))
    if not np.all(np.isfinite(times)):
        raise InputError("t_eval: time t_eval[{}] = {} is not finite".format(
            int(np.argmin(np.isfinite(times))), times[np.argmin(np.isfinite(times))]))
    steps = np.diff(times)
    if np.any(steps <= 0):
        i = int(np.argmax(steps <= 0)) + 1
        raise InputError("t_eval: the times must increase strictly; t_eval[{}] = {} follows {}".format(
            i, times[i], times[i - 1]))
    if times[0] < t0:
        raise InputError("t_eval: t_eval[0] = {} is before the model's start time t0 = {}".format(times[0], t0))
    if times[-1] <= t0:
        raise InputError("t_eval: the last time {} must be after the model's start time t0 = {}".format(times[-1], t0))
    if t_end is not None and times[-1] > t_end:
        raise InputError("t_eval: t_eval[-1] = {} is after t_end = {}; leave t_end out (the run ends at the last "
                         "time) or give a later one".format(times[-1], t_end))
    return times


__all__ = [
    "__version__", "Error", "InputError", "ModelError", "FileError", "SimulationError", "ConstraintWarning",
    "StopConditionWarning", "StiffnessWarning",
    "load", "loads", "builtin_models", "Model", "Result", "Optimum", "Equations", "Linearization", "Sweep",
    "BatchResult", "simulate_batch", "from_sympy", "from_sympy_mechanics",
]


class ConstraintWarning(UserWarning):
    """A constraint whose row of b, or the conditioning of the stacked matrix [D A; b], degraded
    by three orders of magnitude during a run (a form singular along the path, such as
    y' - tan(phi) x' at phi = pi/2): the motion past that time may be wrong. The library's
    constraint watch (docs/cli.md, "Warnings"); Result.summary["constraint_warnings"] has the
    numbers. Filter with warnings.simplefilter("error", nhdyn.ConstraintWarning) to make it fatal."""


class StiffnessWarning(UserWarning):
    """A run whose explicit integrator (dopri5, dop853) spent many of its steps (at least 1000 and a
    quarter of all) held by its stability rather than its accuracy (Hairer's stiffness test; docs/cli.md, "--max-steps"): the
    result is right but an implicit integrator (integrator="cvode-bdf") takes far fewer steps.
    Result.summary["stiffness"] has the words; summary["stiff_steps"] the count."""


def _warn_constraints(model_name, summary, stacklevel, run=None):
    where = "" if run is None else " (run {})".format(run)
    for text in summary.get("warnings", []):
        warnings.warn("nhdyn: {}{}: {}".format(model_name, where, _python_text(text)), ConstraintWarning,
                      stacklevel=stacklevel + 1)
    if summary.get("stiffness"):
        warnings.warn("nhdyn: {}{}: {}".format(model_name, where, _python_text(summary["stiffness"])),
                      StiffnessWarning, stacklevel=stacklevel + 1)


class StopConditionWarning(UserWarning):
    """A stop condition (stop_when=, or an event with action = "stop" in the model file) that never
    held on a run that went to its end: most likely a sign, direction or threshold that cannot be
    met. The words of `nhdyn simulate`'s warning (docs/cli.md, "Events"), in Python's terms; a
    batch warns once per condition, naming the runs. Result.summary["unmet_stops"] has the
    sentences. Filter with warnings.simplefilter("error", nhdyn.StopConditionWarning) to make it
    fatal."""


def _warn_unmet_stops(model_name, summaries, stacklevel, batch=False):
    """Warns with each stop condition that never held: for one run (batch=False, summaries of one
    element) its sentences; for a batch each sentence once with the runs it holds for, as
    `nhdyn batch` prints them."""
    per_run = [summary.get("unmet_stops", []) for summary in summaries]
    texts = _nhdyn.format_batch_unmet_stops(per_run) if batch else [t for run in per_run for t in run]
    for text in texts:
        warnings.warn("nhdyn: {}: {}".format(model_name, _python_text(text)), StopConditionWarning,
                      stacklevel=stacklevel + 1)


def _output_path(path, what, source=None):
    """`path` as a file name for `what` to write: a str, bytes or os.PathLike (an int would be a
    file descriptor, which open() then closes), never the model file the result was run from
    (the command line refuses it too)."""
    if isinstance(path, (bool, int)) or not isinstance(path, (str, bytes, os.PathLike)):
        raise InputError("{}: expected a file path, got {!r}".format(what, path))
    path = os.fsdecode(os.fspath(path))
    model_file = getattr(source, "file_name", "") if source is not None and not source.is_builtin else ""
    if model_file and os.path.exists(path) and os.path.exists(model_file) and os.path.samefile(path, model_file):
        raise InputError("{}: '{}' is the model file of this run; write to another path".format(what, path))
    return path


def _write_whole(path, text):
    """Writes `text` to `path` as the command line writes its outputs (io/atomic_file.hpp): through a
    temporary file renamed into place once whole, so that a failure leaves the old file (or none);
    a device or a pipe written straight, a symbolic link written through, a replaced file's mode
    kept, a full disk a FileError."""
    _nhdyn.write_file(path, text)


def builtin_models():
    """The built-in models as a dict name -> description (what `nhdyn list` shows)."""
    return dict(_nhdyn.builtin_models())


@_python_errors
def load(source, **parameters):
    """A model from a model file's path or a built-in model's name; keyword arguments override
    the file's parameters (numbers, or the text of one)."""
    return Model(_nhdyn.read_source(str(source)), parameters)


@_python_errors
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

    @_python_errors
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


def _names(value, keyword):
    """A list of coordinate names: one name given as a str is that name (list("psi") read as the
    letters p, s, i); anything but names is an InputError naming the keyword."""
    if isinstance(value, str):
        return [value]
    try:
        names = list(value)
    except TypeError:
        raise InputError("{}={!r}: expected a coordinate name or a list of names".format(keyword, value)) from None
    for i, name in enumerate(names):
        if not isinstance(name, str):  # numpy.str_ is one
            raise InputError("{}: entry {} is {!r} ({}), not a coordinate name; give names as strings, e.g. "
                             "{}=[\"psi\"]".format(keyword, i, name, type(name).__name__, keyword))
    return [str(name) for name in names]


class Model:
    """A model and where it came from: its source (a built-in name or a model file's text) and
    the parameter overrides, from which it can be compiled again (here, or on a Dask worker)."""

    @_python_errors
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
    @_python_errors
    def simulate(self, t_end=None, *, rtol=None, atol=None, method=None, integrator=None, output_step=None,
                 complement=None, step=None, fix_initial=None, stabilize=None, q0=None, qd0=None,
                 stop_when=None, events=None, max_steps=None, program_feedback=None, t_eval=None):
        """One run from the model's initial state (or q0, qd0) with the model's run options, any of
        them overridden here. Events: the model file's [[events]], plus stop_when (a condition such
        as "abs(phi) > 1", or a list of them: the run ends when one becomes true) and events (a
        dict of names to expressions whose zero crossings are recorded); they are located exactly
        and listed in Result.events, each also a row of the outputs. For a model with programs,
        program_feedback=(alpha, beta) adds PD feedback on the programs' residuals (rates in 1/s, as
        `nhdyn simulate --program-feedback alpha,beta`; docs/derivations/program-motion.md section 5).
        t_eval (increasing times from t0 on, as SciPy's solve_ivp takes them) gives the output
        times instead of output_step's grid: the rows are at exactly those times (the integrator's
        dense output), plus the events' rows; the run ends at the last one.
        Returns a Result; a run that fails numerically raises nhdyn.SimulationError with the
        library's message, its time `t` and the rows up to the failure in `result`. With
        fix_initial=True, Result.summary["initial_fix"] says where the initial state was moved
        (q, qd and the changes dq, dqd)."""
        if t_eval is not None:
            t_eval = _check_t_eval(t_eval, self.t0, t_end)
        options = dict(t_end=t_end, rtol=rtol, atol=atol, method=method, integrator=integrator,
                       output_step=output_step, complement=complement, step=step, fix_initial=fix_initial,
                       stabilize=stabilize, q0=q0, v0=qd0, stop_when=stop_when, events=events,
                       max_steps=max_steps, program_feedback=program_feedback, t_eval=t_eval)
        try:
            out = _nhdyn.simulate(self._cpp, **options)
        except Error as error:
            raise _in_python_terms(error) from None
        _warn_constraints(self.name, out["summary"], stacklevel=2)
        _warn_unmet_stops(self.name, [out["summary"]], stacklevel=2)
        # The provenance header is made when asked for (Result.provenance), from the compiled model
        # as it ran (a later parameter change makes a new one) and the same options.
        cpp, source = self._cpp, self.source
        result = Result(self, out, lambda: _nhdyn.provenance(cpp, source, **options))
        if not out["ok"]:
            summary = out["summary"]
            error = SimulationError("simulation of '{}' failed at t = {:.6g}: {}".format(
                self.name, summary["t_reached"], _python_text(summary["message"])))
            error.t = summary["t_reached"]  # where it failed
            error.result = result           # the rows up to the failure
            raise error
        return result

    @_python_errors
    def report(self, result, path, max_frames=2000):
        """Writes the HTML report of `result` (a run of this model) to `path`: the page `nhdyn
        simulate --html` writes (3-D animation, plots, equations; docs/report.md), with the run's
        provenance at its top. Returns the page's note ("" when none: nothing to draw, rows
        thinned)."""
        if not isinstance(result, Result):
            raise InputError("report: expected a Result of Model.simulate, got {}".format(type(result).__name__))
        if isinstance(max_frames, bool) or not isinstance(max_frames, (int, np.integer)):
            raise InputError("report: max_frames={!r}: give a whole number of rows (at least 2)".format(max_frames))
        if max_frames < 2:
            raise InputError("report: max_frames={}: give at least 2 (the first and the last row)".format(max_frames))
        max_frames = int(min(max_frames, 2**31 - 1))  # more frames than rows are the rows
        if result._source.is_builtin != self.source.is_builtin or result._source.text != self.source.text or \
                result._source.builtin != self.source.builtin:
            raise InputError("report: the result is a run of model '{}' from {}, not of this model '{}' ({}); call "
                             "report on the model that made it".format(
                                 result.model_name, result._source.file_name or result._source.builtin, self.name,
                                 self.source.file_name or self.source.builtin))
        path = _output_path(path, "report", self.source)
        names, rows = result.table()
        comments = [line[1:] for line in result.provenance.splitlines()]
        title = "{}: {}".format(result.model_name, os.fspath(path))
        summary = result.summary
        extra = [("steps", "{} (rejected {})".format(summary["steps"], summary["rejected_steps"])),
                 ("right-hand sides", str(summary["rhs_evaluations"]))]
        return _nhdyn.write_report(self.source, list(result._overrides.items()), names, rows, comments,
                                   os.fspath(path), title, extra, max_frames)

    @_python_errors
    def optimize(self, guess=None, *, tolerance=1e-8, max_iterations=3000):
        """The optimal program of the model file's [optimize] section, as `nhdyn optimize` finds
        it (direct collocation of the Do Sanh form with IPOPT; docs/optimize.md), with this model's
        parameters. guess: a CSV path with the columns `nhdyn optimize` writes (t, the coordinates
        and their velocities, optionally x'' and u_NAME), else the straight line between the
        boundary states. Returns an Optimum; one that did not converge (Optimum.converged False,
        its last iterate in it), or whose replay says it is not a motion of the model (the replay
        rule of docs/optimize.md: converged False, replay_verdict says why), also warns."""
        if self.source.is_builtin:
            raise InputError("optimize: '{}' is a built-in model; optimize reads the [optimize] section of a model "
                             "file".format(self.name))
        # float() and int() took tolerance="1e-3" and max_iterations=1.9 or True silently, and a
        # budget beyond a C int reached pybind11's signature error.
        if isinstance(tolerance, bool) or not isinstance(tolerance, (int, float, np.integer, np.floating)):
            raise InputError("optimize: tolerance={!r}: give a real number above 0 and at most 0.01 (the default is "
                             "1e-8)".format(tolerance))
        if isinstance(max_iterations, bool) or not isinstance(max_iterations, (int, np.integer)):
            raise InputError("optimize: max_iterations={!r}: give a whole number of iterations, at least 1 (the "
                             "default is 3000)".format(max_iterations))
        if not -2**31 <= max_iterations <= 2**31 - 1:
            raise InputError("optimize: max_iterations={}: give a whole number from 1 to {} (IPOPT counts its "
                             "iterations in a C int; the default is 3000)".format(max_iterations, 2**31 - 1))
        out = _nhdyn.optimize(self.source, list(self.overrides.items()), "" if guess is None else os.fspath(guess),
                              float(tolerance), int(max_iterations))
        result = Optimum(self, out)
        if result.replay_verdict:
            warnings.warn("optimize '{}': {}; the result is the discrete optimum".format(
                self.name, result.replay_verdict), RuntimeWarning, stacklevel=2)
        elif not result.converged:
            warnings.warn("optimize '{}': IPOPT did not converge: {} ({}); the result is its last iterate".format(
                self.name, result.status, result.solver_message), RuntimeWarning, stacklevel=2)
        return result

    @_python_errors
    def equations(self, format="latex"):
        """The equations of motion (T, V, A, Q, G, b, b0, D, A0 = D A, C = D (Q + G)) as
        `nhdyn equations` shows them; displayed as LaTeX in Jupyter."""
        return Equations(_nhdyn.equations(self.source, list(self.overrides.items()), "text"),
                         _nhdyn.equations(self.source, list(self.overrides.items()), "latex"))

    @_python_errors
    def linearize(self, cyclic=(), independent=(), speeds=(), detect_cyclic=True):
        """The linearization about the model's steady motion (its initial state): state names,
        state matrix and eigenvalues (docs/linearization.md)."""
        return Linearization(_nhdyn.linearize(self._cpp, _names(cyclic, "cyclic"), _names(independent, "independent"),
                                              _names(speeds, "speeds"), detect_cyclic))

    @_python_errors
    def sweep(self, parameter, values, cyclic=(), independent=(), speeds=(), detect_cyclic=True,
              find_crossings=True):
        """The eigenvalues of the linearization at each of `values` (evenly spaced, increasing) of
        a parameter, and the values where a real part crosses zero (located by bisection)."""
        values = _real_numbers(values, "sweep values")
        if values.ndim != 1 or values.size < 2:
            raise InputError("sweep values: give at least two values in a 1-D array")
        first, last = float(values[0]), float(values[-1])
        if not last > first:
            raise InputError("sweep values: give increasing values (values[0] = {:g} is not below values[-1] = {:g}), "
                             "e.g. np.linspace(0, 10, 101)".format(first, last))
        grid = np.linspace(first, last, values.size)
        if not np.allclose(values, grid, rtol=0, atol=1e-12 * max(1.0, abs(first), abs(last))):
            raise InputError("sweep values: give evenly spaced increasing values, e.g. np.linspace(0, 10, 101)")
        return Sweep(_nhdyn.sweep(self.source, list(self.overrides.items()), parameter, first, last, values.size,
                                  _names(cyclic, "cyclic"), _names(independent, "independent"),
                                  _names(speeds, "speeds"), detect_cyclic, find_crossings))


class Result:
    """The outputs of one run, one row per output time: t (rows), q, qd, qdd, R (rows x n),
    residuals (rows x residual columns: position, velocity, acceleration level) and energy (rows,
    or None); for a model with programs, u (rows x m, the actuator forces) and program_residuals
    (rows x the programs' residual columns, position, velocity, acceleration level), both with no
    columns otherwise; outputs (name -> rows, the derived outputs of docs/model-format.md [outputs]).
    `columns` holds the names, the same as the CSV written by `nhdyn simulate`."""

    def __init__(self, model, out, provenance=None):
        self.model_name = model.name
        self._provenance = provenance  # a function that makes the text, or None
        self._source, self._overrides = model.source, dict(model.overrides)
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

    @property
    def provenance(self):
        """The run's provenance header, "# key: value" lines (nhdyn version, model name, file and
        hash, parameters, initial state, options; docs/cli.md "The CSV"), as to_csv writes it and
        `nhdyn report` reads it."""
        if callable(self._provenance):
            self._provenance = self._provenance()
        return self._provenance or ""

    # Not iterable: result[name] takes a column's name, and Python's fallback iteration asked for
    # result[0], result[1], ... ("KeyError: 0 is not a column"). result.columns["all"] lists them.
    __iter__ = None

    def __getitem__(self, name):
        """One column by its CSV name: r["x"], r["phi'"], r["R_x"], r["energy"], an output's name."""
        if not hasattr(self, "_index"):
            self._names, self._values = self.table()
            self._index = {column: i for i, column in enumerate(self._names)}
        i = self._index.get(name)
        if i is None:
            import difflib

            near = difflib.get_close_matches(str(name), self._names, n=1)
            raise KeyError("{!r} is not a column of this result{}; the columns are {}".format(
                name, " (did you mean {!r}?)".format(near[0]) if near else "", ", ".join(self._names)))
        return self._values[:, i]

    def __contains__(self, name):
        return name in self.columns["all"]

    def keys(self):
        """The column names, in the CSV's order."""
        return list(self.columns["all"])

    def to_pandas(self, index=None):
        """A pandas DataFrame with the CSV's column names (needs pandas); index="t" (or another
        column's name) makes that column the index."""
        import pandas as pd

        names, values = self.table()
        frame = pd.DataFrame(values, columns=names)
        if index is not None:
            if index not in names:
                raise KeyError("index={!r}: not a column of this result; the columns are {}".format(
                    index, ", ".join(names)))
            frame = frame.set_index(index)
        return frame

    def to_csv(self, path):
        """Writes the result as `nhdyn simulate` writes its CSV: the provenance header, the column
        names, one row per output time (numbers in the shortest form that reads back the same)."""
        path = _output_path(path, "to_csv", self._source)
        names, values = self.table()
        lines = [self.provenance, ",".join(names) + "\n"]
        for row in values:
            lines.append(",".join(repr(float(x)) if np.isfinite(x) else ("nan" if np.isnan(x) else
                                                                        ("inf" if x > 0 else "-inf")) for x in row))
            lines.append("\n")
        _write_whole(path, "".join(lines))

    def plot(self, columns=None, path=None):
        """The run's panels with matplotlib: the coordinates, the velocities, the constraint
        residuals (|value|, logarithmic) and the energy (or its balance error), or the named
        `columns`, one panel each. Returns the Figure; `path` also saves it (PNG, PDF, SVG)."""
        import matplotlib

        if path is not None and "matplotlib.pyplot" not in sys.modules and not os.environ.get("MPLBACKEND"):
            matplotlib.use("Agg")  # saving needs no window
        import matplotlib.pyplot as plt

        if columns is not None:
            panels = [(str(c), [str(c)], False) for c in ([columns] if isinstance(columns, str) else columns)]
            if not panels:
                raise InputError("plot: columns=[] names no column; give at least one, or leave it out for the "
                                 "default panels")
            for _, names, _ in panels:
                self[names[0]]  # KeyError naming the columns
        else:
            panels = [("coordinates", list(self.coordinates), False),
                      ("velocities", [c + "'" for c in self.coordinates], False)]
            if self.columns["residuals"]:
                panels.append(("|constraint residuals|", list(self.columns["residuals"]), True))
            if "balance_error" in self.columns["all"]:
                panels.append(("energy balance error h - h0 - W", ["balance_error"], False))
            elif self.columns["energy"]:
                panels.append(("energy E - E0", [self.columns["energy"]], False))
        figure, axes = plt.subplots(len(panels), 1, sharex=True, figsize=(8, 2.4 * len(panels)), squeeze=False)
        for ax, (title, names, logarithmic) in zip(axes[:, 0], panels):
            for name in names:
                values = self[name]
                if title.startswith("energy E"):
                    values = values - values[0]
                if logarithmic:
                    values = np.abs(values)
                    values = np.where(values > 0, values, np.nan)  # log scale: an exact 0 is a gap
                ax.plot(self.t, values, label=name)
            if logarithmic:
                ax.set_yscale("log")
            ax.set_title(title, fontsize=10)
            if len(names) > 1:
                ax.legend(fontsize=8, loc="best")
            ax.grid(True, alpha=0.3)
        axes[-1, 0].set_xlabel("t [s]")
        figure.suptitle(self.model_name)
        figure.tight_layout()
        if path is not None:
            figure.savefig(os.fspath(path))
        return figure

    def __repr__(self):
        return "<nhdyn.Result {!r}: {} rows, t = {:g} .. {:g}>".format(
            self.model_name, len(self.t), self.t[0], self.t[-1])


class Optimum:
    """An optimal program (Model.optimize), one row per point (the nodes and, for Hermite-Simpson,
    the midpoints): t (points), q, qd, qdd (points x n), u (points x controls, named in
    `controls`). `columns` and `rows` are the CSV that `nhdyn optimize -o` writes (t, the
    coordinates, x', x'', u_NAME); `summary` its summary text. status ("solved", "solved to
    acceptable level", "infeasible", "iteration limit", "failed", "not a motion of the model"),
    iterations, objective, t_end, constraint_violation, replay_difference (None when the replay
    failed: replay_message says why), interval_replay (the largest error of an interval replayed
    from the optimum's state at its start, in the coordinate replay_coordinate), replay_limit and
    notes are the summary's values. converged is True when IPOPT converged and the replay confirms
    a motion of the model; replay_verdict says why not when the replay rule rejects the result
    ("" otherwise)."""

    def __init__(self, model, out):
        self.model_name = model.name
        self._source = model.source  # to_csv never writes over the model file
        self.coordinates = model.coordinates
        self.controls = list(out["controls"])
        self.t, self.q, self.qd, self.qdd, self.u = out["t"], out["q"], out["qd"], out["qdd"], out["u"]
        self.columns, self.rows = list(out["columns"]), out["table"]
        self.summary = out["summary_text"]
        for key in ("status", "solver_message", "converged", "iterations", "objective", "t_end", "free_time",
                    "constraint_violation", "replay_difference", "replay_message", "replay_limit",
                    "interval_replay", "replay_coordinate"):
            setattr(self, key, out[key])
        self.replay_verdict = _python_text(out["replay_verdict"])
        self.notes = [_python_text(note) for note in out["notes"]]

    def column(self, name):
        """The column `name` of the CSV (e.g. "x", "x'", "u_F")."""
        if name not in self.columns:
            raise InputError("no column '{}': the columns are {}".format(name, ", ".join(self.columns)))
        return self.rows[:, self.columns.index(name)]

    def to_csv(self, path):
        """Writes the CSV of `nhdyn optimize -o` to `path`."""
        path = _output_path(path, "to_csv", self._source)
        lines = [",".join(self.columns) + "\n"]
        lines += [",".join(repr(float(v)) for v in row) + "\n" for row in self.rows]
        _write_whole(path, "".join(lines))

    def __repr__(self):
        return "<nhdyn.Optimum {!r}: {}, objective {:.10g}, {} points>".format(
            self.model_name, self.status, self.objective, len(self.t))


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
    """The runs of simulate_batch stacked: t (rows), q, qd, qdd, R (runs x rows x n, also for
    n = 1), residuals (runs x rows x columns), energy (runs x rows or None), q_end, qd_end
    (runs x n), max_residual (runs), ok (runs, bool), messages (runs: empty, or why the run
    failed), events (runs lists of {name, t, q, qd}), parameters (name -> runs values). Rows after
    a failed run's end are NaN. t is one vector when every run has the same output times; with
    events or a stop condition each run has its own rows, and t is runs x rows (NaN after a
    run's last row). contact_forces (runs x rows x columns, or None) holds a multibody model's
    contact forces and, for contacts with modes, NAME_mode, NAME_slip_speed, NAME_slip_x/y/z,
    NAME_gap, work_friction and impact_loss, named by columns["contact_forces"] as in Model.simulate's
    Result (the same from nhdyn.dask.simulate_batch);
    batch["ball_mode"] gives one of them (or a coordinate, "x'", "energy") as runs x rows."""

    def __init__(self, out, parameters, coordinates, columns=None):
        self.t, self.q, self.qd, self.qdd = out["t"], out["q"], out["qd"], out["qdd"]
        self.contact_forces = out.get("contact_forces")
        self.columns = columns or {}
        self.R, self.residuals, self.energy = out["R"], out["residuals"], out["energy"]
        self.q_end, self.qd_end, self.max_residual = out["q_end"], out["qd_end"], out["max_residual"]
        self.ok = np.asarray(out["ok"], dtype=bool)
        self.messages = [_python_text(message) for message in out["messages"]]
        self.summaries = out["summaries"]
        self.events = out.get("events", [[] for _ in out["ok"]])
        self.threads = out["threads"]
        self.cpp_seconds = out["cpp_seconds"]
        self.parameters = parameters
        self.coordinates = coordinates

    def __len__(self):
        return len(self.ok)

    def __getitem__(self, name):
        """One column of every run by its CSV name, runs x rows: a coordinate ("x"), its velocity
        ("x'"), "energy", or a contact column ("ball_N", "ball_mode", "work_friction")."""
        if name in self.coordinates:
            return self.q[:, :, self.coordinates.index(name)]
        if name.endswith("'") and name[:-1] in self.coordinates:
            return self.qd[:, :, self.coordinates.index(name[:-1])]
        if name == "energy" and self.energy is not None:
            return self.energy
        contact = list(self.columns.get("contact_forces", []))
        if self.contact_forces is not None and name in contact:
            return self.contact_forces[:, :, contact.index(name)]
        names = list(self.coordinates) + [c + "'" for c in self.coordinates] + contact
        raise KeyError("{!r} is not a column of this batch; the columns are {}".format(name, ", ".join(names)))

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
        values = _real_numbers(parameters[name], "parameters[{!r}]".format(name))
        if values.ndim != 1:
            raise InputError("parameters[{!r}]: expected a 1-D array of values, got shape {}".format(
                name, values.shape))
        bad = np.flatnonzero(~np.isfinite(values))
        if bad.size:  # checked here, so that a batch spread in chunks (nhdyn.dask) names the run in the batch
            raise InputError("run {}: parameter {} = {} is not a finite number".format(bad[0], name, values[bad[0]]))
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


@_python_errors
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
    out = _nhdyn.simulate_batch(models, q0=q0, v0=qd0, threads=threads, keep_trajectories=keep_trajectories,
                                t_end=t_end, **options)
    for run, summary in enumerate(out["summaries"]):
        _warn_constraints(model.name, summary, stacklevel=2, run=run)
    _warn_unmet_stops(model.name, out["summaries"], stacklevel=2, batch=True)
    return BatchResult(out, {name: values[:, j] for j, name in enumerate(names)}, model.coordinates,
                       model._cpp.columns)
