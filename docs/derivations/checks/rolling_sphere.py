#!/usr/bin/python3
"""(a) A ball in a spherical bowl and (b) a ball on a turntable, simulated with the independent
Newton-Euler model of rolling_contact.py, against the closed forms

    (a) omega^2 = g / ((1 + k) (R - r))            k = I / (m r^2)
    (b) the centre circles at Omega' = k Omega / (1 + k), about a fixed centre.
The turntable case is also run with "rubber" rolling (no spin relative to the table about the
normal, n . w = Omega, held by a moment about n): the centre's motion must be the same.
"""
import numpy as np
import sympy as sp
from rolling_contact import (RollingBody, X, T, quat_axis_angle, measured_omega)

g = 9.81

# ---------------- (a) ball in a bowl ----------------
m, r, R, k = 0.7, 0.05, 0.4, 2.0 / 5.0
O = sp.Matrix([0, 0, R])                       # bowl centre; its lowest point is the origin
d = X - O
r_c = r * d / sp.sqrt(d.dot(d))                # contact: from the ball's centre, away from O
ball = RollingBody(m, k * m * r * r * np.eye(3), r_c)
amp = 1e-4                                     # angle of the centre from the bowl's bottom
x0 = np.array([(R - r) * np.sin(amp), 0.0, R - (R - r) * np.cos(amp)])
y0 = np.concatenate([x0, [1, 0, 0, 0], np.zeros(6)])
t_end = 12.0
sol = ball.integrate(y0, t_end)
w_num, n = measured_omega(sol, lambda y: y[0], t_end)
w_cf = np.sqrt(g / ((1 + k) * (R - r)))
print(f"(a) ball in bowl, k = {k}: omega measured {w_num:.12f}, closed form {w_cf:.12f}, "
      f"rel. diff {w_num / w_cf - 1:.1e} ({n} crossings;\n"
      f"    the amplitude {amp} rad shifts it by -amp^2/16 = {-amp**2 / 16:.1e})")
assert abs(w_num / w_cf - 1) < 1e-8
# a wrong inertia term (e.g. omitting the rolling, k -> 0) would be off by 18 %; the
# non-rolling pendulum g/(R-r) is excluded by the tolerance above.
E = [ball.energy(t, sol.sol(t)) for t in np.linspace(0, t_end, 50)]
assert np.ptp(E) < 1e-12

# a hollow ball (k = 2/3) in a shallower bowl
k2, R2 = 2.0 / 3.0, 1.3
O2 = sp.Matrix([0, 0, R2])
d2 = X - O2
ball2 = RollingBody(m, k2 * m * r * r * np.eye(3), r * d2 / sp.sqrt(d2.dot(d2)))
x0 = np.array([(R2 - r) * np.sin(amp), 0.0, R2 - (R2 - r) * np.cos(amp)])
y0 = np.concatenate([x0, [1, 0, 0, 0], np.zeros(6)])
sol2 = ball2.integrate(y0, 20.0)
w_num2, _ = measured_omega(sol2, lambda y: y[0], 20.0)
w_cf2 = np.sqrt(g / ((1 + k2) * (R2 - r)))
print(f"(a) ball in bowl, k = 2/3, R = {R2}: omega measured {w_num2:.12f}, closed form "
      f"{w_cf2:.12f}, rel. diff {w_num2 / w_cf2 - 1:.1e}")
assert abs(w_num2 / w_cf2 - 1) < 1e-8

# ---------------- (b) ball on a turntable ----------------
Om = 1.7
table = RollingBody(m, k * m * r * r * np.eye(3), sp.Matrix([0, 0, -r]),
                    u_g=lambda p: sp.Matrix([-Om * p[1], Om * p[0], 0]))
x0 = np.array([0.3, -0.1, r])
w0 = np.array([2.0, -1.0, 0.8])
# the rolling constraint fixes v: v = Omega e_z x p - w x r_c
v0 = np.array([-Om * x0[1], Om * x0[0], 0]) - np.cross(w0, [0, 0, -r])
y0 = np.concatenate([x0, [1, 0, 0, 0], v0, w0])
t_end = 15.0
sol = table.integrate(y0, t_end)
Omp = k * Om / (1 + k)
centre = x0[:2] + np.array([-v0[1], v0[0]]) / Omp        # x_c = x + e_z x v / Omega'
worst = 0.0
for t in np.linspace(0, t_end, 200):
    y = sol.sol(t)
    c, s = np.cos(Omp * t), np.sin(Omp * t)
    rel = x0[:2] - centre
    pred = centre + np.array([c * rel[0] - s * rel[1], s * rel[0] + c * rel[1]])
    worst = max(worst, np.linalg.norm(y[:2] - pred))
    assert abs(y[12] - w0[2]) < 1e-10             # the vertical spin is constant
print(f"(b) turntable Omega = {Om}: centre circles at k Omega/(1+k) = {Omp:.6f} about "
      f"({centre[0]:.6f}, {centre[1]:.6f}); max |x - closed form| over {t_end} s = {worst:.1e} m")
assert worst < 1e-9
# the rate: fit the angle of v
vang = np.unwrap([np.arctan2(sol.sol(t)[8], sol.sol(t)[7]) for t in np.linspace(0, t_end, 400)])
rate = np.polyfit(np.linspace(0, t_end, 400), vang, 1)[0]
print(f"(b) fitted circling rate {rate:.12f}, closed form {Omp:.12f}")
assert abs(rate / Omp - 1) < 1e-9

# the same with rubber rolling: n . w = Omega held by a moment about n; the centre's motion is
# unchanged (M_s n x n = 0 in the horizontal balance)
rubber = RollingBody(m, k * m * r * r * np.eye(3), sp.Matrix([0, 0, -r]),
                     u_g=lambda p: sp.Matrix([-Om * p[1], Om * p[0], 0]), no_spin=([0, 0, 1], Om))
w0r = np.array([2.0, -1.0, Om])
v0r = np.array([-Om * x0[1], Om * x0[0], 0]) - np.cross(w0r, [0, 0, -r])
solr = rubber.integrate(np.concatenate([x0, [1, 0, 0, 0], v0r, w0r]), t_end)
centre_r = x0[:2] + np.array([-v0r[1], v0r[0]]) / Omp
worst_r = 0.0
for t in np.linspace(0, t_end, 200):
    y = solr.sol(t)
    c, s = np.cos(Omp * t), np.sin(Omp * t)
    rel = x0[:2] - centre_r
    pred = centre_r + np.array([c * rel[0] - s * rel[1], s * rel[0] + c * rel[1]])
    worst_r = max(worst_r, np.linalg.norm(y[:2] - pred))
    assert abs(y[12] - Om) < 1e-10
print(f"(b) the same with rubber rolling (n . w = Omega): max |x - closed form| = {worst_r:.1e} m")
assert worst_r < 1e-9
