#!/usr/bin/env python3
"""Checks of docs/derivations/contact-modes.md, section 10 (the closed forms the tests compare with).

Each closed form is compared with an independent numerical integration of Newton-Euler's
equations for the body (RK4, events located by bisection on the step), not with the Do Sanh form.
10.1 a ball, a hollow sphere, a disk and a hoop thrown sliding on a plane: t*, final speed,
     backspin, a spatial throw (slip not along the velocity), the friction's work;
10.2 a ball released near the top of a fixed sphere: the slip angle, the rolling lift-off angle,
     the lift-off angle while sliding (closed form of theta'^2 along the sliding phase);
10.3 a solid cylinder on an incline: slides from the start iff tan(alpha) > 3 mu.
Run: python3 closed_forms.py (needs numpy); exits 1 on any failure.
"""
import sys
import numpy as np

failures = 0


def check(name, ok, detail=""):
    global failures
    print(("PASS " if ok else "FAIL ") + name + ("" if ok else "  " + detail))
    if not ok:
        failures += 1


def rk4(f, y, h):
    k1 = f(y); k2 = f(y + h / 2 * k1); k3 = f(y + h / 2 * k2); k4 = f(y + h * k3)
    return y + h / 6 * (k1 + 2 * k2 + 2 * k3 + k4)


def integrate_until(f, y, h, event, tmax):
    """RK4 with step h until event(y) changes sign; the crossing by bisection on the step size.

    f(y, y_start) may use the step's start state: the sliding bodies keep the slip direction of the
    step's start (contact-modes.md section 6), so that a stage past s = 0 continues smoothly.
    """
    t = 0.0
    g0 = event(y)
    while t < tmax:
        fs = lambda yy, ys=y: f(yy, ys)
        y1 = rk4(fs, y, h)
        if np.sign(event(y1)) != np.sign(g0) and event(y1) != 0:
            lo, hi = 0.0, h
            for _ in range(80):
                mid = (lo + hi) / 2
                if np.sign(event(rk4(fs, y, mid))) == np.sign(g0):
                    lo = mid
                else:
                    hi = mid
            return t + hi, rk4(fs, y, hi)
        y, t = y1, t + h
    return None, y


g = 9.81
# ---------------------------------------------------------------- 10.1 sliding on a plane, spatial
ez = np.array([0.0, 0.0, 1.0])
for name, k in (("solid ball", 2 / 5), ("hollow sphere", 2 / 3)):
    m, r, mu = 0.17, 0.0286, 0.2
    I = k * m * r**2
    v0 = np.array([2.0, 0.5, 0.0])
    w0 = np.array([10.0, -30.0, 5.0])        # spin not about the rolling axis: the slip is not along v0
    def slip(y):
        return y[0:3] + np.cross(y[3:6], -r * ez)
    def f(y, ys):
        s = slip(y); e = s / np.linalg.norm(s) * np.sign(s @ slip(ys))   # continued through s = 0
        F = -mu * m * g * e                 # N = m g: the ball's normal and tangential responses decouple
        return np.concatenate([F / m, np.cross(-r * ez, F) / I, y[0:3], [mu * m * g * np.linalg.norm(s) * -1]])
    y0 = np.concatenate([v0, w0, np.zeros(3), [0.0]])
    s0 = slip(y0)
    # event: the slip along its initial direction (it keeps that direction)
    tstar, y = integrate_until(f, y0, 1e-3, lambda y: slip(y) @ s0, 5.0)
    tc = k * np.linalg.norm(s0) / (mu * g * (1 + k))
    check(f"10.1 {name}: t* = k |s0| / (mu g (1 + k))", abs(tstar - tc) < 1e-9, f"{tstar} vs {tc}")
    vf = (v0 + k * r * np.cross(w0, ez)) / (1 + k)
    vf[2] = 0
    check(f"{name}: v(t*) = (v0 + k r w0 x e_z) / (1 + k)", np.allclose(y[0:3], vf, atol=1e-9), f"{y[0:3]} vs {vf}")
    # the centre's path is a parabola: x(t*) = v0 t* - mu g t*^2 e_s0 / 2
    es0 = s0 / np.linalg.norm(s0)
    check(f"{name}: the centre moves on the parabola v0 t - mu g t^2 e_s0 / 2",
          np.allclose(y[6:9], v0 * tstar - mu * g * tstar**2 / 2 * es0, atol=1e-9))
    T = lambda yy: 0.5 * m * yy[0:3] @ yy[0:3] + 0.5 * I * yy[3:6] @ yy[3:6]
    check(f"{name}: work of friction = T(t*) - T(0)", abs(y[9] - (T(y) - T(y0))) < 1e-9 * T(y0))
# rolling along x with a spin omega about y: v = r omega; planar closed forms for the four bodies
for name, k in (("solid ball", 2 / 5), ("disk", 1 / 2), ("hollow sphere", 2 / 3), ("hoop", 1.0)):
    mu, r, v0 = 0.25, 0.1, 3.0
    for w0, label in ((0.0, "no spin"), (-80.0, "backspin")):
        def f(y, ys):   # y = (v, omega, x, W/m): m v' = -mu m g sgn(s), k m r^2 omega' = mu m g r sgn(s)
            s = y[0] - r * y[1]; sg = np.sign(ys[0] - r * ys[1])     # the sign of the step's start
            return np.array([-mu * g * sg, mu * g * sg / (k * r), y[0], -mu * g * abs(s)])
        y0 = np.array([v0, w0, 0.0, 0.0])
        tstar, y = integrate_until(f, y0, 1e-3, lambda y: y[0] - r * y[1], 10.0)
        s0 = v0 - r * w0
        tc = k * s0 / (mu * g * (1 + k))
        vf = (v0 + k * r * w0) / (1 + k)
        check(f"10.1 {name}, {label}: t* = k (v0 - r w0) / (mu g (1 + k)) = {tc:.6f} s", abs(tstar - tc) < 1e-9)
        check(f"{name}, {label}: final speed (v0 + k r w0) / (1 + k) = {vf:.6f} m/s", abs(y[0] - vf) < 1e-9)
        loss = 0.5 * v0**2 + 0.5 * k * r**2 * w0**2 - 0.5 * vf**2 * (1 + k)
        check(f"{name}, {label}: work_friction = -m (v0 - r w0)^2 k / (2 (1 + k))",
              abs(y[3] + loss) < 1e-9 and abs(loss - s0**2 * k / (2 * (1 + k))) < 1e-12)
        if label == "no spin" and name == "solid ball":
            check("solid ball: t* = 2 v0 / (7 mu g), v = 5 v0 / 7",
                  abs(tc - 2 * v0 / (7 * mu * g)) < 1e-15 and abs(vf - 5 * v0 / 7) < 1e-15)
        if label == "backspin":
            # it comes back iff k r |w0| > v0; the centre stops at v0 / (mu g) < t*
            comes_back = vf < 0
            check(f"{name}, backspin: comes back iff k r |w0| > v0 ({comes_back})",
                  comes_back == (k * r * abs(w0) > v0) and (not comes_back or v0 / (mu * g) < tc))

# ---------------------------------------------------------------- 10.2 a ball on top of a fixed sphere
k = 2 / 5
R, r = 1.0, 0.1
rho = R + r


def slip_angle(mu, k, th0=0.0):
    # k sin(th) = mu ((3 + k) cos(th) - 2 cos(th0))
    return np.arctan2((3 + k) * mu, k) - np.arcsin(2 * mu * np.cos(th0) / np.hypot(k, (3 + k) * mu))


def u_sliding(th, ths, us, mu):
    """theta'^2 along the sliding phase from (ths, us): the linear ODE du/dth = (2g/rho)(sin - mu cos) + 2 mu u."""
    E = np.exp(2 * mu * (th - ths))
    prim = lambda x: (2 * mu**2 - 1) * np.cos(x) - 3 * mu * np.sin(x)
    return us * E + 2 * g / (rho * (1 + 4 * mu**2)) * (prim(th) - E * prim(ths))


th0 = 1e-3
check("10.2 rolling lift-off from rest at the top: cos = 2 / (3 + k) = 10/17", abs(2 / (3 + k) - 10 / 17) < 1e-15)


def rolling_rhs(y, ys=None):   # y = (th, thd): rolling on the fixed sphere: rho th'' = g sin(th) / (1 + k)
    return np.array([y[1], g * np.sin(y[0]) / ((1 + k) * rho)])


def rolling_NF(y):   # normal and friction per unit mass from Newton: m g cos - N = m rho th'^2, m rho th'' = m g sin - F
    N = g * np.cos(y[0]) - rho * y[1]**2
    F = g * np.sin(y[0]) - rho * rolling_rhs(y)[1]
    return N, F


tL, yL = integrate_until(rolling_rhs, np.array([th0, 0.0]), 1e-3, lambda y: rolling_NF(y)[0], 20.0)
cL = 2 * np.cos(th0) / (3 + k)
check(f"10.2 rolling without a friction limit lifts off at cos(theta) = 2 cos(theta0) / (3 + k) (theta0 = {th0})",
      abs(np.cos(yL[0]) - cL) < 1e-9, f"{np.cos(yL[0])} vs {cL}")
for mu in (0.1, 0.3, 0.6, 1.0):
    # rolling until the friction needed reaches mu N
    ts, ys = integrate_until(rolling_rhs, np.array([th0, 0.0]), 1e-3,
                             lambda y: mu * rolling_NF(y)[0] - rolling_NF(y)[1], 20.0)
    thc = slip_angle(mu, k, th0)
    check(f"10.2 mu = {mu}: slip starts at theta_s = {thc:.9f} rad (closed form)", abs(ys[0] - thc) < 1e-9,
          f"{ys[0]} vs {thc}")
    check(f"mu = {mu}: slip starts before the rolling lift-off", thc < np.arccos(cL))
    # sliding: y = (th, thd, omega); N = m (g cos - rho th'^2); friction mu N up the slope (s > 0)
    def sliding_rhs(y, ys=None):
        N = g * np.cos(y[0]) - rho * y[1]**2
        return np.array([y[1], (g * np.sin(y[0]) - mu * N) / rho, mu * N / (k * r)])
    om_s = rho * ys[1] / r        # rolling at the switch: r omega = rho th'
    tl, yl = integrate_until(sliding_rhs, np.array([ys[0], ys[1], om_s]), 1e-4,
                             lambda y: g * np.cos(y[0]) - rho * y[1]**2, 20.0)
    # closed form: the root of rho u(th) = g cos(th) after ths
    us = ys[1]**2
    hfun = lambda th: rho * u_sliding(th, ys[0], us, mu) - g * np.cos(th)
    lo, hi = ys[0] + 1e-9, np.pi / 2
    for _ in range(200):
        mid = (lo + hi) / 2
        lo, hi = (mid, hi) if hfun(mid) < 0 else (lo, mid)
    check(f"mu = {mu}: lift-off while sliding at theta = {lo:.9f} rad (closed form of theta'^2) = Newton-Euler",
          abs(yl[0] - lo) < 1e-8, f"{yl[0]} vs {lo}")
    # the ball slides forward all along: s = rho th' - r omega > 0 (checked on the end state and midway)
    check(f"mu = {mu}: the slip stays positive until lift-off", rho * yl[1] - r * yl[2] > 0)
    print(f"      mu = {mu}: theta_slip = {thc:.6f} rad ({np.degrees(thc):.3f} deg), "
          f"lift-off while sliding at {lo:.6f} rad ({np.degrees(lo):.3f} deg), t_slip = {ts:.6f} s, t_lift = {ts + tl:.6f} s")
print(f"      rolling lift-off at {np.arccos(cL):.9f} rad ({np.degrees(np.arccos(cL)):.4f} deg), t = {tL:.6f} s (theta0 = {th0})")

# ---------------------------------------------------------------- 10.3 a cylinder on an incline
for mu in (0.1, 0.25):
    for alpha in (np.arctan(3 * mu) - 0.01, np.arctan(3 * mu) + 0.01):
        k = 0.5
        # rolling: a = g sin / (1 + k), friction needed F/m = g sin k / (1 + k), N/m = g cos
        need = g * np.sin(alpha) * k / (1 + k)
        avail = mu * g * np.cos(alpha)
        slides = need > avail
        check(f"10.3 mu = {mu}, alpha = {alpha:.4f}: slides from rest iff tan(alpha) > 3 mu",
              slides == (np.tan(alpha) > 3 * mu))
        if slides:
            # sliding from rest, friction up the slope (section 5, isotropic): the slip grows, never sticks
            sdot = g * (np.sin(alpha) - mu * np.cos(alpha) * (1 + 1 / k))
            check(f"mu = {mu}, alpha = {alpha:.4f}: sliding slip acceleration g (sin - 3 mu cos) > 0", sdot > 0
                  and abs(sdot - g * (np.sin(alpha) - 3 * mu * np.cos(alpha))) < 1e-12)
# ---------------------------------------------------------------- 10.5 the falling disk's lift-off
# Rolling about the fixed contact point (contact-forces.md 6.4): theta'' = (4 g / (5 r)) sin(theta);
# integrate it independently to N = 0 and evaluate the free disk's gap acceleration there.
m, r, th0 = 0.5, 0.2, 0.1
def disk_rhs(y, ys=None):
    return np.array([y[1], 4 * g / (5 * r) * np.sin(y[0])])
def disk_N(y):   # N = m (g - r cos th th'^2 - r sin th th'') (contact-forces.md (D1), psi' = phi' = 0)
    return m * (g - r * np.cos(y[0]) * y[1]**2 - r * np.sin(y[0]) * disk_rhs(y)[1])
tl, yl = integrate_until(disk_rhs, np.array([th0, 0.0]), 1e-4, disk_N, 5.0)
kk = np.cos(th0)
cL = (2 * kk + np.sqrt(4 * kk**2 - 3)) / 6
check("10.5 disk: N = 0 at cos = (2k + sqrt(4k^2 - 3))/6, theta = 1.052986", abs(np.cos(yl[0]) - cL) < 1e-9
      and abs(yl[0] - 1.052986) < 1e-6)
Flat = 0.8 * m * g * np.sin(yl[0]) * (2 * kk - 3 * cL)
gdd_free = -g + r * np.cos(yl[0]) * yl[1]**2        # free: z_C'' = -g, theta'' = 0
check(f"10.5 disk: F_lat = {Flat:.4f} N != 0 there, and the free gap acceleration -g + r cos th th'^2 = "
      f"{gdd_free / g:.4f} g < 0 (= -g + (8g/5) c (k - c))", Flat > 0.1 and gdd_free < 0
      and abs(gdd_free - (-g + 1.6 * g * cL * (kk - cL))) < 1e-8)
print("closed_forms: %d failure(s)" % failures)
sys.exit(1 if failures else 0)
