#!/usr/bin/env python3
"""Checks of docs/derivations/contact-modes.md, section 10.4 (the tippe top and Jellett's quantity),
and of the switching rules of sections 5 and 6 on a body whose contact is coupled and anisotropic.

A tippe top (a sphere of radius R whose centre of mass G lies a below its centre O on the symmetry
axis k; inertia I1, I1, I3 about G) spun nearly upright on a plane with Coulomb friction mu.
Newton-Euler in contact space: the contact point's acceleration is c = a_f + Lambda F (a_f without
contact force, Lambda = I/m + [d]x^T I_G^-1 [d]x, d = P - G); rolling: c = 0; sliding:
F = N (e_z - mu e_s), c_z = 0. Switches as section 6 says (sliding: s . e_s through 0 -> stick test;
rolling: mu N - |F_t| through 0 -> slide in the onset direction of (O3), found by a scan of the
circle). RK4 with a fixed step, events by bisection on the step. Checked along the run:
  Jellett's J = L_G . (G - P) constant to the integration error in both modes and through the
  switches; E - E0 - W_friction at the integration error; N > 0 all along; the top inverts.
Run: python3 tippe_top.py (needs numpy; about a minute); exits 1 on any failure.
"""
import sys
import numpy as np

failures = 0


def check(name, ok, detail=""):
    global failures
    print(("PASS " if ok else "FAIL ") + name + ("" if ok else "  " + detail))
    if not ok:
        failures += 1


import os
m, R, g, mu = 0.02, 0.02, 9.81, float(os.environ.get("MU", "0.1"))
a = float(os.environ.get("AR", "0.2")) * R
I1, I3 = float(os.environ.get("I1", "0.42")) * m * R**2, 0.40 * m * R**2        # 1 - a/R < I3/I1 = 0.952 < 1 + a/R
Ib = np.diag([I1, I1, I3])
ez = np.array([0.0, 0.0, 1.0])


def skew(w):
    return np.array([[0, -w[2], w[1]], [w[2], 0, -w[0]], [-w[1], w[0], 0]])


def contact(y):
    """d, slip s, the free contact acceleration a_f, Lambda, I_G (world), the gyroscopic term."""
    vG, Rm, w = y[3:6], y[6:15].reshape(3, 3), y[15:18]
    k = Rm[:, 2]
    Iw = Rm @ Ib @ Rm.T
    Iinv = Rm @ np.diag(1 / np.diag(Ib)) @ Rm.T
    d = -R * ez + a * k
    s = vG + np.cross(w, d); s[2] = 0.0
    wd0 = -Iinv @ np.cross(w, Iw @ w)
    # contact point acceleration c = a_G + wdot x d + a w x (w x k) (d moves with k only)
    af = -g * ez + np.cross(wd0, d) + a * np.cross(w, np.cross(w, k))
    Dx = skew(d)
    Lam = np.eye(3) / m + Dx.T @ Iinv @ Dx
    return d, s, af, Lam, Iinv, wd0


def sliding_force(af, Lam, e):
    dvec = ez - mu * np.array([e[0], e[1], 0.0])
    N = -af[2] / (Lam[2] @ dvec)
    return N * dvec, N


def onset_direction(af, Lam):
    def sig(beta):
        e = np.array([np.cos(beta), np.sin(beta)])
        F, N = sliding_force(af, Lam, e)
        return e, (af + Lam @ F)[:2], N
    def gf(beta):
        e, sg, _ = sig(beta)
        return e[0] * sg[1] - e[1] * sg[0]
    betas = np.linspace(0, 2 * np.pi, 721)
    roots = []
    for b1, b2 in zip(betas[:-1], betas[1:]):
        if gf(b1) * gf(b2) < 0:
            lo, hi = b1, b2
            for _ in range(60):
                mid = (lo + hi) / 2
                lo, hi = (mid, hi) if gf(lo) * gf(mid) > 0 else (lo, mid)
            e, sg, N = sig(lo)
            if e @ sg > 0 and N > 0:
                roots.append(np.array([e[0], e[1], 0.0]))
    if len(roots) != 1:
        raise RuntimeError(f"onset direction: {len(roots)} roots")
    return roots[0]


def rhs(y, mode, eref):
    d, s, af, Lam, Iinv, wd0 = contact(y)
    if mode == "rolling":
        F = -np.linalg.solve(Lam, af)
        work = 0.0
    else:
        ns = np.linalg.norm(s)
        e = s / ns * np.sign(s @ eref) if ns > 1e-12 else eref      # continued through s = 0
        F, N = sliding_force(af, Lam, e)
        work = -mu * F[2] * ns
    aG = F / m - g * ez
    wd = wd0 + Iinv @ np.cross(d, F)
    Rm, w = y[6:15].reshape(3, 3), y[15:18]
    return np.concatenate([y[3:6], aG, (skew(w) @ Rm).ravel(), wd, [work]])


def event(y, mode, eref):
    d, s, af, Lam, *_ = contact(y)
    if mode == "rolling":
        F = -np.linalg.solve(Lam, af)
        return mu * F[2] - np.hypot(F[0], F[1])
    return s @ eref


def energy(y):
    Rm, w = y[6:15].reshape(3, 3), y[15:18]
    return 0.5 * m * y[3:6] @ y[3:6] + 0.5 * w @ (Rm @ Ib @ Rm.T) @ w + m * g * y[2]


def jellett(y):
    Rm, w = y[6:15].reshape(3, 3), y[15:18]
    return (Rm @ Ib @ Rm.T @ w) @ (R * ez - a * Rm[:, 2])


def rk4(y, h, mode, eref):
    f = lambda yy: rhs(yy, mode, eref)
    k1 = f(y); k2 = f(y + h / 2 * k1); k3 = f(y + h / 2 * k2); k4 = f(y + h * k3)
    return y + h / 6 * (k1 + 2 * k2 + 2 * k3 + k4)


th0, spin = float(os.environ.get('TH0', '0.1')), float(os.environ.get('SPIN', '150'))
Rm0 = np.array([[1, 0, 0], [0, np.cos(th0), -np.sin(th0)], [0, np.sin(th0), np.cos(th0)]])
k0 = Rm0[:, 2]
w0 = spin * k0
y = np.concatenate([[0.0, 0.0, R - a * k0[2]], [0.0, 0.0, -a * np.cross(w0, k0)[2]], Rm0.ravel(), w0, [0.0]])
E0, J0 = energy(y), jellett(y)
mode = "sliding"
s0 = contact(y)[1]
eref = s0 / np.linalg.norm(s0)
h, t = 2e-4, 0.0
switches = []
Jdev = Edev = 0.0
minN = np.inf
TMAX = float(os.environ.get('TMAX', '12'))
while t < TMAX and y[14] > -0.9 and len(switches) < 2000:
    g0 = event(y, mode, eref)
    y1 = rk4(y, h, mode, eref)
    if event(y1, mode, eref) < 0 < g0:
        lo, hi = 0.0, h
        for _ in range(60):
            mid = (lo + hi) / 2
            lo, hi = (mid, hi) if event(rk4(y, mid, mode, eref), mode, eref) > 0 else (lo, mid)
        y, t = rk4(y, hi, mode, eref), t + hi
        d, s, af, Lam, *_ = contact(y)
        F = -np.linalg.solve(Lam, af)
        if mode == "sliding" and np.hypot(F[0], F[1]) <= mu * F[2]:
            mode = "rolling"                                   # stick
        else:
            mode, eref = "sliding", onset_direction(af, Lam)   # slip starts, or slides on
        switches.append((t, mode))
    else:
        y, t = y1, t + h
        if mode == "sliding":
            s = contact(y)[1]
            if np.linalg.norm(s) > 1e-12:
                eref = s / np.linalg.norm(s) * np.sign(s @ eref)
    d, s, af, Lam, *_ = contact(y)
    F = -np.linalg.solve(Lam, af) if mode == "rolling" else sliding_force(af, Lam, eref)[0]
    minN = min(minN, F[2])
    Jdev = max(Jdev, abs(jellett(y) - J0))
    Edev = max(Edev, abs(energy(y) - E0 - y[18]))
nstick = sum(1 for _, md in switches if md == "rolling")
print(f"      t = {t:.4f} s, k_z = {y[14]:.4f}, {len(switches)} switches ({nstick} sticks; first at "
      f"{switches[0][0] if switches else float('nan'):.4f} s, last at {switches[-1][0] if switches else float('nan'):.4f} s), "
      f"J0 = {J0:.6e}, max |J - J0| = {Jdev:.2e}, friction work {y[18]:.4e} J of E0 = {E0:.4e} J, "
      f"max |E - E0 - W| = {Edev:.2e}, min N = {minN:.4f} N")
check("tippe top: stays on the ground (N > 0 all along)", minN > 0)
check("tippe top: inverts (k_z from 0.995 to below -0.9)", y[14] < -0.9)
check("tippe top: Jellett's L_G . (G - P) constant to the integration error through every mode and switch",
      Jdev < 1e-9 * abs(J0), f"{Jdev} vs {J0}")
check("tippe top: E - E0 - W_friction at the integration error, and friction did work",
      Edev < 1e-8 * E0 and y[18] < -0.05 * E0, f"{Edev} {y[18]}")
print("tippe_top: %d failure(s)" % failures)
sys.exit(1 if failures else 0)
