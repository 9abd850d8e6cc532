"""The fused small-dense implementation of the dense paths ``eigh`` and ``companion``.

For a real dense problem of order n ≤ :data:`SMALL_MAX` the general driver
(:func:`mbseig.eigen.dense.solve_qep`) spends most of its time in the generality around a
LAPACK call of a few microseconds: dispatch, row-blocked measures, repeated structure tests,
validated scipy wrappers.  :func:`solve_small` runs the same mathematical path with the same
LAPACK routines on the same matrices and the same formulas for η and κ, each shared quantity
formed once (the reversal t = 1/s, the weights w(s), the products M X and P X), and returns the
same :class:`~mbseig.eigen.base.QEPSolution` (the solver name is the path's: ``eigh`` or
``companion``; ``details["implementation"]`` says that the fused implementation ran).

It returns None, and the caller takes the general driver, wherever that driver would do more
than this implementation knows: a problem scaled for range, complex or non-finite matrices, the
``proportional`` and ``qz`` paths, refinement of a companion vector (η above
:data:`~mbseig.eigen.dense_paths.REFINE_ETA`), a pair that fails verification, or LAPACK's
undocumented layout of conjugate pairs.  tests/test_small_modes.py checks both give the same
numbers.
"""

from __future__ import annotations

import math

import numpy as np
import scipy.linalg as sla
from scipy.linalg.blas import daxpy as _daxpy

from .base import QEPSolution
from .dense import COMPANION_COND, STRUCTURED_COND, problem_scaling, small_blas
from .dense_paths import REFINE_ETA, diagonal_mass_eigh, diagonal_positive
from .measures import EPS_LD, LD
from .small_measures import better_half, cn, coefficients, conditions, unit
from .structure import SUMSQ_HI, SUMSQ_LO
from .undamped import undamped_roots

__all__ = ["SMALL_MAX", "solve_small", "small_problem"]

#: largest order n solved by the fused implementation.  Measured (modes() of random damped and
#: undamped problems, one BLAS thread, medians of 7 interleaved runs, a loaded 2-core machine):
#: the fused path is 2.0–2.3x faster at n = 4–8, 1.4–2.1x at 16–32, 1.1–1.5x at 64 (LAPACK then
#: dominates; 1.1x at 96); the same numbers bitwise on 460 random problems up to n = 64.  Kept
#: below the general driver's thresholds of a different evaluation (SMALL_BLAS = 100, the
#: sparse products of ``_fast_operand`` above 10⁴ entries).
SMALL_MAX = 64
IMPLEMENTATION = "fused small-dense"
_LAPACK = {}  # name -> routine (float64 / complex128)
_LWORK = {}  # (n2, left) -> geev's optimal workspace (its own query, once per size)


def _lapack(name):
    f = _LAPACK.get(name)
    if f is None:
        f = _LAPACK[name] = sla.get_lapack_funcs(name[1:], dtype=np.dtype(
            {"d": np.float64, "z": np.complex128}[name[0]]))
    return f


def small_problem(M, P, Q):
    """Whether (M, P, Q) may take the fused implementation: real float arrays, square, one
    order n ≤ :data:`SMALL_MAX` (P may be None)."""
    for A in (M, Q) if P is None else (M, P, Q):
        if type(A) is not np.ndarray or A.dtype != np.float64 or A.ndim != 2:
            return False
    n = M.shape[0]
    return (0 < n <= SMALL_MAX and M.shape == (n, n) == Q.shape
            and (P is None or P.shape == (n, n)))


class _General(Exception):
    """The general driver must run (a case this implementation does not cover)."""


def _fro(A, sums):
    """‖A‖_F as :func:`mbseig.eigen.structure.fro` computes it where one dot is exact (Σ a²
    appended to ``sums``), 0.0 for a zero A; :class:`_General` otherwise (non-finite, extreme
    magnitudes)."""
    flat = A.reshape(-1)
    ss = float(np.dot(flat, flat))
    sums.append(ss)
    if SUMSQ_LO <= ss <= SUMSQ_HI:
        return math.sqrt(ss)
    if ss == 0.0 and not flat.any():
        return 0.0
    raise _General


def _proportional(M, P, Q, sums, tol):
    """Whether structure.rayleigh_fit(M, P, Q, tol, residual=True) finds P = αM + βQ (its dense
    fit, from the sums of squares of M, P, Q already formed); :class:`_General` where it would
    take its least-squares fit."""
    a, b, q = (X.reshape(-1) for X in (M, P, Q))
    aa, bb, qq = sums
    if aa == 0.0 or not all(x == 0.0 or SUMSQ_LO <= x <= SUMSQ_HI for x in (aa, qq, bb)):
        raise _General
    na = np.sqrt(aa)
    r12 = float(np.dot(a, q)) / na
    t1 = float(np.dot(a, b)) / na
    w2 = qq - r12 * r12
    if qq == 0.0:
        alpha, beta = t1 / na, 0.0
    elif w2 <= 1e-6 * qq:
        raise _General
    else:
        r22 = np.sqrt(w2)
        beta = ((float(np.dot(q, b)) - r12 * t1) / r22) / r22
        alpha = (t1 - r12 * beta) / na
    if not (np.isfinite(alpha) and np.isfinite(beta)):
        return False
    with np.errstate(all="ignore"):
        r = _daxpy(a, b.copy(), a=-alpha)
        if beta != 0.0:
            r = _daxpy(q, r, a=-beta)
        rn2 = float(np.dot(r, r))
    return bool(np.isfinite(rn2)) and float(np.sqrt(rn2)) <= tol * np.sqrt(bb)


def _sym(A, nA, tol):
    """is_symmetric(A, tol, norm=nA) on its fast path (one block of the antisymmetric sum)."""
    if nA == 0:
        return True
    if (tol * nA) ** 2 < 1e-190:
        raise _General
    flat = (A - A.T).ravel()
    ss = float(np.dot(flat, flat))
    if not ss <= SUMSQ_HI:
        raise _General
    return math.sqrt(ss) <= tol * nA


def _structure(M, P, Q, norms, sums, sym_tol, rayleigh_tol, companion_cond, memo):
    """(name, reason) of :func:`mbseig.eigen.dense.choose_solver` for a small real problem, its
    memo filled alike ("diagonal", "L", "cond_M", and "M", "Q", "P" where it tested them);
    :class:`_General` where the general driver decides otherwise (proportional, qz)."""

    def sym(key, A, nA):
        if key not in memo:
            memo[key] = _sym(A, nA, sym_tol)
        return memo[key]

    nM, nP, nQ = norms
    diag = memo["diagonal"] = diagonal_positive(M)
    pd, cond = False, np.inf
    if diag is not None:
        memo["M"] = True
        if diag:
            d = np.diagonal(M)
            pd, cond = True, float(d.max() / d.min())
    elif sym("M", M, nM):
        L, info = _lapack("dpotrf")(0.5 * (M + M.T), lower=1, clean=1)
        if info < 0:
            raise _General
        if info == 0:
            memo["L"] = L
            anorm = float(np.abs(M).sum(axis=0).max())
            rcond, info = _lapack("dpocon")(L, anorm, uplo="L")
            pd, cond = True, (np.inf if info != 0 or rcond <= 0 else float(1.0 / rcond))
    memo["mass_condition"] = (pd, cond)
    memo["cond_M"] = cond
    if pd and sym("Q", Q, nQ) and cond <= STRUCTURED_COND:
        if not P.any():
            return "eigh", "P = 0, M and Q symmetric, M positive definite"
        if not np.array_equal(P[0], P[:, 0]):
            sym("P", P, nP)
        if memo.get("P", True) and _proportional(M, P, Q, sums, rayleigh_tol):
            raise _General  # Rayleigh damping: the proportional path
    if pd and cond <= companion_cond:
        return "companion", "M symmetric positive definite: mass-normalized companion"
    raise _General  # qz


def solve_small(M, P, Q, *, sym_tol=1e-13, rayleigh_tol=1e-12, left="auto",
                companion_cond=COMPANION_COND, verify_tol=1e-8, scale=True):
    """The dense driver's result for a small real problem (module docstring), or None."""
    try:
        with np.errstate(over="raise", invalid="raise", divide="raise", under="ignore"):
            return _solve(M, P, Q, sym_tol, rayleigh_tol, left, companion_cond, verify_tol)
    except (_General, FloatingPointError):
        return None


def _solve(M, P, Q, sym_tol, rayleigh_tol, left, companion_cond, verify_tol):
    if P is None:
        P = np.zeros(M.shape)
    sums = []  # Σ m², Σ p², Σ q²
    norms = (_fro(M, sums), _fro(P, sums), _fro(Q, sums))
    if problem_scaling(norms) != (0.0, 0.0):
        return None
    n = M.shape[0]
    memo = {}
    name, reason = _structure(M, P, Q, norms, sums, sym_tol, rayleigh_tol, companion_cond, memo)
    if left == "auto":
        left = not all(memo[k] if k in memo else _sym(A, nA, sym_tol)
                       for k, A, nA in (("M", M, norms[0]), ("Q", Q, norms[2]),
                                        ("P", P, norms[1])))
    with small_blas(n):
        if name == "eigh":
            out = _eigh(M, P, Q, memo, norms)
        else:
            out = _companion(M, P, Q, memo, norms, bool(left))
    if out is None:
        return None
    s, X, eta, kappa, Yc, details = out
    if not np.isfinite(s).all() or (eta > verify_tol).any() or np.isnan(eta).any():
        return None  # the general driver refuses or verifies componentwise
    details.update({"cond_M": memo["cond_M"], "scaled": False,
                    "problem_log10_gamma": 0.0 / np.log(10), "problem_log10_delta":
                    0.0 / np.log(10), "verify_tol": verify_tol, "implementation": IMPLEMENTATION})
    return QEPSolution(s, X, eta, kappa, name, reason, 0, norms, details, None, left_vectors=Yc,
                       n_dof=n, complex_problem=False, problem=(M, P, Q, 1.0))


# ---------------------------------------------------------------------------------------------
# eigh: P = 0, the undamped modes of eigh(Q, M) (dense_paths._structured with α = β = 0)
# ---------------------------------------------------------------------------------------------
def _eigh(M, P, Q, memo, norms):
    fit = norms[1]  # ‖P‖_F (P = 0 here: 0.0)
    diag = memo["diagonal"] if "diagonal" in memo else diagonal_positive(M)
    Qs = np.add(Q, Q.T)
    Qs *= 0.5
    if diag:
        m = np.diagonal(M).copy()
        w, V = diagonal_mass_eigh(Qs, m)
    else:
        m = None
        Ms = np.add(M, M.T)
        Ms *= 0.5
        w, U, info = _lapack("dsygvd")(Qs, Ms, itype=1, jobz="V", uplo="L", overwrite_a=1,
                                      overwrite_b=1)
        if info != 0:
            return None  # the general driver reports LAPACK's failure
        V = np.ascontiguousarray(U)
    V /= cn(V)
    MV = V * m[:, None] if m is not None else M @ V
    R = Q @ V
    R -= MV * w
    a = np.einsum("ij,ij->j", V, MV)  # vᵀMv (vᵀr enters undamped_pairs times β = 0 only)
    s, eta, kappa = _undamped_pairs(w, cn(MV), cn(R), a, norms)
    X = np.concatenate([V, V], axis=1)
    details = {"second_half_vectors": 0, "left_vectors": False, "alpha": 0.0, "beta": 0.0,
               "fit_residual": fit}
    return s, X, eta, kappa, X, details


def _undamped_pairs(w, mv_norm, r_norm, a, norms):
    """undamped.undamped_pairs(w, mv_norm, r_norm, a, vr, 0, 0, 0, norms) (P = 0): the same
    numbers, its terms in α, β and the fit residual dropped where they are exact zeros (c = 0,
    |1 + βs| = 1, a zero added to a non-negative sum; a zero's sign never reaches an absolute
    value)."""
    s = undamped_roots(w, 0.0, 0.0)
    def two(x):
        return np.concatenate([x, x]).astype(LD)

    with np.errstate(over="ignore", invalid="ignore", divide="ignore", under="ignore"):
        S = s.astype(np.clongdouble)
        W = two(w)
        A = np.abs(S)
        AA = A * A
        num = (np.abs(S * S + W) + 8 * EPS_LD * (AA + np.abs(W))) * two(mv_norm) + two(r_norm)
        weight = AA * LD(norms[0]) + LD(norms[2])
        pos = weight > 0
        eta = np.where(pos, num / np.where(pos, weight, 1), np.where(num == 0, 0, np.inf))
        den = np.abs((2 * S) * two(a))
        kappa = np.where(den > 0, weight / np.where(den > 0, den, 1), np.inf)
        kappa = np.where(weight == 0, 0, kappa)
        return s, eta.astype(float), kappa.astype(float)


# ---------------------------------------------------------------------------------------------
# companion: geev of the mass-normalized companion matrix (dense_paths.solve_companion)
# ---------------------------------------------------------------------------------------------
def _lower(L, B, trans=0):
    """L⁻¹B (L⁻ᵀB with trans=1) by LAPACK trtrs, as dense_paths' triangular solves call it."""
    if B.dtype == np.float64:
        x, info = _lapack("dtrtrs")(L, B, lower=1, trans=trans)
    else:
        x, info = _lapack("ztrtrs")(L, B, lower=1, trans=trans)
    return x if info == 0 else None


def _companion(M, P, Q, memo, norms, left):
    n = M.shape[0]
    if memo["diagonal"] if "diagonal" in memo else diagonal_positive(M):
        root = np.sqrt(np.diagonal(M).real)
        ll = np.outer(root, root)
        Qt, Pt = Q / ll, P / ll
        def back(Y):
            return Y / root[:, None]
    else:
        L = memo.get("L")
        if L is None or not L.flags.f_contiguous:
            return None
        Qt = _lower(L, _lower(L, Q).T).T
        Pt = _lower(L, _lower(L, P).T).T
        def back(Y):
            return _lower(L, Y, trans=1)

    gamma = np.sqrt(np.linalg.norm(Qt) / np.sqrt(n)) if np.any(Qt) else 1.0
    gamma = gamma if np.isfinite(gamma) and gamma > 0 else 1.0
    A = np.zeros((2 * n, 2 * n), order="F")
    A[:n, n:] = np.eye(n)
    A[n:, :n] = Qt
    A[n:, :n] *= -1.0 / gamma**2
    A[n:, n:] = Pt
    A[n:, n:] *= -1.0 / gamma
    if not np.isfinite(A).all():
        return None
    got = _geev(A, left)
    if got is None:
        return None
    mu, Z, W, pos, partner = got
    mu_m = mu[~partner]
    X1, Z2 = back(Z[:n]), back(Z[n:])
    Y = back(W[n:]) if W is not None else None
    if X1 is None or Z2 is None or (W is not None and Y is None):
        return None
    with np.errstate(over="ignore", invalid="ignore", divide="ignore"):
        X2 = Z2 / np.where(mu_m != 0, mu_m, 1.0)
    if not np.isfinite(X2).all():
        return None  # the general driver's substitution of the first half
    s = gamma * mu_m
    k = s.size
    co = coefficients(np.concatenate([s, s]), norms)  # for both halves side by side
    X, eta, MX, PX, n_second = better_half(M, P, Q, X1, X2, co)
    if (eta > REFINE_ETA).any():
        return None  # the general driver refines these vectors
    Yc = X if Y is None else unit(Y).conj()
    kappa = conditions(s, X, Yc, MX, PX, {key: v[:k] for key, v in co.items()})
    details = {"gamma": gamma, "second_half_vectors": n_second, "left_vectors": left,
               "refined_vectors": 0, "measured_columns": int(s.size)}
    se = s[pos]
    se = np.where(partner, np.conj(se), se)
    Xe = _expand(X, pos, partner)
    Ye = Xe if Yc is X else _expand(Yc, pos, partner)
    return se, Xe, eta[pos], kappa[pos], Ye, details


def _expand(X, pos, partner):
    """measures.expand_pairs: the columns X[:, pos] (C order), conjugated where ``partner``."""
    out = np.ascontiguousarray(X[:, pos])
    flip = np.flatnonzero(partner)
    if flip.size:
        out.imag[:, flip] *= -1.0
    return out


def _geev(A, left):
    """dense_paths' geev call on A (overwritten) with the vectors of one member per conjugate
    pair; None where LAPACK fails or the pairs are not in the documented layout."""
    n2 = A.shape[0]
    key = (n2, left)
    lwork = _LWORK.get(key)
    if lwork is None:
        work, info = _lapack("dgeev_lwork")(n2, compute_vl=int(left), compute_vr=1)
        lwork = _LWORK[key] = max(int(work.real), 1) if info == 0 else max(1, 4 * n2)
    wr, wi, vl, vr, info = _lapack("dgeev")(A, lwork=lwork, compute_vl=int(left), compute_vr=1,
                                            overwrite_a=1)
    if info != 0:
        return None
    partner = wi < 0
    first, j = np.flatnonzero(wi > 0), np.flatnonzero(partner)
    if not (first.size == j.size and np.array_equal(first + 1, j)
            and np.array_equal(wr[first], wr[j]) and np.array_equal(wi[first], -wi[j])):
        return None
    mu = wr + 1j * wi
    pos = np.cumsum(~partner) - 1
    measured = np.flatnonzero(~partner)
    fp = pos[first]

    def vectors(V):
        Z = V[:, measured].astype(complex)
        Z.imag[:, fp] = V[:, j]
        return Z

    return mu, vectors(vr), (vectors(vl) if left else None), pos, partner
