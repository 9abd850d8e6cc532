"""Error bounds of the eigenvalues and the stability each one decides (docs/design.md, "Modes
and stability"): δ = 0 means |δ| within the eigenvalue's bound (10 κ η, the componentwise bound
where sharper, a cluster bound for defective or nearly defective groups, a floor for the zero
pair of a rigid-body mode); the tolerances recorded with the rule that made them."""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
import scipy.linalg as sla
import scipy.sparse as sp

from ..eigen import EPS
from .result import STABILITY_ORDER


# ---------------------------------------------------------------------------------------------
# error bounds and tolerances
# ---------------------------------------------------------------------------------------------
def frequency_scale(norms):
    nM, nP, nQ = norms
    if nM > 0 and nQ > 0:
        return math.sqrt(nQ / nM)
    if nM > 0 and nP > 0:
        return nP / nM
    if nP > 0 and nQ > 0:
        return nQ / nP
    return 1.0


def numerical_rank(X, rank_tol):
    """Numerical rank of the columns of X (pivoted QR, relative pivot threshold)."""
    if X.shape[1] == 0:
        return 0
    Xn = X / np.maximum(np.linalg.norm(X, axis=0), np.finfo(float).tiny)
    d = np.abs(np.diag(_pivoted_r(Xn)))
    return int(np.sum(d > rank_tol * d[0])) if d.size and d[0] > 0 else 0


def _pivoted_r(X):
    """The R of X's column-pivoted QR: LAPACK ``geqp3`` with its own workspace query, as
    ``scipy.linalg.qr(X, mode="r", pivoting=True)`` calls it (the same R), without that
    function's checks (≈ 40 µs, once per cluster); scipy's function for a non-finite X or a
    LAPACK complaint (its messages)."""
    if np.all(np.isfinite(X)):
        key = (X.dtype.char, X.shape)
        if key not in _GEQP3:  # the routine and its workspace query depend on these alone
            if len(_GEQP3) > 256:
                _GEQP3.clear()
            geqp3 = sla.get_lapack_funcs("geqp3", (X,))
            _GEQP3[key] = geqp3, int(geqp3(X.copy(), lwork=-1)[-2][0].real)
        geqp3, lwork = _GEQP3[key]
        qr, _, _, _, info = geqp3(X, lwork=lwork, overwrite_a=1)
        if info == 0:
            return qr
    return sla.qr(X, mode="r", pivoting=True)[0]


_GEQP3 = {}  # (dtype, shape) -> (geqp3, its optimal lwork): one query per cluster shape


def numerical_ranks(X, rank_tol):
    """:func:`numerical_rank` of G blocks of columns at once, X (G, n, k): the same
    normalization and the same pivoted QR's diagonal, by Gram–Schmidt with column pivoting
    (each step the remaining column of largest norm; its norm is |R_jj|, the distance of that
    column from the span of the columns chosen before it, as Householder's ``geqp3`` computes
    it), with the projection done twice so that the remaining norms keep their absolute
    accuracy ε; the rank counts |R_jj| > rank_tol·|R_11|."""
    X = np.asarray(X)
    G, _, k = X.shape
    if k == 0 or G == 0:
        return np.zeros(G, int)
    A = X / np.maximum(np.linalg.norm(X, axis=1, keepdims=True), np.finfo(float).tiny)
    rows = np.arange(G)
    d = np.zeros((G, k))
    free = np.ones((G, k), bool)
    for j in range(k):
        norms = np.where(free, np.linalg.norm(A, axis=1), -1.0)
        piv = np.argmax(norms, axis=1)
        r = norms[rows, piv]
        d[:, j] = r
        free[rows, piv] = False
        q = A[rows, :, piv] / np.where(r > 0, r, 1.0)[:, None]
        A[rows, :, piv] = 0.0
        for _ in range(2):
            A = A - q[:, :, None] * np.einsum("gn,gnk->gk", q.conj(), A)[:, None, :]
    d0 = d[:, 0]
    return np.where(d0 > 0, np.sum(d > rank_tol * d0[:, None], axis=1), 0)


def _nullity_counts(M, P, Q, mu, r, scale):
    """The nullity rule of :func:`nullity` on G dense problems (G, n, n) at once: means μ (G,)
    already divided by γ, spreads r (G,) likewise, scale (G,) the √ε term's scale over γ.  Where
    |μ| > 1 the reversed T(μ)/μ² and T′(μ)/μ (the same ratios without overflow), each problem
    formed by its own branch only."""
    a = np.abs(mu)
    rev = a > 1
    G = mu.shape[0]
    T = np.empty(M.shape, complex)
    Td = np.empty(M.shape, complex)
    rr = np.array(r, float)
    i, j = np.flatnonzero(rev), np.flatnonzero(~rev)
    if i.size:  # reversed
        t = (1.0 / mu[i])[:, None, None]
        T[i] = M[i] + t * P[i] + (t * t) * Q[i]
        Td[i] = 2 * M[i] + t * P[i]
        rr[i] = rr[i] / a[i]
    if j.size:
        t = mu[j][:, None, None]
        T[j] = (t * t) * M[j] + t * P[j] + Q[j]
        Td[j] = 2 * t * M[j] + P[j]
    finite = np.all(np.isfinite(T), axis=(1, 2)) & np.all(np.isfinite(Td), axis=(1, 2))
    out = np.zeros(G, int)
    k = np.flatnonzero(finite)
    if k.size:
        sv = np.linalg.svd(T[k], compute_uv=False)
        thr = (10 * (rr[k] + np.sqrt(EPS) * scale[k] / np.maximum(a[k], 1.0))
               * np.linalg.norm(Td[k], axis=(1, 2)) + 1e3 * EPS * sv[:, 0])
        out[k] = np.sum(sv <= thr[:, None], axis=1)
    return out


def nullities(M, P, Q, mean, spread, scale):
    """:func:`nullity` of G unscaled (γ = 1) dense real problems M, P, Q (G, n, n) at once, at
    the clusters' means (G,) with their spreads and scales (G,)."""
    return _nullity_counts(M, P, Q, np.asarray(mean, complex), np.asarray(spread, float),
                           np.asarray(scale, float))


def nullity(sol, mean, spread, scale, max_order=2000):
    """Independent eigenvectors of a cluster: the nullity of T(s̄) = s̄²M + s̄P + Q at its mean
    (singular values within 10 (spread + √ε·scale)‖T′(s̄)‖ + 10³ε‖T(s̄)‖), for dense problems up
    to ``max_order`` (0 otherwise).  The computed eigenvectors of a derogatory defective
    eigenvalue need not span its eigenspace; T's singular values do."""
    prob = sol.problem
    if not (isinstance(prob, tuple) and len(prob) == 4):  # a partial path's: no dense pencil
        return 0
    M, P, Q, gamma = prob
    if M.shape[0] > max_order:
        return 0
    M, P, Q = (A.toarray() if sp.issparse(A) else np.asarray(A) for A in (M, P, Q))
    mu = mean.real / gamma + 1j * (mean.imag / gamma)
    return int(_nullity_counts(M[None], P[None], Q[None], np.array([mu]),
                               np.array([spread / gamma]), np.array([scale / gamma]))[0])


def components(n, pairs):
    """Connected components (labels: the smallest node of each) of the graph on n nodes with the
    given edges; union-find on a list (Python integers: faster than numpy scalars here)."""
    if not pairs:  # every node its own component (the common case: well separated eigenvalues)
        return np.arange(n)
    parent = list(range(n))

    def find(i):
        while parent[i] != i:
            parent[i] = parent[parent[i]]
            i = parent[i]
        return i

    for i, j in pairs:
        ri, rj = find(i), find(j)
        if ri != rj:
            parent[max(ri, rj)] = min(ri, rj)
    return np.array([find(i) for i in range(n)])


@dataclass(frozen=True)
class Bounds:
    err: np.ndarray  # error bound of s
    tol: np.ndarray  # tolerance for the rigid-body and real tests
    tol_re: np.ndarray  # tolerance for the δ test
    rigid: np.ndarray
    cluster: np.ndarray  # cluster label per eigenvalue (its own index when alone)
    block: np.ndarray  # estimated Jordan block size of the eigenvalue's cluster
    geometric: np.ndarray = None  # independent eigenvectors of the eigenvalue's cluster


class AllPairs:
    """The two cKDTree queries :func:`error_bounds` uses, by all pairs: for the few eigenvalues of a
    small model this is faster than importing scipy.spatial (≈ 0.1 s of start-up)."""

    def __init__(self, points):
        self.z = points[:, 0] + 1j * points[:, 1]

    def query(self, points, k=2):
        z = points[:, 0] + 1j * points[:, 1]
        d = np.abs(z[:, None] - self.z[None, :])
        if k < d.shape[1]:  # the k smallest of each row, sorted: a partition, not a full sort
            d = np.partition(d, k - 1, axis=1)[:, :k]
        return np.sort(d, axis=1), None

    def query_ball_point(self, x, r, return_length=False):
        x = np.asarray(x, float)
        single = x.ndim == 1
        x = np.atleast_2d(x)
        d = np.abs((x[:, 0] + 1j * x[:, 1])[:, None] - self.z[None, :])
        r = np.broadcast_to(np.asarray(r, float), (x.shape[0],))
        mask = d <= r[:, None]
        if return_length:
            counts = mask.sum(axis=1)
            return counts[0] if single else counts
        cols, out, i = np.nonzero(mask)[1].tolist(), [], 0  # row by row, ascending columns
        for count in mask.sum(axis=1).tolist():
            out.append(cols[i:i + count])
            i += count
        return out[0] if single else out


def neighbour_index(points, small=256):
    """Nearest-neighbour queries on the eigenvalues: all pairs for a small spectrum, a k-d tree
    (scipy.spatial, imported here: off the start-up path) above."""
    if points.shape[0] <= small:
        return AllPairs(points)
    from scipy.spatial import cKDTree

    return cKDTree(points)


def sharpen(err, idx, eta_c, kappa_c):
    """err[idx] lowered, in place, to the componentwise bound κ_c·max(η_c, ε) where that is
    smaller (a NaN bound counts as none)."""
    with np.errstate(over="ignore", invalid="ignore"):
        err_c = kappa_c * np.maximum(eta_c, EPS)
    err_c = np.where(np.isnan(err_c), np.inf, err_c)
    err[idx] = np.minimum(err[idx], err_c)


def _holder_blocks(tree, points, S, eta, safety, first_reach):
    """The size k of the block each eigenvalue may belong to: the number of eigenvalues within
    safety·S·η^{1/k} of it, grown from k = 2 until it stops growing (radii in units of the
    points).  Counting within the first-order reach instead would let an unreliable first-order
    bound (κη of a nearly defective root: κ ≈ 1e18 for a spinning shaft's free rotation) sweep
    in far neighbours and make the Hölder radius as large as itself, so that whirl modes at
    83 rad/s took the zero's bound and were called rigid-body.  The first-order reach still caps
    the count: a block is never larger than what the first-order bound allows."""
    k = np.full(points.shape[0], 2)
    while True:
        reach = np.minimum(safety * S * eta ** (1.0 / k), first_reach)
        counts = np.asarray(tree.query_ball_point(points, reach, return_length=True))
        grown = counts > k
        if not grown.any():
            return counts
        k = np.where(grown, counts, k)


def error_bounds(sol, *, safety=10.0, stability_rtol=1e-12, stability_atol=0.0, rank_tol=1e-6):
    """Error bounds, tolerances and clusters of every eigenvalue of ``sol`` (module docstring)."""
    s = np.asarray(sol.eigenvalues)
    k = s.size
    eta = np.maximum(np.asarray(sol.backward_error, float), EPS)
    with np.errstate(over="ignore", invalid="ignore"):
        err = np.asarray(sol.condition, float) * eta
    err = np.where(np.isnan(err), np.inf, err)
    scale = frequency_scale(sol.norms)
    S = np.maximum(np.abs(s), scale)
    holder2 = S * np.sqrt(eta)
    # componentwise bounds where the normwise one does not separate s from 0, from the real axis
    # or from its neighbours (computed only there: they cost a product with |M|, |P|, |Q|)
    if k > 1:  # the tree on s / max|s|: squared distances of |s| ~ 1e300 would overflow
        unit = float(np.max(np.abs(s))) or 1.0
        points = np.column_stack([s.real, s.imag]) / unit
        tree = neighbour_index(points)
        near = tree.query(points, k=2)[0][:, 1] * unit
    else:
        near = np.full(k, np.inf)
    # (an exactly zero Re s is critical whatever the bound: no need to sharpen it for that)
    gaps = [np.abs(s), np.where(s.real != 0, np.abs(s.real), np.inf),
            np.where(s.imag != 0, np.abs(s.imag), np.inf), near]
    undecided = safety * err >= np.minimum.reduce(gaps)
    idx = np.flatnonzero(undecided)
    if idx.size:
        sharpen(err, idx, *sol.componentwise(idx))
    # linking radius: the first-order bound, but where other eigenvalues lie within it (first
    # order is then unreliable) no more than the Hölder radius S·η^{1/k} of a block of all k of
    # them; an infinite bound (an exactly defective pair) links within the double's S·√η
    radius = np.where(np.isfinite(err), err, holder2)
    cluster = np.arange(k)
    block = np.ones(k, int)
    if k > 1:
        finite = np.flatnonzero(np.isfinite(err) & (err > 0))
        if finite.size:
            counts = _holder_blocks(tree, points[finite], S[finite] / unit, eta[finite], safety,
                                    np.minimum(safety * err[finite] / unit, 4.0))
            holder_k = S[finite] * eta[finite] ** (1.0 / np.maximum(counts, 1))
            radius[finite] = np.where(counts > 1, np.minimum(err[finite], holder_k), err[finite])
        pairs = set()
        reach = np.minimum(2 * safety * radius / unit, 4.0)  # beyond 4 max|s|: everything
        # one query for all points (radius 0 still finds exact duplicates); the candidates are
        # tested in one vectorized comparison
        counts = np.asarray(tree.query_ball_point(points, reach, return_length=True))
        if counts.sum() > k:  # some point has a neighbour besides itself: the lists
            hits = tree.query_ball_point(points, reach)
            ii = np.repeat(np.arange(k), counts)
            jj = np.fromiter((j for h in hits for j in h), int, int(counts.sum()))
            ok = (jj != ii) & (np.abs(s[ii] - s[jj]) <= safety * (radius[ii] + radius[jj]))
            pairs = set(zip(np.minimum(ii, jj)[ok].tolist(), np.maximum(ii, jj)[ok].tolist(),
                            strict=True))
        cluster = components(k, pairs)
    err = err.copy()
    sizes = np.bincount(cluster, minlength=k)  # members per label (labels are indices < k)
    alone = (sizes[cluster] == 1) & ~np.isfinite(err)  # κ = ∞ alone: a defective root, Hölder
    err[alone], block[alone] = holder2[alone], 2
    geometric = np.ones(k, int)
    for c in np.flatnonzero(sizes > 1):  # the clusters, in ascending label
        members = np.flatnonzero(cluster == c)
        mean0 = s[members].sum() / members.size  # np.mean's own sum and division
        spread0 = float(np.max(np.abs(s[members] - mean0)))
        g = numerical_rank(sol.vectors[:, members], rank_tol)
        if g < members.size:  # the vectors alone do not show a full set: T's singular values
            g = min(max(g, nullity(sol, mean0, spread0, max(abs(mean0), scale))), members.size)
        geometric[members] = g
        b = max(1, math.ceil(members.size / max(g, 1)))
        mean, spread = mean0, spread0
        if b == 1:
            first = np.max(np.where(np.isfinite(err[members]), err[members], holder2[members]))
            err[members] = spread + first
        else:
            Sc = max(abs(mean), scale)
            err[members] = spread + Sc * float(np.max(eta[members])) ** (1.0 / b)
        block[members] = b
    floor = [stability_rtol * np.abs(s), np.full(k, stability_atol)]
    tol = np.maximum.reduce([safety * err, *floor])
    re_err = sol.real_error
    if re_err is None:
        tol_re = tol
    else:
        # the path's Re s bound is first order: not inside a defective cluster
        clustered = block > 1
        re_bound = np.where(clustered, err, np.minimum(err, re_err))
        tol_re = np.maximum.reduce([safety * re_bound, *floor])
    return Bounds(err, tol, tol_re, np.abs(s) <= tol, cluster, block, geometric)


def zero_pair_floor(b, sol, M, P, safety, nQ=None, gamma=1.0):
    """Near s = 0, an undamped eigenvalue comes from s² = −ω² with ω² a small difference of
    stiffness terms: an ε-relative error of Q (its formation Nᵀ K N, rounding of K) moves ω² by
    up to ε‖Q‖‖x‖²/|xᴴMx| and s by the square root of that, which no first-order bound sees.  For
    an eigenvalue whose damping term is below its inertia term (|xᴴPx| ≤ |s||xᴴMx|, the ±√ω²
    structure), the error bound is raised to that Hölder radius,
    h = √(max(η, ε) ‖Q‖_F ‖x‖² / |xᴴMx|),  with the mode's own modal mass (a light body's spin
    has a far larger h than the global √(ε‖Q‖/‖M‖)).

    ω² is then known within h² (safety·h² with the safety factor), so s = ±√(−ω²) may be 0 when
    |s|² ≤ safety·h², i.e. |s| ≤ √safety·h (beyond h, s itself moves by h²/|s| < h): s within
    √safety·h of 0 is rigid-body (critical), its bound h and tolerance safety·h.  An eigenvalue
    beyond it keeps its verdict."""
    import dataclasses

    s = np.asarray(sol.eigenvalues)
    if s.size == 0 or sol.complex_problem or sol.vectors is None or M is None:
        return b
    scale = frequency_scale(sol.norms)
    cand = np.flatnonzero(np.abs(s) <= 1e-3 * scale)
    if cand.size == 0:
        return b
    nQ = float(sol.norms[2]) if nQ is None else nQ
    s = s / gamma  # M, P, Q of a problem scaled by s = γ μ: work in μ, radius back in s
    eta = np.maximum(np.asarray(sol.backward_error, float), EPS)
    err, tol, tol_re, rigid = b.err.copy(), b.tol.copy(), b.tol_re.copy(), b.rigid.copy()
    Mm = M if sp.issparse(M) else np.asarray(M)
    Pm = None if P is None else (P if sp.issparse(P) else np.asarray(P))
    if sol.vectors.shape[0] != Mm.shape[0]:
        return b
    forms = modal_forms(sol.vectors, cand, Mm, Pm)
    reach = math.sqrt(safety)
    for j, k in enumerate(cand):
        mx, px, xx = forms[j]
        if mx == 0 or px > abs(s[k]) * mx:
            continue
        h = math.sqrt(float(eta[k]) * float(nQ) * float(xx) / float(mx))
        if not math.isfinite(h):  # (a floor beyond the range of doubles decides nothing)
            continue
        s_k, h = s[k] * gamma, h * gamma
        if abs(s_k) <= reach * h:
            err[k] = max(err[k], h)
            tol[k] = max(tol[k], safety * h)
            tol_re[k] = max(tol_re[k], safety * h)
            rigid[k] = True
    return dataclasses.replace(b, err=err, tol=tol, tol_re=tol_re, rigid=rigid)


#: entries of one block of rows in :func:`modal_forms` (as the measures' blocks)
FORM_BLOCK = 1 << 20


def modal_forms(X, cand, M, P):
    """(|xᴴMx|, |xᴴPx| (0 without P), ‖x‖²) of the columns ``cand`` of X.  Column by column
    for a small problem; for a large sparse one the products of all columns at once, a block
    of rows at a time (one pass over M and P instead of one per column, no strided copies)."""
    n = X.shape[0]
    if not (sp.issparse(M) and n * len(cand) > FORM_BLOCK):
        out = []
        for k in cand:
            x = X[:, k]
            px = 0.0 if P is None else abs(np.vdot(x, P @ x))
            out.append((abs(np.vdot(x, M @ x)), px, float(np.vdot(x, x).real)))
        return out
    Xc = X if np.array_equal(cand, np.arange(X.shape[1])) else np.take(X, cand, axis=1)
    Xc = np.ascontiguousarray(Xc)
    M = M.tocsr()
    P = None if P is None else (P.tocsr() if sp.issparse(P) else P)
    dt = np.result_type(Xc, M.dtype, *(() if P is None else (P.dtype,)))
    mx, px = np.zeros(len(cand), dt), np.zeros(len(cand), dt)
    xx = np.zeros(len(cand))
    step = max(1, FORM_BLOCK // max(len(cand), 1))
    for i in range(0, n, step):
        r = slice(i, min(i + step, n))
        Xr = Xc[r].conj()
        mx += np.einsum("ij,ij->j", Xr, M[r] @ Xc)
        if P is not None:
            px += np.einsum("ij,ij->j", Xr, P[r] @ Xc)
        xx += np.einsum("ij,ij->j", Xr, Xc[r]).real
    return list(zip(np.abs(mx).tolist(), np.abs(px).tolist(), xx.tolist(), strict=True))


def tolerances(sol, *, safety=10.0, stability_rtol=1e-12, stability_atol=0.0, rank_tol=1e-6):
    """(err, tol, tol_re, rigid) per eigenvalue of a :class:`~mbseig.eigen.QEPSolution`.

    err: error bound of s (first order, normwise or componentwise, or the cluster bound of a
    defective or nearly defective cluster: module docstring); tol = max(safety·err,
    stability_rtol·|s|, stability_atol) for the rigid-body and real tests, tol_re the same with
    the path's sharper bound of Re s where it has one (the δ test), rigid: |s| ≤ tol, with the
    zero-pair floor of :func:`zero_pair_floor` (from the problem the pairs refer to).  The one
    definition used by :func:`modes` and by the sweeps.
    """
    b = error_bounds(sol, safety=safety, stability_rtol=stability_rtol,
                     stability_atol=stability_atol, rank_tol=rank_tol)
    prob = sol.problem
    if isinstance(prob, tuple) and len(prob) == 4:  # the zero-pair floor, as modes() applies it
        Ms, Ps, Qs, gamma = prob
        nQs = float(np.linalg.norm(Qs.tocsr().data) if sp.issparse(Qs) else np.linalg.norm(Qs))
        b = zero_pair_floor(b, sol, Ms, Ps, safety, nQ=nQs, gamma=float(gamma))
    return b.err, b.tol, b.tol_re, b.rigid


def worst(stabilities) -> str:
    """The verdict over modes: the worst of their stabilities ("stable" for none)."""
    return max(stabilities, key=STABILITY_ORDER.get) if len(stabilities) else "stable"


def tolerance_rule(tolerances) -> str:
    """The rule that made each mode's stability tolerance, from the values a :class:`Modes`
    recorded (``safety``, ``stability_rtol``, ``stability_atol``): ``max(safety κ η, rtol |s|
    [, atol])``, κ η the eigenvalue's error bound (first order, componentwise where sharper, a
    cluster's bound for a defective or nearly defective group)."""
    terms = [f"{tolerances.get('safety', 10.0):g} κ η",
             f"{tolerances.get('stability_rtol', 1e-12):g} |s|"]
    atol = tolerances.get("stability_atol", 0.0)
    if atol:
        terms.append(f"{atol:g}")
    return f"max({', '.join(terms)})"
