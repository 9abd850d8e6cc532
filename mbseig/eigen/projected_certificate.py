"""The count certificate of the projected path (:mod:`mbseig.eigen.projected`): by Rouché's
theorem, every eigenvalue of the damped problem inside the disc |s| < R was found when the
hypotheses hold (P symmetric, M and Q positive definite on the constraints, damping of the high
modes small enough); the smallest singular value on the circle bounds what was not."""

from __future__ import annotations

import numpy as np
import scipy.linalg as sla
import scipy.sparse as sp

from ..numerics import LazyModule
from .measures import EPS, fro, is_symmetric

spla = LazyModule("scipy.sparse.linalg")

TIE = 1e-6  # relative |s| within which Ritz values at the edge count as one repeated value


RHO_MARGIN = 1.01  # the Arnoldi estimate of ρ is raised by 1 %


N_CIRCLE = 2048  # sample points of the half circle (more when the margin is thin)


def pd_on_constraints(A, Gc):
    """True when A (symmetric, sparse) is shown positive definite on null(G): A + αGᵀG has an
    LDLᵀ (symmetric pivots) with positive pivots, which implies it (xᵀAx = xᵀ(A + αGᵀG)x)."""
    if Gc is not None and Gc.shape[0]:
        GtG = (Gc.T @ Gc).tocsr()
        alpha = fro(A) / max(fro(GtG), np.finfo(float).tiny)
        A = (A + alpha * GtG).tocsr()
    d = A.diagonal()
    off = A - sp.diags(d, format="csr")
    if off.nnz == 0 or not np.any(off.data):
        return bool(np.all(d > 0))
    try:
        lu = spla.splu(A.tocsc(), permc_spec="MMD_AT_PLUS_A", diag_pivot_thresh=0.0,
                       options={"SymmetricMode": True})
    except RuntimeError:
        return False
    piv = lu.U.diagonal()
    return bool(np.array_equal(lu.perm_r, lu.perm_c) and np.all(piv > 0)
                and np.min(piv) > 1e3 * EPS * np.max(piv))


def small_qep(Ms, Ps, Qs):
    """All eigenvalues and (right) vectors of the small dense (Ms s² + Ps s + Qs) y = 0 with Ms
    symmetric positive definite: Cholesky, γ-scaled companion, LAPACK ``geev``."""
    L = np.linalg.cholesky(0.5 * (Ms + Ms.T))
    Li = sla.solve_triangular(L, np.eye(L.shape[0]), lower=True)
    Pt, Qt = Li @ Ps @ Li.T, Li @ Qs @ Li.T
    gamma = np.sqrt(max(np.linalg.norm(Qt, 2), np.finfo(float).tiny))
    k = Ms.shape[0]
    A = np.zeros((2 * k, 2 * k))
    A[:k, k:] = np.eye(k)
    A[k:, :k] = -Qt / gamma**2
    A[k:, k:] = -Pt / gamma
    mu, Z = np.linalg.eig(A)
    s = gamma * mu
    Y = Li.T @ Z[:k]  # first half: y (the second half is μ y)
    return s, Y


def basis_products(P, Phi, ZP):
    """(ΦᵀPΦ, (PΦ)ᵀ ZP) with ZP = Q_b⁻¹[PΦ; 0] (x rows, a view into the basis' solves): the
    k × k products the certificate needs, without an n-row copy of ZP."""
    PPhi = P @ Phi
    return Phi.T @ PPhi, PPhi.T @ ZP


def hypotheses(M, P, Q, Gc, sym_tol, sig):
    """The certificate's structural hypotheses: (ok, why)."""
    if sig != 0.0:
        return False, (f"Q_b is (nearly) singular at 0 (factorized at σ = {sig:.3g}): Q is not "
                       f"shown positive definite on the constraints")
    if not is_symmetric(P, sym_tol):
        return False, "P is not symmetric"
    if not pd_on_constraints(M, Gc):
        return False, "M is not shown positive definite on the constraint null space"
    if not pd_on_constraints(Q, Gc):
        return False, "Q is not shown positive definite on the constraint null space"
    return True, ""


def sigma_min_circle(Pll, lam, R, n_pts):
    """Lower bound of σ_min(T_LL(z)) on |z| = R: the sampled minimum over the upper half circle
    (conjugate symmetry gives the lower) minus the Lipschitz bound R(2R + ‖Π_LL‖)·h/2."""
    th = np.linspace(0.0, np.pi, n_pts)
    z = R * np.exp(1j * th)
    k = lam.size
    T = (z**2)[:, None, None] * np.eye(k)[None] + z[:, None, None] * Pll[None] + np.diag(lam)[None]
    smin = np.linalg.svd(T, compute_uv=False)[:, -1]
    lip = R * (2 * R + np.linalg.norm(Pll, 2))
    return float(np.min(smin) - lip * (th[1] - th[0]) / 2), float(np.min(smin))


def certificate(lu, hyp, Phi, lam, products, s_found, s_ritz, M, P, n, m):
    """The count certificate of the module docstring: dict with ``verified``, ``why``, R, τ,
    ρ, Ω, counts; ``grow`` when more undamped modes could help.  ``products``: (ΦᵀPΦ,
    (PΦ)ᵀ Q_b⁻¹[PΦ; 0]) from the basis (:func:`basis_products`), None when ``hyp`` fails."""
    out = {"verified": False, "grow": False, "R": 0.0, "n_inside": 0}
    ok, why = hyp
    if not ok:
        out["why"] = why
        return out
    k = lam.size
    Omega2 = float(np.max(lam))
    if not float(np.min(lam)) > 0:
        out["why"] = "an undamped ω² ≤ 0 (Q not positive definite on the constraints)"
        return out
    Pll, G1 = products
    Pll = 0.5 * (Pll + Pll.T)
    # ‖Λ_H^-½ Π_HL‖² ≤ λ_max(Φ_LᵀP Q_b⁻¹ P Φ_L − Π_LL Λ_L⁻¹ Π_LL)
    G1 = 0.5 * (G1 + G1.T)
    D = G1 - Pll @ (Pll / lam[:, None])
    b2 = max(float(np.max(np.linalg.eigvalsh(0.5 * (D + D.T)))), 0.0) \
        + 10 * k * EPS * (np.linalg.norm(G1, 2) + np.linalg.norm(Pll, 2) ** 2 / float(np.min(lam)))
    # ρ = max |vᵀPv / vᵀQv| on C ∩ H: Arnoldi on (I − Φ_LΦ_LᵀM) Q_b⁻¹ P (I − Φ_LΦ_LᵀM)
    MPhi = M @ Phi

    def proj(x):
        return x - Phi @ (MPhi.T @ x)

    def op(x):  # Π_H Q⁻¹P: the same nonzero eigenvalues as Π_H Q⁻¹P Π_H (Π_H² = Π_H)
        z = lu.solve(np.concatenate([P @ np.asarray(x).ravel(), np.zeros(m)]))[:n]
        return proj(z)

    if fro(P.A) == 0 or n - m - k == 0:
        rho = 0.0  # no damping, or no H part: T_HH = Λ_H + s²I
    elif n <= 16:  # a tiny model: the operator in full
        Op = np.column_stack([op(e) for e in np.eye(n)])
        rho = float(np.max(np.abs(np.linalg.eigvals(Op)))) * RHO_MARGIN
    else:
        try:
            A = spla.LinearOperator((n, n), matvec=op, dtype=float)
            th = spla.eigs(A, k=1, which="LM", ncv=min(12, n - 1), tol=1e-4, maxiter=500,
                           return_eigenvectors=False,
                           v0=np.random.default_rng(3).standard_normal(n))
            rho = float(np.max(np.abs(th))) * RHO_MARGIN
        except (spla.ArpackNoConvergence, spla.ArpackError) as exc:
            out["why"] = f"ρ (damping/stiffness ratio on the high modes) not estimated: {exc}"
            return out
    out.update(rho=rho, Omega=float(np.sqrt(Omega2)), coupling=float(np.sqrt(b2)), k_u=k)
    # the radius: between the farthest pair found and the next Ritz value
    r_sel = float(np.max(np.abs(s_found)))
    ar = np.abs(s_ritz)
    beyond = ar[ar > r_sel * (1 + TIE)]
    r_next = float(np.min(beyond)) if beyond.size else np.sqrt(Omega2)
    # eigenvalues of the undamped-mode projection T_LL (the count it certifies)
    s_ll, _ = small_qep(np.eye(k), Pll, np.diag(lam))
    last = "no radius tried"
    for f in (0.5, 0.25, 0.75, 0.1, 0.9):
        R = r_sel + f * (r_next - r_sel)
        den = 1.0 - R * rho - R * R / Omega2
        if not den > 0:
            last = (f"Rρ + R²/Ω² = {R * rho + R * R / Omega2:.3g} ≥ 1 at R = {R:.6g} "
                    f"(ρ = {rho:.3g} s, Ω = {np.sqrt(Omega2):.6g} rad/s): the damping of the high "
                    f"modes is too strong for the bound, or too few undamped modes")
            out["grow"] = R * R / Omega2 > 0.5 * (1 - R * rho) or out["grow"]
            continue
        tau = R * R * b2 / den
        lo, smin = sigma_min_circle(Pll, lam, R, N_CIRCLE)
        if not lo > tau and smin > tau:
            lo, smin = sigma_min_circle(Pll, lam, R, 16 * N_CIRCLE)
        if not lo > tau:
            last = (f"σ_min(T_LL) on |s| = {R:.6g} is {smin:.3g} (bound {lo:.3g}), not above "
                    f"τ = {tau:.3g}: the coupling to the high modes blurs the count")
            out["grow"] = True
            continue
        n_ll = int(np.sum(np.abs(s_ll) < R))
        n_in = int(np.sum(np.abs(s_found) < R)) + int(np.sum(
            (np.abs(s_found) < R) & (np.abs(s_found.imag) > 1e-9 * np.abs(s_found))))
        out.update(R=R, tau=tau, sigma_min=lo, n_projected=n_ll, n_inside=n_in)
        if n_ll != n_in:
            out["why"] = (f"the disc |s| < {R:.6g} holds {n_ll} eigenvalues (Rouché count), "
                          f"{n_in} were found")
            out["grow"] = True
            return out
        out.update(verified=True, why="")
        return out
    out["why"] = last
    return out
