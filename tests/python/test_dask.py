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
