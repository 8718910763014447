#!/usr/bin/python3
"""(g) The rattleback of Kane & Levinson (1982), "Realistic mathematical modeling of the
rattleback", Int. J. Non-Linear Mech. 17, 175-186; the same body as MotionGenesis' RattlebackKane
example (axes relabelled there). Simulated with the independent Newton-Euler model of
rolling_contact.py (no slip, no dissipation).

Body: the lower surface is the ellipsoid x^2/a^2 + y^2/b^2 + z^2/c^2 = 1 (body axes 1 = a, 2 = b,
3 = c, c upward when it rests); the centre of mass G lies on the c-axis a distance h BELOW the
ellipsoid's centre (toward the contact), so G is c - h above the plane at rest.
    a = 0.20 m, b = 0.03 m, c = 0.02 m, h = 0.01 m, m = 1 kg, g = 9.81 m/s^2
    inertia about G, body axes: [[A, D, 0], [D, B, 0], [0, 0, C]] (D is the matrix entry, i.e.
    -int x y dm), A = 2e-4, B = 1.6e-3, C = 1.7e-3, D = -2e-5 kg m^2.
Reference runs: from upright-ish (a tilt of 0.5 deg about the a-axis, then 0.5 deg about the
new b-axis: q = q_x(0.5 deg) * q_y(0.5 deg)), at rest except a spin w3 = +5 or -5 rad/s about the
body's c-axis; G placed so that the contact is on the plane, v_G = -w x r_c.

Two models of my own, checked against each other:
  1. the generic world-frame Newton-Euler model of rolling_contact.py, the contact term
     differentiated by sympy (slow: used on short runs and at random states);
  2. a hand-derived body-frame form, fast enough for the 12 s runs. Body axes, r = G -> contact
     = (0, 0, h) + p(n), p(n) = -M^-1 n / s, s = sqrt(n^T M^-1 n), n = the upward vertical,
     n' = n x w. Rolling: v_G = -w x r. Then a_G = -alpha x r - w x (w x r + p'(n) n'),
     p'(n) n' = -M^-1 n'/s + M^-1 n (n . M^-1 n')/s^3, and with the contact force
     L = m a_G + m g n (body axes: gravity is -g n):
       (I + m (|r|^2 1 - r r^T)) alpha = -w x I w - m r x (w x (w x r + p' n')) + m g r x n.
"""
import math
import numpy as np
import sympy as sp
from scipy.integrate import solve_ivp
from scipy.optimize import brentq
from rolling_contact import (RollingBody, Q, quat_to_R, quat_axis_angle, quat_mul,
                             ellipsoid_contact_body)

a, b, c, h = 0.20, 0.03, 0.02, 0.01
m, g = 1.0, 9.81
A, B, C, D = 2e-4, 1.6e-3, 1.7e-3, -2e-5
Ib = np.array([[A, D, 0], [D, B, 0], [0, 0, C]])
Minv = sp.diag(a**2, b**2, c**2)
R = quat_to_R(Q)
r_c = R * (sp.Matrix([0, 0, h]) + ellipsoid_contact_body(Minv, R.T * sp.Matrix([0, 0, 1])))
body = RollingBody(m, Ib, r_c, gravity=(0, 0, -g))



# ---- model 2: hand-derived body-frame equations; state (q, w_b) ----
a2, b2, c2 = a * a, b * b, c * c


def cross3(u, v):
    return (u[1] * v[2] - u[2] * v[1], u[2] * v[0] - u[0] * v[2], u[0] * v[1] - u[1] * v[0])


def fast_rhs(t, y):
    q0, q1, q2, q3, w1, w2, w3 = y
    nq2 = 1.0 / (q0 * q0 + q1 * q1 + q2 * q2 + q3 * q3)
    # n = R^T e_z = the third row of R
    n = (2 * (q1 * q3 - q0 * q2) * nq2, 2 * (q2 * q3 + q0 * q1) * nq2, 1 - 2 * (q1 * q1 + q2 * q2) * nq2)
    Mn = (a2 * n[0], b2 * n[1], c2 * n[2])
    s = math.sqrt(n[0] * Mn[0] + n[1] * Mn[1] + n[2] * Mn[2])
    r = (-Mn[0] / s, -Mn[1] / s, h - Mn[2] / s)
    w = (w1, w2, w3)
    nd = cross3(n, w)
    Mnd = (a2 * nd[0], b2 * nd[1], c2 * nd[2])
    k = (n[0] * Mnd[0] + n[1] * Mnd[1] + n[2] * Mnd[2]) / (s * s * s)
    dp = (-Mnd[0] / s + Mn[0] * k, -Mnd[1] / s + Mn[1] * k, -Mnd[2] / s + Mn[2] * k)
    wr = cross3(w, r)
    u = cross3(w, (wr[0] + dp[0], wr[1] + dp[1], wr[2] + dp[2]))
    Iw = (A * w1 + D * w2, D * w1 + B * w2, C * w3)
    gy = cross3(w, Iw)
    ru = cross3(r, u)
    rn = cross3(r, n)
    f = [-gy[i] - m * ru[i] + m * g * rn[i] for i in range(3)]
    rr = r[0] * r[0] + r[1] * r[1] + r[2] * r[2]
    k11, k12, k13 = A + m * (rr - r[0] * r[0]), D - m * r[0] * r[1], -m * r[0] * r[2]
    k22, k23, k33 = B + m * (rr - r[1] * r[1]), -m * r[1] * r[2], C + m * (rr - r[2] * r[2])
    c11, c12, c13 = k22 * k33 - k23 * k23, k13 * k23 - k12 * k33, k12 * k23 - k13 * k22
    c22, c23, c33 = k11 * k33 - k13 * k13, k12 * k13 - k11 * k23, k11 * k22 - k12 * k12
    det = k11 * c11 + k12 * c12 + k13 * c13
    al = ((c11 * f[0] + c12 * f[1] + c13 * f[2]) / det, (c12 * f[0] + c22 * f[1] + c23 * f[2]) / det,
          (c13 * f[0] + c23 * f[1] + c33 * f[2]) / det)
    # q' = 1/2 q * (0, w_b)
    return [0.5 * (-q1 * w1 - q2 * w2 - q3 * w3), 0.5 * (q0 * w1 + q2 * w3 - q3 * w2),
            0.5 * (q0 * w2 + q3 * w1 - q1 * w3), 0.5 * (q0 * w3 + q1 * w2 - q2 * w1),
            al[0], al[1], al[2]]


def fast_energy(y):
    q, wb = y[:4] / np.linalg.norm(y[:4]), y[4:]
    n = quat_to_R(q)[2, :]
    r = np.array([0, 0, h]) + (-np.diag([a2, b2, c2]) @ n / np.sqrt(n @ np.diag([a2, b2, c2]) @ n))
    v = -np.cross(wb, r)
    return 0.5 * wb @ Ib @ wb + 0.5 * m * v @ v - m * g * (n @ r)   # z_G = -n . r


def initial_state(tilt_a_deg, tilt_b_deg, spin):
    q = quat_mul(quat_axis_angle([1, 0, 0], np.radians(tilt_a_deg)),
                 quat_axis_angle([0, 1, 0], np.radians(tilt_b_deg)))
    Rn = quat_to_R(q)
    w = Rn @ np.array([0.0, 0.0, spin])                    # spin about the body's c-axis
    y = np.concatenate([[0, 0, 0], q, [0, 0, 0], w])
    rc = body.r_c(0.0, y)
    y[2] = -rc[2]                                          # contact point on the plane z = 0
    y[7:10] = -np.cross(w, rc)                             # rolling: v_G = -w x r_c
    assert np.linalg.norm(body.constraint(0.0, y)) < 1e-15
    return y


def to_fast(y):
    """(q, w_b) of a world-frame state of model 1."""
    q = y[3:7] / np.linalg.norm(y[3:7])
    return np.concatenate([q, quat_to_R(q).T @ y[10:13]])


# ---- the two models agree: at random states, and along a short run ----
rng = np.random.default_rng(3)
worst = 0.0
for _ in range(20):
    q = rng.normal(size=4)
    q[0] += 2
    q /= np.linalg.norm(q)
    y = np.concatenate([[0, 0, 0], q, [0, 0, 0], quat_to_R(q) @ (3 * rng.normal(size=3))])
    rc = body.r_c(0.0, y)
    y[2], y[7:10] = -rc[2], -np.cross(y[10:13], rc)
    _, alpha, _ = body.solve(0.0, y)
    ab = quat_to_R(q).T @ alpha
    worst = max(worst, np.linalg.norm(ab - fast_rhs(0, to_fast(y))[4:]) / np.linalg.norm(ab))
print(f"(g) body-frame hand derivation vs sympy-differentiated model: max rel. diff of the "
      f"angular acceleration at 20 random states {worst:.1e}")
assert worst < 1e-12
y0 = initial_state(0.5, 0.5, -5.0)
t_short = 0.3
s1 = body.integrate(y0, t_short, rtol=1e-12, atol=1e-13)
s2 = solve_ivp(fast_rhs, (0, t_short), to_fast(y0), method='DOP853', rtol=1e-12, atol=1e-13)
dw = np.linalg.norm(to_fast(s1.y[:, -1])[4:] - s2.y[4:, -1])
print(f"(g) the two models after {t_short} s from the -5 rad/s start: |w_b difference| = {dw:.1e}")
assert dw < 1e-8

# ---- the reference runs ----
t_end = 12.0
ts = np.linspace(0, t_end, 12001)
results = {}
for spin in (+5.0, -5.0):
    y0 = to_fast(initial_state(0.5, 0.5, spin))
    sol = solve_ivp(fast_rhs, (0, t_end), y0, method='DOP853', rtol=1e-10, atol=1e-11,
                    dense_output=True)
    w3 = sol.sol(ts)[6]
    E = np.array([fast_energy(sol.sol(t)) for t in ts[::200]])
    flips = np.nonzero(np.sign(w3[1:]) != np.sign(w3[:-1]))[0]
    t_rev = (brentq(lambda t: sol.sol(t)[6], ts[flips[0]], ts[flips[0] + 1], xtol=1e-12)
             if len(flips) else None)
    results[spin] = (t_rev, w3)
    print(f"(g) w3(0) = {spin:+.1f} rad/s (E = {E[0]:.9f} J): first reversal of w3 "
          f"{'at t = %.4f s' % t_rev if t_rev is not None else 'none'} in {t_end:g} s; "
          f"energy spread {np.ptp(E):.1e} J")
    print("      w3 at t = " + ", ".join(f"{tt:g}: {sol.sol(tt)[6]:+.6f}"
                                          for tt in (1, 2, 3, 5, 8, 10, 12)))
    assert np.ptp(E) < 1e-9
    # coordinate-free state for comparisons: n = the upward vertical in body axes, w in body axes,
    # and the contact force (world; N its vertical component) from model 1 at that state
    for tt in (1.0, 5.0, 10.0):
        yf = sol.sol(tt)
        qn = yf[:4] / np.linalg.norm(yf[:4])
        Rn = quat_to_R(qn)
        yw = np.concatenate([[0, 0, 0], qn, [0, 0, 0], Rn @ yf[4:]])
        rc = body.r_c(0.0, yw)
        yw[2], yw[7:10] = -rc[2], -np.cross(yw[10:13], rc)
        _, _, L = body.solve(0.0, yw)
        print(f"      t = {tt:4.1f}: n_body = ({Rn[2, 0]:+.9f}, {Rn[2, 1]:+.9f}, {Rn[2, 2]:+.9f}), "
              f"w_body = ({yf[4]:+.7f}, {yf[5]:+.7f}, {yf[6]:+.7f}), contact force "
              f"({L[0]:+.6f}, {L[1]:+.6f}, {L[2]:+.6f}) N")

t_pos, t_neg = results[5.0][0], results[-5.0][0]
assert t_neg is not None and abs(t_neg - 2.3527) < 2e-3
assert t_pos is not None and abs(t_pos - 11.461) < 2e-2 and min(results[5.0][1][:10000]) > 1.0
print(f"(g) w3(0) = -5 reverses at {t_neg:.4f} s; w3(0) = +5 keeps its sense (w3 > 1 rad/s) "
      f"for 10 s and, with no dissipation, reverses only at {t_pos:.4f} s (see the growth rates)")

# ---- linearised rattleback about upright spin, from the same model ----
# reduced state (gamma, w_b): gamma = the upward vertical in body axes, w_b in body axes.


def reduced_rhs(s):
    gam, wb = s[:3], s[3:]
    gam = gam / np.linalg.norm(gam)
    # a rotation R with R^T e_z = gam (any one; the plane is invariant under turns about e_z)
    ez = np.array([0.0, 0.0, 1.0])
    axis = np.cross(gam, ez)
    sn, cs = np.linalg.norm(axis), gam @ ez
    q = (np.array([1.0, 0, 0, 0]) if sn < 1e-300 else
         quat_axis_angle(axis, np.arctan2(sn, cs)))          # rotates gam onto e_z
    Rn = quat_to_R(q)
    w = Rn @ wb
    y = np.concatenate([[0, 0, 0], q, [0, 0, 0], w])
    rc = body.r_c(0.0, y)
    y[2] = -rc[2]
    y[7:10] = -np.cross(w, rc)
    _, alpha, _ = body.solve(0.0, y)
    return np.concatenate([np.cross(gam, wb), Rn.T @ alpha])


for s in (+5.0, -5.0, +2.0, -2.0):
    s0 = np.array([0, 0, 1.0, 0, 0, s])
    assert np.linalg.norm(reduced_rhs(s0)) < 1e-12              # upright spin is steady
    J = np.zeros((6, 6))
    eps = 1e-6
    for j in range(6):
        dp = np.zeros(6)
        dp[j] = eps
        J[:, j] = (reduced_rhs(s0 + dp) - reduced_rhs(s0 - dp)) / (2 * eps)
    # drop the directions along gamma (|gamma| = 1) and the spin family: rows/cols of
    # gamma_3 and w_3 give zero eigenvalues; keep (gamma_1, gamma_2, w_1, w_2)
    keep = [0, 1, 3, 4]
    ev = np.linalg.eigvals(J[np.ix_(keep, keep)])
    ev = ev[np.argsort(-ev.imag)]
    print(f"(g) linearised about upright spin w3 = {s:+.0f}: eigenvalues " +
          ", ".join(f"{e.real:+.6f}{e.imag:+.6f}i" for e in ev))
    if s == 5.0:
        ev_pos = ev
    if s == -5.0:
        ev_neg = ev
# reversibility: the spectrum at -s is minus the spectrum at +s
assert np.allclose(np.sort_complex(ev_neg), np.sort_complex(-ev_pos), atol=1e-6)
gp, gn = ev_pos.real.max(), ev_neg.real.max()
print(f"(g) growth rates at |w3| = 5: w3 = +5: {gp:.5f} 1/s (the roll mode, ~34 rad/s); "
      f"w3 = -5: {gn:.5f} 1/s (the pitch mode, ~109 rad/s): both senses are unstable without "
      f"dissipation, the -5 sense {gn / gp:.1f} times faster")
assert gn > 10 * gp > 0

# ---- the characteristic polynomial in closed form ----
# Linearise the body-frame equations of model 2 (exact contact point p(n)) about n = e3, w = s e3
# in (n1, n2, w1, w2), symbolically; rho1 = a^2/c, rho2 = b^2/c, ell = c - h (G's height at rest),
# A1 = A + m ell^2, B1 = B + m ell^2. Claimed closed form:
#   Delta l^4 - D m ell (rho1 - rho2) s l^3 + [A1 P1 + B1 P2 + (Delta + Delta') s^2] l^2
#     - D m ell (rho1 - rho2) s^3 l + [P1 P2 - s^2 (P1 B' + P2 A') + Delta' s^4] = 0
#   P1 = m g (rho1 - ell), P2 = m g (rho2 - ell), A' = A1 - C - m ell rho1, B' = B1 - C - m ell rho2,
#   Delta = A1 B1 - D^2, Delta' = A' B' - D^2.
ep, x1, x2, u1, u2, sv, lam = sp.symbols('epsilon x1 x2 u1 u2 s lambda', real=True)
sa, sb, sc, sh, sm, sg, sA, sB, sC = sp.symbols('a b c h m g A B C', positive=True)
sD = sp.Symbol('D', real=True)
r1, r2, ell, A1, B1 = sp.symbols('rho1 rho2 ell A1 B1', positive=True)
n = sp.Matrix([ep * x1, ep * x2, sp.sqrt(1 - ep**2 * (x1**2 + x2**2))])
w = sp.Matrix([ep * u1, ep * u2, sv])
Mi = sp.diag(sa**2, sb**2, sc**2)
Mn = Mi * n
S = sp.sqrt((n.T * Mn)[0])
rv = sp.Matrix([0, 0, sh]) - Mn / S
Mnd = Mi * n.cross(w)
dpv = -Mnd / S + Mn * (n.T * Mnd)[0] / S**3
Is = sp.Matrix([[sA, sD, 0], [sD, sB, 0], [0, 0, sC]])
fv = (-w.cross(Is * w) - sm * rv.cross(w.cross(w.cross(rv) + dpv)) + sm * sg * rv.cross(n))
df = (fv.diff(ep).subs(ep, 0)
      .subs({sa: sp.sqrt(r1 * sc), sb: sp.sqrt(r2 * sc), sh: sc - ell})
      .subs({sA: A1 - sm * ell**2, sB: B1 - sm * ell**2}))
acc = sp.Matrix([[A1, sD], [sD, B1]]).inv() * sp.Matrix(df[:2])   # K0 = [[A1, D], [D, B1]] + C
rows = [sv * x2 - u2, u1 - sv * x1, acc[0], acc[1]]                 # n' = n x w
Jl = sp.Matrix([[sp.diff(rw, v) for v in (x1, x2, u1, u2)] for rw in rows])
charpoly = sp.expand(sp.simplify((lam * sp.eye(4) - Jl).det() * (A1 * B1 - sD**2)))
P1, P2 = sm * sg * (r1 - ell), sm * sg * (r2 - ell)
Ap, Bp = A1 - sC - sm * ell * r1, B1 - sC - sm * ell * r2
Dl, Dlp = A1 * B1 - sD**2, Ap * Bp - sD**2
odd = sD * sm * ell * (r1 - r2)
closed = (Dl * lam**4 - odd * sv * lam**3 + (A1 * P1 + B1 * P2 + (Dl + Dlp) * sv**2) * lam**2
          - odd * sv**3 * lam + P1 * P2 - sv**2 * (P1 * Bp + P2 * Ap) + Dlp * sv**4)
assert sp.expand(charpoly - closed) == 0
num = {sm: m, sg: g, sC: C, sD: D, r1: a * a / c, r2: b * b / c, ell: c - h,
       A1: A + m * (c - h)**2, B1: B + m * (c - h)**2}
for s_, ev in ((5.0, ev_pos), (-5.0, ev_neg)):
    coeffs = [float(sp.Poly(closed, lam).coeff_monomial(lam**k).subs(num).subs(sv, s_))
              for k in range(4, -1, -1)]
    roots = np.sort_complex(np.roots(coeffs))
    err = np.max(np.abs(roots - np.sort_complex(ev)))
    print(f"(g) closed-form quartic at w3 = {s_:+.0f}: roots " +
          ", ".join(f"{z.real:+.6f}{z.imag:+.6f}i" for z in roots) +
          f"; max |root - finite-difference eigenvalue| = {err:.1e}")
    assert err < 1e-5
