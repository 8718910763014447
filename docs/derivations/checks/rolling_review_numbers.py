#!/usr/bin/python3
"""Checks of the statements in ../rolling-bodies.md that the other rolling_*.py scripts do not
cover: its worked numbers, the disk's and the torus' support mappings (brute force), the
ellipsoid's small-angle height expansion, and the order of the remainder in the rocking formula.
"""
import numpy as np
import sympy as sp
from scipy.optimize import minimize_scalar

g = 9.81
# ---- worked numbers of section 6 ----
k = 2 / 5
w61 = np.sqrt(g / ((1 + k) * (0.5 - 0.05)))
print(f"6.1 ball in bowl r = 0.05, R_g = 0.5: omega^2 = {w61**2:.6f}, omega = {w61:.6f}")
assert abs(w61**2 - 15.571428) < 1e-6 and abs(w61 - 3.946065) < 5e-7
a, b, c = 0.2, 0.15, 0.1
wy = np.sqrt(5 * g * (a * a - c * c) / (c * (a * a + 6 * c * c)))
wx = np.sqrt(5 * g * (b * b - c * c) / (c * (b * b + 6 * c * c)))
print(f"6.4 ellipsoid 0.2, 0.15, 0.1: omega_y^2 = {wy**2:.6f} (omega {wy:.6f}), "
      f"omega_x^2 = {wx**2:.6f} (omega {wx:.6f})")
assert abs(wy**2 - 147.15) < 1e-9 and abs(wy - 12.13054) < 5e-6
assert abs(wx**2 - 74.318182) < 1e-6 and abs(wx - 8.620799) < 5e-7
r = 0.1
w65 = np.sqrt(15 * g / (26 * r))
print(f"6.5 hemisphere r = 0.1: omega^2 = {w65**2:.6f}, omega = {w65:.6f}")
assert abs(w65**2 - 56.596154) < 1e-6 and abs(w65 - 7.523042) < 5e-7
# the intermediate expression printed in 6.5, g (3r/8) / ((13/20) r), is not 15 g/(26 r):
assert abs(g * (3 * r / 8) / ((13 / 20) * r) - 15 * g / 26) < 1e-12          # = 15 g/26
assert abs(g * (3 * r / 8) / ((13 / 20) * r**2) - 15 * g / (26 * r)) < 1e-12  # the right one

# ---- support mappings of the disk and the torus (section 2), brute force ----
rng = np.random.default_rng(5)
worst_d = worst_t = 0.0
for _ in range(200):
    e = rng.normal(size=3)
    e /= np.linalg.norm(e)
    nu = rng.normal(size=3)
    nu /= np.linalg.norm(nu)
    Rd, Rc, rt = rng.uniform(0.2, 1.0), rng.uniform(0.2, 1.0), rng.uniform(0.01, 0.3)
    # orthonormal basis (e1, e2) of the disk's plane
    e1 = np.cross(e, [1, 0, 0] if abs(e[0]) < 0.9 else [0, 1, 0])
    e1 /= np.linalg.norm(e1)
    e2 = np.cross(e, e1)
    t = np.linspace(0, 2 * np.pi, 2001)
    rim = np.outer(np.cos(t), e1) + np.outer(np.sin(t), e2)          # unit rim directions

    def lowest(i):
        # refine the grid's lowest rim direction by a bounded 1-D minimisation
        res = minimize_scalar(lambda s: (np.cos(s) * e1 + np.sin(s) * e2) @ nu,
                              bounds=(t[i] - 0.01, t[i] + 0.01), method='bounded',
                              options={'xatol': 1e-12})
        return np.cos(res.x) * e1 + np.sin(res.x) * e2
    ex = np.linalg.norm(np.cross(e, nu))
    yd = Rd * (e * (e @ nu) - nu) / ex
    u = lowest(np.argmin(rim @ nu))
    worst_d = max(worst_d, np.linalg.norm(Rd * u - yd), abs(-nu @ yd - Rd * ex))
    # torus: the tube centre circle Rc * rim, the tube radius rt; lowest point along nu
    yt = Rc * (e * (e @ nu) - nu) / ex - rt * nu
    yb = Rc * lowest(np.argmin(rim @ nu)) - rt * nu
    worst_t = max(worst_t, np.linalg.norm(yb - yt), abs(-nu @ yt - (Rc * ex + rt)))
print(f"2. disk y* and rho vs brute force over the rim: max diff {worst_d:.1e}; "
      f"torus y* and rho: {worst_t:.1e} (200 random axes and normals)")
assert worst_d < 1e-6 and worst_t < 1e-6

# ---- 6.4: the ellipsoid's height expansion, and 6.3's remainder ----
th = sp.Symbol('theta')
A, C = sp.symbols('a c', positive=True)
hG = sp.sqrt(A**2 * sp.sin(th)**2 + C**2 * sp.cos(th)**2)
ser = sp.series(hG, th, 0, 5).removeO()
assert sp.simplify(ser.coeff(th, 2) - (A**2 - C**2) / (2 * C)) == 0 and ser.coeff(th, 3) == 0
# A profile that is not symmetric about the contact normal: support function p(theta) of G with
# p(0) = l0, p'(0) = 0 (equilibrium) and radius of curvature rho = p + p''. Here
# p = l0 + (rho0 - l0) theta^2/2 + q theta^3/6 is a valid support function near 0 and
# rho(theta) = p + p'' has rho'(0) = q: the height h_G = p has a theta^3 term q/6 unless the
# profile is symmetric, so 6.3's remainder is O(theta^3) in general (O(theta^4) if symmetric).
l0, rho0, q = sp.symbols('l0 rho0 q', positive=True)
p = l0 + (rho0 - l0) * th**2 / 2 + q * th**3 / 6
rho = p + sp.diff(p, th, 2)
assert sp.simplify(rho.subs(th, 0) - rho0) == 0 and sp.simplify(sp.diff(rho, th).subs(th, 0) - q) == 0
print("6.3 the height of G is l0 + (rho0 - l0) theta^2/2 + (drho/dtheta)(0) theta^3/6 + ...: "
      "the remainder is O(theta^3) for an asymmetric profile (the frequency is unaffected)")
