"""Python that feels like Python: columns by name, pandas with an index, output times (t_eval),
SimulationError with its time and partial result, messages in Python's terms, fix_initial in the
summary, the provenance header (to_csv, shared with the CLI), the HTML report and the matplotlib
panels from Python, and the type stubs of the compiled module."""

import ast
import math
import pathlib
import re

import numpy as np
import pytest

import nhdyn
from conftest import read_csv


def appell_exact(t, a, g=9.81):
    """Appell's particle from examples/appell.toml's initial state (test_model.py derives it)."""
    s = math.sqrt(1.25) * t + g * a / (1 + a * a) * t * t / 2
    return np.column_stack([s / math.sqrt(1.25), 0.5 * s / math.sqrt(1.25), a * s])


def test_columns_by_name(examples):
    r = nhdyn.load(examples / "sled.toml").simulate(t_end=1)
    assert np.array_equal(r["x"], r.q[:, 0])
    assert np.array_equal(r["phi'"], r.qd[:, 2])
    assert np.array_equal(r["R_y"], r.R[:, 1])
    assert np.array_equal(r["energy"], r.energy)
    assert np.array_equal(r["t"], r.t)
    assert "x''" in r and "psi" not in r
    assert r.keys() == list(r.columns["all"])
    with pytest.raises(KeyError, match=r"'ph' is not a column of this result \(did you mean 'phi'\?\)"):
        r["ph"]


def test_to_pandas_with_time_as_index(examples):
    pd = pytest.importorskip("pandas")
    r = nhdyn.load(examples / "sled.toml").simulate(t_end=1)
    frame = r.to_pandas(index="t")
    assert isinstance(frame, pd.DataFrame)
    assert frame.index.name == "t" and np.array_equal(frame.index.to_numpy(), r.t)
    assert list(frame.columns) == r.keys()[1:]
    assert np.array_equal(frame["y'"].to_numpy(), r.qd[:, 1])
    assert list(r.to_pandas().columns) == r.keys()  # without index: as before
    with pytest.raises(KeyError, match="index='time': not a column"):
        r.to_pandas(index="time")


def test_t_eval_gives_rows_at_exactly_those_times(examples):
    m = nhdyn.load(examples / "appell.toml")
    t_eval = np.array([0.1, 0.37, 1.0, 1.23, 2.0])
    r = m.simulate(t_eval=t_eval, rtol=1e-11, atol=1e-12)
    assert np.array_equal(r.t, t_eval)  # from t_eval[0] > t0 on: the start is not a row
    exact = appell_exact(r.t, 0.5)
    assert np.max(np.abs(r.q - exact)) < 1e-8 * np.max(np.abs(exact))
    # The same run on the output_step grid passes through t = 1 and 2: the same values there.
    grid = m.simulate(t_end=2.0, rtol=1e-11, atol=1e-12, output_step=0.01)
    for t in (1.0, 2.0):
        i, j = int(np.argmin(np.abs(grid.t - t))), int(np.argmin(np.abs(r.t - t)))
        assert abs(grid.q[i, 0] - r.q[j, 0]) < 1e-12 * abs(grid.q[i, 0])
    # E0 and h0 are the start's, not the first row's: the energy balance error at t = 1 is the
    # grid run's (h - h(0) - W, not h - h(0.1) - W).
    sled = nhdyn.load(examples / "sled.toml")
    a = sled.simulate(t_eval=[0.5, 1.0], rtol=1e-10, atol=1e-12)
    b = sled.simulate(t_end=1.0, rtol=1e-10, atol=1e-12, output_step=0.5)
    assert abs(a["balance_error"][-1] - b["balance_error"][-1]) < 1e-12
    assert abs(a["work"][-1] - b["work"][-1]) < 1e-12 and abs(b["work"][-1]) > 0


@pytest.mark.parametrize("t_eval, message", [
    ([0.5, 0.2, 1.0], r"must increase strictly; t_eval\[1\] = 0.2 follows 0.5"),
    ([0.1, float("nan")], r"t_eval\[1\] = nan is not finite"),
    ([-1.0, 1.0], r"t_eval\[0\] = -1.0 is before the model's start time t0 = 0"),
    ([[0.1, 0.2]], r"expected a non-empty 1-D array"),
    ([], r"expected a non-empty 1-D array"),
    ([0.0], r"the last time 0.0 must be after the model's start time t0 = 0"),
])
def test_bad_t_eval_is_refused_in_python_terms(examples, t_eval, message):
    with pytest.raises(nhdyn.InputError, match=message):
        nhdyn.load("sled").simulate(t_eval=t_eval)


def test_t_eval_past_t_end_is_refused():
    with pytest.raises(nhdyn.InputError, match=r"t_eval\[-1\] = 3.0 is after t_end = 2"):
        nhdyn.load("sled").simulate(t_eval=[1.0, 3.0], t_end=2)


def test_simulation_error_carries_its_time_and_the_rows_so_far():
    m = nhdyn.load("sled")
    with pytest.raises(nhdyn.SimulationError) as caught:
        m.simulate(integrator="rk4", step=5, t_end=20, output_step=5)
    e = caught.value
    assert isinstance(e.result, nhdyn.Result)
    assert 0 < e.t <= 20 and str(e).startswith("simulation of 'sled' failed at t = ")
    assert len(e.result.t) >= 1 and e.result.t[0] == 0.0 and e.result.t[-1] <= e.t
    assert np.array_equal(e.result.q[0], m.q0)


def test_messages_name_python_keywords_not_options():
    m = nhdyn.load("sled")
    with pytest.raises(nhdyn.ModelError) as caught:
        m.simulate(t_end=1, qd0=[1.0, 0.5, 1.0])  # y' = 0.5 breaks the blade at phi = 0
    assert "fix_initial=True" in str(caught.value) and "--fix-initial" not in str(caught.value)


def test_fix_initial_reports_its_changes(examples):
    m = nhdyn.load("sled")
    qd0 = np.array([1.0, 0.5, 1.0])
    r = m.simulate(t_end=1, qd0=qd0, fix_initial=True)
    fix = r.summary["initial_fix"]
    # The blade at phi = 0 is y' = 0: the fix zeroes y' and says by how much it moved each velocity.
    assert abs(fix["qd"][1]) < 1e-13
    assert np.allclose(fix["dqd"], fix["qd"] - qd0, atol=1e-15)
    assert np.array_equal(fix["dq"], np.zeros(3))
    assert np.array_equal(r.qd[0], fix["qd"])
    assert m.simulate(t_end=1).summary["initial_fix"] is None


def test_provenance_is_the_clis_and_to_csv_round_trips_through_report(examples, cli, tmp_path):
    path = str(examples / "sled.toml")
    m = nhdyn.load(path)
    m.parameters["a"] = 0.3
    r = m.simulate(t_end=1, rtol=1e-9)
    cli("simulate", path, "--set", "a=0.3", "--t-end", 1, "--rtol", 1e-9, "-q", "-o", tmp_path / "cli.csv")
    cli_text = (tmp_path / "cli.csv").read_text()
    assert r.provenance == cli_text[:cli_text.index("t,x,y,phi,")]
    assert "# parameters: m=1, a=0.3, " in r.provenance
    r.to_csv(tmp_path / "py.csv")
    names, rows = read_csv(tmp_path / "py.csv")
    cli_names, cli_rows = read_csv(tmp_path / "cli.csv")
    assert names == cli_names and np.array_equal(rows, cli_rows)  # the same run, the same doubles
    # The CLI's report reads the Python run's parameters from its header, and refuses another model.
    cli("report", tmp_path / "py.csv", "--model", path, "-q", "-o", tmp_path / "py.html")
    refused = cli("report", tmp_path / "py.csv", "--model", "sled", "-o", tmp_path / "x.html", check=False)
    assert refused.returncode == 2 and "it is another model" in refused.stderr


def test_report_from_python(examples, cli, tmp_path):
    path = str(examples / "sled.toml")
    m = nhdyn.load(path, a=0.3)
    r = m.simulate(t_end=1)
    note = m.report(r, tmp_path / "run.html")
    page = (tmp_path / "run.html").read_text()
    assert page.startswith("<!DOCTYPE html>\n<!--\n" + r.provenance)
    assert isinstance(note, str)
    assert '"summary":[["steps","{} (rejected {})"],'.format(r.summary["steps"], r.summary["rejected_steps"]) in page
    # The page is the CLI's report of the same rows with the same provenance: the same scene
    # (a = 0.3), plots and equations; only the title and the first lines of the summary differ.
    r.to_csv(tmp_path / "run.csv")
    cli("report", tmp_path / "run.csv", "--model", path, "-q", "-o", tmp_path / "cli.html")
    cli_page = (tmp_path / "cli.html").read_text()
    page = re.sub(r'"summary":\[\["steps","[^"]*"\],\["right-hand sides","[^"]*"\],', '"summary":[', page)
    cli_page = re.sub(r'"summary":\[\["results","[^"]*"\],', '"summary":[', cli_page)
    assert page.replace(str(tmp_path / "run.html"), "T") == cli_page.replace(str(tmp_path / "run.csv"), "T")
    with pytest.raises(nhdyn.InputError, match="the result is a run of model 'sled' from .*sled.toml, not of this "
                                                "model 'appell'"):
        nhdyn.load(examples / "appell.toml").report(r, tmp_path / "other.html")


def test_plot_draws_the_panels(examples, tmp_path):
    pytest.importorskip("matplotlib")
    r = nhdyn.load(examples / "sled.toml").simulate(t_end=1)
    figure = r.plot(path=tmp_path / "sled.png")
    assert (tmp_path / "sled.png").read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    titles = [ax.get_title() for ax in figure.axes]
    assert titles == ["coordinates", "velocities", "|constraint residuals|", "energy balance error h - h0 - W"]
    lines = figure.axes[0].get_lines()
    assert [line.get_label() for line in lines] == ["x", "y", "phi"]
    assert np.array_equal(lines[2].get_ydata(), r["phi"])
    chosen = r.plot(["phi", "R_y"])
    assert [ax.get_title() for ax in chosen.axes] == ["phi", "R_y"]
    with pytest.raises(KeyError, match="'psi' is not a column"):
        r.plot(["psi"])


def test_the_stubs_name_what_the_module_has():
    package = pathlib.Path(nhdyn.__file__).parent
    assert (package / "py.typed").exists()
    stub = ast.parse((package / "_nhdyn.pyi").read_text())
    declared = {node.name for node in stub.body if isinstance(node, (ast.FunctionDef, ast.ClassDef))}
    declared |= {t.id for node in stub.body if isinstance(node, ast.AnnAssign) for t in [node.target]}
    public = {name for name in dir(nhdyn._nhdyn) if not name.startswith("_")} | {"__version__", "__git_commit__"}
    assert public <= declared, "not in _nhdyn.pyi: {}".format(sorted(public - declared))
    assert declared - public <= {"ParameterValue", "Overrides", "FloatArray"}, sorted(declared - public)
