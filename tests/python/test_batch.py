"""Batch runs: the thread pool gives the same arrays as one run after another, whatever the
number of threads; a failed member keeps its error without losing the others; the CLI's batch
writes the same final states."""

import numpy as np
import pytest

import nhdyn
from conftest import read_csv

QUANTITIES = ("q", "qd", "qdd", "R", "residuals", "energy")


def sequential(model, name, values, **options):
    runs = []
    for value in values:
        m = model.copy()
        m.parameters[name] = value
        runs.append(m.simulate(**options))
    return runs


@pytest.mark.parametrize("threads", [1, 2])
def test_batch_over_parameters_equals_sequential_runs(examples, threads):
    m = nhdyn.load(examples / "sled.toml")
    values = np.linspace(0.2, 0.6, 7)
    batch = nhdyn.simulate_batch(m, parameters={"a": values}, t_end=2.0, threads=threads)
    assert batch.threads == threads and batch.ok.all() and len(batch) == 7
    assert batch.q.shape == (7, 201, 3) and batch.energy.shape == (7, 201)
    for i, run in enumerate(sequential(m, "a", values, t_end=2.0)):
        assert np.array_equal(batch.t, run.t)
        for name in QUANTITIES:
            assert np.array_equal(getattr(batch, name)[i], getattr(run, name)), (i, name)
        assert np.array_equal(batch.q_end[i], run.q[-1])
    assert np.array_equal(batch.parameters["a"], values)
    # different parameters give different runs (the comparison above is not vacuous)
    assert np.max(np.abs(batch.q[0] - batch.q[-1])) > 1e-2


@pytest.mark.parametrize("threads", [1, 2])
def test_batch_over_initial_states_equals_sequential_runs(examples, threads):
    m = nhdyn.load("sled")
    speeds = np.linspace(0.5, 2.0, 5)
    qd0 = np.column_stack([speeds, np.zeros(5), np.ones(5)])  # along the blade (phi = 0): consistent
    batch = nhdyn.simulate_batch(m, initial={"qd": qd0}, t_end=1.0, rtol=1e-10, threads=threads)
    assert batch.ok.all()
    for i in range(5):
        run = m.simulate(t_end=1.0, rtol=1e-10, qd0=qd0[i])
        for name in QUANTITIES:
            assert np.array_equal(getattr(batch, name)[i], getattr(run, name)), (i, name)


def test_a_failing_member_keeps_its_error_and_the_others(examples):
    m = nhdyn.load(examples / "sled.toml")
    qd0 = np.tile(m.qd0, (4, 1))
    qd0[2] = [1.0, 1.0, 0.0]  # off the blade constraint: refused before any step
    batch = nhdyn.simulate_batch(m, initial={"qd": qd0}, t_end=1.0, threads=2)
    assert list(batch.ok) == [True, True, False, True]
    assert "blade" in batch.messages[2] and batch.messages[0] == ""
    assert np.isnan(batch.q[2]).all() and np.isnan(batch.q_end[2]).all()
    run = m.simulate(t_end=1.0)
    for i in (0, 1, 3):
        assert np.array_equal(batch.q[i], run.q)
    frame = batch.summary()
    assert list(frame["status"]) == ["ok", "ok", "failed", "ok"]


def test_batch_refuses_wrong_shapes_and_names(examples):
    m = nhdyn.load(examples / "sled.toml")
    with pytest.raises(nhdyn.InputError, match="shape \\(runs, n\\)"):
        nhdyn.simulate_batch(m, initial={"q": np.zeros((3, 2))})
    with pytest.raises(nhdyn.InputError, match="other inputs give 3 runs"):
        nhdyn.simulate_batch(m, parameters={"a": [0.1, 0.2, 0.3], "rho": [0.7, 0.8]})
    with pytest.raises(nhdyn.InputError, match="1-D"):
        nhdyn.simulate_batch(m, parameters={"a": [[0.1, 0.2]]})
    with pytest.raises(nhdyn.InputError, match="no parameter 'b'"):
        nhdyn.simulate_batch(m, parameters={"b": [0.1]})
    with pytest.raises(nhdyn.InputError, match="unknown key"):
        nhdyn.simulate_batch(m, initial={"v": np.zeros((1, 3))})
    with pytest.raises(nhdyn.InputError, match="give parameters"):
        nhdyn.simulate_batch(m)
    with pytest.raises(nhdyn.InputError, match="threads"):
        nhdyn.simulate_batch(m, parameters={"a": [0.1]}, threads=-1)


def test_cli_batch_writes_the_same_final_states(examples, cli, tmp_path):
    out = tmp_path / "out"
    cli("batch", examples / "sled.toml", "--grid", "a=0.2:0.6:3", "--grid", "phi'(0)=0.5:1:2", "--t-end", 1,
        "--threads", 2, "--write-runs", "-q", "-o", out)
    with open(out / "summary.csv") as f:
        lines = [line for line in f if not line.startswith("#")]  # the provenance header first
    header = lines[0].rstrip("\n").split(",")
    rows = [line.rstrip("\n").split(",") for line in lines[1:]]
    assert header[:5] == ["run", "a", "phi'(0)", "status", "t_reached"]
    assert len(rows) == 6 and all(row[3] == "ok" for row in rows)
    m = nhdyn.load(examples / "sled.toml")
    for k, row in enumerate(rows):
        a, w = float(row[1]), float(row[2])
        mk = m.copy()
        mk.parameters["a"] = a
        qd0 = mk.qd0.copy()
        qd0[2] = w
        run = mk.simulate(t_end=1.0, qd0=qd0)
        final = np.array([float(x) for x in row[5:11]])
        assert np.array_equal(final, np.concatenate([run.q[-1], run.qd[-1]])), k
        names, table = read_csv(out / "run_{}.csv".format(k))
        assert np.array_equal(table, run.table()[1])
    # y'(0) = 1 violates the blade constraint: that run fails, the other is kept, exit 1
    failed = cli("batch", examples / "sled.toml", "--grid", "y'(0)=0:1:2", "-q", "-o", tmp_path / "f", check=False)
    assert failed.returncode == 1
    with open(tmp_path / "f" / "summary.csv") as f:
        lines = [line for line in f.read().splitlines() if not line.startswith("#")]
    assert lines[1].split(",")[2] == "ok" and lines[2].split(",")[2] == "failed" and "blade" in lines[2]
    bad = cli("batch", examples / "sled.toml", "--grid", "v=0:1:2", "-q", "-o", tmp_path / "g", check=False)
    assert bad.returncode == 2 and "no parameter 'v'" in bad.stderr
