"""Branch points, folds and correctors of a continuation (:mod:`~mbseig.statics.continuation`):
the tangent of the branch, the fixed-parameter and pseudo-arclength correctors, the sign of the
bordered determinant and the parity of its pivots, and the location of folds (dp/ds = 0, Brent)
and branch points (a sign change of the determinant, bisection)."""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np
import scipy.linalg as sla
import scipy.sparse as sp

from ..errors import EquilibriumError, MbseigError
from ..numerics import LazyModule, dense
from .cache import Memo
from .family import CORRECTOR_ITER, CTOL
from .linalg import (
    DENSE_LIMIT,
    SMALL,
    NewtonMatrix,
    solve_bordered,
)
from .newton import Stall, newton, settings_for

spla = LazyModule("scipy.sparse.linalg")  # sparse solvers: imported at first use

CHORD = 1e-5  # a corrector reuses its Newton matrix after a correction below this (model
# scales): the next step is then a chord step, contracting by ≈ CHORD, ample below CTOL



@dataclass
class BranchPoint:
    """An equilibrium on a branch: parameter p, y = (q, λ_S), the tangent's ṗ and the signs of
    det J and det B there, and what it is (``kind``: start, step, grid, fold, branch point,
    jump, switch)."""

    p: float
    y: np.ndarray
    kind: str = "step"
    segment: int = 0
    tangent: np.ndarray = None
    det_J: int = 0
    det_B: int = 0
    iterations: int = 0
    grid_index: int = -1

    @property
    def pdot(self):
        return float(self.tangent[-1]) if self.tangent is not None else math.nan


@dataclass
class Branch:
    """The followed branch(es) of one sweep line: every point in order, the grid points, and
    the events (folds, branch points, switches, jumps)."""

    points: list = field(default_factory=list)
    grid: list = field(default_factory=list)
    events: list = field(default_factory=list)
    record: dict = field(default_factory=dict)


# ---------------------------------------------------------------------------------------------
SINGULAR_PIVOT = 100  # a pivot below SINGULAR_PIVOT·n·ε·max|pivot|: det A is numerically 0


def _det_sign(A) -> int:
    """Sign of det A (dense LU up to DENSE_LIMIT, sparse LU above); 0 when A is singular or
    numerically singular: a pivot below ``SINGULAR_PIVOT``·n·ε of the largest.  A zero-stiffness
    direction that persists along a branch (the free spin of a link between two ball joints)
    leaves a pivot of rounding size whose sign is noise; counting its flips as branch points
    reported bifurcations where there are none.  Such points carry no sign, and the follower
    records how many there were (``record["det_undecided"]``): a branch point crossed where the
    sign is undecided is not detected."""
    import warnings

    with np.errstate(all="ignore"), warnings.catch_warnings():
        warnings.simplefilter("ignore", sla.LinAlgWarning)
        if A.shape[0] <= DENSE_LIMIT:
            try:
                lu, piv = sla.lu_factor(dense(A), check_finite=False)
            except (ValueError, sla.LinAlgError):
                return 0
            d = np.diag(lu)
            if _numerically_singular(d):
                return 0
            swaps = int(np.sum(piv != np.arange(piv.size)))
            sign = (-1) ** swaps * int(np.prod(np.sign(d)))
            return int(sign)
        try:
            lu = spla.splu(sp.csc_matrix(A))
        except RuntimeError:
            return 0
        d = lu.U.diagonal()
        if _numerically_singular(d):
            return 0
        return int(np.prod(np.sign(d))) * _parity(lu.perm_r) * _parity(lu.perm_c)


def _numerically_singular(pivots) -> bool:
    a = np.abs(pivots)
    top = float(np.max(a)) if a.size else 0.0
    return not (top > 0 and np.isfinite(top)) or \
        float(np.min(a)) <= SINGULAR_PIVOT * a.size * np.finfo(float).eps * top


def _parity(perm) -> int:
    perm = np.asarray(perm)
    seen = np.zeros(perm.size, bool)
    sign = 1
    for i in range(perm.size):
        if seen[i]:
            continue
        j, length = i, 0
        while not seen[j]:
            seen[j] = True
            j = perm[j]
            length += 1
        if length % 2 == 0:
            sign = -sign
    return sign


def _bordered(fam, y, p, t, w):
    A = fam.J(y, p)
    rp = fam.Rp(y, p)
    c = w * t
    if not sp.issparse(A):  # a small model's dense J
        return A, rp, np.block([[A, -rp[:, None]], [c[None, :-1], np.array([[c[-1]]])]])
    B = sp.bmat([[A, sp.csr_matrix(-rp[:, None])],
                 [sp.csr_matrix(c[None, :-1]), sp.csr_matrix([[c[-1]]])]], format="csr")
    return A, rp, B


def tangent(fam, y, p, *, prev=None, direction=1.0, rp=None):
    """The unit tangent (ẏ, ṗ) at (y, p) (module docstring); None when it cannot be formed.
    rp: ∂R/∂p when known (:meth:`Family.Rp_back`), else the forward difference."""
    w = fam.weights()
    A = fam.J(y, p)
    rp = fam.Rp(y, p) if rp is None else rp
    try:
        NM = NewtonMatrix(A, weights=w[:-1])
        a, e = NM.solve(rp)
    except (EquilibriumError, ArithmeticError, ValueError):
        return None
    big = float(np.linalg.norm(e)) > 1e-8 * max(float(np.linalg.norm(rp)), 1e-300)
    if big or not np.all(np.isfinite(a)):  # J singular at a fold: the tangent is its null vector
        Z = getattr(NM, "null", np.zeros((A.shape[0], 0)))
        if not Z.shape[1]:
            return None
        t = np.concatenate([Z[:, 0], [0.0]])
    else:
        t = np.concatenate([a, [1.0]])
    norm = math.sqrt(float(np.sum(w * t * t)))
    if not norm or not np.isfinite(norm):
        return None
    t = t / norm
    if prev is not None:
        if float(np.sum(w * t * prev)) < 0:
            t = -t
    elif t[-1] * direction < 0:
        t = -t
    return t


def correct_fixed(fam, y, p, reach):
    """The equilibrium at fixed p from the predictor y to ``CTOL``: plain Newton on R(y, p) = 0
    while its corrections shrink (at most ``CORRECTOR_ITER``), then, from its last iterate, the
    statics' own Newton (:func:`mbseig.statics.newton.newton`: position solve, trust region,
    homotopy steps for stiff members); (y, iterations), or None when neither converges or the
    result is farther than ``reach`` (model scales) from the predictor (it would have left the
    branch)."""
    n = fam.n
    w = fam.weights()[:-1]
    y0, yk, last, its = y, y, np.inf, 0
    NM = None
    for it in range(1, CORRECTOR_ITER + 1):
        try:
            if NM is None or last > CHORD:  # the chord (last matrix) once corrections are small
                NM = NewtonMatrix(fam.J(yk, p), weights=w)
            dy = NM.solve(fam.R(yk, p))[0]
        except (EquilibriumError, ArithmeticError, ValueError):
            break
        size = fam.scales.size(dy[:n])
        if not np.isfinite(size) or size > reach or size >= last:
            break
        yk, last, its = yk + dy, size, it
        if size <= CTOL:
            return (yk, it) if fam.scales.size(yk[:n] - y0[:n]) <= reach else None
    model = Memo(fam.model(p))
    try:
        s = settings_for(model, yk[:n], tol=1e-12, xtol=CTOL, floor_tol=1e-8,
                         max_iter=2 * CORRECTOR_ITER, rank_tol=1e-10)
        sol = newton(model, yk[:n], s, prove=False)
    except (Stall, MbseigError, ArithmeticError, ValueError):
        return None
    if fam.scales.size(sol.q - y0[:n]) > reach:
        return None
    return fam.start(sol.q, p), its + sol.iterations + sol.position_iterations


def correct_arclength(fam, z0, t, ds, tol=CTOL):
    """Newton on [R = 0; (Wt)ᵀ(z − z0 − ds t) = 0] from the predictor to ``tol``; (z,
    iterations) or None."""
    n = fam.n
    w = fam.weights()
    zp = z0 + ds * t
    z = zp.copy()
    c = w * t
    for it in range(1, CORRECTOR_ITER + 1):
        y, p = z[:-1], z[-1]
        try:
            with np.errstate(all="ignore"):
                dy, dp = solve_bordered(fam.J(y, p), -fam.Rp(y, p), c[:-1], c[-1], fam.R(y, p),
                                        -float(np.sum(c * (z - zp))), weights=w)
            dz = np.concatenate([dy, [dp]])
        except (EquilibriumError, ArithmeticError, ValueError, MbseigError):
            return None
        if not np.all(np.isfinite(dz)):
            return None
        z = z + dz
        size = max(fam.scales.size(dz[:n]), abs(dz[-1]) / fam.p_scale)
        if size > max(0.5, 2 * abs(ds)):
            return None
        if size <= tol:
            return z, it
    return None


def _det_B(fam, y, p, t):
    """sign det B, B = [[J, −R_p], [(Wt)ᵀ]]: above SMALL unknowns as sign det J times the sign
    of the Schur complement (the dense border would fill a factorization of B)."""
    w = fam.weights()
    if fam.N > SMALL:
        J, rp = fam.J(y, p), fam.Rp(y, p)
        sj = _det_sign(J)
        if sj:
            try:
                b = NewtonMatrix(J).solve(-rp)[0]
            except EquilibriumError:
                b = None
            if b is not None and np.all(np.isfinite(b)):
                c = w * t
                schur = c[-1] - float(c[:-1] @ b)
                return int(sj * np.sign(schur))
    return _det_sign(_bordered(fam, y, p, t, w)[2])


def branch_point_at(fam, z, t, kind, segment, iterations=0):
    """A branch point with the signs of det J and det B.  Where ṗ ≠ 0, sign det B =
    sign det J · sign ṗ (block elimination: the Schur complement of J in B is
    (w_p + ẏᵀW ẏ/ṗ²)·ṗ/|t|² up to a positive factor), so one factorization gives both."""
    y, p = z[:-1], z[-1]
    dj = _det_sign(fam.J(y, p))
    db = dj * int(np.sign(t[-1])) if dj and abs(t[-1]) > 1e-12 else _det_B(fam, y, p, t)
    return BranchPoint(p=float(p), y=y, kind=kind, segment=segment, tangent=t, det_J=dj,
                       det_B=db, iterations=iterations)


def _on_hyperplane(fam, z0, t0, s):
    """The branch point at arclength s along t0 from z0 and its tangent oriented along t0."""
    res = correct_arclength(fam, z0, t0, s)
    if res is None:
        return None, None
    z = res[0]
    t = tangent(fam, z[:-1], z[-1], prev=t0)
    return z, t


def locate_fold(fam, z0, t0, ds, xtol):
    """(z, t) at the fold between z0 (arclength 0) and ds: Brent on ṗ(s)."""
    from scipy.optimize import brentq

    cache = {}

    def pdot(s):
        z, t = _on_hyperplane(fam, z0, t0, s)
        if z is None or t is None:
            raise EquilibriumError("the fold could not be located", element="continuation")
        cache[s] = (z, t)
        return float(t[-1])

    a, b = 0.0, ds
    fa, fb = float(t0[-1]), pdot(b)
    if fa * fb > 0:
        raise EquilibriumError("no sign change of the tangent's dp", element="continuation")
    s = brentq(pdot, a, b, xtol=xtol * abs(ds), rtol=4 * np.finfo(float).eps)
    z, t = cache.get(s) or _on_hyperplane(fam, z0, t0, s)
    return z, t


def locate_branch_point(fam, z0, t0, ds, sign0, iterations=48):
    """(z, t) at the sign change of det B between z0 (sign sign0) and arclength ds: bisection."""
    lo, hi = 0.0, ds
    best = None
    for _ in range(iterations):
        mid = 0.5 * (lo + hi)
        z, t = _on_hyperplane(fam, z0, t0, mid)
        if z is None or t is None:
            break
        best = (z, t)
        if _det_B(fam, z[:-1], z[-1], t) == sign0:
            lo = mid
        else:
            hi = mid
        if hi - lo <= 1e-13 * abs(ds):
            break
    return best


def second_direction(fam, z, t):
    """The direction of the other branch at a branch point: the null vector of [J, −R_p]
    W-orthogonal to the tangent t (dense SVD), or None."""
    y, p = z[:-1], z[-1]
    if fam.N + 1 > DENSE_LIMIT:
        return None
    w = fam.weights()
    M = sp.hstack([fam.J(y, p), sp.csr_matrix(-fam.Rp(y, p)[:, None])]).toarray()
    _, sv, vt = np.linalg.svd(M)
    cand = vt[-2:] if vt.shape[0] >= 2 else vt
    # remove the component along t (W inner product) from both null candidates, keep the larger
    best = None
    for v in cand:
        v = v - float(np.sum(w * v * t)) * t
        nrm = math.sqrt(float(np.sum(w * v * v)))
        if nrm > 1e-8 and (best is None or nrm > best[1]):
            best = (v / nrm, nrm)
    if best is None:
        return None
    v = best[0]
    k = int(np.argmax(np.abs(v[:fam.n]) / fam.scales.ell))
    return v if v[k] >= 0 else -v
