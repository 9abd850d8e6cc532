"""Partial spectrum of large sparse models: shift-invert Krylov methods
(docs/design.md, "Eigensolvers").

The modes asked for (``n_modes`` nearest a target frequency, or every mode in a band of ω_n)
of (M s² + P s + Q) x = 0 with sparse M, P, Q, without ever forming a dense matrix.  Paths
(recorded in the result as ``solver``):

``partial-eigh``          P = 0, M and Q symmetric: ARPACK Lanczos (``eigsh``) in shift-invert
                          mode on Q v = ω² M v with one sparse LU of Q − σM per shift.
``partial-proportional``  P = αM + βQ (Rayleigh damping, checked on random probe vectors): the
                          same undamped modes, then s² + (α + βω²) s + ω² = 0 per mode.
``partial-companion``     anything else: ARPACK Arnoldi (``eigs``) on the companion pencil
                          A − sB of size 2n, shift-invert operator (A − σB)⁻¹B applied through
                          one sparse LU of the n×n matrix σ²M + σP + Q per shift:

                              (A − σB) z = B v  ⇔  (σ²M + σP + Q) z₁ = −(M v₂ + (P + σM) v₁),
                                                    z₂ = v₁ + σ z₁,         s = σ + 1/μ.
``partial-projected``     general damping, lowest modes, M and Q symmetric
                          (:mod:`mbseig.eigen.projected`): Lanczos for n_modes + 6 undamped
                          modes with one LU of Q, Rayleigh–Ritz of the damped problem on their
                          span, refinement by block solves with the same LU, and a count
                          certificate (Rouché) that every eigenvalue inside the disc |s| < R was
                          found.  ``auto`` takes it for general damping when the lowest modes
                          are asked (no band, no target) and M, P, Q are symmetric, and runs
                          ``partial-companion`` instead when the certificate does not hold (its
                          hypotheses: P symmetric, M and Q positive definite on the constraints,
                          damping of the high modes small enough) or the refinement fails; the
                          result says why (``reason``, ``details["projected_fallback"]``).
                          Measured on the bench's 10⁶-coordinate model (docs/scaling.md §4):
                          32–43 s against 112–177 s for ``partial-companion``, 3–4× the
                          undamped ``eigsh`` floor, 2.6 GB peak.
``partial-slepc``         optional SLEPc backend (TOAR), lowest modes (:mod:`mbseig.eigen.slepc`).

Which modes, and where the shifts go.  The modes are ranked by one measure throughout, ω_n = |s|
(the undamped ω_n = √|ω²| on the symmetric paths, so that a divergence ω² < 0 ranks by its
rate): ``n_modes`` nearest ``target``, or every mode with ω_lo ≤ ω_n ≤ ω_hi.  Shift-invert finds
the eigenvalues nearest its shift, so the shifts are placed where the ranking looks: at σ = 0 for
the lowest modes; on the circle |s| = ω_t at angles π/2, 0, π (then π/4, 3π/4 if those do not
cover) for a target, so that a divergence at s = +ω_t is found as surely as a mode at iω_t; at
±ω_t² for the symmetric paths.
Every ARPACK run finds all eigenvalues within the distance r of its shift of the farthest one
returned; the result is verified to *cover* the region the ranking selects from (the annulus
| |s| − ω_t | ≤ d of the selected modes, or the band), else the count grows.  What was covered is
returned in ``coverage`` (and said in the listing: a partial verdict is "of the modes computed").
A repeated eigenvalue is never cut in half: the selection takes every member of equal ω_n, and
``coverage["note"]`` says so.

Shifts: a shift that makes σ²M + σP + Q exactly or nearly singular (an eigenvalue at the shift,
e.g. the double zero of a free-free chain, a Jordan block) is moved left by 10⁻⁶, 10⁻⁴, 10⁻²
of the frequency scale until the LU's condition (estimated by one solve) is below 1/(10⁴ ε), so
that the other eigenvalues keep their accuracy.

Constraints Φ_q = G (m × n) stay in the pencil as a bordered matrix instead of a null-space
basis (the multipliers λ are extra unknowns; their infinite eigenvalues map to μ = 0 and are
never returned):

    M_b = ┌ M  0 ┐    P_b = ┌ P  0 ┐    Q_b = ┌ Q    c Gᵀ ┐     (c = ‖Q‖/‖G‖ balances the rows)
          └ 0  0 ┘          └ 0  0 ┘          └ c G   0   ┘

Ritz vectors of a pencil with singular M_b carry components along its infinite eigenvectors;
each is *purified* by one more application of the shift-invert operator (Ericsson 1986), which
annihilates them.  With stiffness-proportional damping (β ≠ 0) the multiplier part of an
undamped mode v = [x; λ] is not that of the damped one: from (s²M + sP + Q)x + cGᵀμ = 0 and
P = αM + βQ, μ = (1 + βs)λ, so the multiplier rows are scaled per root.

Every returned pair is verified by its backward error on the (bordered) problem; a pair whose η
exceeds ``verify_tol`` or an ARPACK run that does not converge raises :class:`SolverError`.
Eigenvectors are returned in the coordinates of M (full coordinates when G is given).
"""

from __future__ import annotations

import numpy as np
import scipy.sparse as sp

from ..errors import SolverError
from . import contract
from .base import QEPSolution
from .measures import (
    fro,
    is_symmetric,
    rayleigh_fit,
)
from .partial_pairs import general_pairs, symmetric_pairs
from .searches import companion_search, slepc_search, symmetric_search
from .shift_invert import (
    SHIFT_OFFSETS,
    Search,
    bordered,
)
from .undamped import proportional_real_error

__all__ = ["solve_partial", "sparse_structure"]

# only when the first does not cover the annulus the selection looks at


def _csr(A, n=None):
    if A is None:
        return sp.csr_matrix((n, n))
    A = sp.csr_matrix(A) if not sp.issparse(A) else A.tocsr()
    if np.iscomplexobj(A.data):
        if np.any(A.data.imag):
            raise SolverError("the partial paths take real M, P, Q; a complex problem (e.g. "
                              "hysteretic damping) needs the dense path")
        A = sp.csr_matrix((A.data.real, A.indices, A.indptr), shape=A.shape)
    return A.astype(float, copy=False)  # the caller's float CSR itself: nothing here writes to it


def sparse_structure(M, P, Q, *, sym_tol=1e-13, rayleigh_tol=1e-12, probes=3, seed=0):
    """(name, reason, extras) for sparse M, P, Q: the partial path ``auto`` takes.

    Proportional damping P = αM + βQ is fitted on ``probes`` random vectors v (P v against
    M v, Q v) and accepted when the relative residual is below ``rayleigh_tol``.
    """
    symmetric = is_symmetric(M, sym_tol) and is_symmetric(Q, sym_tol)
    if symmetric and fro(P) == 0:
        return "partial-eigh", "P = 0, M and Q symmetric", {}
    if symmetric and is_symmetric(P, sym_tol):
        ab = rayleigh_fit(M, P, Q, rayleigh_tol, probes=probes, seed=seed)
        if ab is not None:
            return ("partial-proportional", f"P = {ab[0]:.6g} M + {ab[1]:.6g} Q (Rayleigh damping)",
                    {"alpha": ab[0], "beta": ab[1]})
    return ("partial-companion",
            "general damping or non-symmetric: shift-invert on the companion pencil", {})


def solve_partial(M, P, Q, *, n_modes: int | None = None, target: float | None = None,
                  band=None, G=None, solver: str = "auto", sym_tol: float = 1e-13,
                  rayleigh_tol: float = 1e-12, verify_tol: float = 1e-8, arpack_tol: float = 0.0,
                  ncv: int | None = None, maxiter: int | None = None, left: bool = True,
                  max_modes: int = 2000) -> QEPSolution:
    """The requested modes of (M s² + P s + Q) x = 0 (M, P, Q sparse or dense, never densified).

    n_modes : number of modes (a complex pair counts once) nearest ``target``; default 20.  A
        repeated eigenvalue at the edge is taken whole (``coverage["note"]`` says so).
    target : angular frequency ω (rad/s) the modes are sought around, ranked by | |s| − ω |;
        default 0 (lowest modes).
    band : (ω_lo, ω_hi): every mode with ω_lo ≤ ω_n ≤ ω_hi (the count grows until all are found).
    G : constraint Jacobian Φ_q (m × n); M, P, Q are then in full coordinates (bordered pencil).
    solver : ``auto`` or a partial path of :data:`mbseig.eigen.base.SOLVERS`.
    verify_tol : largest backward error accepted for a returned pair (else SolverError).
    arpack_tol, ncv, maxiter : ARPACK's own options (0 = machine precision).
    left : on the companion path with non-symmetric matrices, compute left eigenvectors (inverse
        iteration on the transposed problem at each eigenvalue) for the condition numbers;
        otherwise κ is estimated with the right vector (exact for symmetric M, P, Q).

    The result's ``coverage`` = {"measure", "omega_n": (lo, hi), "dof", "shifts", "note",
    "verified"}: when ``verified``, every eigenvalue whose measure (|s|, or the undamped ω_n) lies
    in [lo, hi] was found; the note says on what grounds (for ``partial-projected``: the count
    certificate, or why it did not hold).

    η, κ and the componentwise measures of a conjugate partner (s̄, x̄) equal those of (s, x) for
    real M, P, Q: they are formed once per pair and copied.
    """
    n = M.shape[0]
    M, Q = _csr(M), _csr(Q)
    P = _csr(P, n)
    if not (M.shape == P.shape == Q.shape == (n, n)):
        raise SolverError(f"M, P, Q must be square and of one size, got {M.shape}, {P.shape}, "
                          f"{Q.shape}")
    for A in (M, P, Q):
        if not np.all(np.isfinite(A.data)):
            raise SolverError("M, P and Q must be finite")
    if band is not None:
        lo, hi = (float(b) for b in band)
        if not (0 <= lo <= hi):
            raise SolverError(f"band must be (ω_lo, ω_hi) with 0 ≤ ω_lo ≤ ω_hi, got {band!r}")
    if n_modes is not None and int(n_modes) < 1:
        raise SolverError(f"n_modes must be a positive integer, got {n_modes!r}")
    if target is not None and not (np.isfinite(target) and target >= 0):
        raise SolverError(f"target must be a finite angular frequency ≥ 0, got {target!r}")
    name, reason, extras = sparse_structure(M, P, Q, sym_tol=sym_tol, rayleigh_tol=rayleigh_tol)
    name, reason, extras = contract.select_path(solver, contract.Structure(name, reason, extras),
                                                "partial", "partial solver")
    m = 0 if G is None else G.shape[0]
    if m:
        G = _csr(G) if sp.issparse(G) else sp.csr_matrix(np.asarray(G, dtype=float))
        if G.shape[1] != n:
            raise SolverError(f"G must have {n} columns like M, got {G.shape}")
        Mb, Pb, Qb, c = bordered(M, P, Q, G)
        reason += f"; {m} constraint rows kept in a bordered pencil (row scale {c:.3g})"
    else:
        Mb, Pb, Qb = M, P, Q
    norms = (fro(Mb), fro(Pb), fro(Qb))
    w_scale = np.sqrt(norms[2] / norms[0]) if norms[0] > 0 and norms[2] > 0 else 1.0
    omega_t = 0.0 if target is None else float(target)
    want = 20 if n_modes is None else int(n_modes)
    symmetric_path = name in ("partial-eigh", "partial-proportional")
    dof = n - m  # finite eigenvalues: 2·dof (the multipliers' are infinite)
    run = Search(Mb=Mb, Pb=Pb, Qb=Qb, ncv=ncv, maxiter=maxiter, tol=arpack_tol, purify=m > 0,
                 w_scale=w_scale, dof=dof, limit=(dof - 1 if symmetric_path else 2 * dof - 2),
                 M=M, P=P, Q=Q, sym_tol=sym_tol, norms=norms)
    lowest = band is None and omega_t == 0.0
    # auto: general damping, lowest modes, symmetric M, P, Q -> the projected path first, and
    # partial-companion when it cannot verify its coverage (or fails)
    auto_projected = (solver == "auto" and name == "partial-companion" and lowest
                      and dof - 1 >= want + 2
                      and all(is_symmetric(A, sym_tol) for A in (M, P, Q)))
    if name == "partial-projected" and not lowest:
        raise SolverError("solver 'partial-projected' computes the lowest modes (n_modes, target "
                          "0); for a band or a target use partial-companion")
    found = None
    if name == "partial-projected" or auto_projected:
        found, name, reason = _projected_first(run, want, omega_t, band, max_modes, verify_tol,
                                               auto_projected, name, reason, extras)
    if found is None:
        found = contract.SOLVERS[name].kernel(run, want, omega_t, band, max_modes, verify_tol)
    if symmetric_path:
        s, Xq, Yq, eta, kappa, lazy, n_second = symmetric_pairs(
            found, extras, (Mb, Pb, Qb), norms, n, m, verify_tol, name)
    else:
        s, Xq, Yq, eta, kappa, lazy, n_second = general_pairs(
            found, (Mb, Pb, Qb), norms, n, m, verify_tol, name, sym_tol, left)
    real_error = None
    if name == "partial-proportional":
        a, b = extras["alpha"], extras["beta"]
        fit = fro((P - a * M - b * Q).tocsr())
        real_error = proportional_real_error(s, kappa, eta, norms, a, b, fit)
    coverage = {**found["coverage"], "dof": n - m}
    details = {**extras, "shifts": found["shifts"], "n_requested": want, "arpack_k": found["k"],
               "n_constraint_rows": m, "verify_tol": verify_tol, "second_half_vectors": n_second,
               "shift_offsets_tried": list(SHIFT_OFFSETS)}
    if "slepc" in found:
        details["slepc"] = found["slepc"]
    return QEPSolution(s, Xq, eta, kappa, name, reason, 0, norms, details, real_error,
                       left_vectors=Yq, partial=True,
                       n_dof=n - m, coverage=coverage, problem=lazy)


def _projected_first(run, want, omega_t, band, max_modes, verify_tol, auto_projected, name,
                     reason, extras):
    """The projected path, asked for or tried first by ``auto`` (general damping, lowest modes,
    symmetric M, P, Q): (found or None, path, reason); ``auto`` falls back, saying why, when its
    coverage is not verified or it fails (module docstring)."""
    why = None
    try:
        found = contract.SOLVERS["partial-projected"].kernel(run, want, omega_t, band, max_modes,
                                                    verify_tol)
        if auto_projected and not found["coverage"]["verified"]:
            why = f"its coverage is not verified: {found['projected']['certificate']['why']}"
            extras["projected_attempt"] = found.pop("projected")
            found = None
    except SolverError as exc:
        if not auto_projected:
            raise
        found, why = None, str(exc)
    if found is not None:
        reason = ("general damping, lowest modes, symmetric M, P, Q: undamped Lanczos, "
                  "projection and refinement with one LU, count certificate"
                  + (reason[reason.index(";"):] if ";" in reason else ""))
        extras["projected"] = found.pop("projected")
        return found, "partial-projected", reason
    extras["projected_fallback"] = why
    return None, name, reason + f"; partial-projected tried first and not used ({why})"


def partial_driver(problem, request) -> QEPSolution:
    """The ``partial`` family of :func:`mbseig.eigen.solve`: the modes the request selects."""
    return solve_partial(problem.M, problem.P, problem.Q, n_modes=request.n_modes,
                         target=request.target, band=request.band, G=problem.G,
                         solver=request.solver, **request.options)


def _projected(run, want, omega_t, band, max_modes, verify_tol):
    from .projected import (
        projected_search,  # its certificate machinery: loaded when used
    )

    return projected_search(run, want, verify_tol=verify_tol)


contract.register_family("partial", partial_driver)
contract.register("partial-eigh", family="partial", needs="P = 0, M and Q symmetric",
         kernel=lambda run, want, omega_t, band, max_modes, verify_tol: symmetric_search(
             run, want, omega_t, band, max_modes), applies=contract.structured_applies("eigh"))
contract.register("partial-proportional", family="partial",
         needs="P = αM + βQ with M and Q symmetric",
         kernel=lambda run, want, omega_t, band, max_modes, verify_tol: symmetric_search(
             run, want, omega_t, band, max_modes),
         applies=contract.structured_applies("proportional"))
contract.register("partial-companion", family="partial", needs="nothing (any sparse M, P, Q)",
         kernel=lambda run, want, omega_t, band, max_modes, verify_tol: companion_search(
             run, want, omega_t, band, max_modes))
contract.register("partial-slepc", family="partial",
         needs="slepc4py (optional backend: SLEPc's TOAR, lowest modes)",
         kernel=lambda run, want, omega_t, band, max_modes, verify_tol: slepc_search(
             run, want, omega_t, band))
contract.register("partial-projected", family="partial",
         needs=("M and Q symmetric (lowest modes; the coverage certificate also needs P "
                "symmetric, M and Q > 0 on the constraints)"), kernel=_projected)
