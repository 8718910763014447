#!/usr/bin/python3
"""(c) a uniform solid ellipsoid resting on its short axis c and (d) a uniform solid hemisphere
on its curved face, rocking on a plane without slip: small-oscillation frequencies.

Closed form (a convex body rocking on a plane, centre of mass at height h above the contact,
radius of curvature rho of the section at the contact, I_G about the rocking axis through G):
    omega^2 = m g (rho - h) / (I_G + m h^2)
  (c) about the a-axis: rho = b^2/c, h = c, I_G = m (b^2 + c^2)/5
        omega_a^2 = 5 g (b^2 - c^2) / (c (b^2 + 6 c^2));   about the b-axis swap a and b.
  (d) rho = r, h = 5r/8, I_G = (2/5 - 9/64) m r^2 = 83/320 m r^2  ->  omega^2 = 15 g / (26 r).
Checked twice: a planar Lagrangian in sympy (exact contact point, linearised), and the 3-D
Newton-Euler simulation of rolling_contact.py at small amplitude.
"""
import numpy as np
import sympy as sp
from rolling_contact import (RollingBody, Q, quat_to_R, ellipsoid_contact_body, quat_axis_angle,
                             measured_omega)

g = 9.81
# ---------- planar Lagrangian, symbolic ----------
th, m, gs = sp.symbols('theta m g', positive=True)
a, b, c, r = sp.symbols('a b c r', positive=True)


def planar_omega2(Minv2, com, IG):
    """Section x^T M x = 1 (2-D, axes (y, z)) tilted by theta; com: centre of mass relative to
    the section's centre. V = m g z_G, T = 1/2 (I_G + m |G - P|^2) theta'^2 (rotation about the
    contact P, which is at rest). Returns omega^2 = V''(0) / (I_G + m |G - P|^2)(0)."""
    Rt = sp.Matrix([[sp.cos(th), -sp.sin(th)], [sp.sin(th), sp.cos(th)]])
    n_b = Rt.T * sp.Matrix([0, 1])
    p_b = -Minv2 * n_b / sp.sqrt((n_b.T * Minv2 * n_b)[0, 0])   # contact point, body axes
    zG = (Rt * (sp.Matrix(com) - p_b))[1]                          # height of G above the plane
    Vpp = sp.diff(m * gs * zG, th, 2).subs(th, 0)
    GP = (sp.Matrix(com) - p_b).subs(th, 0)
    Ip = IG + m * GP.dot(GP)
    return sp.simplify(Vpp / Ip)


w2_a = planar_omega2(sp.diag(b**2, c**2), [0, 0], m * (b**2 + c**2) / 5)
w2_a_cf = 5 * gs * (b**2 - c**2) / (c * (b**2 + 6 * c**2))
assert sp.simplify(w2_a - w2_a_cf) == 0
print(f"(c) planar Lagrangian, rocking about the a-axis: omega^2 = {sp.factor(w2_a)}")
# hemisphere: a circle of radius r, centre of mass 3r/8 below the flat face (toward the curve)
w2_h = planar_omega2(sp.diag(r**2, r**2), [0, -3 * r / 8], m * r**2 * sp.Rational(83, 320))
assert sp.simplify(w2_h - 15 * gs / (26 * r)) == 0
print(f"(d) planar Lagrangian, hemisphere: omega^2 = {w2_h}")
# check the hemisphere's inertia about G from the integral (uniform density, z from the face)
z, rho_ = sp.symbols('z rho_', positive=True)
vol = sp.integrate(sp.pi * (r**2 - z**2), (z, 0, r))
zc = sp.integrate(z * sp.pi * (r**2 - z**2), (z, 0, r)) / vol
Ixx_centre = sp.integrate(sp.pi * (r**2 - z**2) * ((r**2 - z**2) / 4 + z**2), (z, 0, r)) / vol
assert zc == 3 * r / 8 and sp.simplify(Ixx_centre - zc**2 - sp.Rational(83, 320) * r**2) == 0

# ---------- 3-D Newton-Euler simulation ----------
amp = 3e-5   # the measured frequency moves as amp^2 (checked: 1e-4 gives 11x the difference)


def ellipsoid_run(A, B, C, axis):
    Minv = sp.diag(A**2, B**2, C**2)
    R = quat_to_R(Q)
    rc = R * ellipsoid_contact_body(Minv, R.T * sp.Matrix([0, 0, 1]))
    mass = 1.3
    I = mass / 5 * np.diag([B**2 + C**2, A**2 + C**2, A**2 + B**2])
    body = RollingBody(mass, I, rc)
    q0 = quat_axis_angle(axis, amp)
    R0 = quat_to_R(q0)
    n_b = R0.T @ [0, 0, 1]
    height = np.sqrt(n_b @ np.diag([A**2, B**2, C**2]) @ n_b)
    y0 = np.concatenate([[0.2, -0.1, height], q0, np.zeros(6)])
    wcf = (np.sqrt(5 * g * (B**2 - C**2) / (C * (B**2 + 6 * C**2))) if axis[0] else
           np.sqrt(5 * g * (A**2 - C**2) / (C * (A**2 + 6 * C**2))))
    t_end = 8 * 2 * np.pi / wcf
    sol = body.integrate(y0, t_end)
    # tilt: the world component of the body's c-axis along the direction it tilts
    comp = 1 if axis[0] else 0
    wnum, _ = measured_omega(sol, lambda y: quat_to_R(y[3:7])[comp, 2], t_end)
    # the contact condition z_G = sqrt(n^T M^-1 n) holds along the run
    drift = 0.0
    for t in np.linspace(0, t_end, 30):
        y = sol.sol(t)
        nb = quat_to_R(y[3:7] / np.linalg.norm(y[3:7])).T @ [0, 0, 1]
        drift = max(drift, abs(y[2] - np.sqrt(nb @ np.diag([A**2, B**2, C**2]) @ nb)))
    return wnum, wcf, drift


A_, B_, C_ = 0.3, 0.2, 0.1
for axis, name in (([1, 0, 0], 'a'), ([0, 1, 0], 'b')):
    wnum, wcf, drift = ellipsoid_run(A_, B_, C_, axis)
    print(f"(c) ellipsoid a,b,c = {A_},{B_},{C_} rocking about the {name}-axis: omega measured "
          f"{wnum:.12f}, closed form {wcf:.12f}, rel. diff {wnum / wcf - 1:.1e}; "
          f"contact-height drift {drift:.1e}")
    assert abs(wnum / wcf - 1) < 2e-8 and drift < 1e-10

# (d) hemisphere: body frame at G, sphere centre 3r/8 above G (the flat face up)
rr, mass = 0.12, 0.8
R = quat_to_R(Q)
rc = R * sp.Matrix([0, 0, 3 * rr / 8]) + sp.Matrix([0, 0, -rr])
I = mass * rr**2 * np.diag([83 / 320, 83 / 320, 2 / 5])
hemi = RollingBody(mass, I, rc)
q0 = quat_axis_angle([1, 0, 0], amp)
R0 = quat_to_R(q0)
zG = rr - R0[2, 2] * 3 * rr / 8
y0 = np.concatenate([[0, 0, zG], q0, np.zeros(6)])
wcf = np.sqrt(15 * g / (26 * rr))
t_end = 8 * 2 * np.pi / wcf
sol = hemi.integrate(y0, t_end)
wnum, _ = measured_omega(sol, lambda y: quat_to_R(y[3:7])[1, 2], t_end)
print(f"(d) hemisphere r = {rr}: omega measured {wnum:.12f}, closed form sqrt(15 g/(26 r)) = "
      f"{wcf:.12f}, rel. diff {wnum / wcf - 1:.1e}")
assert abs(wnum / wcf - 1) < 2e-9
