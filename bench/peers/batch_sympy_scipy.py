#!/usr/bin/env python3
"""Batch throughput on the sled: runs per second of nhdyn.simulate_batch on 1 and 2 threads
against a SymPy + SciPy loop doing the same runs (docs/python.md).

    PYTHONPATH=build/python /usr/bin/python3 bench/peers/batch_sympy_scipy.py [--runs 1000] [--scipy-runs 100]

The runs: the sled of examples/sled.toml for t = 0..5 s (outputs every 0.01 s) at `runs` values of
the offset a from 0.2 to 0.6 m, dopri5 / RK45 at rtol 1e-8, atol 1e-10. The SciPy peer derives
the same equations with SymPy once (A = d2T/dq'2, the velocity terms and b, b0 of the blade
constraint), lambdifies them for a as an argument, and solves the stacked system
[A -b^T; b 0] [q''; lambda] = [h; -b0] per right-hand side in solve_ivp, one run after another.
The SymPy derivation time is reported apart. Both sides' final states are compared."""

import argparse
import time

import numpy as np
import sympy as sp
from scipy.integrate import solve_ivp

import nhdyn


def sympy_sled():
    m, a, rho, alpha, g = 1.0, sp.Symbol("a"), 0.7, sp.pi / 6, 9.81
    q = sp.symbols("x y phi")
    qd = sp.symbols("xd yd phid")
    x, y, phi = q
    xd, yd, phid = qd
    T = m / 2 * (xd**2 + yd**2) + m * a * phid * (sp.cos(phi) * yd - sp.sin(phi) * xd) + m * rho**2 / 2 * phid**2
    V = -m * g * sp.sin(alpha) * (x + a * sp.cos(phi))
    p = sp.Matrix([sp.diff(T, v) for v in qd])
    A = p.jacobian(qd)
    h = -sp.Matrix([sp.diff(V, c) for c in q]) + sp.Matrix([sp.diff(T, c) for c in q]) - p.jacobian(q) * sp.Matrix(qd)
    f = sp.Matrix([-sp.sin(phi) * xd + sp.cos(phi) * yd])
    b = f.jacobian(qd)
    b0 = f.jacobian(q) * sp.Matrix(qd)
    args = (a, *q, *qd)
    return sp.lambdify(args, A, "numpy"), sp.lambdify(args, h, "numpy"), sp.lambdify(args, b, "numpy"), \
        sp.lambdify(args, b0, "numpy")


def scipy_runs(values, t_eval, y0):
    A_f, h_f, b_f, b0_f = sympy_sled()
    K = np.zeros((4, 4))
    rhs = np.zeros(4)
    finals = []
    for a in values:
        def f(t, y, a=a):
            args = (a, *y)
            A = A_f(*args)
            b = b_f(*args)
            K[:3, :3] = A
            K[:3, 3:] = -b.T
            K[3:, :3] = b
            rhs[:3] = h_f(*args)[:, 0]
            rhs[3:] = -b0_f(*args)[:, 0]
            sol = np.linalg.solve(K, rhs)
            return np.concatenate([y[3:], sol[:3]])
        r = solve_ivp(f, (t_eval[0], t_eval[-1]), y0, method="RK45", t_eval=t_eval, rtol=1e-8, atol=1e-10)
        finals.append(r.y[:, -1])
    return np.array(finals)


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--runs", type=int, default=1000)
    parser.add_argument("--scipy-runs", type=int, default=100, help="runs of the (slow) SciPy loop; its rate is per run")
    args = parser.parse_args()
    m = nhdyn.load("examples/sled.toml")
    values = np.linspace(0.2, 0.6, args.runs)
    options = dict(t_end=5.0, output_step=0.01, rtol=1e-8, atol=1e-10)
    print("sled, t = 0..5 s, 501 outputs per run, dopri5 / RK45 at rtol 1e-8, atol 1e-10")
    start = time.perf_counter()
    models = nhdyn._batch_models(m, ["a"], values[:, None], args.runs)
    print("nhdyn: {} models made in {:.2f} s (one load, then a copy per parameter value with the value set)".format(
        args.runs, time.perf_counter() - start))
    results = {}
    for threads in (1, 2):
        start = time.perf_counter()
        out = nhdyn._nhdyn.simulate_batch(models, threads=threads, **options)
        wall = time.perf_counter() - start
        results[threads] = out
        print("nhdyn.simulate_batch, {} thread{}: {:.3f} s, {:.0f} runs/s".format(
            threads, "" if threads == 1 else "s", wall, args.runs / wall))
    print("speed-up 2 threads / 1 thread: {:.2f}".format(
        results[1]["cpp_seconds"] / results[2]["cpp_seconds"]))
    assert np.array_equal(results[1]["q_end"], results[2]["q_end"])

    start = time.perf_counter()
    sympy_sled()
    print("SymPy derivation and lambdify: {:.2f} s".format(time.perf_counter() - start))
    k = min(args.scipy_runs, args.runs)
    sub = values[:: max(1, args.runs // k)][:k]
    t_eval = np.linspace(0.0, 5.0, 501)
    y0 = np.concatenate([m.q0, m.qd0])
    start = time.perf_counter()
    finals = scipy_runs(sub, t_eval, y0)
    wall = time.perf_counter() - start
    print("SymPy + SciPy solve_ivp loop: {} runs in {:.2f} s, {:.1f} runs/s".format(k, wall, k / wall))
    idx = [int(np.argmin(np.abs(values - a))) for a in sub]
    ours = np.hstack([results[1]["q_end"][idx], results[1]["qd_end"][idx]])
    print("largest difference of the final states (nhdyn vs SciPy): {:.2e}".format(np.max(np.abs(ours - finals))))


if __name__ == "__main__":
    main()
