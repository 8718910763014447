"""Optimal programs from Python (docs/optimize.md, docs/python.md): Model.optimize against the CLI's
CSV and summary on the Brockett integrator, against its closed form J = 2 pi a / T, with --set's
parameters, and a solve that does not converge."""

import math
import subprocess
import sys
import warnings

import numpy as np
import pytest

import nhdyn
from conftest import read_csv


def needs_ipopt(call):
    try:
        return call()
    except nhdyn.InputError as error:
        if "built without IPOPT" in str(error):
            pytest.skip(str(error))
        raise


def test_brockett_matches_the_cli(examples, cli, tmp_path):
    guess = examples / "brockett_guess.csv"
    m = nhdyn.load(examples / "brockett.toml")
    r = needs_ipopt(lambda: m.optimize(guess, tolerance=1e-10))
    assert r.converged and r.status == "solved"
    run = cli("optimize", examples / "brockett.toml", "--guess", guess, "--tolerance", "1e-10", "-o",
              tmp_path / "b.csv")
    header, rows = read_csv(tmp_path / "b.csv")
    assert r.columns == header
    assert r.columns[-2:] == ["u_Fx", "u_Fy"] and r.controls == ["Fx", "Fy"]
    assert r.rows.shape == rows.shape == (17, 12)  # 9 nodes and 8 midpoints
    # The same solve: the CSV's numbers are printed to the shortest round trip.
    np.testing.assert_allclose(r.rows, rows, rtol=0, atol=1e-12)
    np.testing.assert_array_equal(r.t, r.column("t"))
    np.testing.assert_array_equal(r.q[:, 2], r.column("z"))
    np.testing.assert_array_equal(r.qd[:, 0], r.column("x'"))
    np.testing.assert_array_equal(r.u[:, 1], r.column("u_Fy"))
    # The summary is the CLI's, line for line.
    assert r.summary.splitlines() == run.stdout.splitlines()[:len(r.summary.splitlines())]
    assert "objective: {:.10g}".format(r.objective) in run.stdout
    # Hermite-Simpson at 9 nodes: J_N - 2 pi = 1.32e-3 (docs/derivations/optimal-programs.md 10.2).
    assert r.objective - 2 * math.pi == pytest.approx(1.32e-3, abs=3e-5)
    assert 0 < r.replay_difference < 2e-2  # the drift of the constraint at the level given, 9.7e-3
    r.to_csv(tmp_path / "again.csv")
    np.testing.assert_array_equal(read_csv(tmp_path / "again.csv")[1], r.rows)


def test_parameters_reach_the_problem(examples):
    # J = 12 d^2 / T^3 for the double integrator, exact with Hermite-Simpson: d = 2, T = 1 -> 48.
    m = nhdyn.load(examples / "double_integrator.toml", d=2.0, duration=1.0)
    r = needs_ipopt(lambda: m.optimize())
    assert r.objective == pytest.approx(48.0, rel=1e-9)
    assert r.t_end == pytest.approx(1.0) and r.q[-1, 0] == pytest.approx(2.0)


def test_not_converged_warns_and_keeps_the_last_iterate(examples):
    m = nhdyn.load(examples / "brockett.toml")
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        r = needs_ipopt(lambda: m.optimize())  # the straight line: a stationary point of the violation
    assert not r.converged and r.status in ("infeasible", "failed", "iteration limit")
    assert any("did not converge" in str(w.message) for w in caught)
    assert r.rows.shape == (17, 12)
    assert any('guess="FILE.csv"' in note and "--" not in note for note in r.notes)


def test_builtin_model_is_refused():
    m = nhdyn.load(next(iter(nhdyn.builtin_models())))
    with pytest.raises(nhdyn.InputError, match="model file"):
        m.optimize()


def test_ipopt_is_mapped_by_optimize_alone(examples):
    # IPOPT is a module the package loads when a program is first solved: importing nhdyn and
    # simulating map none of its libraries (the process's own memory map says so), optimizing does.
    code = """
import sys, nhdyn
def mapped():
    maps = open("/proc/self/maps").read()
    return "libnhdyn_ipopt.so" in maps, "libipopt.so" in maps
nhdyn.load(sys.argv[1] + "/sled.toml").simulate(t_end=1)
before = mapped()
try:
    nhdyn.load(sys.argv[1] + "/double_integrator.toml").optimize()
except nhdyn.InputError as error:
    print("error", error)
    sys.exit(0)
print(before, mapped())
"""
    run = subprocess.run([sys.executable, "-c", code, str(examples)], capture_output=True, text=True, check=True)
    if run.stdout.startswith("error") and "built without IPOPT" in run.stdout:
        pytest.skip(run.stdout)
    assert run.stdout.strip() == "(False, False) (True, True)", run.stdout + run.stderr


def test_solver_options_are_checked_before_any_work(examples):
    # IPOPT dropped tol 0 and max_iter -5 for its defaults, and took tolerance 1e300 to call the
    # straight-line start solved.
    m = nhdyn.load(examples / "double_integrator.toml")
    for tolerance in (0.0, -1e-8, math.nan, math.inf, 1e300, 0.02):
        with pytest.raises(nhdyn.InputError, match="the optimizer's tolerance .* must be a number above 0 and at most"):
            m.optimize(tolerance=tolerance)
    for budget in (0, -5):
        with pytest.raises(nhdyn.InputError, match=f"the optimizer's iteration budget {budget} must be at least 1"):
            m.optimize(max_iterations=budget)


def test_an_optimum_the_replay_does_not_confirm_is_not_converged(examples, tmp_path):
    # x'' = x F / m from rest at x = 0 never moves, whatever F: IPOPT "solves" the discrete
    # problem by a jump in the last interval, the replay stays at 0 (docs/optimize.md, the replay
    # rule). The CLI exits 1; Python warns and says converged False, as for a failed solve.
    text = (examples / "double_integrator.toml").read_text().replace('actuator = "x"', 'actuator = ["x"]')
    (tmp_path / "stuck.toml").write_text(text)
    m = nhdyn.load(tmp_path / "stuck.toml")
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        r = needs_ipopt(lambda: m.optimize())
    assert not r.converged and r.status == "not a motion of the model"
    assert r.replay_difference > r.replay_limit > 0
    assert "its optimum is not a motion of the model" in r.replay_verdict
    assert "a tighter tolerance" in r.replay_verdict and "--" not in r.replay_verdict
    assert any("not a motion of the model" in str(w.message) for w in caught)
    # A confirmed optimum: converged, no verdict, the replay far inside its limit.
    ok = needs_ipopt(lambda: nhdyn.load(examples / "double_integrator.toml").optimize())
    assert ok.converged and ok.status == "solved" and ok.replay_verdict == ""
    assert ok.replay_difference < 1e-6 * ok.replay_limit


def test_solver_options_of_the_wrong_type_are_refused_in_words(examples):
    # float() and int() took "1e-3" and 1.9 or True (as 1) silently; 10**30 reached pybind11's
    # "incompatible function arguments", which shows the binding's internals.
    m = nhdyn.load(examples / "double_integrator.toml")
    for tolerance in ("1e-3", True, None, 1e-3j):
        with pytest.raises(nhdyn.InputError, match=r"optimize: tolerance=.*: give a real number above 0"):
            m.optimize(tolerance=tolerance)
    for budget in (1.9, True, "10", 3000.0):
        with pytest.raises(nhdyn.InputError, match=r"optimize: max_iterations=.*: give a whole number of iterations"):
            m.optimize(max_iterations=budget)
    for budget in (10**30, -10**30):
        with pytest.raises(nhdyn.InputError, match=r"max_iterations=-?1000000000000000000000000000000: give a whole "
                                                   r"number from 1 to 2147483647"):
            m.optimize(max_iterations=budget)
    # NumPy's numbers are numbers.
    r = needs_ipopt(lambda: m.optimize(tolerance=np.float64(1e-9), max_iterations=np.int64(100)))
    assert r.converged and r.objective == pytest.approx(1.5, rel=1e-9)
