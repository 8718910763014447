"""Hostile input against the Python package (docs/cli.md, "What bad input gets"): deeply nested
parameter expressions are refused like the model file's, thread counts must be whole numbers and
are capped, batch arrays keep their documented shapes for one coordinate, a batch with events
gives each run its own times and events (the same as one run), and Ctrl-C stops a batch promptly."""

import os
import signal
import stat
import subprocess
import sys
import textwrap
import time

import numpy as np
import pytest

import nhdyn

OSCILLATOR = """name = "oscillator"
coordinates = ["x"]
kinetic_energy = "m/2 * x'^2"
potential_energy = "k/2 * x^2"
[parameters]
m = 1.0
k = 1.0
[initial]
position = { x = 1 }
velocity = { x = 0 }
"""


@pytest.fixture
def oscillator(tmp_path):
    path = tmp_path / "oscillator.toml"
    path.write_text(OSCILLATOR)
    return nhdyn.load(path)


def test_deeply_nested_parameter_expression_is_refused(oscillator):
    for text in ("sqrt(" * 20000 + "2" + ")" * 20000, "-" * 100000 + "1"):
        with pytest.raises(nhdyn.InputError, match="nested deeper than 256 levels"):
            oscillator.parameters["k"] = text
    assert oscillator.parameters["k"] == 1.0
    oscillator.parameters["k"] = "(" * 100 + "4" + ")" * 100
    assert oscillator.parameters["k"] == 4.0


@pytest.mark.parametrize("bad", [2.5, "2", True, None])
def test_threads_must_be_a_whole_number(oscillator, bad):
    with pytest.raises(nhdyn.InputError, match="threads"):
        nhdyn.simulate_batch(oscillator, parameters={"k": [1.0]}, t_end=0.1, threads=bad)


def test_huge_thread_counts_are_capped(oscillator):
    for threads in (40000, 10**20):
        b = nhdyn.simulate_batch(oscillator, parameters={"k": [1.0, 2.0, 3.0]}, t_end=0.1, threads=threads)
        assert b.ok.all() and 1 <= b.threads <= 3


def test_boolean_parameter_values_are_refused(oscillator):
    with pytest.raises(nhdyn.InputError, match="booleans"):
        nhdyn.simulate_batch(oscillator, parameters={"k": [True, False]}, t_end=0.1)


def test_complex_and_boolean_times_and_sweep_values_are_refused(oscillator):
    # NumPy would drop the imaginary part with a warning only, and read True as 1.
    with pytest.raises(nhdyn.InputError, match="t_eval: expected real numbers.*complex"):
        oscillator.simulate(t_eval=np.array([0.0, 1.0 + 1e-3j, 2.0]))
    with pytest.raises(nhdyn.InputError, match="t_eval: expected real numbers.*booleans"):
        oscillator.simulate(t_eval=[False, True])
    with pytest.raises(nhdyn.InputError, match="sweep values: expected real numbers"):
        oscillator.sweep("k", [True, False])
    with pytest.raises(nhdyn.InputError, match="sweep values: expected real numbers"):
        oscillator.sweep("k", np.linspace(1, 2, 3) + 0j)
    # A boolean among numbers (NumPy makes the list numbers, True 1).
    with pytest.raises(nhdyn.InputError, match="t_eval: entry 1 is True, a boolean, not a number"):
        oscillator.simulate(t_eval=[0, True, 1.5])
    with pytest.raises(nhdyn.InputError, match="sweep values: entry 0 is True, a boolean"):
        oscillator.sweep("k", [np.bool_(True), 2.0])
    # Whole numbers stay numbers: times 0, 1, 2 as integers run.
    assert list(oscillator.simulate(t_eval=[0, 1, 2]).t) == [0.0, 1.0, 2.0]


def test_one_coordinate_keeps_the_documented_shapes(oscillator):
    b = nhdyn.simulate_batch(oscillator, parameters={"k": [1.0, 4.0]}, t_end=1.0)
    rows = len(b.t)
    assert b.q.shape == (2, rows, 1) and b.qd.shape == (2, rows, 1) and b.R.shape == (2, rows, 1)
    assert b.energy.shape == (2, rows) and b.q_end.shape == (2, 1)
    # x = cos(sqrt(k) t): a closed form the columns must meet
    assert np.max(np.abs(b.q[1, :, 0] - np.cos(2.0 * b.t))) < 1e-5


def test_batch_with_events_gives_each_run_its_times_and_events(oscillator):
    b = nhdyn.simulate_batch(oscillator, parameters={"k": [1.0, 4.0]}, t_end=3.0, events={"zero": "x"})
    assert b.t.ndim == 2 and b.t.shape[0] == 2
    for i, k in enumerate((1.0, 4.0)):
        m = oscillator.copy()
        m.parameters["k"] = k
        run = m.simulate(t_end=3.0, events={"zero": "x"})
        rows = len(run.t)
        assert np.array_equal(b.t[i, :rows], run.t) and np.isnan(b.t[i, rows:]).all()
        assert np.array_equal(b.q[i, :rows], run.q)
        # x = cos(sqrt(k) t) crosses zero at (2j+1) pi / (2 sqrt(k))
        expected = [(2 * j + 1) * np.pi / (2 * np.sqrt(k)) for j in range(3) if (2 * j + 1) * np.pi / (2 * np.sqrt(k)) < 3]
        got = [e["t"] for e in b.events[i]]
        assert len(got) == len(expected) and np.max(np.abs(np.array(got) - expected)) < 1e-6
        for e in b.events[i]:  # the event's row is at its own time, with x = 0 there
            row = int(np.flatnonzero(b.t[i] == e["t"])[0])
            assert abs(b.q[i, row, 0]) < 1e-9


def test_ctrl_c_stops_a_batch_promptly(tmp_path):
    (tmp_path / "oscillator.toml").write_text(OSCILLATOR)
    script = textwrap.dedent("""
        import os, signal, sys, threading, time
        import nhdyn
        m = nhdyn.load(sys.argv[1])
        threading.Timer(1.0, lambda: os.kill(os.getpid(), signal.SIGINT)).start()
        start = time.monotonic()
        try:
            nhdyn.simulate_batch(m, parameters={"k": [1.0 + i for i in range(4000)]}, t_end=200.0, threads=2,
                                 keep_trajectories=False)
            print("finished", time.monotonic() - start)
        except KeyboardInterrupt:
            print("interrupted", time.monotonic() - start)
    """)
    out = subprocess.run([sys.executable, "-c", script, str(tmp_path / "oscillator.toml")], capture_output=True,
                         text=True, timeout=300, env=dict(os.environ))
    assert out.stdout.startswith("interrupted"), out.stdout + out.stderr
    assert float(out.stdout.split()[1]) < 10.0


def test_a_stop_condition_that_never_holds_is_warned(oscillator):
    """The sentence of `nhdyn simulate`'s warning, in Python's terms, as a StopConditionWarning;
    a batch says it once, naming the runs: x = cos(sqrt(k) t) never exceeds 1, and falls below
    0 at pi / (2 sqrt(k)), within t_end = 1 for k = 4 (0.785) but not for k = 1 (1.571)."""
    with pytest.warns(nhdyn.StopConditionWarning) as caught:
        r = oscillator.simulate(t_end=1.0, stop_when="x > 2")
    texts = [str(w.message) for w in caught]
    assert texts == ["nhdyn: oscillator: the stop condition stop_when=\"x > 2\" never became true between t = 0 and "
                     "t = 1: the run went to the end; check its sign, direction or threshold"]
    assert r.summary["unmet_stops"] and r.summary["stopped_by"] is None
    with pytest.warns(nhdyn.StopConditionWarning) as caught:
        b = nhdyn.simulate_batch(oscillator, parameters={"k": [1.0, 4.0, 1.0]}, t_end=1.0, stop_when="x < 0")
    texts = [str(w.message) for w in caught]
    assert len(texts) == 1 and texts[0].endswith("check its sign, direction or threshold (runs 0 and 2 of 3)"), texts
    assert [s["stopped_by"] for s in b.summaries] == [None, "x < 0", None]
    import warnings
    with warnings.catch_warnings():
        warnings.simplefilter("error", nhdyn.StopConditionWarning)
        oscillator.simulate(t_end=2.0, stop_when="x < 0")  # met: no warning


def test_a_non_finite_parameter_value_names_its_run(oscillator):
    with pytest.raises(nhdyn.InputError, match=r"run 3: parameter k = nan is not a finite number"):
        nhdyn.simulate_batch(oscillator, parameters={"k": [1.0, 2.0, 3.0, float("nan")]}, t_end=0.1)


def test_a_batch_larger_than_memory_is_refused_before_any_run(oscillator):
    # It ran until the system ended Python (or the machine thrashed for minutes).
    with pytest.raises(nhdyn.InputError, match=r"simulate_batch: 100 runs of 100000002 rows .* GB held at once, more "
                                               r"than this machine's"):
        nhdyn.simulate_batch(oscillator, parameters={"k": np.linspace(1.0, 2.0, 100)}, t_end=1e5, output_step=1e-3)


def test_a_non_finite_number_for_a_parameter_is_named(tmp_path):
    # float('nan') was read as the text 'nan', an unknown parameter ("did you mean ...").
    path = tmp_path / "oscillator.toml"
    path.write_text(OSCILLATOR)
    for value in (float("nan"), float("inf"), -float("inf")):
        with pytest.raises(nhdyn.InputError, match=r"parameter k = -?(nan|inf): the value is not a finite number"):
            nhdyn.load(path, k=value)


def test_a_non_finite_initial_value_names_its_run(oscillator):
    # It was run, and failed with words that blamed the model's overflow.
    with pytest.raises(nhdyn.InputError, match=r"batch run 1: the initial value x'\(0\) = nan is not a finite number"):
        nhdyn.simulate_batch(oscillator, initial={"qd": [[0.0], [float("nan")]]}, t_end=0.1)


# Each call passes a keyword that the command line spells as an option; the message must name the
# keyword (or the Python way to do it), never the option ("--set", "--cyclic", ...).
SLED = """name = "sled"
coordinates = ["x", "y", "phi"]
kinetic_energy = "m/2 * (x'^2 + y'^2) + m*a*phi' * (cos(phi)*y' - sin(phi)*x') + m*rho^2/2 * phi'^2"
[parameters]
m = 1.0
a = 0.5
rho = 0.7
[[constraints]]
name = "blade"
velocity = "-sin(phi)*x' + cos(phi)*y'"
[initial]
position = { x = 0, y = 0, phi = 0 }
velocity = { x = 1, y = 0, phi = 0 }
"""
KEYWORD_MESSAGES = [
    (lambda m: nhdyn.loads(OSCILLATOR, k="1/0"), "k=1/0: '1/0' has no finite value: it divides by zero"),
    (lambda m: nhdyn.loads(OSCILLATOR, zz=1), "zz=1: model 'oscillator' has no parameter 'zz'"),
    (lambda m: m.simulate(1.0, max_steps=0), "the step budget max_steps = 0 must be at least 1"),
    (lambda m: m.simulate(1.0, stop_when="x"), 'stop_when="x": expected a condition'),
    (lambda m: m.simulate(1.0, events={"": "x"}), 'events={"": "x"}: expected a name'),
    (lambda m: m.simulate(1.0, program_feedback=(1, 1)), "program_feedback needs programs"),
    (lambda m: m.simulate(1.0, complement="analytic"), "choose complement qr or partition"),
    (lambda m: nhdyn.simulate_batch(m, parameters={"k": [1.0]}, t_end=0.1, max_steps=0), "max_steps = 0"),
    (lambda m: nhdyn.simulate_batch(m, parameters={"k": [1.0]}, t_end=0.1, stop_when="x"), 'stop_when="x"'),
    (lambda m: nhdyn.simulate_batch(m, parameters={"k": [1.0]}, t_end=0.1, events={"": "x"}), 'events={"": "x"}'),
    (lambda m: nhdyn.simulate_batch(m, parameters={"k": [1.0]}, t_end=0.1, complement="analytic"),
     "choose complement qr"),
    (lambda m: nhdyn.simulate_batch(m, parameters={"k": [1.0]}, t_end=0.1, program_feedback=(1, 1)),
     "program_feedback needs programs"),
    (lambda m: m.linearize(), "the coordinates that may move steadily with cyclic=[...]"),
    (lambda m: nhdyn.loads(SLED).linearize(cyclic=["zz"]), "cyclic=[...]: 'zz' is not a coordinate"),
    (lambda m: nhdyn.loads(SLED).linearize(cyclic=["x", "y"], independent=["zz"]),
     "independent=[...]: 'zz' is not a coordinate"),
    (lambda m: nhdyn.loads(SLED).linearize(cyclic=["x", "y"], speeds=["zz"]), "speeds=[...]: 'zz' is not a coordinate"),
    (lambda m: m.sweep("k", [2.0, 1.0]), "sweep values: give increasing values"),
    (lambda m: m.sweep("k", np.linspace(0.0, 1.0, 1000001)), "len(values) = 1000001: give the number of grid points"),
]


@pytest.mark.parametrize("call, expected", KEYWORD_MESSAGES)
def test_messages_name_the_python_keyword_not_the_command_line_option(oscillator, call, expected):
    with pytest.raises(nhdyn.Error) as caught:
        call(oscillator)
    message = str(caught.value)
    assert expected in message, message
    assert "--" not in message, message


def test_a_size_or_mass_set_negative_is_refused_and_the_model_kept(examples):
    m = nhdyn.load(examples / "ball_in_bowl.toml")
    radius = m.parameters["r"]
    with pytest.raises(nhdyn.InputError, match=r"ball_in_bowl.toml:38:.*contact 'ball': sphere r: \"r\" must be positive, but it is -0.1"):
        m.parameters["r"] = -0.1
    assert m.parameters["r"] == radius
    with pytest.raises(nhdyn.InputError, match=r"body 'ball': mass: \"m\" must be positive"):
        nhdyn.simulate_batch(m, parameters={"m": [1.0, -1.0]}, t_end=0.01)
    m.parameters["r"] = 0.04  # a positive one is taken
    assert m.parameters["r"] == 0.04
    # The semi-axes of an ellipsoid more than 1e6 apart: flat to double precision.
    rattleback = nhdyn.load(examples / "rattleback.toml")
    with pytest.raises(nhdyn.InputError, match=r'its sizes "a" = 1e-09 and "b" = 0.03 are more than 1e\+06 apart'):
        rattleback.parameters["a"] = 1e-9
    assert rattleback.parameters["a"] == 0.2


def test_outputs_never_replace_the_model_file_and_take_only_paths(tmp_path):
    # to_csv and report wrote over the model file they were run from (the command line refuses
    # it), to_csv truncated before writing, and an int was taken as a file descriptor and closed.
    path = tmp_path / "oscillator.toml"
    path.write_text(OSCILLATOR)
    m = nhdyn.load(path)
    r = m.simulate(0.1)
    for call in (lambda: r.to_csv(path), lambda: m.report(r, path), lambda: r.to_csv(str(path))):
        with pytest.raises(nhdyn.InputError, match="is the model file of this run; write to another path"):
            call()
    assert path.read_text() == OSCILLATOR
    for bad in (True, 1, 3.5, None):
        with pytest.raises(nhdyn.InputError, match="to_csv: expected a file path"):
            r.to_csv(bad)
    out = tmp_path / "run.csv"
    r.to_csv(out)
    assert out.read_text().startswith("# nhdyn version")
    assert [p.name for p in tmp_path.iterdir() if p.name.endswith(".tmp")] == []


def test_to_csv_writes_by_the_command_lines_rules(examples, tmp_path):
    # Both to_csv replaced a device, a pipe or a symbolic link by a regular file (as root, /dev/full
    # itself), reset a replaced file's mode to the umask's, took a full disk silently, and
    # Optimum.to_csv wrote over its model file.
    model_path = tmp_path / "double_integrator.toml"
    model_path.write_text((examples / "double_integrator.toml").read_text())
    model = nhdyn.load(model_path)
    optimum = model.optimize()
    result = nhdyn.load("sled").simulate(t_end=0.5)
    with pytest.raises(nhdyn.InputError, match="is the model file of this run"):
        optimum.to_csv(model_path)
    assert model_path.read_text() == (examples / "double_integrator.toml").read_text()
    for table in (optimum, result):
        target = tmp_path / "target.csv"
        target.write_text("old\n")
        link = tmp_path / "link.csv"
        if link.is_symlink():
            link.unlink()
        link.symlink_to(target.name)
        table.to_csv(link)
        first_line = "t,x,x',x'',u_F" if table is optimum else "# nhdyn version"
        assert link.is_symlink() and target.read_text().startswith(first_line), "written through the link"
        private = tmp_path / "private.csv"
        private.write_text("old\n")
        private.chmod(0o600)
        table.to_csv(private)
        assert private.stat().st_mode & 0o777 == 0o600 and private.read_text() != "old\n"
        if os.geteuid() == 0:  # device nodes of our own (mknod needs root); CI runs as root
            null, full = tmp_path / "null", tmp_path / "full"
            for node, minor in ((null, 3), (full, 7)):
                if not node.exists():
                    os.mknod(node, 0o666 | stat.S_IFCHR, os.makedev(1, minor))
            table.to_csv(null)
            with pytest.raises(nhdyn.FileError, match="No space left on device"):
                table.to_csv(full)
            assert null.is_char_device() and full.is_char_device()
    assert [p.name for p in tmp_path.iterdir() if p.name.endswith(".tmp")] == []


def test_one_coordinate_name_given_as_a_string_is_that_name(examples):
    # cyclic="psi" was read as the letters p, s, i ("'p' is not a coordinate").
    m = nhdyn.load(examples / "rolling_disk_upright.toml")
    one = m.linearize(cyclic="psi")
    listed = m.linearize(cyclic=["psi"])
    assert "psi" in one.cyclic and one.cyclic == listed.cyclic
    np.testing.assert_array_equal(one.state_matrix, listed.state_matrix)
    # A name that is not a string is named with its keyword (pybind11 listed its C++ signatures).
    with pytest.raises(nhdyn.InputError, match=r"cyclic: entry 0 is 1 \(int\), not a coordinate name"):
        m.linearize(cyclic=[1])
    with pytest.raises(nhdyn.InputError, match=r"speeds=3: expected a coordinate name or a list of names"):
        m.sweep("m", np.linspace(1, 2, 3), speeds=3)


def test_report_frames_are_a_whole_number(oscillator, tmp_path):
    r = oscillator.simulate(t_end=1.0)
    for bad in (1.5, "3", True):
        with pytest.raises(nhdyn.InputError, match=r"max_frames=.*: give a whole number of rows"):
            oscillator.report(r, tmp_path / "r.html", max_frames=bad)
    for few in (np.int64(1), -2**40):
        with pytest.raises(nhdyn.InputError, match=r"max_frames=-?\d+: give at least 2"):
            oscillator.report(r, tmp_path / "r.html", max_frames=few)
    assert not (tmp_path / "r.html").exists()
    oscillator.report(r, tmp_path / "r.html", max_frames=10**30)  # beyond a C int: every row
    assert (tmp_path / "r.html").read_text().startswith("<!DOCTYPE html>")


def test_a_bool_is_not_a_number_and_a_result_is_not_iterable(oscillator):
    # t_end=True ran for 1 s; iter(result) asked for result[0] ("KeyError: 0 is not a column");
    # plot([]) failed inside matplotlib.
    with pytest.raises(nhdyn.InputError, match=r"t_end=True: give a number, not a bool"):
        oscillator.simulate(t_end=True)
    with pytest.raises(nhdyn.InputError, match=r"rtol=False: give a number, not a bool"):
        oscillator.simulate(0.1, rtol=False)
    r = oscillator.simulate(0.1)
    with pytest.raises(TypeError, match="not iterable"):
        iter(r)
    with pytest.raises(nhdyn.InputError, match=r"plot: columns=\[\] names no column"):
        r.plot([])
    assert r["x"][0] == 1.0
