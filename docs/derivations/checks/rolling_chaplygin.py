#!/usr/bin/python3
"""(e) The Chaplygin ball: a ball of radius r, centre of mass at its geometric centre, inertia
tensor I (unequal principal moments, here not even aligned with the body axes), rolling without
slip on a horizontal plane.

Integrals (gamma = the upward vertical in body axes, w the angular velocity in body axes):
    K = I w + m r^2 (w - (gamma . w) gamma)      angular momentum about the contact point
    K is constant in space (the contact force and gravity act through the contact point, and the
    contact point moves parallel to v_G, so v_P x m v_G = 0). In body axes K' = K x w,
    gamma' = gamma x w, hence
    E = 1/2 K . w = 1/2 w . I w + 1/2 m |v|^2     (energy)
    |K|^2,  K . gamma (the Casimir-type integral),  |gamma|^2 = 1.
Checked by (1) the world-frame Newton-Euler simulation of rolling_contact.py, (2) the body-frame
reduced equations above, integrated separately: the two trajectories must agree.
"""
import numpy as np
import sympy as sp
from scipy.integrate import solve_ivp
from rolling_contact import RollingBody, quat_to_R, quat_axis_angle

m, r = 1.4, 0.1
rng = np.random.default_rng(7)
Rot, _ = np.linalg.qr(rng.normal(size=(3, 3)))
Ib = Rot @ np.diag([0.004, 0.009, 0.013]) @ Rot.T       # body axes not principal
ball = RollingBody(m, Ib, sp.Matrix([0, 0, -r]))

q0 = quat_axis_angle([0.3, -0.5, 0.8], 0.9)
w0 = np.array([3.0, -7.0, 11.0])                      # world axes
x0 = np.array([0.0, 0.0, r])
v0 = -np.cross(w0, [0, 0, -r])
y0 = np.concatenate([x0, q0, v0, w0])
t_end = 20.0
sol = ball.integrate(y0, t_end, rtol=1e-12, atol=1e-14)
ts = np.linspace(0, t_end, 401)


def integrals(y):
    R = quat_to_R(y[3:7] / np.linalg.norm(y[3:7]))
    wb = R.T @ y[10:13]
    gam = R.T @ [0, 0, 1]
    Kb = Ib @ wb + m * r * r * (wb - (gam @ wb) * gam)
    Kw_direct = R @ Ib @ R.T @ y[10:13] + m * np.cross([0, 0, r], y[7:10])   # I_w w + m (G-P) x v
    return (0.5 * Kb @ wb, R @ Kb, Kw_direct, Kb @ Kb, Kb @ gam, gam @ gam,
            0.5 * m * y[7:10] @ y[7:10] + 0.5 * wb @ Ib @ wb)


vals = [integrals(sol.sol(t)) for t in ts]
E = np.array([v[0] for v in vals])
Kw = np.array([v[1] for v in vals])
Kd = np.array([v[2] for v in vals])
K2 = np.array([v[3] for v in vals])
Kg = np.array([v[4] for v in vals])
Edirect = np.array([v[6] for v in vals])
print(f"(e) Chaplygin ball over {t_end} s (rtol 1e-12):")
print(f"    energy 1/2 K.w = {E[0]:.12f}, spread {np.ptp(E):.1e}; "
      f"|1/2 K.w - (1/2 w.Iw + 1/2 m v^2)| max {np.max(np.abs(E - Edirect)):.1e}")
print(f"    K (world) = {Kw[0]}, max spread {np.max(np.ptp(Kw, axis=0)):.1e}; "
      f"same as I_w w + m (G-P) x v to {np.max(np.abs(Kw - Kd)):.1e}")
print(f"    |K|^2 spread {np.ptp(K2):.1e}, K.gamma = {Kg[0]:.12f} spread {np.ptp(Kg):.1e}")
scale = np.max(np.abs(Kw))
assert np.ptp(E) < 1e-10 * E[0] and np.max(np.abs(E - Edirect)) < 1e-13
assert np.max(np.ptp(Kw, axis=0)) < 1e-10 * scale and np.max(np.abs(Kw - Kd)) < 1e-13
assert np.ptp(K2) < 1e-10 * K2[0] and np.ptp(Kg) < 1e-10 * scale
# the spin is not trivially steady: w must actually move in the body
wb_all = np.array([quat_to_R(sol.sol(t)[3:7]).T @ sol.sol(t)[10:13] for t in ts])
assert np.max(np.ptp(wb_all, axis=0)) > 1.0

# ---- the body-frame reduced equations, integrated on their own ----
D = Ib + m * r * r * np.eye(3)


def w_of(K, gam):
    # K = D w - m r^2 (gam . w) gam  ->  solve the 3x3 linear system
    return np.linalg.solve(D - m * r * r * np.outer(gam, gam), K)


def reduced(t, s):
    K, gam = s[:3], s[3:]
    w = w_of(K, gam)
    return np.concatenate([np.cross(K, w), np.cross(gam, w)])


R0 = quat_to_R(q0)
wb0 = R0.T @ w0
gam0 = R0.T @ [0, 0, 1]
K0 = Ib @ wb0 + m * r * r * (wb0 - (gam0 @ wb0) * gam0)
red = solve_ivp(reduced, (0, t_end), np.concatenate([K0, gam0]), method='DOP853', rtol=1e-12,
                atol=1e-14, dense_output=True)
diff = max(np.linalg.norm(w_of(red.sol(t)[:3], red.sol(t)[3:]) - wb_all[i])
           for i, t in enumerate(ts))
print(f"    body-frame reduced equations K' = K x w, gamma' = gamma x w: max |w_reduced - "
      f"w_Newton-Euler| = {diff:.1e} rad/s (|w| ~ {np.linalg.norm(w0):.1f})")
assert diff < 1e-8
