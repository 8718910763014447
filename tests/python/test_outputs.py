"""Derived outputs from Python (docs/model-format.md [outputs]): Result.outputs holds each output
by name, Result.table() puts them last as the CSV does, and their values follow the closed forms of
the Cartesian pendulum (energy -m g l cos(theta0), tension m g (3 cos(theta) - 2 cos(theta0)));
parameters set from Python reach the outputs; a multibody model's points come without writing."""

import math

import numpy as np

import nhdyn


def test_pendulum_outputs_follow_their_closed_forms(examples):
    m = nhdyn.load(examples / "pendulum_outputs.toml")
    r = m.simulate(t_end=3.0, rtol=1e-11, atol=1e-13)
    assert list(r.outputs) == ["total_energy", "tension", "tension_closed_form", "theta", "speed"]
    mass, g, l, theta0 = 0.5, 9.81, 1.5, 2.0
    assert np.max(np.abs(r.outputs["total_energy"] + mass * g * l * math.cos(theta0))) < 1e-8
    cos_theta = -r.q[:, 1] / l
    assert np.max(np.abs(r.outputs["tension"] - mass * g * (3 * cos_theta - 2 * math.cos(theta0)))) < 1e-7
    names, values = r.table()
    assert names[-5:] == list(r.outputs)
    assert values.shape == (len(r.t), len(names))
    assert np.array_equal(values[:, -1], r.outputs["speed"])
    # The slack event, on the tension (read from the reactions), is a row of the outputs.
    slack = [e for e in r.events if e["name"] == "slack"]
    assert slack
    for e in slack:
        assert abs(-e["q"][1] / l - 2 * math.cos(theta0) / 3) < 1e-9


def test_parameters_reach_the_outputs(examples):
    m = nhdyn.load(examples / "pendulum_outputs.toml", m=2.0)
    r = m.simulate(t_end=0.1)
    assert abs(r.outputs["total_energy"][0] + 2.0 * 9.81 * 1.5 * math.cos(2.0)) < 1e-12


def test_multibody_points_are_outputs(examples):
    r = nhdyn.load(examples / "rolling_disk_bodies.toml").simulate(t_end=0.2)
    theta = r.q[:, 3]
    assert np.max(np.abs(r.outputs["disk_z"] - 0.2 * np.cos(theta))) < 1e-13
