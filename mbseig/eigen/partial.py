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
from ..numerics import LazyModule
from .base import QEPSolution, partial_solvers, register, requested_path
from .measures import (
    EPS,
    backward_errors,
    better_half,
    colnorm,
    componentwise,
    conditions,
    expand_pairs,
    fro,
    is_symmetric,
    proportional_real_error,
    rayleigh_fit,
    undamped_roots,
    unit_columns,
)

spla = LazyModule("scipy.sparse.linalg")  # sparse solvers: imported at first use

__all__ = ["solve_partial", "sparse_structure"]

SHIFT_OFFSETS = (0.0, 1e-6, 1e-4, 1e-2)  # relative moves of a shift that sits on an eigenvalue
SHIFT_COND = 1.0 / (1e4 * EPS)
TARGET_ANGLES = ((0.5, 0.0, 1.0), (0.25, 0.75))  # × π: shifts on |s| = ω_t, the second set
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
    return A.astype(float)


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
    return "partial-companion", "general damping or non-symmetric: shift-invert on the companion pencil", {}


class _ShiftLU:
    """LU of σ²M + σP + Q (``quadratic``) or Q − σM, at σ or, when that is (nearly) singular,
    at σ moved left by ``SHIFT_OFFSETS`` × ``scale`` (module docstring)."""

    def __init__(self, M, P, Q, sigma, scale, quadratic=True):
        best, last = None, None
        b = np.random.default_rng(7).standard_normal(M.shape[0])
        for off in SHIFT_OFFSETS:
            sig = sigma - off * scale
            A = (sig * sig * M + sig * P + Q) if quadratic else (Q - sig * M)
            try:
                lu = spla.splu(A.tocsc())
            except RuntimeError as exc:  # exactly singular: σ is an eigenvalue
                last = exc
                continue
            with np.errstate(over="ignore", invalid="ignore"):
                x = lu.solve(b.astype(lu.U.dtype))  # one solve: ‖A⁻¹‖ from below
                cond = fro(A) * float(np.linalg.norm(x)) / float(np.linalg.norm(b))
            cond = cond if np.isfinite(cond) else np.inf
            if best is None or cond < best[2]:
                best = (lu, sig, cond)
            if cond <= SHIFT_COND:
                break
        if best is None:
            raise SolverError(f"shift-invert: σ²M + σP + Q is singular at σ = {sigma:.6g} and "
                              f"every nearby shift tried ({last}): a coordinate without mass, "
                              f"damping or stiffness?")
        self.lu, self.sigma, self.cond = best
        self.n_solves = 0  # right-hand sides solved (real columns), for the path's details

    def solve(self, b, trans="N"):
        b = np.asarray(b)
        self.n_solves += (1 if b.ndim == 1 else b.shape[1]) * (2 if np.iscomplexobj(b) else 1)
        if np.iscomplexobj(b) and not np.iscomplexobj(self.lu.U.data):  # real factors
            return self.lu.solve(np.ascontiguousarray(b.real), trans=trans) \
                + 1j * self.lu.solve(np.ascontiguousarray(b.imag), trans=trans)
        return self.lu.solve(b, trans=trans)


def _bordered(M, P, Q, G):
    m = G.shape[0]
    nQ, nG = fro(Q), fro(G)
    c = nQ / nG if nG > 0 and nQ > 0 else 1.0
    Z = sp.csr_matrix((m, m))
    Mb = sp.block_diag([M, Z], format="csr")
    Pb = sp.block_diag([P, Z], format="csr")
    Qb = sp.bmat([[Q, c * G.T], [c * G, Z]], format="csr")
    return Mb, Pb, Qb, c


def _arpack(fn, what, **kw):
    try:
        return fn(**kw)
    except spla.ArpackNoConvergence as exc:
        got = 0 if exc.eigenvalues is None else len(exc.eigenvalues)
        raise SolverError(f"{what}: ARPACK did not converge ({got} of {kw.get('k')} eigenvalues "
                          f"after {kw.get('maxiter') or 'default'} iterations); ask for fewer modes, "
                          f"move the target or raise maxiter") from None
    except spla.ArpackError as exc:
        raise SolverError(f"{what}: ARPACK failed: {exc}") from None


def _undamped_partial(Mb, Qb, k, sigma, scale, ncv, maxiter, tol, purify, lu=None):
    """k eigenpairs (ω², v) of Q v = ω² M v nearest σ (Lanczos, shift-invert mode), purified
    when M is singular (bordered), and the shift actually used; ``lu``: a :class:`_ShiftLU` of
    Q − σM already made (else one is made here)."""
    nb = Mb.shape[0]
    lu = lu if lu is not None else _ShiftLU(Mb, None, Qb, sigma, scale, quadratic=False)
    OPinv = spla.LinearOperator((nb, nb), matvec=lambda x: lu.solve(np.asarray(x).ravel()), dtype=float)
    w, V = _arpack(spla.eigsh, "partial-eigh", A=Qb, k=k, M=Mb, sigma=lu.sigma, which="LM",
                   OPinv=OPinv, ncv=ncv, maxiter=maxiter, tol=tol)
    if purify:  # v ← (Q − σM)⁻¹ M v: the component along M's null space (multipliers) is removed
        V = lu.solve(np.asarray(Mb @ V))
        mv = np.sqrt(np.abs(np.einsum("ij,ij->j", V, Mb @ V)))
        V = V / np.where(mv > 0, mv, 1.0)
    return w, V, lu.sigma


def _companion_partial(Mb, Pb, Qb, k, sigma, scale, ncv, maxiter, tol, purify):
    """k eigenpairs of the companion pencil nearest σ in the s-plane (Arnoldi, shift-invert):
    (s, first halves, second halves / s, coverage (σ, ν_min, real_part)).

    A complex σ on real matrices runs real Arnoldi on the real part of the shift-invert operator,
    Re (A − σB)⁻¹B, whose eigenvalues ν = ½[1/(s − σ) + 1/(s − σ̄)] are largest for s near σ
    or σ̄ (Parlett & Saad 1987; complex Arnoldi is two orders slower here); s is recovered from
    each Ritz vector by one application of the complex operator.  Every eigenvalue not returned
    has |ν| ≤ ν_min, which is what the coverage test uses."""
    nb = Mb.shape[0]
    lu = _ShiftLU(Mb, Pb, Qb, sigma, scale)
    sig = lu.sigma
    PsM = (Pb + sig * Mb).tocsr()
    real_part = bool(np.iscomplex(sig))

    def op(v):
        v = np.asarray(v)
        v1, v2 = v[:nb], v[nb:]
        b = np.asarray(Mb @ v2 + PsM @ v1)
        z1 = -lu.solve(b.astype(np.result_type(b, complex if real_part else float)))
        return np.concatenate([z1, v1 + sig * z1])

    if real_part:
        OP = spla.LinearOperator((2 * nb, 2 * nb), matvec=lambda v: op(v).real, dtype=float)
    else:
        OP = spla.LinearOperator((2 * nb, 2 * nb), matvec=op, dtype=float)
    nu, Z = _arpack(spla.eigs, "partial-companion", A=OP, k=k, which="LM", ncv=ncv,
                    maxiter=maxiter, tol=tol)
    ok = nu != 0
    nu, Z = nu[ok], Z[:, ok]
    nu_min = float(np.min(np.abs(nu))) if nu.size else np.inf
    if real_part or purify:  # (A − σB)⁻¹B once more: s from the Ritz vector, and purified
        W = np.empty(Z.shape, dtype=complex)  # filled column by column: no list of copies
        for j in range(Z.shape[1]):
            W[:, j] = op(Z[:, j])
        with np.errstate(divide="ignore", invalid="ignore"):
            mu = np.einsum("ij,ij->j", Z.conj(), W) / np.einsum("ij,ij->j", Z.conj(), Z)
        Z = W
        del W
    else:
        mu = nu
    s = sig + 1.0 / mu
    return s, Z[:nb], Z[nb:] / np.where(s != 0, s, 1.0), (complex(sig), nu_min, real_part)


def _nu(points, sigma, real_part):
    """|ν| of the shift-invert operator at the points (see :func:`_companion_partial`)."""
    with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
        if real_part:
            nu = np.abs(0.5 * (1 / (points - sigma) + 1 / (points - np.conj(sigma))))
        else:
            nu = np.abs(1 / (points - sigma))
    return np.where(np.isfinite(nu), nu, np.inf)  # at the shift itself: found for sure


def _dedupe(values, X, rtol, floor):
    """Indices of the eigenpairs to keep when several shifts found the same one: a pair is
    dropped when its value equals kept ones (|Δ| ≤ rtol·max(|s|, floor)) and its vector lies in
    their span (an independent vector of a repeated eigenvalue is kept)."""
    keep = []
    for i in range(values.size):
        if keep:
            kv = values[keep]
            dup = np.flatnonzero(np.abs(kv - values[i]) <= rtol * max(abs(values[i]), floor))
        else:
            dup = np.zeros(0, int)
        if dup.size:
            B = np.linalg.qr(X[:, np.asarray(keep)[dup]])[0]
            v = X[:, i] / max(np.linalg.norm(X[:, i]), np.finfo(float).tiny)
            if np.linalg.norm(v - B @ (B.conj().T @ v)) <= 1e-6:
                continue
        keep.append(i)
    return np.array(keep, int)


def _covered(points, runs, margin=1e-9):
    """Every point (complex) where some run would have found an eigenvalue (|ν| > ν_min)?"""
    if not runs:
        return False
    hit = np.zeros(points.size, bool)
    for sigma, nu_min, real_part in runs:
        hit |= _nu(points, sigma, real_part) > nu_min * (1 + margin)
    return bool(np.all(hit))


def _annulus_points(lo, hi, n_angle=73, n_radius=5):
    """Sample points of {lo ≤ |s| ≤ hi, Im s ≥ 0} (boundary and interior)."""
    th = np.linspace(0.0, np.pi, n_angle)
    rad = np.linspace(max(lo, 0.0), hi, n_radius)
    pts = (rad[:, None] * np.exp(1j * th[None, :])).ravel()
    return pts if lo > 0 else np.concatenate([pts, [0.0]])


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
        raise SolverError(f"M, P, Q must be square and of one size, got {M.shape}, {P.shape}, {Q.shape}")
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
    name, reason, extras = requested_path(solver, name, reason, extras, partial_solvers(),
                                          "partial solver")
    m = 0 if G is None else G.shape[0]
    if m:
        G = _csr(G) if sp.issparse(G) else sp.csr_matrix(np.asarray(G, dtype=float))
        if G.shape[1] != n:
            raise SolverError(f"G must have {n} columns like M, got {G.shape}")
        Mb, Pb, Qb, c = _bordered(M, P, Q, G)
        reason += f"; {m} constraint rows kept in a bordered pencil (row scale {c:.3g})"
    else:
        Mb, Pb, Qb = M, P, Q
    norms = (fro(Mb), fro(Pb), fro(Qb))
    w_scale = np.sqrt(norms[2] / norms[0]) if norms[0] > 0 and norms[2] > 0 else 1.0
    omega_t = 0.0 if target is None else float(target)
    want = 20 if n_modes is None else int(n_modes)
    symmetric_path = name in ("partial-eigh", "partial-proportional")
    dof = n - m  # finite eigenvalues: 2·dof (the multipliers' are infinite)
    run = {"Mb": Mb, "Pb": Pb, "Qb": Qb, "ncv": ncv, "maxiter": maxiter, "tol": arpack_tol,
           "purify": m > 0, "w_scale": w_scale, "dof": dof,
           "limit": (dof - 1 if symmetric_path else 2 * dof - 2),
           "M": M, "P": P, "Q": Q, "sym_tol": sym_tol, "norms": norms}
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
        from types import SimpleNamespace

        from .projected import projected_search

        run["kit"] = SimpleNamespace(ShiftLU=_ShiftLU, undamped_partial=_undamped_partial,
                                     slots=_slots, pick=_pick, cluster_tol=_cluster_tol,
                                     with_partners=_with_partners)
        why = None
        try:
            found = projected_search(run, want, verify_tol=verify_tol)
            if auto_projected and not found["coverage"]["verified"]:
                why = f"its coverage is not verified: {found['projected']['certificate']['why']}"
                extras["projected_attempt"] = found.pop("projected")
                found = None
        except SolverError as exc:
            if not auto_projected:
                raise
            why = str(exc)
        if found is not None:
            name = "partial-projected"
            reason = ("general damping, lowest modes, symmetric M, P, Q: undamped Lanczos, "
                      "projection and refinement with one LU, count certificate"
                      + (reason[reason.index(";"):] if ";" in reason else ""))
            extras["projected"] = found.pop("projected")
        else:
            reason += f"; partial-projected tried first and not used ({why})"
            extras["projected_fallback"] = why
    if found is None:
        if name == "partial-slepc":
            found = _slepc_search(run, want, omega_t, band)
        elif symmetric_path:
            found = _symmetric_search(run, want, omega_t, band, max_modes)
        else:
            found = _companion_search(run, want, omega_t, band, max_modes)
    if symmetric_path:
        w, V = found["w"], found["V"]
        alpha, beta = extras.get("alpha", 0.0), extras.get("beta", 0.0)
        s = undamped_roots(w, alpha, beta)
        V = np.divide(V, colnorm(V), order="C")  # row-major: the measures run over blocks of rows
        X = np.concatenate([V, V], axis=1)
        if m and beta != 0.0:  # multipliers of the damped mode: μ = (1 + βs) λ (module doc)
            X = X.astype(complex)
            X[n:, :] *= (1.0 + beta * s)[None, :]
            X = unit_columns(X)
        eta, MX, PX = backward_errors((Mb, Pb, Qb), s, X, norms)
        Yc = X
        kappa = conditions(s, X, Yc, MX, PX, norms)
        n_second = 0
    else:
        # a conjugate partner (s̄, x̄) of real M, P, Q has the η, κ, η_c, κ_c of (s, x): the
        # measures are formed on one column per pair (half the work) and copied to the partner
        s_all, X1, X2 = found["s"], found["X1"], found["X2"]
        src = _partner_columns(s_all, X1)
        uniq = np.flatnonzero(src == np.arange(s_all.size))
        s = s_all[uniq]
        if uniq.size < s_all.size:
            X1, X2 = X1[:, uniq], (None if X2 is X1 else X2[:, uniq])
            X2 = X1 if X2 is None else X2
        del found["X1"], found["X2"]
        X, eta, MX, PX, n_second = better_half((Mb, Pb, Qb), s, X1, X2, norms)
        del X1, X2
        symmetric_all = all(is_symmetric(A, sym_tol) for A in (Mb, Pb, Qb))
        Yc = X if symmetric_all or not left else _left_vectors(Mb, Pb, Qb, s)
        kappa = conditions(s, X, Yc, MX, PX, norms)
        del MX, PX
    if not symmetric_path:
        pos = np.searchsorted(uniq, src)  # the measured column of each returned pair
        partner = src != np.arange(s_all.size)
    bad = ~(eta <= verify_tol)
    if np.any(bad):
        worst = ", ".join(f"{z.real:.6g}{z.imag:+.6g}j (η={e:.1e})" for z, e in zip(s[bad][:5], eta[bad][:5]))
        raise SolverError(f"{name}: {int(bad.sum())} returned pairs fail the backward-error check "
                          f"η ≤ {verify_tol:g}: {worst}")
    # the componentwise measures on demand (the listing asks for the few pairs the normwise
    # bound leaves undecided; at 10⁶ coordinates all of them cost ≈ 4 s)
    lazy = _Componentwise((Mb, Pb, Qb), s, X, Yc,
                          None if symmetric_path else pos, None if symmetric_path else partner)
    Xq = unit_columns(X[:n]) if m else X
    Yq = Xq if Yc is X else (unit_columns(Yc[:n]) if m else Yc)
    del X, Yc
    if not symmetric_path:  # back to every returned pair: partners conjugated
        s, eta, kappa = s_all, eta[pos], kappa[pos]
        same = Yq is None or Yq is Xq  # y = x̄: the left vectors are the right ones, expanded once
        Xq = expand_pairs(Xq, pos, partner)
        Yq = Xq if same else expand_pairs(Yq, pos, partner)
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


def _partner_columns(s, X):
    """src[j] = i < j where pair j is exactly the conjugate of pair i (s_j = s̄_i, x_j = x̄_i, as
    the searches build the partners), else j."""
    src = np.arange(s.size)
    taken = np.zeros(s.size, bool)
    for j in range(s.size):
        if s[j].imag == 0:
            continue
        for i in np.flatnonzero((s[:j] == np.conj(s[j])) & ~taken[:j]):
            if src[i] == i and np.array_equal(X[:, j], np.conj(X[:, i])):
                src[j] = i
                taken[i] = True
                break
    return src


class _Componentwise:
    """(η_c, κ_c) of returned pairs on demand (:meth:`QEPSolution.componentwise`), from the
    bordered pencil and the bordered vectors they were verified with; ``pos``/``partner`` map a
    returned pair to its measured column (a conjugate partner has the same measures).  A plain
    object (not a closure), so a solution stays picklable."""

    def __init__(self, pencil, s, X, Y, pos=None, partner=None):
        self.pencil, self.s, self.X, self.Y, self.pos, self.partner = pencil, s, X, Y, pos, partner

    def __call__(self, idx):
        cols = np.asarray(idx) if self.pos is None else np.unique(self.pos[np.asarray(idx)])
        Y = None if self.Y is None else self.Y[:, cols]
        eta_c, kappa_c = componentwise(self.pencil, self.s[cols], self.X[:, cols], Y)
        if self.pos is None:
            return eta_c, kappa_c
        where = np.searchsorted(cols, self.pos[np.asarray(idx)])
        return eta_c[where], kappa_c[where]


def _with_partners(chosen, s, tol):
    """(columns, conjugated?, eigenvalues): each kept mode of the upper half-plane followed by
    its conjugate partner where |Im s| exceeds its tolerance (exact for real matrices)."""
    cols, conj = [], []
    for i in chosen:
        cols.append(i)
        conj.append(False)
        if abs(s[i].imag) > tol[i]:
            cols.append(i)
            conj.append(True)
    cols, conj = np.array(cols, int), np.array(conj, bool)
    s_out = np.where(conj, np.conj(s[cols]), s[cols]) if cols.size else np.zeros(0, complex)
    return cols, conj, s_out


# ---------------------------------------------------------------------------------------------
# the searches: shifts, coverage, selection
# ---------------------------------------------------------------------------------------------
def _cluster_tol(scale):
    return 1e-8 * scale


def _slots(s, X, tie):
    """Slot label per eigenvalue: members of a defective cluster (equal within ``tie``, parallel
    vectors: the two halves of a rigid-body double zero, a Jordan block) share one mode slot."""
    slot = np.arange(s.size)
    for i in range(s.size):
        for j in range(i):
            if slot[j] == j and abs(s[i] - s[j]) <= tie:
                a, b = X[:, i], X[:, j]
                cos = abs(np.vdot(a, b)) / max(np.linalg.norm(a) * np.linalg.norm(b), 1e-300)
                if cos >= 1 - 1e-6:
                    slot[i] = j
                    break
    return slot


def _pick(measure, count, omega_t, band, scale):
    """Indices of the modes to keep: inside the band, or the ``count`` nearest ω_t in the
    measure, extended by every mode of the same measure as the last (a repeated eigenvalue);
    returns (indices, distance d of the last kept, extension note)."""
    if band is not None:
        keep = np.flatnonzero((measure >= band[0]) & (measure <= band[1]))
        return keep, None, ""
    key = np.abs(measure - omega_t)
    order = np.argsort(key, kind="stable")
    if order.size == 0:
        return order, 0.0, ""
    head = order[:count]
    d = float(key[head[-1]]) if head.size else 0.0
    tie = _cluster_tol(max(float(measure[head[-1]]) if head.size else 0.0, scale))
    extra = order[count:][key[order[count:]] <= d + tie]
    note = ""
    if extra.size:
        note = (f"n_modes = {count} extended to {count + extra.size}: the mode at ω_n = "
                f"{float(measure[head[-1]]):.6g} rad/s is repeated (its {1 + extra.size} members "
                f"are listed together)")
    return np.concatenate([head, extra]), d + tie, note


def _symmetric_search(run, want, omega_t, band, max_modes):
    """Undamped modes (ω², v) for the symmetric paths, ranked by ω_n = √|ω²|."""
    Mb, Qb = run["Mb"], run["Qb"]
    scale = run["w_scale"]
    if band is not None:
        mid = 0.5 * (band[0] ** 2 + band[1] ** 2)
        sigmas = [mid, -mid] if band[0] > 0 else [0.0]
    else:
        sigmas = [omega_t**2, -omega_t**2] if omega_t > 0 else [0.0]
    k = want + 2
    while True:
        k = min(k, run["limit"])
        if k < 1 or (want > run["limit"]):
            raise SolverError(f"{want} modes asked of a problem with {run['dof']} degrees of "
                              f"freedom: use the dense path")
        ws, Vs, covered = [], [], []
        for sg in sigmas:
            w, V, used = _undamped_partial(Mb, Qb, k, sg, scale**2, run["ncv"], run["maxiter"],
                                           run["tol"], run["purify"])
            ws.append(w)
            Vs.append(V)
            covered.append((used, float(np.max(np.abs(w - used)))))
        w, V = np.concatenate(ws), np.column_stack(Vs)
        if len(sigmas) > 1:
            keep = _dedupe(w, V, 1e-10, scale * scale)
            w, V = w[keep], V[:, keep]
        omega = np.sqrt(np.abs(w))
        idx, d, note = _pick(omega, want, omega_t, band, scale)
        lo, hi = (band if band is not None else (max(omega_t - d, 0.0), omega_t + d))
        # the selection is right when both w-intervals [lo², hi²] and [−hi², −lo²] are covered
        need = [(lo * lo, hi * hi), (-hi * hi, -lo * lo)]
        ok = all(any(c - r * 0.999 <= a and b <= c + r * 0.999 for c, r in covered) for a, b in need)
        if ok or k >= run["limit"]:
            break
        if k >= max_modes:
            raise SolverError(f"the requested modes need more than max_modes = {max_modes} "
                              f"eigenpairs per shift")
        k = min(2 * k, max_modes)
    order = idx[np.argsort(w[idx], kind="stable")]
    return {"w": w[order], "V": V[:, order], "k": k, "shifts": [c for c, _ in covered],
            "coverage": {"measure": "undamped ω_n", "omega_n": (lo, hi), "note": note,
                         "verified": ok}}


def _companion_search(run, want, omega_t, band, max_modes):
    """Eigenvalues of the general (companion) path ranked by |s|."""
    Mb, Pb, Qb = run["Mb"], run["Pb"], run["Qb"]
    scale = run["w_scale"]
    def on_circle(angles):
        out = []
        for a in angles:
            z = omega_t * np.exp(1j * np.pi * a)
            out.append(complex(z.real, z.imag) if abs(z.imag) > 1e-12 * omega_t else float(z.real))
        return out

    circle = band is None and omega_t > 0
    sigmas = on_circle(TARGET_ANGLES[0]) if circle else [0.0]
    extra = list(TARGET_ANGLES[1:]) if circle else []
    k = 2 * want + 1
    runs = {}
    while True:
        if k > run["limit"]:
            raise SolverError(f"{want} modes asked of a problem with {run['dof']} degrees of "
                              f"freedom: use the dense path")
        for sg in sigmas:
            if (sg, k) not in runs:
                runs[(sg, k)] = _companion_partial(Mb, Pb, Qb, k, sg, scale, run["ncv"],
                                                   run["maxiter"], run["tol"], run["purify"])
        parts = [runs[(sg, k)] for sg in sigmas]
        discs = [p[3] for p in parts]
        if len(parts) == 1:  # one shift (the lowest modes): no copies
            s, X1, X2 = parts[0][:3]
        else:
            s = np.concatenate([p[0] for p in parts])
            X1 = np.concatenate([p[1] for p in parts], axis=1)
            X2 = np.concatenate([p[2] for p in parts], axis=1)
        if len(sigmas) > 1:
            keep = _dedupe(s, X1, 1e-9, scale)
            s, X1, X2 = s[keep], X1[:, keep], X2[:, keep]
        tol = 1e-9 * np.maximum(np.abs(s), 1e-300)
        upper = np.flatnonzero(s.imag >= -tol)
        slot = _slots(s[upper], X1[:, upper], _cluster_tol(scale))
        first = np.flatnonzero(slot == np.arange(slot.size))  # one candidate per slot
        idx, d, note = _pick(np.abs(s[upper[first]]), want, omega_t, band, scale)
        idx = np.flatnonzero(np.isin(slot, first[idx]))  # every member of the slots picked
        lo, hi = (band if band is not None else (max(omega_t - d, 0.0), omega_t + d))
        ok = _covered(_annulus_points(lo, hi), discs)
        if ok:
            break
        if extra:  # more shifts on the circle before more eigenvalues per shift
            sigmas = sigmas + on_circle(extra.pop(0))
            continue
        if k >= run["limit"] or want >= max_modes:
            if band is not None:
                raise SolverError(f"band {band!r} holds more than max_modes = {max_modes} modes")
            break
        k = min(2 * k, run["limit"])
    cols, conj, s_out = _with_partners(upper[idx], s, tol)

    def gather(X):  # the kept columns, conjugated where they are the partners (one copy)
        out = np.asarray(X)[:, cols].astype(complex)
        out[:, conj] = out[:, conj].conj()
        return out

    X1o = gather(X1)
    X2o = X1o if X2 is X1 else gather(X2)
    del runs, parts, X1, X2
    return {"s": np.asarray(s_out, complex), "X1": X1o, "X2": X2o, "k": k,
            "shifts": [c if c.imag else float(c.real) for c, _, _ in discs],
            "coverage": {"measure": "|s|", "omega_n": (lo, hi), "note": note, "verified": ok}}


def _slepc_search(run, want, omega_t, band):
    """The lowest modes from SLEPc (:mod:`mbseig.eigen.slepc`): TOAR with shift-and-invert at 0
    on the same bordered pencil, selected and covered as :func:`_companion_search` does."""
    from .slepc import slepc_solve

    if band is not None or omega_t != 0.0:
        raise SolverError("solver 'partial-slepc' computes the lowest modes (n_modes, target 0); "
                          "for a band or a target use partial-companion")
    Mb, Pb, Qb = run["Mb"], run["Pb"], run["Qb"]
    scale = run["w_scale"]
    nev = 2 * want + 1
    while True:
        if nev > run["limit"]:
            raise SolverError(f"{want} modes asked of a problem with {run['dof']} degrees of "
                              f"freedom: use the dense path")
        s_all, X_all, info = slepc_solve(Mb, Pb, Qb, nev, 0.0, ncv=run["ncv"])
        if not (np.all(np.isfinite(s_all)) and np.all(np.isfinite(X_all))):
            raise SolverError("partial-slepc returned non-finite eigenpairs (is T(0) = Q "
                              "singular? a rigid-body mode: use partial-companion)")
        # SLEPc guarantees the nev nearest to the target; pairs it converged beyond them are
        # not, so the disc |s| ≤ reach that is known complete ends at the nev-th
        reach = (float(np.sort(np.abs(s_all))[min(nev, s_all.size) - 1]) if s_all.size
                 else 0.0)
        disc = (0.0 + 0.0j, 1.0 / reach if reach > 0 else np.inf, False)
        tol = 1e-9 * np.maximum(np.abs(s_all), 1e-300)
        upper = np.flatnonzero(s_all.imag >= -tol)
        slot = _slots(s_all[upper], X_all[:, upper], _cluster_tol(scale))
        first = np.flatnonzero(slot == np.arange(slot.size))
        idx, d, note = _pick(np.abs(s_all[upper[first]]), want, 0.0, None, scale)
        idx = np.flatnonzero(np.isin(slot, first[idx]))
        lo, hi = 0.0, d
        ok = first.size > want and _covered(_annulus_points(lo, hi), [disc])
        if ok or nev >= run["limit"]:
            break
        nev = min(2 * nev, run["limit"])
    cols, conj, s_out = _with_partners(upper[idx], s_all, tol)
    X = expand_pairs(np.asarray(X_all, complex), cols, conj)
    return {"s": s_out, "X1": X, "X2": X, "k": nev, "shifts": [0.0],
            "coverage": {"measure": "|s|", "omega_n": (lo, hi), "note": note, "verified": ok},
            "slepc": info}


def _left_vectors(Mb, Pb, Qb, s, steps=3):
    """Conjugated left eigenvectors ȳ, (s²Mᵀ + sPᵀ + Qᵀ) ȳ = 0, by inverse iteration at each
    eigenvalue (one sparse LU each; a conjugate partner takes the conjugate)."""
    nb = Mb.shape[0]
    Y = np.empty((nb, s.size), complex)
    Mt, Pt, Qt = Mb.T.tocsc(), Pb.T.tocsc(), Qb.T.tocsc()
    rng = np.random.default_rng(11)
    for j, z in enumerate(s):
        partner = [i for i in range(j) if s[i] == np.conj(z)]
        if partner:
            Y[:, j] = np.conj(Y[:, partner[0]])
            continue
        lu = None
        for rel in (1e-13, 1e-11, 1e-9):  # exactly singular at the eigenvalue: step off it
            zz = z * (1 + rel) + rel
            try:
                lu = spla.splu((zz * zz * Mt + zz * Pt + Qt).tocsc())
                break
            except RuntimeError:
                continue
        if lu is None:
            raise SolverError(f"left eigenvector of s = {z:.6g}: every factorization near it is singular")
        y = rng.standard_normal(nb) + 1j * rng.standard_normal(nb)
        for _ in range(steps):
            y = lu.solve(y / np.linalg.norm(y))
        Y[:, j] = y / np.linalg.norm(y)
    return Y


for _name, _needs in (("partial-eigh", "P = 0, M and Q symmetric"),
                      ("partial-proportional", "P = αM + βQ with M and Q symmetric"),
                      ("partial-companion", "nothing (any sparse M, P, Q)"),
                      ("partial-slepc", "slepc4py (optional backend: SLEPc's TOAR, lowest modes)"),
                      ("partial-projected", ("M and Q symmetric (lowest modes; the coverage "
                                             "certificate also needs P symmetric, M and Q > 0 "
                                             "on the constraints)"))):
    register(_name, partial=True, needs=_needs, driver=solve_partial)
