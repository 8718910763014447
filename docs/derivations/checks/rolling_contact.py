#!/usr/bin/python3
"""Independent Newton-Euler model of one rigid body rolling without slip, shared by the
rolling_*.py checks; run directly it checks the ellipsoid's closed-form contact point (f).

Why Newton-Euler and not the project's formulation: these checks must not share a derivation
with nhdyn. The body's state is y = [x (centre of mass, world), q (unit quaternion w,x,y,z,
body -> world), v (velocity of the centre of mass), w (angular velocity, world axes)].
A shape supplies r_c(x, q, t): the vector from the centre of mass to the contact point (world
axes), in closed form. The ground supplies u_g(p, t): the velocity of the ground's material point
at p. The rolling constraint (no slip) is

    C = v + w x r_c - u_g(x + r_c, t) = 0        (3 equations; its normal component is the
                                                  derivative of the contact condition)

Newton and Euler with the contact force L at the contact point:

    m a = m g + L,      I_w alpha + w x (I_w w) = r_c x L,      I_w = R I_b R^T

and dC/dt = 0:  a + alpha x r_c + [dC/dx v + dC/dq q' + dC/dt] = 0, with q' = 1/2 (0, w) * q.
The bracket ("bias") is formed by sympy differentiating r_c and u_g exactly: this is the term
of the contact point moving over the body and over the ground. The 9 x 9 linear system
[[m 1, 0, -1], [0, I_w, -[r_c]x], [1, -[r_c]x, 0]] (a, alpha, L) = rhs is solved at each step.
"""
import numpy as np
import sympy as sp
from scipy.integrate import solve_ivp

X = sp.Matrix(sp.symbols('px0:3', real=True))
Q = sp.Matrix(sp.symbols('qu0:4', real=True))
V = sp.Matrix(sp.symbols('vel0:3', real=True))
W = sp.Matrix(sp.symbols('om0:3', real=True))
T = sp.Symbol('time', real=True)


def quat_to_R(q):
    """Rotation matrix of a unit quaternion (w, x, y, z); works for sympy and numpy."""
    w, x, y, z = q[0], q[1], q[2], q[3]
    rows = [[1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)],
            [2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)],
            [2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)]]
    if isinstance(q, sp.MatrixBase):
        return sp.Matrix(rows)
    return np.array(rows, dtype=float)


def quat_rate(q, w):
    """q' for the world-axes angular velocity w: q' = 1/2 (0, w) * q."""
    w0, w1, w2 = w[0], w[1], w[2]
    q0, q1, q2, q3 = q[0], q[1], q[2], q[3]
    vals = [-(w0 * q1 + w1 * q2 + w2 * q3) / 2,
            (w0 * q0 + w1 * q3 - w2 * q2) / 2,
            (-w0 * q3 + w1 * q0 + w2 * q1) / 2,
            (w0 * q2 - w1 * q1 + w2 * q0) / 2]
    if isinstance(q, sp.MatrixBase):
        return sp.Matrix(vals)
    return np.array(vals)


def quat_axis_angle(axis, angle):
    axis = np.asarray(axis, float) / np.linalg.norm(axis)
    return np.concatenate([[np.cos(angle / 2)], np.sin(angle / 2) * axis])


def quat_mul(a, b):
    w1, x1, y1, z1 = a
    w2, x2, y2, z2 = b
    return np.array([w1 * w2 - x1 * x2 - y1 * y2 - z1 * z2,
                     w1 * x2 + x1 * w2 + y1 * z2 - z1 * y2,
                     w1 * y2 - x1 * z2 + y1 * w2 + z1 * x2,
                     w1 * z2 + x1 * y2 - y1 * x2 + z1 * w2])


def skew(r):
    return np.array([[0, -r[2], r[1]], [r[2], 0, -r[0]], [-r[1], r[0], 0]])


def ellipsoid_contact_body(Minv, n):
    """Point of the ellipsoid x^T M x = 1 whose outward normal is -n (n: the plane's unit normal
    pointing into the body's side, body axes): p = -M^-1 n / sqrt(n^T M^-1 n)."""
    Mn = Minv * n
    return -Mn / sp.sqrt((n.T * Mn)[0, 0])


class RollingBody:
    """r_c_expr: sympy 3-vector in X, Q, T (and parameter symbols already substituted).
    u_g_expr: function p -> sympy 3-vector (the ground's velocity field), may use T."""

    def __init__(self, m, I_body, r_c_expr, u_g=None, gravity=(0.0, 0.0, -9.81), no_spin=None):
        """no_spin = (n, Omega): "rubber" rolling on a plane of constant normal n turning at the
        constant rate Omega: also n . w = Omega, held by a moment M_s n (a tenth unknown)."""
        self.no_spin = None if no_spin is None else (np.array(no_spin[0], float), float(no_spin[1]))
        self.m = float(m)
        self.Ib = np.array(I_body, dtype=float)
        self.g = np.array(gravity, dtype=float)
        r_c = sp.Matrix(r_c_expr)
        p = X + r_c
        ug = sp.zeros(3, 1) if u_g is None else sp.Matrix(u_g(p))
        C = V + W.cross(r_c) - ug
        qdot = quat_rate(Q, W)
        bias = C.jacobian(X) * V + C.jacobian(Q) * qdot + C.diff(T)
        args = (T, *X, *Q, *V, *W)
        self._rc = sp.lambdify(args, list(r_c), 'numpy', cse=True)
        self._bias = sp.lambdify(args, list(bias), 'numpy', cse=True)
        self._ug = sp.lambdify(args, list(ug), 'numpy', cse=True)

    def split(self, y):
        return y[0:3], y[3:7], y[7:10], y[10:13]

    def r_c(self, t, y):
        return np.array(self._rc(t, *y), dtype=float)

    def ground_velocity(self, t, y):
        return np.array(self._ug(t, *y), dtype=float)

    def solve(self, t, y):
        """Accelerations and contact force at the state y."""
        x, q, v, w = self.split(y)
        R = quat_to_R(q / np.linalg.norm(q))
        Iw = R @ self.Ib @ R.T
        rc = self.r_c(t, y)
        bias = np.array(self._bias(t, *y), dtype=float)
        S = skew(rc)
        N = 9 if self.no_spin is None else 10
        K = np.zeros((N, N))
        K[0:3, 0:3] = self.m * np.eye(3)
        K[0:3, 6:9] = -np.eye(3)
        K[3:6, 3:6] = Iw
        K[3:6, 6:9] = -S
        K[6:9, 0:3] = np.eye(3)
        K[6:9, 3:6] = -S          # alpha x r_c = -r_c x alpha
        rhs = np.concatenate([self.m * self.g, -np.cross(w, Iw @ w), -bias])
        if self.no_spin is not None:
            n = self.no_spin[0]
            K[3:6, 9] = -n            # Euler: I_w alpha + w x I_w w = r_c x L + M_s n
            K[9, 3:6] = n             # d/dt (n . w) = n . alpha = 0
            rhs = np.concatenate([rhs, [0.0]])
        sol = np.linalg.solve(K, rhs)
        return sol[0:3], sol[3:6], sol[6:9]

    def rhs(self, t, y):
        x, q, v, w = self.split(y)
        a, alpha, _ = self.solve(t, y)
        return np.concatenate([v, quat_rate(q, w), a, alpha])

    def constraint(self, t, y):
        x, q, v, w = self.split(y)
        return v + np.cross(w, self.r_c(t, y)) - self.ground_velocity(t, y)

    def energy(self, t, y):
        x, q, v, w = self.split(y)
        R = quat_to_R(q / np.linalg.norm(q))
        Iw = R @ self.Ib @ R.T
        return 0.5 * self.m * v @ v + 0.5 * w @ Iw @ w - self.m * self.g @ x

    def integrate(self, y0, t_end, rtol=1e-12, atol=1e-13, **kw):
        return solve_ivp(self.rhs, (0.0, t_end), y0, method='DOP853', rtol=rtol, atol=atol,
                         dense_output=True, **kw)


def zero_crossings(sol, f, t0, t1, n=4000):
    """Upward zero crossings of the scalar f(y) along a dense solution, refined by brentq."""
    from scipy.optimize import brentq
    ts = np.linspace(t0, t1, n)
    vals = np.array([f(sol.sol(t)) for t in ts])
    out = []
    for i in range(len(ts) - 1):
        if vals[i] < 0 <= vals[i + 1]:
            out.append(brentq(lambda s: f(sol.sol(s)), ts[i], ts[i + 1], xtol=1e-14))
    return np.array(out)


def measured_omega(sol, f, t_end):
    """Angular frequency from the mean spacing of upward zero crossings of f."""
    zc = zero_crossings(sol, f, 0.0, t_end)
    period = (zc[-1] - zc[0]) / (len(zc) - 1)
    return 2 * np.pi / period, len(zc)


if __name__ == '__main__':
    # (f) The contact point of x^T M x = 1 on a plane with normal n (body axes, pointing into
    # the body's side) is p = -M^-1 n / sqrt(n^T M^-1 n); the centre's height is sqrt(n^T M^-1 n).
    # Check against a brute-force minimisation of n . x over the surface at random M and n.
    from scipy.optimize import minimize
    rng = np.random.default_rng(1)
    worst_p, worst_h = 0.0, 0.0
    for trial in range(20):
        A = rng.normal(size=(3, 3))
        Rr, _ = np.linalg.qr(A)
        semi = rng.uniform(0.3, 2.0, 3)
        M = Rr @ np.diag(1 / semi**2) @ Rr.T         # a general (rotated) ellipsoid
        n = rng.normal(size=3)
        n /= np.linalg.norm(n)
        Minv = np.linalg.inv(M)
        p = -Minv @ n / np.sqrt(n @ Minv @ n)
        h = np.sqrt(n @ Minv @ n)
        # surface point x(u, v) = L s(u, v) with M = L^-T L^-1, s on the unit sphere
        L = np.linalg.inv(np.linalg.cholesky(M).T)
        def height(uv):
            s = np.array([np.cos(uv[0]) * np.cos(uv[1]), np.cos(uv[0]) * np.sin(uv[1]),
                          np.sin(uv[0])])
            return n @ (L @ s)
        best = None
        for start in rng.uniform(-3, 3, size=(8, 2)):
            r = minimize(height, start, method='Nelder-Mead',
                         options={'xatol': 1e-13, 'fatol': 1e-15, 'maxiter': 20000})
            if best is None or r.fun < best.fun:
                best = r
        uv = best.x
        s = np.array([np.cos(uv[0]) * np.cos(uv[1]), np.cos(uv[0]) * np.sin(uv[1]), np.sin(uv[0])])
        pnum = L @ s
        worst_p = max(worst_p, np.linalg.norm(pnum - p))
        worst_h = max(worst_h, abs(-best.fun - h))
        assert abs(p @ M @ p - 1) < 1e-13                     # on the surface
        g = M @ p
        assert np.linalg.norm(g / np.linalg.norm(g) + n) < 1e-13  # outward normal is -n
    print(f"(f) ellipsoid contact point p = -M^-1 n / sqrt(n^T M^-1 n): max |p - brute force| = "
          f"{worst_p:.2e}, max height error = {worst_h:.2e} over 20 random M, n")
    assert worst_p < 1e-6 and worst_h < 1e-12

    # (f) The normal component of the rolling constraint v + w x R p(R^T e_z) is the time
    # derivative of the contact condition z_G - sqrt(n^T M^-1 n) = 0 (CoM at the centre):
    # check symbolically, with n = R^T e_z and R from a quaternion.
    a, b, c = sp.symbols('a b c', positive=True)
    Minv_s = sp.diag(a**2, b**2, c**2)
    Rs = quat_to_R(Q)
    n_b = Rs.T * sp.Matrix([0, 0, 1])
    rc = Rs * ellipsoid_contact_body(Minv_s, n_b)
    hgt = sp.sqrt((n_b.T * Minv_s * n_b)[0, 0])
    phi = X[2] - hgt                                   # contact condition
    dphi = (sp.Matrix([phi]).jacobian(X) * V + sp.Matrix([phi]).jacobian(Q) * quat_rate(Q, W))[0]
    normal_c = V[2] + W.cross(rc)[2]
    vals = {a: 0.7, b: 0.4, c: 0.25}
    qq = np.array([0.8, 0.3, -0.4, 0.2]); qq /= np.linalg.norm(qq)
    vals.update(dict(zip(Q, qq)))
    vals.update(dict(zip(V, [0.3, -0.2, 0.5])))
    vals.update(dict(zip(W, [1.1, -0.7, 0.4])))
    diff = float((dphi - normal_c).subs(vals))
    print(f"(f) normal rolling constraint minus d/dt(contact condition) at a random state: {diff:.1e}")
    assert abs(diff) < 1e-14
