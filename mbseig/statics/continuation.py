"""Equilibrium branches along a parameter: pseudo-arclength continuation with folds and branch
points (docs/design.md, "Equilibrium").

A family p ↦ model(p) (built by the studies from a case, :mod:`mbseig.studies.continuation`)
defines

    R(y, p) = [g(q) − Φ_Sᵀ λ; −Φ_S(q)] = 0,     y = (q, λ),

on an independent subset S of the constraint rows (redundant rows carry no information on the
branch; the multipliers of all rows are recomputed by least squares at each reported point).
J = −∂R/∂y is the Newton matrix of :mod:`~mbseig.statics.newton`, R_p = ∂R/∂p a forward
difference with step ``FD_REL``·p_scale (p_scale: the span of the sweep).

Tangent: J ẏ = R_p ṗ, normalized so that ‖ẏ_q‖²_W + (ṗ/p_scale)² = 1 in the model's scales
(W = diag 1/ℓ², multipliers weightless), oriented along the previous tangent.  At a grid point
reached directly from the previous one, R_p is the difference to the previous point's model
(:meth:`Family.Rp_back`, no model built at p + h: in a sweep whose parameter enters inverse
statics, a build costs a resolve of the commands); it serves the predictor and the sense of p.
When the sense of p or the sign of det J differs from the previous point's (a fold or branch
point between them), or det J has no sign, both tangents are recomputed with the forward
difference and the events are decided on those (``record["tangents_by_difference"]`` counts
the points that kept the difference tangent).

Step: while the branch moves towards the next grid value p_g, the equilibrium at p_g from the
tangent predictor bent through the previous point (second order, :func:`_predict`): plain Newton
while its corrections shrink, then the statics' own Newton (natural-parameter continuation: the
grid point itself), accepted when it converges within ``REACH`` × the predicted step of its
predictor (so it cannot land on another branch) and the tangent keeps its sense of p (no fold
between); otherwise a pseudo-arclength step
(Keller): predictor z + ds·t, corrector Newton on [R(y, p) = 0; (Wt)ᵀ(z − z_pred) = 0] with the
bordered matrix B = [[J, −R_p], [(Wt)ᵀ]] (:func:`~mbseig.statics.linalg.solve_bordered`),
to ``STEP_TOL``.  An arclength step whose corrector does not converge in ``CORRECTOR_ITER``
iterations is halved; an easy one (≤ ``EASY`` iterations) lengthens the next
by 3/2, up to ds_max.  Grid values an arclength step passes are corrected at their value.

Folds (limit points): ṗ changes sign between two points; located by Brent's method on ṗ(s)
along the arclength (each evaluation a corrector on the hyperplane at distance s), so p at the
fold, an extremum of p(s), is accurate to O(xtol_s²).  Branch points: the sign of det B
changes (it does not at a fold); located by bisection on that sign.  There the null space of
[J, −R_p] is two-dimensional; its vector orthogonal to the tangent is the direction of the
other branch, and the follower switches to it when the branch it is on has lost static stability
there and the other is statically stable.  After a fold the branch turns back; it is followed
until it turns forward again (an S-curve), leaves the swept range or has run ``BACK_ARC`` of
the normalized arclength, and the next grid value is then reached by a fresh static solve from
the fold (the jump of a snap-through), which starts a new segment.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np
import scipy.linalg as sla
import scipy.sparse as sp

from ..errors import EquilibriumError, MbseigError
from ..numerics import LazyModule, constraint_rank, dense, saddle
from .cache import Memo
from .linalg import (
    DENSE_LIMIT,
    SMALL,
    NewtonMatrix,
    StepScales,
    multipliers,
    solve_bordered,
)
from .newton import Stall, newton, settings_for

spla = LazyModule("scipy.sparse.linalg")  # sparse solvers: imported at first use

__all__ = ["Family", "BranchPoint", "Branch", "follow", "CORRECTOR_ITER", "FD_REL", "CTOL"]

CORRECTOR_ITER = 8  # Newton iterations of a continuation corrector
STEP_TOL = 1e-8  # an arclength step between grid points is corrected to this (model scales)
EASY = 3  # a corrector converged in at most EASY iterations lengthens the next step
FD_REL = 1e-7  # forward-difference step of ∂R/∂p, relative to p_scale
CTOL = 1e-11  # corrector converged: correction below CTOL in the model's scales (and p_scale)
DS_MIN = 1e-9  # smallest step (normalized arclength) before a segment is given up
DS_MAX = 0.1  # largest step (normalized arclength: at least ten steps over the swept range)
CHORD = 1e-5  # a corrector reuses its Newton matrix after a correction below this (model
# scales): the next step is then a chord step, contracting by ≈ CHORD, ample below CTOL
REACH = 0.25  # a grid point's corrector may end this far from its predictor (× the step)
BACK_ARC = 0.3  # arclength followed along a branch that turned back, before jumping forward


class Family:
    """p ↦ model(p) with the residual, Newton matrix and ∂R/∂p of the branch equations."""

    def __init__(self, make, p_scale, model0, q0, *, rank_tol=1e-10):
        self.make = make
        self.p_scale = float(p_scale) if p_scale else 1.0
        self._cache: dict = {}
        self.scales = StepScales(model0)
        self.n = model0.n
        Phi_q = model0.phi_q(q0)
        self.m = Phi_q.shape[0]
        self.rows = np.arange(self.m)
        if self.m and model0.n + self.m <= DENSE_LIMIT:
            rank = constraint_rank(Phi_q, rank_tol)[0]
            if rank < self.m:
                _, _, piv = sla.qr(Phi_q.toarray().T, pivoting=True, mode="economic")
                self.rows = np.sort(piv[:rank])
        self.N = self.n + self.rows.size
        # a small model's R and J from dense evaluations (mbseig.numerics.DENSE_ASSEMBLY)
        self.dense = bool(getattr(model0, "dense_assembly", False))
        self.evaluations = 0
        self._memo_store: dict = {}

    def model(self, p):
        key = float(p)
        m = self._cache.get(key)
        if m is None:
            m = self.make(key)
            self.evaluations += 1
            if len(self._cache) > 256:
                self._cache.pop(next(iter(self._cache)))
            self._cache[key] = m
        return m

    def lam_full(self, y):
        lam = np.zeros(self.m)
        lam[self.rows] = y[self.n:]
        return lam

    def start(self, q, p):
        """y = (q, least-squares λ_S) at an equilibrium q of model(p)."""
        model = self.model(p)
        Phi_q = model.phi_q(q)[self.rows] if self.m else model.phi_q(q)
        lam = multipliers(Phi_q, model.generalized_force(q), 1e-10, check=False)[0]
        return np.concatenate([q, lam])

    def _memo(self, what, y, p, compute):
        key = (what, float(p), y.tobytes())
        hit = self._memo_store.get(key)
        if hit is None:
            hit = compute()
            if len(self._memo_store) > 16:
                self._memo_store.pop(next(iter(self._memo_store)))
            self._memo_store[key] = hit
        return hit

    def R(self, y, p):
        return self._memo("R", y, p, lambda: self._R(y, p))

    def J(self, y, p):
        return self._memo("J", y, p, lambda: self._J(y, p))

    def Rp(self, y, p):
        return self._memo("Rp", y, p, lambda: self._Rp(y, p))

    def _R(self, y, p):
        model = self.model(p)
        q, lam = y[:self.n], y[self.n:]
        with np.errstate(all="ignore"):
            g = model.generalized_force(q)
            if not self.m:
                return g
            Phi_q = model.phi_q(q, dense=self.dense)[self.rows]
            return np.concatenate([g - Phi_q.T @ lam, -model.phi(q)[self.rows]])

    def _J(self, y, p):
        model = self.model(p)
        q = y[:self.n]
        with np.errstate(all="ignore"):
            K, _ = model.force_jacobians(q, dense=self.dense)
            if not self.m:
                return K if self.dense else K.tocsr()
            Phi_q = model.phi_q(q, dense=self.dense)[self.rows]
            H = model.constraint_hessian(q, self.lam_full(y), dense=self.dense)
            return saddle(K + H, Phi_q)

    def _Rp(self, y, p):
        h = FD_REL * self.p_scale
        return (self.R(y, p + h) - self.R(y, p)) / h

    def Rp_back(self, y, p, p_prev):
        """∂R/∂p by the difference to the previous point's parameter, whose model is built
        already: (R(y, p) − R(y, p_prev)) / (p − p_prev), accurate to O(p − p_prev).  Used for
        the tangent at a grid point reached directly (the predictor of the next one and the
        sense of p); an exact tangent replaces it wherever the sense of p or the sign of det J
        changes (folds, branch points)."""
        return (self.R(y, p) - self.R(y, p_prev)) / (p - p_prev)

    def weights(self):
        """W of z = (q, λ, p): 1/ℓ² on q, 0 on λ, 1/p_scale² on p."""
        w = np.zeros(self.N + 1)
        w[:self.n] = 1.0 / self.scales.ell**2
        w[-1] = 1.0 / self.p_scale**2
        return w


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


def _correct_fixed(fam, y, p, reach):
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


def _correct_arclength(fam, z0, t, ds, tol=CTOL):
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


def _point(fam, z, t, kind, segment, iterations=0):
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
    res = _correct_arclength(fam, z0, t0, s)
    if res is None:
        return None, None
    z = res[0]
    t = tangent(fam, z[:-1], z[-1], prev=t0)
    return z, t


def _locate_fold(fam, z0, t0, ds, xtol):
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


def _locate_branch_point(fam, z0, t0, ds, sign0, iterations=48):
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


def _second_direction(fam, z, t):
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


# ---------------------------------------------------------------------------------------------
def follow(fam, values, y0, *, stability=None, restart=None, switch=True, ds_max=None,
           max_steps=None, xtol=1e-10):
    """Follow the branch through (values[0], y0) across the grid ``values`` (module docstring).

    stability(model, q, λ) → "stable" | "unstable" | ...: the static stability used to decide a
        branch switch (None: never switch).
    restart(p, q_start) → q: a static solve at p from q_start (the jump after a fold).
    Returns a :class:`Branch`: ``grid[k]`` the point at values[k] (None where not reached),
    ``events`` the folds, branch points, switches and jumps with their parameter values.
    """
    values = np.asarray(values, dtype=float)
    dirn = 1.0 if values[-1] >= values[0] else -1.0
    spacing = float(np.min(np.abs(np.diff(values)))) / fam.p_scale if values.size > 1 else 1.0
    ds_max = min(2.0 * spacing, DS_MAX) if ds_max is None else ds_max
    spacing = min(spacing, ds_max)
    max_steps = 40 * values.size if max_steps is None else max_steps
    br = Branch(grid=[None] * values.size)
    segment = 0
    t = tangent(fam, y0, values[0], direction=dirn)
    if t is None:
        raise EquilibriumError("no tangent at the first point of the sweep", element="continuation")
    z = np.concatenate([y0, [values[0]]])
    cur = _point(fam, z, t, "start", segment)
    cur.grid_index = 0
    br.points.append(cur)
    br.grid[0] = cur
    k_next, ds, steps, back = 1, spacing, 0, 0
    accepted = rejected = approx = 0
    land, t_exact = True, True
    fold_z = None  # the last fold: where a jump past it starts from
    last_B = cur.det_B
    z_prev, t_prev, ds_prev = z, t, 0.0

    def jump():
        """A fresh solve at the next grid value from the last fold (or point): the new
        segment's (z, t, point), its number and the next grid index, or None."""
        jumped = _jump(fam, br, z if fold_z is None else fold_z, values, k_next, restart,
                       segment + 1, dirn)
        return None if jumped is None else (jumped, segment + 1, jumped[2].grid_index + 1)

    pending_jump = False
    while k_next < values.size and steps < max_steps:
        if pending_jump:
            pending_jump, state = False, jump()
            if state is None:
                break
            (z, t, cur), segment, k_next = state
            t_exact = True
            z_prev, t_prev, ds_prev, ds, back, last_B, fold_z = _fresh(z, t, cur, spacing)
            continue
        steps += 1
        p_g = values[k_next]
        forward = t[-1] * dirn > 0
        new = None
        if land and forward:  # the next grid value directly, from the tangent predictor
            ds_g = (p_g - z[-1]) / t[-1]
            res = _correct_fixed(fam, _predict(z, t, z_prev, p_g), p_g, REACH * abs(ds_g) + 1e-9)
            if res is not None:
                new_z, its = np.concatenate([res[0], [p_g]]), res[1]
                new = (new_z, its, ds_g, True)
        if new is None:
            res = _correct_arclength(fam, z, t, ds, STEP_TOL)
            if res is not None:
                new = (res[0], res[1], ds, False)
        if new is None:
            rejected += 1
            ds *= 0.5
            pending_jump = ds < DS_MIN * max(spacing, 1.0)
            continue
        new_z, its, ds_used, landed = new
        t_new = None
        if landed and new_z[-1] != z[-1]:  # ∂R/∂p from the previous point's model (no build)
            t_new = tangent(fam, new_z[:-1], new_z[-1], prev=t,
                            rp=fam.Rp_back(new_z[:-1], new_z[-1], z[-1]))
            if t_new is not None:
                newp = _point(fam, new_z, t_new, "grid", segment, its)
                if not (newp.det_J and newp.det_J == cur.det_J and t[-1] * t_new[-1] > 0):
                    t_new = None  # a sign changed: decided on the exact tangents below
                else:
                    approx += 1
        if t_new is None:
            if not t_exact:  # the exact tangent at the start of the step
                t_z = tangent(fam, z[:-1], z[-1], prev=t)
                if t_z is not None:
                    t = cur.tangent = t_z
                    if cur.det_J and abs(t[-1]) > 1e-12:  # its det B from the exact ṗ
                        cur.det_B = last_B = cur.det_J * int(np.sign(t[-1]))
                t_exact = True
            t_new = tangent(fam, new_z[:-1], new_z[-1], prev=t)
            newp = None
            if t_new is None:
                rejected += 1
                ds *= 0.5
                continue
        if landed and t[-1] * t_new[-1] < 0:  # the landing passed a fold: step along the arc
            land, ds = False, abs(ds_used)
            continue
        t_exact_new = newp is None
        land = True
        accepted += 1
        # folds: ṗ changes sign
        fold = t[-1] * t_new[-1] < 0
        if fold:
            try:
                zf, tf = _locate_fold(fam, z, t, ds_used, xtol)
                fold_z = zf
                fp = _point(fam, zf, tf, "fold", segment)
                br.points.append(fp)
                br.events.append({"type": "fold", "p": fp.p, "segment": segment,
                                  "turns": "back" if t_new[-1] * dirn < 0 else "forward",
                                  "point": len(br.points) - 1})
            except MbseigError:
                br.events.append({"type": "fold", "p": float(0.5 * (z[-1] + new_z[-1])),
                                  "segment": segment, "located": False})
        if newp is None:
            newp = _point(fam, new_z, t_new, "grid" if landed else "step", segment, its)
        # branch points: det B changes sign (B singular on a point itself: judged at the next).
        # Not at a fold: where Φ_q loses rank (a kinematic fold, a dead point) det J has a
        # double zero and det B changes sign there instead
        if newp.det_B and last_B and newp.det_B != last_B and not fold:
            z_from, t_from, ds_from = (z, t, ds_used) if cur.det_B else (z_prev, t_prev, ds_prev + ds_used)
            found = _locate_branch_point(fam, z_from, t_from, ds_from, last_B)
            if found is not None:
                bp = _point(fam, found[0], found[1], "branch point", segment)
                br.points.append(bp)
                ev = {"type": "branch point", "p": bp.p, "segment": segment,
                      "point": len(br.points) - 1}
                br.events.append(ev)
                if switch and stability is not None:
                    sw = _switch(fam, bp, newp, ds_used, stability, segment + 1, dirn)
                    if sw is not None:
                        ev["switched"] = True
                        (z, t, cur), segment = sw, segment + 1
                        t_exact = True
                        br.points.append(cur)
                        z_prev, t_prev, ds_prev, ds, back, last_B, fold_z = _fresh(z, t, cur,
                                                                                   spacing)
                        continue
        if landed:
            newp.grid_index = k_next
            br.grid[k_next] = newp
            k_next += 1
        else:  # grid values the arc passed going forward: each by a corrector at its value
            while (k_next < values.size and t[-1] * dirn > 0 and t_new[-1] * dirn > 0
                   and (new_z[-1] - values[k_next]) * dirn >= 0):
                p_g = values[k_next]
                w_ = (p_g - z[-1]) / (new_z[-1] - z[-1]) if new_z[-1] != z[-1] else 1.0
                res = _correct_fixed(fam, (1 - w_) * z[:-1] + w_ * new_z[:-1], p_g,
                                     fam.scales.size(new_z[:fam.n] - z[:fam.n]) + 1e-9)
                if res is None:
                    break
                gz = np.concatenate([res[0], [p_g]])
                gt = tangent(fam, res[0], p_g, prev=t)
                if gt is None:
                    break
                gp = _point(fam, gz, gt, "grid", segment, res[1])
                gp.grid_index = k_next
                br.grid[k_next] = gp
                br.points.append(gp)
                k_next += 1
        br.points.append(newp)
        z_prev, t_prev, ds_prev = z, t, ds_used
        z, t, cur, t_exact = new_z, t_new, newp, t_exact_new
        last_B = cur.det_B or last_B
        back = back + abs(ds_used) if t[-1] * dirn < 0 else 0.0
        out_of_range = (z[-1] - values[0]) * dirn < -0.5 * spacing * fam.p_scale
        if back > BACK_ARC or (t[-1] * dirn < 0 and out_of_range):
            pending_jump = True
            continue
        ds = min(1.5 * ds, ds_max) if its <= EASY else ds
    br.record = {"steps": steps, "accepted": accepted, "rejected": rejected,
                 "model_builds": fam.evaluations, "fd_rel": FD_REL, "ctol": CTOL,
                 "corrector_iter": CORRECTOR_ITER, "step_tol": STEP_TOL,
                 "xtol_fold": xtol, "ds_max": ds_max,
                 "ds_min": DS_MIN, "reach": REACH, "back_arc": BACK_ARC, "easy": EASY,
                 "segments": segment + 1, "constraint_rows": int(fam.rows.size),
                 "constraint_rows_dropped": int(fam.m - fam.rows.size),
                 "det_undecided": int(sum(1 for b in br.points if b.det_B == 0)),
                 "tangents_by_difference": approx}
    return br


def _predict(z, t, z_prev, p):
    """y at p: the tangent at z, bent by the previous point of the segment when there is one
    (y ≈ y_k + a (p − p_k) + c (p − p_k)² with a = ẏ/ṗ and c fitted to z_prev), so that a
    rotation of the equilibrium is predicted to second order."""
    a = t[:-1] / t[-1]
    dp = p - z[-1]
    y = z[:-1] + a * dp
    h = z_prev[-1] - z[-1]
    if z_prev is not z and h * dp < 0 and abs(h) > 1e-12 * (abs(dp) + abs(z[-1])):
        c = (z_prev[:-1] - z[:-1] - a * h) / (h * h)
        y = y + c * dp * dp
    return y


def _fresh(z, t, cur, spacing):
    """The follower's state at the start of a segment: (z_prev, t_prev, ds_prev, ds, back,
    last det B, last fold)."""
    return z, t, 0.0, spacing, 0.0, cur.det_B, None


def _switch(fam, bp, beyond, ds, stability, segment, dirn):
    """Switch to the other branch at ``bp`` when the current branch is statically unstable
    beyond it and the other is stable: (z, t, point) on the other branch, or None."""
    model = fam.model(beyond.p)
    q = beyond.y[:fam.n]
    if stability(model, q, fam.lam_full(beyond.y)) != "unstable":
        return None
    z_b = np.concatenate([bp.y, [bp.p]])
    v = _second_direction(fam, z_b, bp.tangent)
    if v is None:
        return None
    for sign in (1.0, -1.0):
        res = _correct_arclength(fam, z_b, sign * v, abs(ds))
        if res is None:
            continue
        z = res[0]
        pm = fam.model(z[-1])
        if stability(pm, z[:fam.n], fam.lam_full(z[:-1])) != "stable":
            continue
        t = tangent(fam, z[:-1], z[-1], prev=sign * v)
        if t is None:
            continue
        if abs(t[-1]) > 1e-12 and t[-1] * dirn < 0:
            t = -t  # continue towards the unprocessed grid values
        return z, t, _point(fam, z, t, "switch", segment, res[1])
    return None


def _jump(fam, br, z, values, k_next, restart, segment, dirn):
    """A fresh static solve at the next grid value from the last point (a snap-through)."""
    if restart is None:
        return None
    p_g = values[k_next]
    try:
        q = restart(p_g, z[:fam.n])
    except MbseigError:
        return None
    y = fam.start(q, p_g)
    t = tangent(fam, y, p_g, direction=dirn)
    if t is None:
        return None
    zz = np.concatenate([y, [p_g]])
    pt = _point(fam, zz, t, "jump", segment)
    pt.grid_index = k_next
    br.grid[k_next] = pt
    br.points.append(pt)
    br.events.append({"type": "jump", "p": float(p_g), "from": float(z[-1]), "segment": segment,
                      "point": len(br.points) - 1})
    return zz, t, pt
