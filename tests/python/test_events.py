"""Events from Python: the Cartesian pendulum's period from its zero crossings against the closed
form 4 sqrt(l/g) K(sin(theta0/2)), a stop condition, and bad input raised before the run."""

import math

import numpy as np
import pytest

import nhdyn


def complete_elliptic_k(k):
    """K(k) by the arithmetic-geometric mean: K = pi / (2 agm(1, sqrt(1 - k^2)))."""
    a, b = 1.0, math.sqrt(1.0 - k * k)
    for _ in range(40):
        a, b = (a + b) / 2, math.sqrt(a * b)
    return math.pi / (2 * a)


def test_pendulum_period_from_its_events(examples):
    m = nhdyn.load(examples / "pendulum_cartesian.toml")
    r = m.simulate(integrator="dop853", rtol=1e-13, atol=1e-15, events={"bottom": "x"})
    period = 4 * math.sqrt(1.5 / 9.81) * complete_elliptic_k(math.sin(1.0))
    times = [e["t"] for e in r.events]
    assert [e["name"] for e in r.events] == ["bottom"] * 6
    assert abs(times[0] - period / 4) < 1e-10
    for k in range(len(times) - 2):
        assert abs(times[k + 2] - times[k] - period) < 1e-10
    # each event is a row of the outputs, with x = 0 there
    for e in r.events:
        row = np.flatnonzero(r.t == e["t"])
        assert row.size == 1 and abs(r.q[row[0], 0]) < 1e-13
    assert r.summary["stopped_by"] is None


def test_stop_when_ends_the_run(examples):
    m = nhdyn.load(examples / "pendulum_cartesian.toml")
    r = m.simulate(stop_when="x < 0")
    assert r.summary["stopped_by"] == "x < 0"
    assert len(r.events) == 1 and r.t[-1] == r.events[0]["t"]
    period = 4 * math.sqrt(1.5 / 9.81) * complete_elliptic_k(math.sin(1.0))
    assert abs(r.t[-1] - period / 4) < 1e-8


def test_bad_events_are_refused(examples):
    m = nhdyn.load(examples / "pendulum_cartesian.toml")
    with pytest.raises(nhdyn.InputError, match="did you mean 'x'"):
        m.simulate(stop_when="abs(xx) > 1")
    with pytest.raises(nhdyn.InputError, match="expected a condition"):
        m.simulate(stop_when="abs(x) 1")
    with pytest.raises(nhdyn.InputError, match="at least 1"):
        m.simulate(max_steps=0)


def test_events_on_contact_forces(examples):
    """The falling disk of docs/derivations/contact-forces.md 6.4 (examples/rolling_disk_liftoff.toml):
    its normal force disk_N falls through zero at cos(theta) = (2k + sqrt(4k^2 - 3)) / 6,
    k = cos(0.1); located to the integration's accuracy (100 rtol, rtol = 1e-11)."""
    m = nhdyn.load(examples / "rolling_disk_liftoff.toml")
    k = math.cos(0.1)
    theta_star = math.acos((2 * k + math.sqrt(4 * k * k - 3)) / 6)
    r = m.simulate()  # the file's [[events]] liftoff: when = "disk_N", falling, stop
    assert r.summary["stopped_by"] == "liftoff"
    assert len(r.events) == 1
    assert abs(r.events[0]["q"][3] - theta_star) < 1e-9
    # the event's row is the last one, with disk_N zero to round-off
    n_column = r.columns["contact_forces"].index("disk_N")
    assert r.t[-1] == r.events[0]["t"]
    assert abs(r.contact_forces[-1, n_column]) < 1e-11
    # stop_when and events name the columns too
    r = m.simulate(stop_when="disk_N < m*g/10")
    tenth = math.acos((8 * k + math.sqrt(64 * k * k - 24)) / 24)
    assert abs(r.events[0]["q"][3] - tenth) < 1e-9
    r = m.simulate(events={"slide": "disk_Flat"})
    assert [e["name"] for e in r.events] == ["slide", "liftoff"]
    assert abs(r.events[0]["q"][3] - math.acos(2 * k / 3)) < 1e-9


def test_bad_contact_force_events_are_refused(examples):
    m = nhdyn.load(examples / "pendulum_cartesian.toml")
    with pytest.raises(nhdyn.InputError, match="has no contact forces"):
        m.simulate(stop_when="disk_N < 0")
