#!/usr/bin/env python3
"""Checks of docs/derivations/contact-modes.md, section 7 (impacts at touchdown).

The impulse equations in the stacked form [D A; b] q'+ = [D A q'-; targets] (D orthogonal to the
impulsive reaction directions, b the rows held after the impact, Newton's law in the normal row)
against the multiplier form A (q'+ - q'-) = B~^T Lambda, b q'+ = targets, on random systems, for
frictionless, sticking and sliding impacts; the energy lost:
  frictionless:  (1 - e^2) (v_n-)^2 / (2 Lambda_nn)   (never negative);
  sticking, Newton:  (v- M v- - e^2 M_nn (v_n-)^2) / 2, M = Lambda^-1, which is negative for some v-
    iff e^2 > 1 - M_tn M_tt^-1 M_nt / M_nn (checked on Painleve's rod);
  sticking, Poisson's law: never negative;
  sliding (Coulomb impulse along the pre-impact slip, no reversal), uncoupled contact: never negative.
Run: python3 impact.py (needs numpy); exits 1 on any failure.
"""
import sys
import numpy as np

failures = 0


def check(name, ok, detail=""):
    global failures
    print(("PASS " if ok else "FAIL ") + name + ("" if ok else "  " + detail))
    if not ok:
        failures += 1


def null_basis(B):
    q, _ = np.linalg.qr(B.T, mode="complete")
    return q[:, B.shape[0]:].T


def stacked_impulse(A, b, Bt, vminus, targets):
    """q'+ from [D A; b] q'+ = [D A q'-; targets], D spanning null(Bt)."""
    D = null_basis(Bt)
    M = np.vstack([D @ A, b])
    return np.linalg.solve(M, np.concatenate([D @ A @ vminus, targets]))


def multiplier_impulse(A, b, Bt, vminus, targets):
    n, s = A.shape[0], b.shape[0]
    K = np.block([[A, -Bt.T], [b, np.zeros((s, s))]])
    sol = np.linalg.solve(K, np.concatenate([A @ vminus, targets]))
    return sol[:n], sol[n:]


rng = np.random.default_rng(11)
n = 7
for trial in range(10):
    X = rng.normal(size=(n, n)); A = X @ X.T + n * np.eye(n)
    bo = rng.normal(size=(2, n))
    J = rng.normal(size=(3, n))                  # rows t_1, t_2, n of the contact
    wt, wn = J[:2], J[2]
    # a pre-impact velocity that satisfies the other constraints (b_o q' = 0) and approaches
    v = null_basis(bo).T @ rng.normal(size=n - 2)
    if wn @ v > 0:
        v = -v
    vn = wn @ v
    e = rng.random()
    T = lambda q: 0.5 * q @ A @ q
    # contact inverse inertia with the other constraints holding
    Ai = np.linalg.inv(A)
    P = Ai - Ai @ bo.T @ np.linalg.solve(bo @ Ai @ bo.T, bo @ Ai)
    Lam = J @ P @ J.T
    # frictionless
    b = np.vstack([bo, wn]); tg = np.array([0, 0, -e * vn])
    vp = stacked_impulse(A, b, b, v, tg)
    vp2, lam = multiplier_impulse(A, b, b, v, tg)
    check(f"{trial} frictionless: stacked = multiplier form, v_n+ = -e v_n-",
          np.allclose(vp, vp2, atol=1e-10) and abs(wn @ vp + e * vn) < 1e-10 and np.allclose(bo @ vp, 0, atol=1e-10))
    loss = T(v) - T(vp)
    check(f"{trial} frictionless: loss = (1 - e^2) v_n^2 / (2 Lambda_nn) >= 0",
          abs(loss - (1 - e**2) * vn**2 / (2 * Lam[2, 2])) < 1e-9 * (1 + loss) and loss >= 0)
    check(f"{trial} frictionless: impulse Pi_n = lambda_n > 0", lam[-1] > 0 and
          abs(lam[-1] - (1 + e) * (-vn) / Lam[2, 2]) < 1e-9 * lam[-1])
    # sticking, Newton
    b = np.vstack([bo, wt, wn]); tg = np.array([0, 0, 0, 0, -e * vn])
    vp = stacked_impulse(A, b, b, v, tg)
    vc = J @ v
    Mi = np.linalg.inv(Lam)
    loss = T(v) - T(vp)
    check(f"{trial} sticking (Newton): slip 0 after, loss = (v M v - e^2 M_nn v_n^2)/2",
          np.allclose(wt @ vp, 0, atol=1e-10) and abs(loss - 0.5 * (vc @ Mi @ vc - e**2 * Mi[2, 2] * vn**2)) < 1e-9 * (1 + abs(loss)))
    # sticking, Poisson: compression to v_c = 0 (stick), then the normal impulse e Pi_n,c with slip held 0
    vcmp = stacked_impulse(A, b, b, v, np.zeros(5))
    Pi_c = np.linalg.lstsq(b.T, A @ (vcmp - v), rcond=None)[0]       # multipliers of the compression
    # restitution: the normal impulse is e Pi_n,c, the tangential one keeps the slip 0: solve for it
    # unknowns (q'+, Pi_t(2), Pi_o(2)): A (q'+ - v_c) = b_o^T Pi_o + w_t^T Pi_t + w_n^T e Pi_nc
    K = np.block([[A, -bo.T, -wt.T], [bo, np.zeros((2, 4))], [wt, np.zeros((2, 4))]])
    rhsP = np.concatenate([A @ vcmp + wn * e * Pi_c[-1], np.zeros(4)])
    vpP = np.linalg.solve(K, rhsP)[:n]
    check(f"{trial} sticking (Poisson): loss >= 0", T(v) - T(vpP) >= -1e-12)
    # sliding along the pre-impact slip (uncoupled contact: make Lambda_nt = 0 by choosing w_n in
    # the P-orthogonal complement of w_t); choose mu small enough that the slip does not reverse
    Pw = P @ wt.T
    wn_u = wn - (wn @ Pw) @ np.linalg.solve(wt @ Pw, wt)      # w_n P w_t^T = 0
    Ju = np.vstack([wt, wn_u]); Lu = Ju @ P @ Ju.T
    if wn_u @ v > 0:
        continue
    vnu = wn_u @ v
    st = wt @ v; es = st / np.linalg.norm(st); ws = es @ wt
    mu = 0.3
    b = np.vstack([bo, wn_u]); Bt = np.vstack([bo, wn_u - mu * ws]); tg = np.array([0, 0, -e * vnu])
    vp = stacked_impulse(A, b, Bt, v, tg)
    vp2, lam = multiplier_impulse(A, b, Bt, v, tg)
    sp_ = wt @ vp
    reversed_ = sp_ @ es < 0
    check(f"{trial} sliding impact: stacked = multiplier, Lambda_nt = 0", np.allclose(vp, vp2, atol=1e-10)
          and np.allclose(Lu[2, :2], 0, atol=1e-9))
    if not reversed_:
        check(f"{trial} sliding impact (uncoupled, no reversal): loss >= 0", T(v) - T(vp) >= -1e-12)

# ---- Painleve's rod hitting the ground: Newton + sticking gains energy for e above the bound
m, l = 1.0, 1.0
th = 0.6
c, s = np.cos(th), np.sin(th)
A = np.diag([m, m, m * l**2 / 3])
J = np.array([[1, 0, l * s], [0, 1, -l * c]])        # rows t (x) and n (y) of the lower end
Lam = J @ np.linalg.inv(A) @ J.T
M = np.linalg.inv(Lam)
bound = np.sqrt(1 - M[0, 1]**2 / (M[0, 0] * M[1, 1]))
gain = False
for e in (bound - 0.05, bound + 0.05):
    # worst pre-impact contact velocity: v_t = -M_tn v_n / M_tt, v_n = -1
    vc = np.array([-M[0, 1] * (-1.0) / M[0, 0], -1.0])
    v = np.linalg.lstsq(J, vc, rcond=None)[0]         # a q' with that contact velocity (theta' free: minimum norm)
    b = J; tg = np.array([0.0, -e * (J[1] @ v)])
    vp = stacked_impulse(A, b, b, v, tg)
    dT = 0.5 * vp @ A @ vp - 0.5 * v @ A @ v
    if e > bound:
        gain = dT > 1e-12
    else:
        check(f"rod th = 0.6: Newton + stick with e = {e:.3f} below the bound {bound:.4f} loses energy", dT < 0)
check(f"rod th = 0.6: Newton + stick with e = {bound + 0.05:.3f} above the bound gains energy", gain)
print("impact: %d failure(s)" % failures)
sys.exit(1 if failures else 0)
