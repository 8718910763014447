"""The constraint watch from Python: the blade written y' - tan(phi) x' = 0, turning at phi' = 1
with no force (phi = t exactly, its row of b of norm 1/|cos t|), raises nhdyn.ConstraintWarning
naming the blade at a time within 1e-3 of pi/2 (where 1/|cos t| reaches the factor 1e3); the
regular form of the sled stays silent over a long run; a batch warns once per run."""

import math
import warnings

import numpy as np
import pytest

import nhdyn

TURNING_BLADE = """name = "turning-blade"
coordinates = ["x", "y", "phi"]
kinetic_energy = "m/2 * (x'^2 + y'^2) + m*rho^2/2 * phi'^2"
[parameters]
m = 1.0
rho = 0.5
[[constraints]]
name = "blade"
velocity = "y' - tan(phi)*x'"
[initial]
position = { x = 0, y = 0, phi = 0 }
velocity = { x = 1, y = 0, phi = 1 }
"""


def test_tan_form_raises_a_constraint_warning_near_half_pi():
    m = nhdyn.loads(TURNING_BLADE)
    with pytest.warns(nhdyn.ConstraintWarning, match="constraint 'blade'") as caught:
        r = m.simulate(t_end=3, output_step=1)
    assert len([w for w in caught if issubclass(w.category, nhdyn.ConstraintWarning)]) == 1
    (w,) = r.summary["constraint_warnings"]
    assert m.constraints[w["constraint"]] == "blade"
    assert w["measure"] == "row_norm"
    assert abs(w["t"] - math.pi / 2) <= 1e-3
    assert w["factor"] == pytest.approx(1 / abs(math.cos(w["t"])), rel=1e-6)
    assert r.summary["warnings"][0].startswith("constraint 'blade': the norm of its row of b")


def test_warning_can_be_made_an_error():
    m = nhdyn.loads(TURNING_BLADE)
    with warnings.catch_warnings():
        warnings.simplefilter("error", nhdyn.ConstraintWarning)
        with pytest.raises(nhdyn.ConstraintWarning):
            m.simulate(t_end=3)


def test_regular_sled_stays_silent(examples):
    m = nhdyn.load(examples / "sled.toml")
    with warnings.catch_warnings():
        warnings.simplefilter("error", nhdyn.ConstraintWarning)
        r = m.simulate(t_end=100)
    assert r.summary["warnings"] == [] and r.summary["constraint_warnings"] == []
    assert r.summary["largest_row_factor"] < 1 + 1e-12


def test_batch_warns_once_per_run():
    m = nhdyn.loads(TURNING_BLADE)
    with pytest.warns(nhdyn.ConstraintWarning) as caught:
        b = nhdyn.simulate_batch(m, parameters={"rho": np.array([0.5, 0.6])}, t_end=2, threads=1)
    texts = [str(w.message) for w in caught if issubclass(w.category, nhdyn.ConstraintWarning)]
    assert len(texts) == 2 and "(run 0)" in texts[0] and "(run 1)" in texts[1]
    assert all(len(s["constraint_warnings"]) == 1 for s in b.summaries)


def test_a_stiff_stretch_is_a_stiffness_warning_not_a_constraint_warning(examples):
    # The sled speeds up down the slope and the rate at which its heading follows its velocity
    # grows with the speed: from about 20 s on, dopri5's steps are held by its stability. The
    # run says so as a StiffnessWarning (the result is right, only slow); cvode-bdf is not held.
    m = nhdyn.load(examples / "sled.toml")
    with warnings.catch_warnings():
        warnings.simplefilter("error", nhdyn.ConstraintWarning)
        with pytest.warns(nhdyn.StiffnessWarning, match=r'the run is stiff from t = 20\.\d+: .*integrator="cvode-bdf"'):
            r = m.simulate(t_end=100)
    assert r.summary["warnings"] == []
    assert 2 * r.summary["stiff_steps"] > r.summary["steps"] > 1000
    with warnings.catch_warnings():
        warnings.simplefilter("error", nhdyn.StiffnessWarning)
        bdf = m.simulate(t_end=100, integrator="cvode-bdf")
    assert bdf.summary["stiffness"] == "" and bdf.summary["stiff_steps"] == 0
    assert 5 * bdf.summary["steps"] < r.summary["steps"]
    # Under projection an implicit integrator restarts at every projected state: the warning says to
    # keep the explicit one rather than advise cvode-bdf.
    with pytest.warns(nhdyn.StiffnessWarning, match=r'with stabilize="projection" keep the explicit integrator') as caught:
        m.simulate(t_end=100, stabilize="projection")
    assert all("an implicit integrator takes far fewer steps there" not in str(w.message) for w in caught)
