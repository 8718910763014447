#!/usr/bin/python3
"""Numerical checks of docs/derivations/optimal-programs.md.

Run with Debian's interpreter (python3-numpy, python3-scipy):

    /usr/bin/python3 docs/derivations/checks/optimal_programs_check.py

What it checks, each against a closed form derived in the document:
  1. the Jacobian identity of the projected defect with the partition complement,
     d(D r) = D (dr - db^T mu), mu = b_d^-T r_d, at points that satisfy no equation;
  2. the double integrator with least control energy: u(t), x(t) and the cost 12 d^2 / T^3;
  3. the Brockett integrator from the origin to (0, 0, a): cost 2 pi a / T, z(t), x^2 + y^2;
  4. the brachistochrone as a knife edge (Chaplygin-sleigh constraint) in least time: the
     cycloid's time and path;
  5. final conditions that fix what a constraint fixes: a mass on a circle in Cartesian
     coordinates, turned from rest to rest (the double integrator in the angle).
Each problem is transcribed exactly as the document states it (q, q', q'', u at every point, the
dynamics defect [D A; b] q'' - [D (Q + G + B u); -b0]), and the NLP is solved by Newton's method
on its optimality conditions (all these optima are interior: no bound is active), with exact
first derivatives (complex step) and the Hessian of the Lagrangian by central differences of
the exact gradient. The errors are printed against the number of intervals, with the observed
order, for the trapezoidal and the Hermite-Simpson (separated) transcriptions; then the controls
are replayed (interpolated as the method defines them) by an adaptive integrator of the KKT form
of the equations, and the largest difference from the collocated states is printed.
The script exits with status 1 if any check fails its tolerance.
"""
import sys

import numpy as np
import scipy.linalg
import scipy.optimize
import scipy.sparse
import scipy.sparse.linalg
from scipy.integrate import solve_ivp

FAILURES = []


def check(what, ok):
    print(("  ok    " if ok else "  FAIL  ") + what)
    if not ok:
        FAILURES.append(what)


# --------------------------------------------------------------------------------------------
# Models: vectorized over P points (arrays with a leading dimension P), complex-safe.
# terms(t, q, v) -> A (P,n,n), h = Q + G (P,n), b (P,s,n), b0 (P,s); B(t, q, v) -> (P,n,m);
# L(t, q, v, u) -> (P,) the Lagrange integrand (None: minimum time);
# vel_res(t, q, v) -> (r,) at one point: the velocity-level constraints (and the position ones
# differentiated); pos_res(t, q) -> (p,).
# --------------------------------------------------------------------------------------------
class DoubleIntegrator:
    """x'' = F / m; least integral of F^2, rest to rest over the distance d in time T."""
    name = "double integrator"
    n, s, m = 1, 0, 1

    def __init__(self, mass=1.0):
        self.mass = mass

    def terms(self, t, q, v):
        P = q.shape[0]
        A = np.zeros((P, 1, 1), dtype=q.dtype) + self.mass
        return A, np.zeros((P, 1), dtype=q.dtype), np.zeros((P, 0, 1), dtype=q.dtype), np.zeros((P, 0), dtype=q.dtype)

    def B(self, t, q, v):
        return np.ones((q.shape[0], 1, 1), dtype=q.dtype)

    def L(self, t, q, v, u):
        return u[:, 0] ** 2

    def vel_res(self, t, q, v):
        return np.zeros(0, dtype=q.dtype)

    def pos_res(self, t, q):
        return np.zeros(0, dtype=q.dtype)


class Brockett:
    """x' = u1, y' = u2, z' = x u2 - y u1 as a mechanical system: a point (x, y) of mass m
    pushed by forces F_x, F_y, a coordinate z of inertia m_z, the nonholonomic constraint
    f = z' - x y' + y x' = 0; objective the integral of x'^2 + y'^2 (the forces cost nothing)."""
    name = "Brockett integrator"
    n, s, m = 3, 1, 2

    def __init__(self, mass=1.0, mass_z=1.0):
        self.mass, self.mass_z = mass, mass_z

    def terms(self, t, q, v):
        P = q.shape[0]
        A = np.zeros((P, 3, 3), dtype=q.dtype)
        A[:, 0, 0] = A[:, 1, 1] = self.mass
        A[:, 2, 2] = self.mass_z
        h = np.zeros((P, 3), dtype=q.dtype)
        b = np.stack([q[:, 1], -q[:, 0], np.ones(P, dtype=q.dtype)], axis=1)[:, None, :]
        # b0 = (df/dq) q' = (-y') x' + (x') y' = 0
        b0 = (-v[:, 1] * v[:, 0] + v[:, 0] * v[:, 1])[:, None]
        return A, h, b, b0

    def B(self, t, q, v):
        B = np.zeros((q.shape[0], 3, 2), dtype=q.dtype)
        B[:, 0, 0] = B[:, 1, 1] = 1.0
        return B

    def L(self, t, q, v, u):
        return v[:, 0] ** 2 + v[:, 1] ** 2

    def vel_res(self, t, q, v):
        return np.array([v[2] - q[0] * v[1] + q[1] * v[0]])

    def pos_res(self, t, q):
        return np.zeros(0, dtype=q.dtype)


class Brachistochrone:
    """A knife edge (Chaplygin-sleigh constraint) in a vertical plane: q = (x, y, theta), y
    downward, the blade's direction theta turned by a torque on a wheel of inertia J;
    f = -sin(theta) x' + cos(theta) y' = 0; least time, as the integral of 1 + w tau^2: the optimal
    torque is zero, so w > 0 leaves the optimum as it is and removes the free mode of the torque
    (document, section 10.3)."""
    name = "brachistochrone"
    n, s, m = 3, 1, 1

    def __init__(self, mass=1.0, inertia=1.0, g=9.81, torque_weight=1e-2):
        self.mass, self.inertia, self.g, self.w = mass, inertia, g, torque_weight

    def terms(self, t, q, v):
        P = q.shape[0]
        A = np.zeros((P, 3, 3), dtype=q.dtype)
        A[:, 0, 0] = A[:, 1, 1] = self.mass
        A[:, 2, 2] = self.inertia
        h = np.zeros((P, 3), dtype=q.dtype)
        h[:, 1] = self.mass * self.g  # Q = -dV/dq with V = -m g y
        th = q[:, 2]
        b = np.stack([-np.sin(th), np.cos(th), np.zeros(P, dtype=q.dtype)], axis=1)[:, None, :]
        b0 = ((-np.cos(th) * v[:, 0] - np.sin(th) * v[:, 1]) * v[:, 2])[:, None]
        return A, h, b, b0

    def B(self, t, q, v):
        B = np.zeros((q.shape[0], 3, 1), dtype=q.dtype)
        B[:, 2, 0] = 1.0
        return B

    def L(self, t, q, v, u):
        return 1.0 + self.w * u[:, 0] ** 2

    def vel_res(self, t, q, v):
        return np.array([-np.sin(q[2]) * v[0] + np.cos(q[2]) * v[1]])

    def pos_res(self, t, q):
        return np.zeros(0, dtype=q.dtype)


class CircleMass:
    """A unit mass on the unit circle in Cartesian coordinates (holonomic constraint
    phi = (x^2 + y^2 - 1)/2), turned by a tangential force u along (-y, x); least integral of u^2."""
    name = "mass on a circle"
    n, s, m = 2, 1, 1

    def terms(self, t, q, v):
        P = q.shape[0]
        A = np.zeros((P, 2, 2), dtype=q.dtype)
        A[:, 0, 0] = A[:, 1, 1] = 1.0
        b = q[:, None, :].copy()  # dphi/dq
        b0 = (v[:, 0] ** 2 + v[:, 1] ** 2)[:, None]
        return A, np.zeros((P, 2), dtype=q.dtype), b, b0

    def B(self, t, q, v):
        return np.stack([-q[:, 1], q[:, 0]], axis=1)[:, :, None]

    def L(self, t, q, v, u):
        return u[:, 0] ** 2

    def vel_res(self, t, q, v):
        return np.array([q[0] * v[0] + q[1] * v[1]])

    def pos_res(self, t, q):
        return np.array([(q[0] ** 2 + q[1] ** 2 - 1) / 2])


# --------------------------------------------------------------------------------------------
# The dynamics defect with the partition complement (document, section 4).
# --------------------------------------------------------------------------------------------
def choose_partition(b):
    """Dependent coordinates per point: the first s pivots of a column-pivoted QR of b."""
    P, s, n = b.shape
    dep = np.zeros((P, s), dtype=int)
    ind = np.zeros((P, n - s), dtype=int)
    for p in range(P):
        if s:
            _, _, piv = scipy.linalg.qr(b[p].real, pivoting=True)
            dep[p] = np.sort(piv[:s])
        ind[p] = np.array([i for i in range(n) if i not in set(dep[p])], dtype=int)
    return dep, ind


def dynamics_defect(model, t, q, v, a, u, dep, ind):
    """[D r; b a + b0] with r = A a - Q - G - B u and D = [I_k, -b_i^T b_d^-T] (partition)."""
    A, h, b, b0 = model.terms(t, q, v)
    B = model.B(t, q, v)
    r = np.einsum("pij,pj->pi", A, a) - h - np.einsum("pij,pj->pi", B, u)
    if model.s == 0:
        return r
    ri = np.take_along_axis(r, ind, axis=1)
    rd = np.take_along_axis(r, dep, axis=1)
    bi = np.take_along_axis(b, ind[:, None, :], axis=2)  # (P, s, k)
    bd = np.take_along_axis(b, dep[:, None, :], axis=2)  # (P, s, s)
    mu = np.linalg.solve(np.transpose(bd, (0, 2, 1)), rd[:, :, None])[:, :, 0]
    Dr = ri - np.einsum("psk,ps->pk", bi, mu)
    e = np.einsum("psn,pn->ps", b, a) + b0
    return np.concatenate([Dr, e], axis=1)


def check_jacobian_identity():
    """d(D r) = D (dr - db^T mu) at random points that satisfy nothing, against the complex-step
    derivative of the whole projected defect (which differentiates D through b_d^-1)."""
    print("\n1. Jacobian of the projected defect without dD (partition complement)")
    rng = np.random.default_rng(7)
    worst = 0.0
    for model in (Brockett(1.3, 0.7), Brachistochrone(1.1, 0.4)):
        dropped = 0.0
        n, s, m = model.n, model.s, model.m
        for trial in range(20):
            q, v, a = (rng.normal(size=(1, n)) for _ in range(3))
            u = rng.normal(size=(1, m))
            t = np.zeros(1)
            _, _, b, _ = model.terms(t, q, v)
            dep, ind = choose_partition(b)
            A, h, b, b0 = model.terms(t, q, v)
            B = model.B(t, q, v)
            r = A[0] @ a[0] - h[0] - B[0] @ u[0]
            bd, bi = b[0][:, dep[0]], b[0][:, ind[0]]
            mu = np.linalg.solve(bd.T, r[dep[0]])
            D = np.zeros((n - s, n))
            D[:, ind[0]] = np.eye(n - s)
            D[:, dep[0]] = -bi.T @ np.linalg.inv(bd.T)
            for which in ("q", "v"):
                for i in range(n):
                    eps = 1e-30
                    dq = np.zeros((1, n), dtype=complex)
                    dq[0, i] = 1j * eps
                    qc = q + dq if which == "q" else q.astype(complex)
                    vc = v + dq if which == "v" else v.astype(complex)
                    Ac, hc, bc, b0c = model.terms(t, qc, vc)
                    Bc = model.B(t, qc, vc)
                    dr = (Ac[0] @ a[0] - hc[0] - Bc[0] @ u[0]).imag / eps
                    db = bc[0].imag / eps
                    formula = D @ (dr - db.T @ mu)
                    whole = dynamics_defect(model, t, qc, vc, a.astype(complex), u.astype(complex), dep, ind)
                    direct = whole[0, : n - s].imag / eps
                    naive = D @ dr  # what one gets by ignoring the dependence of D
                    err = np.max(np.abs(formula - direct)) / max(1.0, np.max(np.abs(direct)))
                    worst = max(worst, err)
                    dropped = max(dropped, np.max(np.abs(naive - direct)))
        print(f"  {model.name}: largest |D dr - d(D r)| = {dropped:.2e} (the term dD r, which the identity "
              f"replaces by -D db^T mu)")
    check(f"D (dr - db^T mu) equals d(D r) to {worst:.1e} (relative) at 40 random states", worst < 1e-13)


# --------------------------------------------------------------------------------------------
# The transcription (document, sections 2 and 4).
# --------------------------------------------------------------------------------------------
class Transcription:
    """Variables: per point z = (q, q', q'', u), then T = t_end - t0 (last entry, always a
    variable; fixed by a constraint when t_end is given). Points: the N + 1 nodes (trapezoidal),
    or nodes and midpoints interleaved, node j at 2j and midpoint j at 2j + 1 (Hermite-Simpson)."""

    def __init__(self, model, method, N, T, initial, final, pins=()):
        self.model, self.method, self.N = model, method, N
        n, m = model.n, model.m
        self.nz = 3 * n + m
        self.P = N + 1 if method == "trapezoidal" else 2 * N + 1
        self.stride = 1 if method == "trapezoidal" else 2
        self.tau = np.arange(self.P) / (self.P - 1)  # t_p = t0 + tau_p T
        self.T_fixed = T  # None: free
        self.initial, self.final, self.pins = initial, final, pins  # {(kind, index): value}
        self.dep = self.ind = None
        self.regularization = 0.0
        self.constraint_level = "acceleration"
        # False when the fixed initial values already imply the constraints there (their rows
        # would repeat the boundary rows: document, section 5)
        self.initial_constraints = True

    def nvar(self):
        return self.P * self.nz + 1

    def split(self, x):
        n, m = self.model.n, self.model.m
        Z = x[:-1].reshape(self.P, self.nz)
        return Z[:, :n], Z[:, n:2 * n], Z[:, 2 * n:3 * n], Z[:, 3 * n:], x[-1]

    def constraints(self, x):
        """The constraint vector and, per row, the points it reads (for the Jacobian's colouring)."""
        model, n = self.model, self.model.n
        q, v, a, u, T = self.split(x)
        h = T / self.N
        rows, pts = [], []
        # collocation defects on y = (q, q'), f = (q', q'')
        for j in range(self.N):
            if self.method == "trapezoidal":
                p0, p1 = j, j + 1
                rows.append(q[p1] - q[p0] - h / 2 * (v[p0] + v[p1]))
                rows.append(v[p1] - v[p0] - h / 2 * (a[p0] + a[p1]))
                pts += [(p0, p1)] * 2
            else:
                p0, pm, p1 = 2 * j, 2 * j + 1, 2 * j + 2
                rows.append(q[p1] - q[p0] - h / 6 * (v[p0] + 4 * v[pm] + v[p1]))
                rows.append(v[p1] - v[p0] - h / 6 * (a[p0] + 4 * a[pm] + a[p1]))
                rows.append(q[pm] - (q[p0] + q[p1]) / 2 - h / 8 * (v[p0] - v[p1]))
                rows.append(v[pm] - (v[p0] + v[p1]) / 2 - h / 8 * (a[p0] - a[p1]))
                pts += [(p0, pm, p1)] * 4
        # dynamics at every point
        t = self.tau * T
        dyn = dynamics_defect(model, t, q, v, a, u, self.dep, self.ind)
        for p in range(self.P):
            if self.constraint_level == "given" and p > 0 and model.s:
                # the velocity-level constraints at every point after the first, in place of
                # b q'' + b0 (document, section 5)
                rows.append(np.concatenate([dyn[p, : model.n - model.s], model.vel_res(t[p], q[p], v[p])]))
            else:
                rows.append(dyn[p])
            pts.append((p,))
        # position and velocity constraints at the first node only
        if self.initial_constraints:
            rows.append(model.pos_res(t[0], q[0]))
            rows.append(model.vel_res(t[0], q[0], v[0]))
            pts += [(0,), (0,)]
        for (kind, i), value in list(self.initial.items()) + list(self.pins):
            rows.append(np.array([(q if kind == "q" else v)[0, i] - value]))
            pts.append((0,))
        for (kind, i), value in self.final.items():
            rows.append(np.array([(q if kind == "q" else v)[-1, i] - value]))
            pts.append((self.P - 1,))
        row_pts = [pp for r, pp in zip(rows, pts) for _ in range(len(r))]
        return np.concatenate(rows), row_pts

    def objective(self, x):
        q, v, a, u, T = self.split(x)
        if self.model.L is None:
            return T
        L = self.model.L(self.tau * T, q, v, u)
        h = T / self.N
        if self.method == "trapezoidal":
            return h / 2 * (L[0] + L[-1]) + h * np.sum(L[1:-1])
        return h / 6 * (L[0::2][:-1].sum() + 4 * L[1::2].sum() + L[0::2][1:].sum())

    # exact first derivatives by the complex step, columns coloured by point index mod 3
    def jacobian(self, x):
        c0, row_pts = self.constraints(x)
        M, nz, P = len(c0), self.nz, self.P
        eps = 1e-30
        rows_i, cols_i, vals = [], [], []
        for colour in range(3):
            for comp in range(nz):
                xc = x.astype(complex)
                cols = [p * nz + comp for p in range(colour, P, 3)]
                xc[cols] += 1j * eps
                dc = np.imag(self.constraints(xc)[0]) / eps
                for r in np.nonzero(dc)[0]:
                    p = [pp for pp in row_pts[r] if pp % 3 == colour]
                    rows_i.append(r)
                    cols_i.append(p[0] * nz + comp)
                    vals.append(dc[r])
        xc = x.astype(complex)
        xc[-1] += 1j * eps
        dc = np.imag(self.constraints(xc)[0]) / eps
        for r in np.nonzero(dc)[0]:
            rows_i.append(r)
            cols_i.append(len(x) - 1)
            vals.append(dc[r])
        J = scipy.sparse.csr_matrix((vals, (rows_i, cols_i)), shape=(M, len(x)))
        return c0, J

    def gradient(self, x):
        """Exact gradient of the objective: a weighted sum of per-point terms, so one complex
        step per component of z gives every point's derivative at once."""
        g = np.zeros(len(x))
        for comp in range(self.nz):
            g[comp:-1:self.nz] = self._point_gradient(x, comp)
        xc = x.astype(complex)
        xc[-1] += 1j * 1e-30
        g[-1] = np.imag(self.objective(xc)) / 1e-30
        return g

    def _point_gradient(self, x, comp):
        q, v, a, u, T = self.split(x)
        if self.model.L is None:
            return np.zeros(self.P)
        eps = 1e-30
        Z = x[:-1].reshape(self.P, self.nz).astype(complex)
        Z[:, comp] += 1j * eps
        n = self.model.n
        L = self.model.L(self.tau * T, Z[:, :n], Z[:, n:2 * n], Z[:, 3 * n:])
        h = T / self.N
        if self.method == "trapezoidal":
            w = np.full(self.P, h)
            w[0] = w[-1] = h / 2
        else:
            w = np.where(np.arange(self.P) % 2 == 1, 4 * h / 6, 2 * h / 6)
            w[0] = w[-1] = h / 6
        return w * np.imag(L) / eps

    def lagrangian_hessian(self, x, lam):
        """Central differences of the exact gradient of the Lagrangian; the Hessian is block
        diagonal per point plus the row and column of T (document, section 8)."""
        nv, nz, P = len(x), self.nz, self.P

        def grad_lag(xx):
            _, J = self.jacobian(xx)
            return self.gradient(xx) + J.T @ lam

        rows_i, cols_i, vals = [], [], []
        for comp in range(nz + 1):
            d = np.zeros(nv)
            if comp < nz:
                delta = 1e-6 * max(1.0, np.max(np.abs(x[comp:-1:nz])))
                d[comp:-1:nz] = delta
            else:
                delta = 1e-6 * max(1.0, abs(x[-1]))
                d[-1] = delta
            col = (grad_lag(x + d) - grad_lag(x - d)) / (2 * delta)
            if comp < nz:
                for p in range(P):
                    blk = col[p * nz:(p + 1) * nz]
                    for i in np.nonzero(blk)[0]:
                        rows_i.append(p * nz + i)
                        cols_i.append(p * nz + comp)
                        vals.append(blk[i])
            else:
                for i in np.nonzero(col)[0]:
                    rows_i.append(i)
                    cols_i.append(nv - 1)
                    vals.append(col[i])
                    if i != nv - 1:  # symmetry gives the row of T
                        rows_i.append(nv - 1)
                        cols_i.append(i)
                        vals.append(col[i])
        H = scipy.sparse.csr_matrix((vals, (rows_i, cols_i)), shape=(nv, nv))
        return 0.5 * (H + H.T)

    def solve(self, x0, tol=1e-11, max_iter=60):
        """Newton's method on the optimality conditions; with t_end given, T is not a variable
        (the last entry of x keeps its value)."""
        x0 = x0.copy()
        if self.T_fixed is not None:
            x0[-1] = self.T_fixed
        nf = len(x0) - (self.T_fixed is not None)  # the variables Newton moves
        q, v, _, _, _ = self.split(x0)
        _, _, b, _ = self.model.terms(self.tau * x0[-1], q, v)
        self.dep, self.ind = choose_partition(b)
        x = x0.copy()
        c, J = self.jacobian(x)
        # least-squares multipliers for the start
        g = self.gradient(x)
        lam = scipy.sparse.linalg.lsqr(J[:, :nf].T, -g[:nf], atol=1e-14, btol=1e-14)[0]
        for it in range(max_iter):
            g = self.gradient(x)
            kkt = np.concatenate([(g + J.T @ lam)[:nf], c])
            res = np.max(np.abs(kkt))
            if res < tol:
                return x, it, res
            # a small multiple of the identity, as IPOPT's inertia correction adds: the Brockett
            # problem leaves q'' and u a mode that changes no state (document, section 5)
            H = self.lagrangian_hessian(x, lam)[:nf, :nf] + self.regularization * scipy.sparse.identity(nf)
            Jf = J[:, :nf]
            K = scipy.sparse.bmat([[H, Jf.T], [Jf, None]], format="csc")
            step = scipy.sparse.linalg.spsolve(K, -kkt)
            alpha = 1.0
            for _ in range(30):
                xn, lamn = x.copy(), lam + alpha * step[nf:]
                xn[:nf] += alpha * step[:nf]
                cn, Jn = self.jacobian(xn)
                rn = np.max(np.abs(np.concatenate([(self.gradient(xn) + Jn.T @ lamn)[:nf], cn])))
                if rn < (1 - 1e-4 * alpha) * res or rn < tol:
                    break
                alpha /= 2
            x, lam, c, J = xn, lamn, cn, Jn
        raise RuntimeError(f"{self.model.name}, {self.method}, N = {self.N}: no convergence (KKT {res:.2e})")

    # the controls as the method interpolates them (document, sections 3 and 9)
    def control_function(self, x):
        _, _, _, u, T = self.split(x)
        h = T / self.N

        def uf(t):
            j = min(int(t / h), self.N - 1)
            s = t / h - j
            if self.method == "trapezoidal":
                return (1 - s) * u[j] + s * u[j + 1]
            u0, um, u1 = u[2 * j], u[2 * j + 1], u[2 * j + 2]
            return u0 * (1 - s) * (1 - 2 * s) + um * 4 * s * (1 - s) + u1 * s * (2 * s - 1)
        return uf

    def replay(self, x):
        """Integrates the equations of motion (KKT form, an independent solve) with the
        interpolated controls from the optimized initial state; largest |q - q_replay| at the
        nodes."""
        model, n = self.model, self.model.n
        q, v, _, _, T = self.split(x)
        uf = self.control_function(x)

        def rhs(t, y):
            qq, vv = y[:n][None, :], y[n:][None, :]
            A, hh, b, b0 = model.terms(np.array([t]), qq, vv)
            B = model.B(np.array([t]), qq, vv)
            s = model.s
            K = np.zeros((n + s, n + s))
            K[:n, :n], K[:n, n:], K[n:, :n] = A[0], b[0].T, b[0]
            rhs_ = np.concatenate([hh[0] + B[0] @ uf(t), -b0[0]])
            return np.concatenate([vv[0], np.linalg.solve(K, rhs_)[:n]])

        h = T / self.N
        worst = 0.0
        y = np.concatenate([q[0], v[0]])
        for j in range(self.N):  # interval by interval: the controls are smooth inside each
            sol = solve_ivp(rhs, (j * h, (j + 1) * h), y, method="DOP853", rtol=1e-13, atol=1e-14)
            y = sol.y[:, -1]
            worst = max(worst, np.max(np.abs(y[:n] - q[(j + 1) * self.stride])))
        return worst


def order(errors):
    return [np.log2(e0 / e1) if e1 > 0 and e0 > 0 else float("nan") for e0, e1 in zip(errors, errors[1:])]


def table(title, Ns, columns):
    print(f"  {title}")
    head = "    N    " + "".join(f"{name:>24}" for name in columns)
    print(head)
    for i, N in enumerate(Ns):
        line = f"    {N:<5}"
        for name, values in columns.items():
            e = values[i]
            o = order(values)[i - 1] if i > 0 else None
            line += f"{e:>14.3e}" + (f" ({o:5.2f})" if o is not None else " " * 8) + "  "
        print(line)


# --------------------------------------------------------------------------------------------
# 2. The double integrator (document, section 10.1)
# --------------------------------------------------------------------------------------------
def double_integrator():
    print("\n2. Double integrator, least integral of u^2, rest to rest: u = 6 d/T^2 (1 - 2t/T), J = 12 d^2/T^3")
    d, T = 1.0, 2.0
    exact_J = 12 * d ** 2 / T ** 3

    def exact(t):
        s = t / T
        return d * (3 * s ** 2 - 2 * s ** 3), d / T * (6 * s - 6 * s ** 2), 6 * d / T ** 2 * (1 - 2 * s)

    # the general closed form (any boundary states) against the same NLP
    x0, v0, x1, v1 = 0.3, -0.5, 1.7, 0.8
    X = x1 - x0 - v0 * T
    general_J = 12 * X ** 2 / T ** 3 - 12 * X * (v1 - v0) / T ** 2 + 4 * (v1 - v0) ** 2 / T
    model = DoubleIntegrator()
    results = {}
    for method, Ns in (("trapezoidal", [4, 8, 16, 32, 64]), ("hermite-simpson", [2, 4, 8, 16])):
        errJ, errx, erru, rep = [], [], [], []
        for N in Ns:
            tr = Transcription(model, method, N, T, {("q", 0): 0.0, ("v", 0): 0.0}, {("q", 0): d, ("v", 0): 0.0})
            t = tr.tau * T
            xs, vs, us = exact(t)
            xg = np.zeros(tr.nvar())
            Z = xg[:-1].reshape(tr.P, tr.nz)
            Z[:, 0], Z[:, 1] = d * tr.tau, d / T  # straight line between the boundary states
            xg[-1] = T
            x, it, res = tr.solve(xg)
            q, v, a, u, _ = tr.split(x)
            errJ.append(abs(tr.objective(x) - exact_J))
            errx.append(np.max(np.abs(q[:, 0] - xs)))
            erru.append(np.max(np.abs(u[:, 0] - us)))
            rep.append(tr.replay(x))
        table(method, Ns, {"|J - 12d^2/T^3|": errJ, "max|x - x(t)|": errx, "max|u - u(t)|": erru,
                           "replay difference": rep})
        results[method] = (Ns, errJ, errx, erru, rep)
    Ns, errJ, errx, erru, rep = results["trapezoidal"]
    o = order(errJ)
    check(f"trapezoidal: objective error of order 2 (last ratio {o[-1]:.3f})", abs(o[-1] - 2) < 0.02)
    check(f"trapezoidal: state error of order 2 (last ratio {order(errx)[-1]:.3f})", abs(order(errx)[-1] - 2) < 0.1)
    check(f"trapezoidal: control error of order 1 only, at the end nodes (last ratio {order(erru)[-1]:.3f})",
          abs(order(erru)[-1] - 1) < 0.15)
    # trapezoidal: the discrete optimum in closed form (document, section 10.1)
    predicted = [exact_J * (4 * N - 3) / (N ** 3 - 4 * N + 3) for N in Ns]
    check("trapezoidal: J_N - J = (12 d^2/T^3) (4N - 3)/(N^3 - 4N + 3) to 1e-12",
          max(abs(e - p) for e, p in zip(errJ, predicted)) < 1e-12)
    Ns, errJ, errx, erru, rep = results["hermite-simpson"]
    check(f"hermite-simpson: exact for this problem (cubic x, linear u): max errors "
          f"{max(errJ):.1e}, {max(errx):.1e}, {max(erru):.1e}, replay {max(rep):.1e}",
          max(errJ + errx + erru + rep) < 1e-9)
    # general boundary states
    tr = Transcription(model, "hermite-simpson", 4, T, {("q", 0): x0, ("v", 0): v0}, {("q", 0): x1, ("v", 0): v1})
    xg = np.zeros(tr.nvar())
    Z = xg[:-1].reshape(tr.P, tr.nz)
    Z[:, 0] = x0 + (x1 - x0) * tr.tau
    xg[-1] = T
    x, _, _ = tr.solve(xg)
    check(f"general boundary states: J = 12X^2/T^3 - 12X dv/T^2 + 4 dv^2/T = {general_J:.12f} "
          f"(solved {tr.objective(x):.12f})", abs(tr.objective(x) - general_J) < 1e-10)


# --------------------------------------------------------------------------------------------
# 3. The Brockett integrator (document, section 10.2)
# --------------------------------------------------------------------------------------------
def brockett():
    print("\n3. Brockett integrator, origin -> (0, 0, a), least integral of u1^2 + u2^2: J = 2 pi a / T")
    a_, T = 1.0, 1.0
    R = np.sqrt(a_ / (2 * np.pi))
    w = 2 * np.pi / T
    exact_J = 2 * np.pi * a_ / T
    model = Brockett()

    def guess(tr):
        # the optimal circle (centre (0, R)) sampled at the points, then moved off it: the guess
        # is not the discrete optimum
        t = tr.tau * T
        x = np.zeros(tr.nvar())
        Z = x[:-1].reshape(tr.P, tr.nz)
        Z[:, 0], Z[:, 1] = R * np.sin(w * t), R * (1 - np.cos(w * t))
        Z[:, 2] = R ** 2 * (w * t - np.sin(w * t))
        Z[:, 3], Z[:, 4] = R * w * np.cos(w * t), R * w * np.sin(w * t)
        Z[:, 5] = R ** 2 * w * (1 - np.cos(w * t))
        Z[:, 6], Z[:, 7] = -R * w ** 2 * np.sin(w * t), R * w ** 2 * np.cos(w * t)
        Z[:, 8] = R ** 2 * w ** 2 * np.sin(w * t)
        Z[:, 9:11] = Z[:, 6:8]  # forces = m q'' on (x, y) up to the reaction
        Z[:, :9] *= 1 + 0.05 * np.sin(3 * w * t)[:, None]
        x[-1] = T
        return x

    for method, Ns in (("trapezoidal", [8, 16, 32, 64]), ("hermite-simpson", [4, 8, 16, 32])):
        errJ, errz, errr, rep, drift = [], [], [], [], []
        for N in Ns:
            # y'(0) = 0 picks one optimum of the family (rotations about z): document, section 10.2
            tr = Transcription(model, method, N, T, {("q", 0): 0.0, ("q", 1): 0.0, ("q", 2): 0.0},
                               {("q", 0): 0.0, ("q", 1): 0.0, ("q", 2): a_}, pins=[(("v", 1), 0.0)])
            # the objective does not see the forces: the constraint is imposed at the level it is
            # given (velocity) at every point, and the mode of q'' and u that moves no state is
            # regularized as IPOPT does (document, sections 5 and 9.2)
            tr.constraint_level, tr.regularization = "given", 1e-9
            x, it, res = tr.solve(guess(tr), tol=1e-9)
            q, v, _, _, _ = tr.split(x)
            t = tr.tau * T
            errJ.append(abs(tr.objective(x) - exact_J))
            errz.append(np.max(np.abs(q[:, 2] - R ** 2 * (w * t - np.sin(w * t)))))
            errr.append(np.max(np.abs(q[:, 0] ** 2 + q[:, 1] ** 2 - 2 * R ** 2 * (1 - np.cos(w * t)))))
            rep.append(tr.replay(x))
            f = v[:, 2] - q[:, 0] * v[:, 1] + q[:, 1] * v[:, 0]
            drift.append(np.max(np.abs(f)))
        table(method, Ns, {"|J - 2 pi a/T|": errJ, "max|z - z(t)|": errz, "max|r^2 - r^2(t)|": errr,
                           "replay difference": rep, "max|f| (drift)": drift})
        p = 2 if method == "trapezoidal" else 4
        check(f"{method}: objective error of order {p} (last ratio {order(errJ)[-1]:.2f})",
              abs(order(errJ)[-1] - p) < 0.2)
        check(f"{method}: state error of order {p} (last ratio {order(errz)[-1]:.2f})",
              abs(order(errz)[-1] - p) < 0.3)
        # with the constraint imposed at velocity level the forces (which carry the accelerations
        # along the constrained direction) converge with order 2 for both methods, and the replay
        # integrates the forces (document, section 10.2)
        check(f"{method}: replay difference of order 2 (last ratio {order(rep)[-1]:.2f})",
              abs(order(rep)[-1] - 2) < 0.3)
    # the same problem with b q'' + b0 = 0 at every point: Newton finds no optimum
    tr = Transcription(model, "trapezoidal", 8, T, {("q", 0): 0.0, ("q", 1): 0.0, ("q", 2): 0.0},
                       {("q", 0): 0.0, ("q", 1): 0.0, ("q", 2): a_}, pins=[(("v", 1), 0.0)])
    tr.regularization = 1e-9
    try:
        tr.solve(guess(tr), max_iter=20)
        converged = True
    except RuntimeError:
        converged = False
    check("acceleration-level constraints at every point, forces free of cost: no convergence in 20 "
          "Newton steps (the pump of section 5)", not converged)
    # the straight-line guess is a stationary point of the infeasibility (document, section 10.2)
    tr = Transcription(model, "trapezoidal", 8, T, {("q", 0): 0.0, ("q", 1): 0.0, ("q", 2): 0.0},
                       {("q", 0): 0.0, ("q", 1): 0.0, ("q", 2): a_})
    xg = np.zeros(tr.nvar())
    Z = xg[:-1].reshape(tr.P, tr.nz)
    Z[:, 2], Z[:, 5] = a_ * tr.tau, a_ / T
    xg[-1] = T
    q, v, _, _, _ = tr.split(xg)
    _, _, b, _ = model.terms(tr.tau * T, q, v)
    tr.dep, tr.ind = choose_partition(b)
    c, J = tr.jacobian(xg)
    grad_infeas = J.T @ c  # gradient of |c|^2 / 2
    planar = [i for i in range(tr.P * tr.nz) if i % tr.nz not in (2, 5, 8)]  # all but z, z', z''
    worst = np.max(np.abs(grad_infeas[planar]))
    check(f"straight-line guess: infeasible (|c| = {np.linalg.norm(c):.2f}) yet the gradient of |c|^2/2 "
          f"with respect to x, y, their derivatives and the forces is {worst:.1e}: a stationary point "
          f"of the infeasibility in the planar motion", np.linalg.norm(c) > 0.1 and worst < 1e-14)


# --------------------------------------------------------------------------------------------
# 4. The brachistochrone (document, section 10.3)
# --------------------------------------------------------------------------------------------
def cycloid_end(x1, y1):
    """The cycloid x = R (phi - sin phi), y = R (1 - cos phi) through (x1, y1): phi1 and R."""
    phi1 = scipy.optimize.brentq(lambda p: (p - np.sin(p)) / (1 - np.cos(p)) - x1 / y1, 1e-6, 2 * np.pi - 1e-6)
    return phi1, y1 / (1 - np.cos(phi1))


def brachistochrone():
    g = 9.81
    x1, y1 = 2.0, 1.0
    phi1, R = cycloid_end(x1, y1)
    w = np.sqrt(g / R)
    exact_T = phi1 / w
    print(f"\n4. Brachistochrone to ({x1}, {y1}), g = {g}: phi1 = {phi1:.12f}, R = {R:.12f}, "
          f"T = phi1 sqrt(R/g) = {exact_T:.12f}")
    model = Brachistochrone(g=g)

    def guess(tr, T):
        t = tr.tau * T
        ph = w * t
        x = np.zeros(tr.nvar())
        Z = x[:-1].reshape(tr.P, tr.nz)
        Z[:, 0], Z[:, 1] = R * (ph - np.sin(ph)), R * (1 - np.cos(ph))
        Z[:, 2] = np.pi / 2 - ph / 2
        Z[:, 3], Z[:, 4], Z[:, 5] = R * w * (1 - np.cos(ph)), R * w * np.sin(ph), -w / 2
        Z[:, 6], Z[:, 7] = R * w ** 2 * np.sin(ph), R * w ** 2 * np.cos(ph)
        Z[:, :8] *= 1 + 0.03 * np.sin(2 * ph)[:, None]
        x[-1] = T * 1.05
        return x

    for method, Ns in (("trapezoidal", [8, 16, 32, 64]), ("hermite-simpson", [4, 8, 16, 32])):
        errT, errxy, rep, drift = [], [], [], []
        for N in Ns:
            tr = Transcription(model, method, N, None,
                               {("q", 0): 0.0, ("q", 1): 0.0, ("v", 0): 0.0, ("v", 1): 0.0},
                               {("q", 0): x1, ("q", 1): y1})
            # at rest the blade's constraint holds whatever theta: its row would repeat x' = y' = 0
            tr.initial_constraints = False
            x, it, res = tr.solve(guess(tr, exact_T), tol=1e-9)
            q, v, _, u, T = tr.split(x)
            t = tr.tau * T
            ph = w * t
            errT.append(abs(T - exact_T))
            # the path against the cycloid at the same arc parameter: compare at the same time
            # of the exact motion (t_p scaled to the exact duration)
            ph = w * tr.tau * exact_T
            errxy.append(np.max(np.hypot(q[:, 0] - R * (ph - np.sin(ph)), q[:, 1] - R * (1 - np.cos(ph)))))
            rep.append(tr.replay(x))
            drift.append(np.max(np.abs(-np.sin(q[:, 2]) * v[:, 0] + np.cos(q[:, 2]) * v[:, 1])))
        table(method, Ns, {"|T - T_cycloid|": errT, "max|(x,y) - cycloid|": errxy, "replay difference": rep,
                           "max|f| (drift)": drift})
        p = 2 if method == "trapezoidal" else 4
        check(f"{method}: minimum time error of order >= {p} (last ratio {order(errT)[-1]:.2f})",
              order(errT)[-1] > p - 0.2)
        check(f"{method}: path error of order >= {p - 0.5} (last ratio {order(errxy)[-1]:.2f})",
              order(errxy)[-1] > p - 0.7)
    # without the torque term (w = 0) the KKT matrix at the sampled cycloid has more negative
    # eigenvalues than there are constraints: directions of negative curvature on the linearized
    # constraints, which grid-scale wiggles of theta (free of cost) follow (document, section 5)
    model0 = Brachistochrone(g=g, torque_weight=0.0)
    tr = Transcription(model0, "hermite-simpson", 8, None,
                       {("q", 0): 0.0, ("q", 1): 0.0, ("v", 0): 0.0, ("v", 1): 0.0}, {("q", 0): x1, ("q", 1): y1})
    tr.initial_constraints = False
    x = guess(tr, exact_T)
    Z = x[:-1].reshape(tr.P, tr.nz)
    t = tr.tau * exact_T
    ph = w * t
    Z[:, 0], Z[:, 1] = R * (ph - np.sin(ph)), R * (1 - np.cos(ph))  # the unperturbed cycloid
    Z[:, 2] = np.pi / 2 - ph / 2
    Z[:, 3], Z[:, 4], Z[:, 5] = R * w * (1 - np.cos(ph)), R * w * np.sin(ph), -w / 2
    Z[:, 6], Z[:, 7], Z[:, 8], Z[:, 9] = R * w ** 2 * np.sin(ph), R * w ** 2 * np.cos(ph), 0.0, 0.0
    x[-1] = exact_T
    q, v, _, _, _ = tr.split(x)
    _, _, b, _ = model0.terms(t, q, v)
    tr.dep, tr.ind = choose_partition(b)
    c, J = tr.jacobian(x)
    lam = scipy.sparse.linalg.lsqr(J.T, -tr.gradient(x), atol=1e-14, btol=1e-14)[0]
    K = scipy.sparse.bmat([[tr.lagrangian_hessian(x, lam), J.T], [J, None]]).toarray()
    eig = np.linalg.eigvalsh(K)
    negative = int(np.sum(eig < -1e-10 * np.max(np.abs(eig))))
    check(f"w = 0: {negative} negative eigenvalues of the KKT matrix for {J.shape[0]} constraints "
          f"(more: a saddle, not a minimum, of the discrete problem)", negative > J.shape[0])


# --------------------------------------------------------------------------------------------
# 5. Final conditions that fix what the constraints fix (document, section 5)
# --------------------------------------------------------------------------------------------
def final_conditions():
    print("\n5. Mass on a circle turned by pi/4 from rest to rest: J = 12 theta1^2 / T^3")
    model = CircleMass()
    T, th1 = 1.0, np.pi / 4
    exact = 12 * th1 ** 2 / T ** 3

    def guess(tr):
        s = tr.tau
        th = th1 * (3 * s ** 2 - 2 * s ** 3)
        w = th1 / T * (6 * s - 6 * s ** 2)
        al = th1 / T ** 2 * (6 - 12 * s)
        x = np.zeros(tr.nvar())
        Z = x[:-1].reshape(tr.P, tr.nz)
        Z[:, 0], Z[:, 1] = np.cos(th), np.sin(th)
        Z[:, 2], Z[:, 3] = -np.sin(th) * w, np.cos(th) * w
        Z[:, 4] = -np.cos(th) * w ** 2 - np.sin(th) * al
        Z[:, 5] = -np.sin(th) * w ** 2 + np.cos(th) * al
        Z[:, 6] = al
        x[-1] = T
        return x

    initial = {("q", 0): 1.0, ("q", 1): 0.0, ("v", 0): 0.0, ("v", 1): 0.0}
    for method, Ns in (("trapezoidal", [8, 16, 32]), ("hermite-simpson", [4, 8, 16])):
        errJ, failed, stalls = [], 0, []
        for N in Ns:
            regular = Transcription(model, method, N, T, initial, {("q", 0): np.cos(th1), ("v", 0): 0.0})
            over = Transcription(model, method, N, T, initial, {("q", 0): np.cos(th1), ("q", 1): np.sin(th1),
                                                               ("v", 0): 0.0, ("v", 1): 0.0})
            for tr in (regular, over):
                tr.initial_constraints = False  # the fixed initial state implies them
            x, _, _ = regular.solve(guess(regular))
            errJ.append(regular.objective(x) - exact)
            try:
                over.solve(guess(over), max_iter=30)
            except RuntimeError as error:
                failed += 1
                stalls.append(str(error).split("KKT ")[1].rstrip(")"))
        print(f"  {method}: x, x' fixed at the end: J_N - J = " + ", ".join(f"{e:.3e}" for e in errJ)
              + " (orders " + ", ".join(f"{o:.2f}" for o in order(np.abs(errJ))) + ")")
        print(f"  {method}: x, y, x', y' fixed at the end: Newton stalls at KKT residuals " + ", ".join(stalls))
        p = 2 if method == "trapezoidal" else 4
        check(f"{method}: final x, x' (independent of the constraint): converges with order {p}",
              abs(order(np.abs(errJ))[-1] - p) < 0.3)
        check(f"{method}: final x, y, x', y' (two of them fixed by the constraint): no optimum found at "
              f"{failed} of {len(Ns)} grids", failed == len(Ns))


if __name__ == "__main__":
    np.set_printoptions(linewidth=160)
    check_jacobian_identity()
    double_integrator()
    brockett()
    brachistochrone()
    final_conditions()
    print()
    if FAILURES:
        print(f"{len(FAILURES)} check(s) failed")
        sys.exit(1)
    print("all checks passed")
