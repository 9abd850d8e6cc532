"""Dense paths for the quadratic eigenvalue problem (M s² + P s + Q) x = 0 (docs/design.md).

Registered in :data:`mbseig.eigen.contract.SOLVERS` (the kernels:
:mod:`~mbseig.eigen.dense_paths`); ``auto`` picks by structure and conditioning
(:func:`choose_solver`) and the result says which path ran and why:

``eigh``          P = 0, M and Q symmetric, M positive definite: ``eigh(Q, M)``, s = ±√(−ω²).
``proportional``  P = αM + βQ (Rayleigh damping, fitted and verified), M, Q symmetric, M > 0:
                  the undamped modes with s² + (α + βω²) s + ω² = 0 solved per mode.
``companion``     M symmetric positive definite and well conditioned (cond(M) ≤
                  ``companion_cond``): mass-normalized (M = LLᵀ, x = L⁻ᵀy) first companion
                  matrix scaled by γ, standard eigenproblem (LAPACK geev):

                      A = ┌    0          I    ┐ ,   s = γ μ
                          └ −Q̃/γ²     −P̃/γ   ┘
``qz``            anything else (singular or ill-conditioned M, non-symmetric M, complex M):
                  Fan–Lin–Van Dooren scaled pencil (γ = √(‖Q‖/‖M‖), δ = 2/(‖Q‖ + γ‖P‖)), QZ
                  (LAPACK ggev); infinite eigenvalues of a singular M dropped and counted.  A
                  singular pencil (det ≡ 0: a coordinate, or a combination of coordinates,
                  without mass, damping or stiffness) is refused before QZ
                  (:class:`~mbseig.eigen.base.SingularPencilError`).

Mass normalization divides by √m: with cond(M) = 10⁹ the companion matrix spans 10⁹ more in
its entries than the pencil and loses that much relative accuracy on the slow modes (measured
in tests/test_eigen_trust.py), hence the conditioning limit.  Problems whose norms lie outside
10^±100 (or whose frequency scale √(‖Q‖/‖M‖) lies outside 10^±50) are first scaled as the QZ
pencil is, s = γ μ, and solved in μ, so that no intermediate quantity overflows: η is invariant
under that scaling and κ scales with γ.  Complex M, P, Q (hysteretic damping) are solved on the
companion path (M real SPD) or the QZ path; their eigenvalues do not pair.

Every pair carries η and κ (:mod:`mbseig.eigen.measures`).  Of a companion eigenvector both
halves are candidates for x; the one with the smaller η is kept.
"""

from __future__ import annotations

import contextlib
import threading
from dataclasses import replace

import numpy as np
import scipy.linalg as sla
import scipy.sparse as sp

from ..errors import SolverError
from ..numerics import blas_limit
from .base import QEPSolution
from .contract import (
    SOLVERS,
    Structure,
    register,
    register_family,
    select_path,
    structured_applies,
)
from .dense_paths import (
    diagonal_positive,
    solve_companion,
    solve_eigh,
    solve_proportional,
    solve_qz,
)
from .measures import (
    EPS,
    componentwise,
    fro,
    is_symmetric,
    pow2_scale,
    rayleigh_fit,
)
from .pencil import check_regular

__all__ = ["choose_solver", "problem_scaling", "solve_qep", "blas_held", "small_blas"]

#: cond(M) above which a positive definite M is not mass-normalized (companion, eigh paths)
COMPANION_COND = 1e5
GENERAL = "qz"  # the dense path that needs nothing of M, P, Q (QZ on the companion pencil)
STRUCTURED_COND = 1.0 / (1e3 * EPS)
SMALL_BLAS = 100  # order up to which the dense solve runs on one BLAS thread
_HELD = threading.local()  # BLAS threads a caller holds capped (mbseig.studies.runners)


@contextlib.contextmanager
def blas_held(n):
    """Tell the dense solves that the caller holds BLAS at ``n`` threads (a sweep task runs
    inside one cap): a solve of a small problem then does not cap it again (≈ 0.1–0.2 ms of
    threadpoolctl per solve, a few per cent of a sweep point)."""
    before = getattr(_HELD, "n", None)
    _HELD.n = n
    try:
        yield
    finally:
        _HELD.n = before


def small_blas(n):
    """The BLAS cap of a dense solve of order n: one thread up to SMALL_BLAS, unless the caller
    holds it at one already."""
    if n > SMALL_BLAS or getattr(_HELD, "n", None) == 1:
        return contextlib.nullcontext()
    return blas_limit(1)



def _dense(A, what):
    A = A.toarray() if sp.issparse(A) else np.asarray(A)
    if A.dtype.kind not in "biufc":
        raise SolverError(f"{what} must be a numeric matrix, got dtype {A.dtype}")
    if A.dtype.kind == "c":
        if np.any(A.imag):
            return np.asarray(A, dtype=complex)
        return np.ascontiguousarray(A.real, dtype=float)  # exactly real: nothing is discarded
    return np.asarray(A, dtype=float)


def _cholesky(M):
    try:
        return sla.cholesky(M, lower=True)
    except np.linalg.LinAlgError:
        return None




def mass_condition(M, memo=None):
    """(positive definite, cond₂(M) estimate) of a real symmetric M; (False, ∞) otherwise.

    Diagonal M: max/min of the diagonal (exact); else the Cholesky factor and LAPACK's 1-norm
    condition estimate (``pocon``).  ``memo`` keeps the Cholesky factor ("L") for the caller.
    """
    memo = {} if memo is None else memo
    if "mass_condition" not in memo:  # the path's choice and its check ask for the same M
        memo["mass_condition"] = _mass_condition(M, memo)
    return memo["mass_condition"]


def diagonal(M, memo):
    """Whether M is diagonal (:func:`diagonal_positive`, once per solve: kept in ``memo``)."""
    if "diagonal" not in memo:
        memo["diagonal"] = diagonal_positive(M)
    return memo["diagonal"] is not None


def _mass_condition(M, memo):
    if np.iscomplexobj(M):
        return False, np.inf
    diagonal(M, memo)
    diag = memo["diagonal"]
    if diag is not None:
        if not diag:
            return False, np.inf
        d = np.diagonal(M).real
        with np.errstate(over="ignore"):  # a subnormal mass: cond = ∞, as it is
            return True, float(d.max() / d.min())
    L = _cholesky(0.5 * (M + M.T))
    if L is None:
        return False, np.inf
    memo["L"] = L
    anorm = float(np.max(np.sum(np.abs(M), axis=0)))
    rcond, info = sla.lapack.dpocon(L, anorm, uplo="L")
    return True, (np.inf if info != 0 or rcond <= 0 else float(1.0 / rcond))


def choose_solver(M, P, Q, *, sym_tol=1e-13, rayleigh_tol=1e-12, memo=None,
                  companion_cond=COMPANION_COND):
    """(name, reason, extras) of the path ``auto`` takes for these matrices.

    memo : optional dict that caches the symmetry tests (keys "M", "P", "Q") and the Cholesky
    factor of M ("L") for the caller.
    companion_cond : largest cond(M) for which M is mass-normalized (companion path); the
    structured paths accept up to 1/(1000 ε).
    """
    memo = {} if memo is None else memo
    norms = memo.get("fro", {})  # ‖A‖_F of the caller's M, P, Q (the same arrays)
    asym = {}  # ‖A − Aᵀ‖_F where a symmetry test computed it

    def sym(key, A):
        if key not in memo:
            found = {}
            memo[key] = is_symmetric(A, sym_tol, norm=norms.get(key), found=found)
            if "asymmetry" in found:
                asym[key] = found["asymmetry"]
        return memo[key]

    complex_problem = any(np.iscomplexobj(A) for A in (M, P, Q))
    if ("M" not in memo and not complex_problem and not sp.issparse(M) and M.ndim == 2
            and diagonal(M, memo)):
        memo["M"] = True  # a diagonal matrix is symmetric: ‖M − Mᵀ‖ = 0
        asym["M"] = 0.0
    pd, cond = (sym("M", M) and mass_condition(M, memo)) or (False, np.inf)
    memo["cond_M"] = cond
    if pd and not complex_problem and sym("Q", Q) and cond <= STRUCTURED_COND:
        if not np.any(P):
            return "eigh", "P = 0, M and Q symmetric, M positive definite", {}
        # the fit first: where P = αM + βQ + E, ‖P − Pᵀ‖ ≤ 2‖E‖ + |α|‖M − Mᵀ‖ + |β|‖Q − Qᵀ‖, a
        # bound that decides P's symmetry without its own pass over P when it is far inside;
        # a P whose first row is not its first column (gyroscopic) is tested first, as before
        if "P" not in memo and not np.array_equal(P[0], P[:, 0]):
            sym("P", P)
        ab = rayleigh_fit(M, P, Q, rayleigh_tol, residual=True) if memo.get("P", True) else None
        if ab is not None and "P" not in memo and "M" in asym and "Q" in asym:
            bound = 2 * ab[2] + abs(ab[0]) * asym["M"] + abs(ab[1]) * asym["Q"]
            nP = norms["P"] if "P" in norms else fro(P)
            if 2 * bound <= sym_tol * nP:
                memo["P"] = True
        if ab is not None and sym("P", P):
            return ("proportional", f"P = {ab[0]:.6g} M + {ab[1]:.6g} Q (Rayleigh damping)",
                    {"alpha": ab[0], "beta": ab[1], "fit_residual": ab[2]})
    what = "complex M, P, Q: " if complex_problem else ""
    if pd and cond <= companion_cond:
        return "companion", f"{what}M symmetric positive definite: mass-normalized companion", {}
    if pd:
        return "qz", (f"{what}M positive definite but cond(M) ≈ {cond:.2g} > {companion_cond:.0g}: "
                      f"scaled QZ on the companion pencil (no division by the mass)"), {}
    return "qz", f"{what}M not symmetric positive definite: scaled QZ on the companion pencil", {}


def problem_scaling(norms, lo=1e-100, hi=1e100, gamma_range=1e50):
    """(log γ, log δ) scaling M, P, Q to γ²δM, γδP, δQ and s to μ = s/γ (after Fan, Lin & Van
    Dooren 2004) when the problem's magnitudes are extreme (a nonzero norm outside [lo, hi], or
    γ outside 10^±50); (0, 0) otherwise, so that ordinary problems are solved as given.

    In logarithms throughout (γ, δ themselves may be out of range, the scaled norms are not):
    γ ≈ √(‖Q‖/‖M‖) (‖P‖/‖M‖ without Q, ‖Q‖/‖P‖ without M), δ ≈ 1/max(γ²‖M‖, γ‖P‖, ‖Q‖), both
    rounded to powers of two so that scaling M, P, Q and mapping s = γμ back add no rounding
    error (an exp(log γ) would carry |log γ|·ε of it: 8e-14 at γ = 1e150); every scaled norm is
    then below 2.
    """
    logs = [np.log(x) if x > 0 else None for x in norms]
    lM, lP, lQ = logs
    if lM is not None and lQ is not None:
        lg = 0.5 * (lQ - lM)
    elif lM is not None and lP is not None:
        lg = lP - lM
    elif lP is not None and lQ is not None:
        lg = lQ - lP
    else:
        lg = 0.0
    present = [x for x in logs if x is not None]
    if not present or (max(present) <= np.log(hi) and min(present) >= np.log(lo)
                        and abs(lg) <= np.log(gamma_range)):
        return 0.0, 0.0
    ln2 = np.log(2.0)  # powers of two: the scaling and s = γμ are then exact in floating point
    lg = round(lg / ln2) * ln2
    scaled = [x + k * lg for x, k in ((lM, 2), (lP, 1), (lQ, 0)) if x is not None]
    return float(lg), float(round(-max(scaled) / ln2) * ln2)


def _scaled(A, log_factor):
    """A · e^log_factor for a log_factor that is a multiple of log 2: exact (ldexp), whatever the
    size of the factor itself."""
    if not log_factor:
        return A
    with np.errstate(under="ignore"):  # an entry below the normal range of the scaled problem
        return pow2_scale(A, int(round(log_factor / np.log(2.0))))  # is negligible against 1


def solve_qep(M, P, Q, *, solver: str = "auto", sym_tol: float = 1e-13,
              rayleigh_tol: float = 1e-12, scale: bool = True, left="auto",
              companion_cond: float = COMPANION_COND, verify_tol: float = 1e-8) -> QEPSolution:
    """Solve (M s² + P s + Q) x = 0 by the dense path ``solver`` (``auto`` picks by structure).

    M, P, Q may be complex (e.g. hysteretic damping (1 + iμ)K); a complex matrix whose imaginary
    part is exactly zero is taken as real.

    Parameters
    ----------
    M, P, Q : array_like
        Mass, damping (with gyroscopic terms) and stiffness, square and of one size.
    solver : str
        A dense path of :data:`mbseig.eigen.SOLVERS` ("eigh", "proportional", "companion",
        "qz"), or "auto".
    sym_tol : float
        Relative tolerance for treating M, Q (and P) as symmetric.
    rayleigh_tol : float
        Relative residual under which P counts as αM + βQ.
    scale : bool
        Fan–Lin–Van Dooren scaling on the QZ path (False only to measure its value).
    left : bool or "auto"
        Left eigenvectors for the condition numbers on the companion and QZ paths.  "auto"
        computes them only when M, P or Q is not symmetric: for symmetric matrices the left
        vector is the conjugate of the right one, exactly, and LAPACK's left vectors cost about
        10–15 % more time (measured by ``mbseig bench``).  False always takes y = x̄, which is
        only an estimate of κ for non-symmetric problems (recorded in ``details``).
    companion_cond : float
        Largest cond(M) for which "auto" mass-normalizes (companion path).
    verify_tol : float
        A pair whose normwise and componentwise backward errors both exceed it is no eigenpair
        of the problem: the solve is refused (SolverError), never listed.

    Returns
    -------
    QEPSolution
        Every finite eigenvalue with its unit right vector (and left vector where formed), the
        backward error η and condition number κ of each pair, the path that ran and why.

    Examples
    --------
    >>> import numpy as np
    >>> sol = solve_qep(np.eye(2), np.zeros((2, 2)), np.diag([1.0, 4.0]))
    >>> sol.solver, sorted(round(float(abs(s)), 12) for s in sol.eigenvalues)
    ('eigh', [1.0, 1.0, 2.0, 2.0])
    """
    M, P, Q = _dense(M, "M"), _dense(P, "P"), _dense(Q, "Q")
    n = M.shape[0]
    if not (M.ndim == P.ndim == Q.ndim == 2 and M.shape == P.shape == Q.shape == (n, n)):
        raise SolverError(f"M, P, Q must be square and of one size, got {M.shape}, {P.shape}, "
                          f"{Q.shape}")
    if not all(np.all(np.isfinite(A)) for A in (M, P, Q)):
        raise SolverError("M, P and Q must be finite")
    complex_problem = any(np.iscomplexobj(A) for A in (M, P, Q))
    norms0 = (fro(M), fro(P), fro(Q))
    lg, ld = problem_scaling(norms0)
    scaled = (lg, ld) != (0.0, 0.0)
    with np.errstate(over="ignore", under="ignore"):
        g0 = float(np.ldexp(1.0, int(round(lg / np.log(2.0)))))
    if not np.isfinite(g0) or g0 == 0.0:
        raise SolverError(f"the frequency scale of M, P, Q (‖M‖, ‖P‖, ‖Q‖ = {norms0[0]:.3g}, "
                          f"{norms0[1]:.3g}, {norms0[2]:.3g}) is beyond double precision: its "
                          f"eigenvalues would overflow or vanish; rescale the units")
    if scaled:  # factors in logarithms: γ²δ, γδ, δ may each be out of range, the products not
        M, P, Q = _scaled(M, 2 * lg + ld), _scaled(P, lg + ld), _scaled(Q, ld)
    norms = (fro(M), fro(P), fro(Q)) if scaled else norms0
    memo = {"fro": dict(zip("MPQ", norms, strict=True))}
    name, reason, extras = choose_solver(M, P, Q, sym_tol=sym_tol, rayleigh_tol=rayleigh_tol,
                                         memo=memo, companion_cond=companion_cond)
    if scaled and SOLVERS[name].divides_by_mass:  # no mass normalization of a problem scaled
        name, reason = GENERAL, reason.replace("mass-normalized companion", "scaled QZ (magnitudes "
                                               "out of range: no division by the mass)")
    structure = Structure(name, reason, extras, complex_problem=complex_problem)
    name, reason, extras = select_path(solver, structure, "dense")
    path = SOLVERS[name]
    if path.needs_definite_mass and not mass_condition(M, memo)[0]:
        raise SolverError(f"solver {name!r} needs {path.needs}")
    if path.real_only and complex_problem:
        raise SolverError(f"solver {name!r} needs real M, P, Q")
    if left == "auto":
        left = not all(memo[k] if k in memo else is_symmetric(A, sym_tol, norm=memo["fro"][k])
                       for k, A in (("M", M), ("Q", Q), ("P", P)))
    opts = {**extras, "scale": scale, "left": bool(left), "L": memo.get("L")}
    if "diagonal" in memo:
        opts["diagonal"] = memo["diagonal"]
    if scaled:
        reason += (f"; scaled s = γμ (γ = 1e{lg / np.log(10):.1f}, δ = 1e{ld / np.log(10):.1f}): "
                   f"magnitudes out of range")
    if n == 0:
        e = np.zeros(0)
        return QEPSolution(e.astype(complex), np.zeros((0, 0), complex), e, e, name, reason, 0,
                           norms0, n_dof=0, complex_problem=complex_problem)
    # small problems on one BLAS thread: a second one only adds synchronization there (and on a
    # loaded machine milliseconds per call, more than the whole solve of a few coordinates)
    with small_blas(n):
        if path.checks_regularity:
            check_regular(M, P, Q, norms)
        sol = path.kernel(M, P, Q, opts, name, reason, norms)
    bad = ~np.isfinite(sol.eigenvalues)
    if np.any(bad):
        raise SolverError(f"{name}: {int(bad.sum())} of {sol.eigenvalues.size} eigenvalues are not "
                          f"finite (NaN or overflow): no listing can be made")
    details = {**sol.details, "cond_M": memo.get("cond_M", np.inf), "scaled": scaled,
               "problem_log10_gamma": lg / np.log(10), "problem_log10_delta": ld / np.log(10),
               "verify_tol": verify_tol}
    _verify(sol, M, P, Q, verify_tol, norms0)
    if not scaled:
        return replace(sol, details=details, n_dof=n, complex_problem=complex_problem,
                        problem=(M, P, Q, 1.0))
    with np.errstate(over="ignore", invalid="ignore"):  # judged just below
        s = sol.eigenvalues * g0
        real_error = None if sol.real_error is None else sol.real_error * g0
        condition = sol.condition * g0  # a bound beyond the double range is ∞: bounds nothing
    keep = np.isfinite(s)  # |s| beyond the double range: an infinite eigenvalue to precision
    if not np.all(keep):
        details["beyond_range"] = int(np.sum(~keep))
        def pick(a):
            return a[..., keep] if a is not None else None

        sol = replace(sol, vectors=sol.vectors[:, keep], backward_error=sol.backward_error[keep],
                      left_vectors=pick(sol.left_vectors),
                      n_infinite=sol.n_infinite + int(np.sum(~keep)))
        s, condition, real_error = s[keep], condition[keep], pick(real_error)
    return replace(sol, eigenvalues=s, condition=condition,
                   real_error=real_error, norms=norms0, details=details, n_dof=n,
                   complex_problem=complex_problem, problem=(M, P, Q, g0))


def _verify(sol, M, P, Q, verify_tol, norms0):
    """Refuse pairs that are no eigenpairs (η and η_c above ``verify_tol``, or η not a number)."""
    eta = np.where(np.isnan(sol.backward_error), np.inf, sol.backward_error)
    bad = np.flatnonzero(eta > verify_tol)
    if not bad.size:
        return
    Yc = None if sol.left_vectors is None else sol.left_vectors[:, bad]
    eta_c, _ = componentwise((M, P, Q), sol.eigenvalues[bad], sol.vectors[:, bad], Yc)
    failed = bad[~(eta_c <= verify_tol)]
    if failed.size:
        raise SolverError(
            f"{sol.solver}: {failed.size} of {sol.eigenvalues.size} eigenpairs fail the "
            f"backward-error check (η up to {float(np.max(eta[failed])):.1e} > {verify_tol:g}): "
            f"the model's magnitudes (‖M‖, ‖P‖, ‖Q‖ = {norms0[0]:.3g}, {norms0[1]:.3g}, "
            f"{norms0[2]:.3g}) span more than double precision resolves in one solve; rescale "
            f"the units or the offending entries")


def dense_driver(problem, request) -> QEPSolution:
    """The ``dense`` family of :func:`mbseig.eigen.solve`: every finite eigenvalue."""
    P = problem.P if problem.P is not None else np.zeros(np.shape(problem.M))
    return solve_qep(problem.M, P, problem.Q, solver=request.solver, **request.options)


register_family("dense", dense_driver)
register("eigh", family="dense", needs="P = 0, M and Q symmetric, M positive definite",
         kernel=solve_eigh, applies=structured_applies("eigh"), needs_definite_mass=True,
         real_only=True)
register("proportional", family="dense",
         needs="P = αM + βQ with M and Q symmetric, M positive definite",
         kernel=solve_proportional, applies=structured_applies("proportional"),
         needs_definite_mass=True, real_only=True)
register("companion", family="dense", needs="M symmetric positive definite",
         kernel=solve_companion, needs_definite_mass=True, divides_by_mass=True)
register(GENERAL, family="dense", needs="nothing (any M, P, Q)", kernel=solve_qz,
         checks_regularity=True)
