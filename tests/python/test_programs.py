"""Program motion from Python (docs/derivations/program-motion.md): the actuator forces u and the
programs' residuals in the Result, the feedback option, and their errors; checked against the sled's
closed form, against the CLI's CSV and against the runs without feedback."""

import math

import numpy as np
import pytest

import nhdyn
from conftest import read_csv


def sled_torque(t, m=1.0, a=0.5, alpha=math.pi / 6, g=9.81, omega=1.0, v0=1.0):
    """examples/sled_heading_program.toml's torque in closed form (program-motion.md section 6)."""
    v = v0 + g * math.sin(alpha) / omega * np.sin(omega * t) + a * omega ** 2 * t
    return m * a * omega * v + m * g * a * math.sin(alpha) * np.sin(omega * t)


def test_actuator_force_follows_the_closed_form(examples):
    m = nhdyn.load(examples / "sled_heading_program.toml")
    r = m.simulate(t_end=5.0, rtol=1e-10, atol=1e-12)
    assert r.u.shape == (len(r.t), 1)
    assert r.columns["actuators"] == ["u_heading"]
    assert r.columns["program_residuals"] == ["residual_pos_heading", "residual_vel_heading", "residual_acc_heading"]
    exact = sled_torque(r.t)
    assert np.max(np.abs(r.u[:, 0] - exact)) < 1e-7 * np.max(np.abs(exact))
    # The program holds: at acceleration level to round-off, at position level to the tolerance.
    assert r.program_residuals.shape == (len(r.t), 3)
    assert np.max(np.abs(r.program_residuals[:, 2])) < 1e-12
    assert np.max(np.abs(r.program_residuals[:, 0])) < 1e-8
    assert np.max(np.abs(r.q[:, 2] - r.t)) < 1e-8  # phi = omega t
    assert r.summary["max_program_acceleration_residual"] < 1e-12
    assert r.summary["max_program_position_residual"] == pytest.approx(np.max(np.abs(r.program_residuals[:, 0])))


def test_table_matches_the_cli_csv(examples, cli, tmp_path):
    m = nhdyn.load(examples / "sled_heading_program.toml")
    r = m.simulate(t_end=1.0)
    names, values = r.table()
    assert names[-4:] == ["u_heading", "residual_pos_heading", "residual_vel_heading", "residual_acc_heading"]
    assert values.shape == (len(r.t), len(names))
    if _has_pandas():
        assert list(r.to_pandas().columns) == names
    csv = tmp_path / "sled.csv"
    cli("simulate", examples / "sled_heading_program.toml", "--t-end", 1, "-o", csv, "-q")
    header, rows = read_csv(csv)
    assert header == names
    np.testing.assert_allclose(values, rows, rtol=1e-12, atol=1e-14)


def test_feedback_reduces_the_tracking_error(examples):
    m = nhdyn.load(examples / "arm_circle_program.toml")
    loose = dict(t_end=6.0, rtol=1e-6, atol=1e-12)
    free = m.simulate(**loose)
    held = m.simulate(program_feedback=(10.0, 10.0), **loose)
    # The tracking error is the position-level program residual (the hand's distance from its point).
    e_free = np.max(np.abs(free.program_residuals[:, :2]))
    e_held = np.max(np.abs(held.program_residuals[:, :2]))
    assert e_held < e_free / 30.0
    # With feedback the acceleration-level residual is the feedback term itself, no longer round-off;
    # without it the programs hold there to round-off.
    assert np.max(np.abs(free.program_residuals[:, 4:])) < 1e-10
    assert np.max(np.abs(held.program_residuals[:, 4:])) > 1e-10
    assert held.summary["max_program_position_residual"] == pytest.approx(e_held)


def test_feedback_errors(examples):
    arm = nhdyn.load(examples / "arm_circle_program.toml")
    with pytest.raises(nhdyn.InputError, match="program_feedback"):
        arm.simulate(t_end=0.1, program_feedback=(1.0,))
    with pytest.raises(nhdyn.InputError, match="alpha"):
        arm.simulate(t_end=0.1, program_feedback=(-1.0, 1.0))
    pendulum = nhdyn.load(examples / "double_pendulum.toml")
    with pytest.raises(nhdyn.InputError, match="needs programs"):
        pendulum.simulate(t_end=0.1, program_feedback=(1.0, 1.0))
    # A model without programs has empty actuator and program residual columns.
    r = pendulum.simulate(t_end=0.1)
    assert r.u.shape == (len(r.t), 0) and r.program_residuals.shape == (len(r.t), 0)


def _has_pandas():
    try:
        import pandas  # noqa: F401
    except ImportError:
        return False
    return True
