"""nhdyn.dask on a LocalCluster of two worker processes gives the same arrays as the batch on one
machine: the workers rebuild the model from its text and parameter overrides."""

import numpy as np
import pytest

import nhdyn

distributed = pytest.importorskip("dask.distributed")
import nhdyn.dask  # noqa: E402


@pytest.fixture(scope="module")
def client():
    cluster = distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=True, dashboard_address=None)
    c = distributed.Client(cluster)
    yield c
    c.close()
    cluster.close()


def test_dask_gives_the_arrays_of_the_local_batch(examples, client):
    m = nhdyn.load(examples / "sled.toml", rho=0.8)  # the override travels with the model
    values = np.linspace(0.2, 0.6, 9)
    local = nhdyn.simulate_batch(m, parameters={"a": values}, t_end=1.0, threads=1)
    spread = nhdyn.dask.simulate_batch(client, m, parameters={"a": values}, t_end=1.0, chunk_size=2)
    assert spread.ok.all()
    assert np.array_equal(spread.t, local.t)
    for name in ("q", "qd", "qdd", "R", "residuals", "energy", "q_end", "qd_end", "max_residual"):
        assert np.array_equal(getattr(spread, name), getattr(local, name)), name
    # both workers took part
    assert len(client.scheduler_info()["workers"]) == 2


def test_dask_keeps_a_failing_member(examples, client):
    m = nhdyn.load("sled")
    qd0 = np.tile(m.qd0, (5, 1))
    qd0[3] = [1.0, 1.0, 0.0]
    spread = nhdyn.dask.simulate_batch(client, m, initial={"qd": qd0}, t_end=0.5, chunk_size=2)
    assert list(spread.ok) == [True, True, True, False, True]
    assert "blade" in spread.messages[3]
    assert np.array_equal(spread.q[0], m.simulate(t_end=0.5).q)


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


def test_dask_numbers_runs_in_the_batch_and_keeps_the_worker_logs_clean(client):
    """Errors and warnings name a run by its number in the whole batch, not in its chunk; an error
    is raised on the client with its own type, and no worker logs a failed task (whose log would
    repeat the whole model text per chunk). x = cos(sqrt(k) t) falls below 0 within t_end = 1 for
    k = 4 only, so the stop condition never holds on runs 0, 2 and 4."""
    m = nhdyn.loads(OSCILLATOR)
    with pytest.raises(nhdyn.InputError, match=r"^run 3: parameter k = nan is not a finite number"):
        nhdyn.dask.simulate_batch(client, m, parameters={"k": [1.0, 2.0, 3.0, float("nan")]}, t_end=0.1,
                                  chunk_size=2)
    with pytest.raises(nhdyn.InputError, match="rtol = -1"):
        nhdyn.dask.simulate_batch(client, m, parameters={"k": [1.0, 2.0, 3.0]}, t_end=0.1, chunk_size=2, rtol=-1)
    with pytest.raises(nhdyn.InputError, match="no runs"):
        nhdyn.dask.simulate_batch(client, m, parameters={"k": []}, t_end=0.1)
    logs = client.get_worker_logs()
    assert not any("Compute Failed" in line for worker in logs.values() for _, line in worker), logs
    with pytest.warns(nhdyn.StopConditionWarning) as caught:
        spread = nhdyn.dask.simulate_batch(client, m, parameters={"k": [1.0, 4.0, 1.0, 4.0, 1.0]}, t_end=1.0,
                                           chunk_size=2, stop_when="x < 0")
    texts = [str(w.message) for w in caught]
    assert len(texts) == 1 and texts[0].endswith("(runs 0, 2 and 4 of 5)"), texts
    assert [s["stopped_by"] for s in spread.summaries] == [None, "x < 0", None, "x < 0", None]
