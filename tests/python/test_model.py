"""nhdyn from Python: loading, one run, parameters, equations, linearization, sweep and errors,
checked against closed forms and against the CLI."""

import math

import numpy as np
import pytest

import nhdyn
from conftest import read_csv


def appell_exact(t, a, g=9.81):
    """Appell's particle from examples/appell.toml's initial state (its [solution] section):
    the horizontal speed grows at c = g a / (1 + a^2) along (1, 0.5)/sqrt(1.25)."""
    s = math.sqrt(1.25) * t + g * a / (1 + a * a) * t * t / 2
    return np.column_stack([s / math.sqrt(1.25), 0.5 * s / math.sqrt(1.25), a * s])


def test_appell_against_its_closed_form(examples):
    m = nhdyn.load(examples / "appell.toml")
    r = m.simulate(t_end=2.0, rtol=1e-11, atol=1e-12)
    assert r.t[0] == 0.0 and r.t[-1] == 2.0 and len(r.t) == 201
    assert r.q.shape == (201, 3) and r.qd.shape == (201, 3) and r.qdd.shape == (201, 3) and r.R.shape == (201, 3)
    exact = appell_exact(r.t, 0.5)
    assert np.max(np.abs(r.q - exact)) < 1e-8 * np.max(np.abs(exact))
    # The reactions do no work: the energy stays, and the constraint holds.
    assert np.max(np.abs(r.energy - r.energy[0])) < 1e-8
    assert np.max(np.abs(r.residuals)) < 1e-8


def test_parameter_changed_from_python_follows_the_closed_form(examples):
    m = nhdyn.load(examples / "appell.toml")
    m.parameters["a"] = 0.3  # enters the initial velocity z' = a |(x', y')| and the dynamics
    assert m.parameters["a"] == 0.3
    r = m.simulate(t_end=1.0, rtol=1e-11, atol=1e-12)
    exact = appell_exact(r.t, 0.3)
    assert np.max(np.abs(r.q - exact)) < 1e-8 * np.max(np.abs(exact))
    # and differs from a = 0.5 by far more than the tolerance (the check is not vacuous)
    assert np.max(np.abs(r.q - appell_exact(r.t, 0.5))) > 1e-2


def test_parameters_changed_from_python_equal_a_recompiled_model(examples, cli, tmp_path):
    m = nhdyn.load(examples / "sled.toml")
    m.parameters["a"] = 0.3
    m.parameters["alpha"] = "0.4"
    changed = m.simulate(t_end=2.0)
    fresh = nhdyn.load(examples / "sled.toml", a=0.3, alpha=0.4).simulate(t_end=2.0)
    for name in ("t", "q", "qd", "qdd", "R", "residuals", "energy"):
        assert np.array_equal(getattr(changed, name), getattr(fresh, name)), name
    cli("simulate", examples / "sled.toml", "--set", "a=0.3", "--set", "alpha=0.4", "--t-end", 2.0, "-q",
        "-o", tmp_path / "sled.csv")
    header, table = read_csv(tmp_path / "sled.csv")
    names, values = changed.table()
    assert header == names
    assert np.array_equal(values, table)


def test_python_and_cli_give_identical_arrays(examples, cli, tmp_path):
    for model, options in ((examples / "sled.toml", ["--t-end", 3, "--rtol", 1e-10, "--atol", 1e-12]),
                           (examples / "slider_crank.toml", ["--t-end", 1, "--method", "lagrange"]),
                           ("sled", ["--t-end", 1, "--integrator", "rk4", "--output-step", 0.05])):
        cli("simulate", model, *options, "-q", "-o", tmp_path / "out.csv")
        header, table = read_csv(tmp_path / "out.csv")
        kwargs = {options[i].lstrip("-").replace("-", "_"): options[i + 1] for i in range(0, len(options), 2)}
        r = nhdyn.load(model).simulate(**kwargs)
        names, values = r.table()
        assert header == names
        assert values.shape == table.shape
        assert np.array_equal(values, table), model
        frame = r.to_pandas()
        assert list(frame.columns) == header
        assert np.array_equal(frame.to_numpy(), table)


def test_run_options_come_from_the_model_file():
    text = """
name = "fall"
coordinates = ["x"]
kinetic_energy = "x'^2/2"
potential_energy = "-g*x"
[parameters]
g = 9.81
[initial]
position = { x = 0 }
velocity = { x = 0 }
[simulation]
t_end = 0.5
output_step = 0.1
integrator = "rk4"
method = "lagrange"
rtol = 1e-6
atol = 1e-7
"""
    m = nhdyn.loads(text, "fall.toml")
    assert m.run_options == {"t_end": 0.5, "output_step": 0.1, "method": "lagrange", "complement": "qr",
                             "integrator": "rk4", "rtol": 1e-6, "atol": 1e-7}
    r = m.simulate()
    assert len(r.t) == 6 and r.t[-1] == 0.5
    # Free fall x = g t^2 / 2: rk4 is exact for a polynomial of degree 2.
    assert np.max(np.abs(r.q[:, 0] - 9.81 * r.t ** 2 / 2)) < 1e-12
    m.parameters["g"] = 1.0
    assert np.max(np.abs(m.simulate().q[:, 0] - m.simulate().t ** 2 / 2)) < 1e-12


def test_equations_render_as_latex(examples):
    eq = nhdyn.load(examples / "sled.toml").equations()
    assert "\\begin{align*}" in eq._repr_latex_() and eq._repr_latex_().startswith("$$")
    assert "T =" in eq.text and "\\dot" in eq.latex
    with pytest.raises(nhdyn.InputError, match="built-in model"):
        nhdyn.load("sled").equations()


def test_linearization_of_the_upright_rolling_disk(examples):
    # Linearized, the tilt obeys theta'' = (4/5) (g/r - 3 w^2) theta (examples/rolling_disk_upright.toml).
    m = nhdyn.load(examples / "rolling_disk_upright.toml", w=6.0)
    lin = m.linearize(cyclic=["psi"])
    assert lin.state_matrix.shape == (len(lin.state), len(lin.state))
    omega = math.sqrt(0.8 * (3 * 36.0 - 9.81 / 0.2))
    tilt = [e for e in lin.eigenvalues if abs(e) > 1e-6]
    assert any(abs(e - 1j * omega) < 1e-8 * omega for e in tilt), lin.eigenvalues
    assert all(abs(e.real) < 1e-8 for e in lin.eigenvalues)


def test_sweep_finds_the_rolling_disk_stability_speed(examples):
    m = nhdyn.load(examples / "rolling_disk_upright.toml")
    s = m.sweep("w", np.linspace(1, 10, 10), cyclic=["psi"])
    assert s.eigenvalues.shape[0] == 10
    assert len(s.crossings) == 1
    assert abs(s.crossings[0]["value"] - math.sqrt(9.81 / (3 * 0.2))) < 1e-8
    with pytest.raises(nhdyn.InputError, match="evenly spaced"):
        m.sweep("w", [1, 2, 5])


def test_bad_input_raises_with_the_library_message(examples, tmp_path):
    with pytest.raises(nhdyn.InputError, match="no parameter 'mm'.*did you mean 'm'"):
        nhdyn.load(examples / "sled.toml", mm=2.0)
    m = nhdyn.load(examples / "sled.toml")
    with pytest.raises(nhdyn.InputError, match="no parameter 'rh'"):
        m.parameters["rh"] = 1.0
    assert m.parameters["rho"] == 0.7  # unchanged after the refused value
    with pytest.raises(nhdyn.InputError, match="'half'.*neither a parameter"):
        m.parameters["a"] = "half"
    m.parameters["a"] = "rho/2"  # an expression in the other parameters
    assert m.parameters["a"] == 0.35
    assert nhdyn.load("sled", m=2.0).parameters["m"] == 2.0  # built-in models take parameters too
    with pytest.raises(nhdyn.InputError):
        nhdyn.load("no-such-model")
    with pytest.raises(nhdyn.FileError):
        nhdyn.load(tmp_path / "missing.toml")
    bad = tmp_path / "bad.toml"
    bad.write_text('name = "bad"\ncoordinates = ["x"]\nkinetic_energy = "x\'^2/2"\npotential_enrgy = "x"\n')
    with pytest.raises(nhdyn.ModelError) as error:
        nhdyn.load(bad)
    assert str(error.value).startswith(str(bad) + ":4:")
    assert "potential_energy" in str(error.value)  # the nearest valid key
    with pytest.raises(nhdyn.ModelError, match="^text.toml:2:"):
        nhdyn.loads('name = "x"\ncoordinates = 3\n', "text.toml")
    with pytest.raises(nhdyn.InputError, match="method"):
        m.simulate(t_end=1, method="sanhh")
    with pytest.raises(nhdyn.InputError, match="q0: expected 3 values"):
        m.simulate(t_end=1, q0=[0.0, 0.0])
    with pytest.raises(TypeError):
        m.simulate(t_end=1, rtoll=1e-3)
    # an initial state off the constraint is refused by the library, naming the residual
    with pytest.raises(nhdyn.Error, match="blade"):
        m.simulate(t_end=1, qd0=[1.0, 1.0, 0.0])
    assert issubclass(nhdyn.InputError, ValueError) and issubclass(nhdyn.FileError, OSError)


def test_contact_forces_of_a_multibody_model_match_the_cli(examples, cli, tmp_path):
    # The rolling disk on its steady circle (docs/derivations/contact-forces.md 6.3): N = m g.
    model = examples / "rolling_disk_bodies.toml"
    r = nhdyn.load(model).simulate(t_end=1.0)
    names = r.columns["contact_forces"]
    assert names == ["disk_Fx", "disk_Fy", "disk_Fz", "disk_N", "disk_Flong", "disk_Flat", "contact_residual"]
    assert r.contact_forces.shape == (len(r.t), 7)
    assert np.max(np.abs(r.contact_forces[:, 3] - 0.5 * 9.81)) < 1e-8
    cli("simulate", model, "--t-end", 1.0, "-q", "-o", tmp_path / "disk.csv")
    header, table = read_csv(tmp_path / "disk.csv")
    header_py, values = r.table()
    assert header == header_py
    assert np.array_equal(values, table)
