#!/usr/bin/python3
"""The N-trailer chain (docs/gallery/chain.md) as a SciPy user would simulate it: the equations of
motion by hand in NumPy, the constraints at acceleration level, one sparse KKT solve
(scipy.sparse.linalg.spsolve of [A b^T; b 0]) per right-hand side, solve_ivp's RK45 (Dormand-Prince,
the pair of nhdyn's dopri5) at the model file's tolerances, and a CSV of q and q' at every output
time. The peer of `nhdyn simulate c.toml` in bench/peers/chain_vs_scipy.sh.

    /usr/bin/python3 bench/peers/chain_scipy.py c.toml out.csv [--t-end T]

Reads N, the parameters (m, J, a, f, r, v0, w0) and [simulation] (output_step, rtol, atol) from
the file `nhdyn example chain --bodies N -o c.toml` wrote. Prints the number of right-hand sides.
"""
import argparse
import sys
import tomllib

import numpy as np
import scipy.sparse as sp
import scipy.sparse.linalg as spla
from scipy.integrate import solve_ivp


def value(entry):
    return entry["value"] if isinstance(entry, dict) else entry


def main():
    parser = argparse.ArgumentParser()
    parser.add_argument("model")
    parser.add_argument("csv")
    parser.add_argument("--t-end", type=float, default=None)
    args = parser.parse_args()
    with open(args.model, "rb") as f:
        doc = tomllib.load(f)
    par = {k: float(value(v)) for k, v in doc["parameters"].items()}
    m, J, a, fh, rh, v0, w0 = (par[k] for k in ("m", "J", "a", "f", "r", "v0", "w0"))
    N = len(doc["coordinates"]) // 3 if "coordinates" in doc else None
    if N is None:
        N = len(doc["initial"]["position"]) // 3
    sim = doc.get("simulation", {})
    t_end = args.t_end if args.t_end is not None else float(sim.get("t_end", 10.0))
    step = float(sim.get("output_step", 0.01))
    rtol, atol = float(sim.get("rtol", 1e-8)), float(sim.get("atol", 1e-10))
    n, s = 3 * N, 3 * N - 2

    # Initial state: all on the x axis heading along +x at v0; body i turns at w0 (-r/f)^(i-1).
    i = np.arange(N)
    q0 = np.zeros(n)
    q0[0::3] = -i * (fh + rh)
    v0v = np.zeros(n)
    v0v[0::3] = v0
    v0v[2::3] = w0 * (-rh / fh) ** i

    # Fixed sparsity: A block diagonal (3 x 3 per body), b rows body by body (blade, pin x, pin y).
    ix, iy, it = 3 * i, 3 * i + 1, 3 * i + 2
    A_rows = np.concatenate([ix, iy, it, ix, it, iy, it])
    A_cols = np.concatenate([ix, iy, it, it, ix, it, iy])
    blade = 3 * i                                     # row of blade i
    j = np.arange(N - 1)                              # pin j joins body j+1's front to body j's rear
    pinx, piny = 3 * j + 1, 3 * j + 2
    b_rows = np.concatenate([blade, blade, pinx, pinx, pinx, pinx, piny, piny, piny, piny])
    b_cols = np.concatenate([ix, iy, 3 * (j + 1), it[j + 1], 3 * j, it[j], 3 * (j + 1) + 1, it[j + 1], 3 * j + 1, it[j]])
    K_rows = np.concatenate([A_rows, n + b_rows, b_cols])
    K_cols = np.concatenate([A_cols, b_cols, n + b_rows])
    calls = [0]

    def rhs(t, y):
        calls[0] += 1
        q, v = y[:n], y[n:]
        th, w = q[2::3], v[2::3]
        c, si = np.cos(th), np.sin(th)
        xd, yd = v[0::3], v[1::3]
        A_vals = np.concatenate([np.full(N, m), np.full(N, m), np.full(N, J + m * a * a),
                                 -m * a * si, -m * a * si, m * a * c, m * a * c])
        h = np.zeros(n)  # Q + G: no applied forces; G from the velocity terms of T
        h[0::3] = m * a * w * w * c
        h[1::3] = m * a * w * w * si
        cj, sj, c1, s1 = c[:-1], si[:-1], c[1:], si[1:]
        b_vals = np.concatenate([-si, c, np.ones(N - 1), -fh * s1, -np.ones(N - 1), -rh * sj,
                                 np.ones(N - 1), fh * c1, -np.ones(N - 1), rh * cj])
        b0 = np.zeros(s)
        b0[blade] = -w * (c * xd + si * yd)
        w1, wj = w[1:], w[:-1]
        b0[pinx] = -fh * c1 * w1 * w1 - rh * cj * wj * wj
        b0[piny] = -fh * s1 * w1 * w1 - rh * sj * wj * wj
        K = sp.csc_matrix((np.concatenate([A_vals, b_vals, b_vals]), (K_rows, K_cols)), shape=(n + s, n + s))
        sol = spla.spsolve(K, np.concatenate([h, -b0]))
        return np.concatenate([v, sol[:n]])

    times = np.arange(0.0, t_end + 1e-9 * step, step)
    if t_end - times[-1] > 1e-9 * step:
        times = np.append(times, t_end)
    times[-1] = t_end
    result = solve_ivp(rhs, (0.0, t_end), np.concatenate([q0, v0v]), method="RK45", t_eval=times,
                       rtol=rtol, atol=atol)
    if not result.success:
        print("solve_ivp failed:", result.message, file=sys.stderr)
        return 1
    np.savetxt(args.csv, np.column_stack([result.t, result.y.T]), delimiter=",", fmt="%.17g")
    print(f"N = {N}, n = {n}: {calls[0]} right-hand sides, {len(result.t)} rows")
    return 0


if __name__ == "__main__":
    sys.exit(main())
