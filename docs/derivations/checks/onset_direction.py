#!/usr/bin/env python3
"""Checks of docs/derivations/contact-modes.md, section 5 (the friction at the onset of slip).

In contact space (components t_1, t_2, n) the contact point's acceleration is a = a_f + Lambda F,
a_f that of the free contact, Lambda the contact's inverse inertia (symmetric positive definite).
The normal constraint a_n = 0 gives N; the slip acceleration is sigma = sigma_f + S F_t (S the Schur
complement) when Lambda_nt = 0. The derived onset friction is the point of the disk |F_t| <= mu N
nearest to the rolling friction F_roll in the metric S: F_t = (S + nu I)^-1 S F_roll. The check
integrates, with the state frozen, the slip under Coulomb's law from tiny slips (1e-12) in random
directions and compares the direction s takes with the derived one; with coupling
(Lambda_nt != 0) it compares the root of e x sigma(e) = 0, e . sigma(e) > 0 with the same runs.
Run: python3 onset_direction.py (needs numpy); exits 1 on any failure.
"""
import sys
import numpy as np

failures = 0


def check(name, ok, detail=""):
    global failures
    print(("PASS " if ok else "FAIL ") + name + ("" if ok else "  " + detail))
    if not ok:
        failures += 1


def regularized_direction(Lam, af, mu, s0):
    """Slip direction reached from a tiny slip s0 under the exact Coulomb law (the state frozen).

    The direction of s moves at the rate |sigma|/|s|, fast while s is tiny: RK4 with steps that
    grow with |s| (h = 0.02 |s| / |sigma|) follows it from |s| = 1e-12 until |s| is 1e5 times larger.
    s0 must be a slip that grows (sigma . s0 > 0); one that shrinks would pass through 0 first.
    """
    def rhs(s):
        u = s / np.linalg.norm(s)
        # F = N n + F_t, F_t = -mu N u (2-vector); normal: af_n + Lam_nt F_t + Lam_nn N = 0
        N = -af[2] / (Lam[2, 2] - mu * Lam[2, :2] @ u)
        F = np.array([-mu * N * u[0], -mu * N * u[1], N])
        return (af + Lam @ F)[:2]
    s = np.array(s0, dtype=float)
    start = np.linalg.norm(s)
    while np.linalg.norm(s) < 1e5 * start:
        h = 0.02 * np.linalg.norm(s) / np.linalg.norm(rhs(s))
        k1 = rhs(s); k2 = rhs(s + h / 2 * k1); k3 = rhs(s + h / 2 * k2); k4 = rhs(s + h * k3)
        s = s + h / 6 * (k1 + 2 * k2 + 2 * k3 + k4)
    return s / np.linalg.norm(s)


def onset_uncoupled(S, F_roll, muN):
    """F_t = (S + nu I)^-1 S F_roll with |F_t| = muN, nu > 0 by bisection (|F_t| falls with nu)."""
    lo, hi = 0.0, 1.0
    f = lambda nu: np.linalg.norm(np.linalg.solve(S + nu * np.eye(2), S @ F_roll))
    while f(hi) > muN:
        hi *= 2
    for _ in range(200):
        mid = (lo + hi) / 2
        lo, hi = (mid, hi) if f(mid) > muN else (lo, mid)
    return np.linalg.solve(S + hi * np.eye(2), S @ F_roll)


def onset_general(Lam, af, mu):
    """Root of e x sigma(e) = 0 with e . sigma(e) > 0 over the circle (scan and bisection)."""
    def sigma(beta):
        e = np.array([np.cos(beta), np.sin(beta)])
        N = -af[2] / (Lam[2, 2] - mu * Lam[2, :2] @ e)
        F = np.array([-mu * N * e[0], -mu * N * e[1], N])
        return e, (af + Lam @ F)[:2]
    def gfun(beta):
        e, sg = sigma(beta)
        return e[0] * sg[1] - e[1] * sg[0]
    betas = np.linspace(0, 2 * np.pi, 3601)
    roots = []
    for b1, b2 in zip(betas[:-1], betas[1:]):
        if gfun(b1) * gfun(b2) < 0:
            lo, hi = b1, b2
            for _ in range(100):
                mid = (lo + hi) / 2
                lo, hi = (mid, hi) if gfun(lo) * gfun(mid) > 0 else (lo, mid)
            e, sg = sigma(lo)
            if e @ sg > 0:
                roots.append(e)
    return roots


rng = np.random.default_rng(3)
for trial in range(12):
    X = rng.normal(size=(3, 3))
    Lam = X @ X.T + 0.3 * np.eye(3)
    coupled = trial >= 6
    if not coupled:
        Lam[2, :2] = Lam[:2, 2] = 0.0
    mu = 0.3 + 0.2 * rng.random()
    # choose a state at which rolling would need more friction than mu N
    for _ in range(1000):
        af = rng.normal(size=3); af[2] = -abs(af[2]) - 1.0      # the free contact presses
        Nr_Ft = np.linalg.solve(Lam, -np.array([af[0], af[1], af[2]]))  # rolling: a = 0
        F_roll, N_roll = Nr_Ft[:2], Nr_Ft[2]
        if N_roll > 0 and np.linalg.norm(F_roll) > 1.2 * mu * N_roll:
            break
    # from three tiny growing slips in random directions: each must end in the derived direction
    def grows(s0):
        u = s0 / np.linalg.norm(s0)
        N = -af[2] / (Lam[2, 2] - mu * Lam[2, :2] @ u)
        return u @ (af + Lam @ np.array([-mu * N * u[0], -mu * N * u[1], N]))[:2] > 0
    starts = [x for x in 1e-12 * rng.normal(size=(40, 2)) if grows(x)][:3]
    e_regs = [regularized_direction(Lam, af, mu, x) for x in starts]
    e_reg = e_regs[0]
    spread = max(np.linalg.norm(x - e_reg) for x in e_regs)
    if not coupled:
        N = -af[2] / Lam[2, 2]
        S = Lam[:2, :2]
        Ft = onset_uncoupled(S, F_roll, mu * N)
        e = -Ft / np.linalg.norm(Ft)
        sg = af[:2] + S @ Ft
        check(f"uncoupled {trial}: sigma(e) parallel to e and along it",
              abs(e[0] * sg[1] - e[1] * sg[0]) < 1e-9 * np.linalg.norm(sg) and e @ sg > 0)
        check(f"uncoupled {trial}: derived direction = where tiny slips in any direction go",
              np.linalg.norm(e - e_reg) < 1e-5 and spread < 1e-5, f"{e} vs {e_regs}")
        # the projection minimizes (F - F_roll)^T S (F - F_roll) over the disk: compare with a fine scan
        betas = np.linspace(0, 2 * np.pi, 200001)
        Fs = mu * N * np.stack([np.cos(betas), np.sin(betas)], 1)
        dF = Fs - F_roll
        cost = np.einsum("ij,jk,ik->i", dF, S, dF)
        Fbest = Fs[np.argmin(cost)]
        check(f"uncoupled {trial}: it minimizes the slip acceleration in the metric S^-1",
              np.linalg.norm(Fbest - Ft) < 1e-3 * mu * N)
    else:
        roots = onset_general(Lam, af, mu)
        ok = len(roots) >= 1 and min(np.linalg.norm(r - e_reg) for r in roots) < 1e-5 and spread < 1e-5
        check(f"coupled {trial}: a root of e x sigma(e) = 0 is where tiny slips go ({len(roots)} root(s))",
              ok, f"{roots} vs {e_reg}")
# isotropic S: the friction points along F_roll
S = 2.0 * np.eye(2); F_roll = np.array([3.0, -1.0]); muN = 1.5
Ft = onset_uncoupled(S, F_roll, muN)
check("isotropic S: F_t = mu N F_roll / |F_roll|", np.allclose(Ft, muN * F_roll / np.linalg.norm(F_roll), atol=1e-12))
print("onset_direction: %d failure(s)" % failures)
sys.exit(1 if failures else 0)
