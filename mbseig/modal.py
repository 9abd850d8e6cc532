"""Stage 4: modes and their stability (docs/design.md, "Tolerances").

For an eigenvalue s_k = −δ_k + iω_k:  ω_n = |s|,  ζ = δ/|s| (0 for a rigid-body mode),
f = ω/2π (``freq_hz``: the damped frequency ω_d/2π, 0 for a real eigenvalue) and
f_n = ω_n/2π (``freq_n_hz``: the natural frequency |s|/2π, what python-control's ``damp``
reports and what ``--band-hz`` and ``--target-hz`` select on), and

    δ > tol_k  stable,   |δ| ≤ tol_k  critical,   δ < −tol_k  unstable,

    tol_k = max(safety · err_k,  stability_rtol · |s_k|,  stability_atol)

where err_k is an error bound of s_k:

* a simple eigenvalue: the smaller of the normwise and the componentwise first-order bounds,
  κ·max(η, ε) and κ_c·max(η_c, ε) (:mod:`mbseig.eigen.measures`; both are valid, the second is
  much sharper for badly scaled models and exact zero patterns);
* a cluster (eigenvalues whose error discs of radius safety·err overlap, e.g. a defective double
  root computed as two eigenvalues √ε apart, or a near-real complex pair): first-order bounds are
  invalid there (κ = ∞ for an exactly defective one), so every member gets
  err = spread + S·max(η, ε)^{1/b} — the distance of the members from their mean plus the
  Hölder-type bound of a Jordan block of size b = ⌈k/g⌉ (k members, g independent eigenvectors,
  S = max(|mean|, √(‖Q‖/‖M‖))); a semisimple cluster (b = 1) keeps spread + its first-order
  bound.

The structured paths (``eigh``, ``proportional``) compute δ = (α + βω²)/2 from an accurate ω² and
supply a sharper bound of the error of Re s, which replaces err in the δ test (not in the
rigid-body and real tests).  So "δ = 0" means "zero within the numerical error of this
eigenvalue", and the tolerance of each verdict is recorded per mode: a computed eigenvalue with
Re s above its bound is never called critical or rigid-body.  Kinds: ``rigid-body`` (|s| ≤ tol: s
= 0 lies within its bound), ``oscillatory`` (complex, δ ≥ −tol), ``flutter`` (complex, δ < −tol),
``overdamped`` (real, negative), ``divergence`` (real, positive); |ω| ≤ tol counts as real.

Listing (real M, P, Q): a complex-conjugate pair once (ω > 0), real eigenvalues each; a pair with
|ω| within its tolerance (a defective or nearly defective double root, e.g. critical damping)
counts as two real eigenvalues and is listed twice with ω = 0; the rigid-body eigenvalues (s = 0,
double when P x = 0) are listed once per independent vector, the member with the largest Re s
first (a ±ε divergence pair shows its positive member).  Complex M, P, Q: every eigenvalue is
listed (no conjugate pairs).  Sorted by ω_n, then δ, then ω (deterministic).

Every listing accounts for the 2n eigenvalues of an n-DOF problem (:attr:`Modes.accounting`):
listed modes (a pair counts 2) + rigid-body eigenvalues + infinite ones = 2n; a dense listing
that does not (or a zero eigenvalue of higher multiplicity than twice its independent vectors:
secular growth tᵏ that no listed mode shows) is refused with :class:`~mbseig.errors.SolverError`.
A partial spectrum lists what it computed: its verdict is "of the modes computed" and
:attr:`Modes.coverage` says which part of the s-plane that is.
"""

from __future__ import annotations

import math
import warnings
from dataclasses import dataclass, field

import numpy as np
import scipy.linalg as sla
import scipy.sparse as sp

from .eigen import EPS, Problem, Request, SingularPencilError, solve
from .errors import SolverError
from .linear import LinearModel

__all__ = ["Modes", "Verdict", "modes", "STABILITY_ORDER", "tolerances", "stability", "worst"]

STABILITY_ORDER = {"stable": 0, "critical": 1, "unstable": 2}
DENSE_MAX = 5000  # sparse input above this size needs a partial-spectrum request
BAND_DENSE_MAX = 2000  # a band of a model up to this size is listed from the dense solution


class Verdict(str):
    """The verdict word ("stable", "critical" or "unstable"): it compares equal to, and is written
    to JSON as, the word; ``scope`` says what it covers ("" for the full spectrum, "of the modes
    computed (...)" for a partial one), and ``str()``/formatting give the word with its scope."""

    def __new__(cls, word, scope=""):
        obj = super().__new__(cls, word)
        obj.scope = scope
        return obj

    @property
    def word(self) -> str:
        return str.__str__(self)

    def __str__(self):
        return f"{self.word} {self.scope}" if self.scope else self.word

    def __format__(self, spec):
        return format(str(self), spec)


@dataclass(frozen=True, eq=False)
class Modes:
    """Listed modes of M s² + P s + Q with per-mode errors, tolerances and classification."""

    eigenvalues: np.ndarray
    delta: np.ndarray
    omega_n: np.ndarray
    omega_d: np.ndarray
    freq_hz: np.ndarray
    zeta: np.ndarray
    stability: list
    kind: list
    backward_error: np.ndarray
    condition: np.ndarray
    error_estimate: np.ndarray
    tolerance: np.ndarray
    vectors: np.ndarray  # reduced coordinates, one column per listed mode
    shapes: np.ndarray  # full coordinates q = N x, normalized to max |component| = 1
    dominant: list  # per mode: [(coordinate name, |component|), ...]
    verdict: str
    solver: str
    solver_reason: str
    n_infinite: int
    all_eigenvalues: np.ndarray
    tolerances: dict = field(default_factory=dict)
    left_vectors: object = None  # conjugated left vectors ȳ of the listed modes (or None)
    multiplicity: np.ndarray = None  # eigenvalues each listed mode stands for (pair 2, real 1)
    accounting: dict = field(default_factory=dict)  # every eigenvalue accounted (module doc)
    coverage: str = ""  # partial spectrum: what was computed ("" for the full spectrum)
    partial: bool = False
    complex_problem: bool = False
    flags: list = field(default_factory=list)  # per mode: notes ("η above eta_warn", ...)

    def __len__(self):
        return self.eigenvalues.size

    @property
    def freq_n_hz(self) -> np.ndarray:
        """Natural frequencies ω_n/2π = |s|/2π (Hz); ``freq_hz`` is the damped ω_d/2π."""
        return self.omega_n / (2 * np.pi)

    def __repr__(self):
        n = len(self)
        scope = f", {self.coverage}" if self.coverage else ""
        if n == 0:
            return f"<Modes: none listed, verdict {self.verdict}, solver {self.solver}{scope}>"
        lo, hi = float(np.min(self.freq_n_hz)), float(np.max(self.freq_n_hz))
        return (f"<Modes: {n} listed, f_n {lo:.4g} … {hi:.4g} Hz, verdict {self.verdict}, "
                f"solver {self.solver}{scope}>")

    def to_dataframe(self):
        """The listed modes as a pandas DataFrame, one row a mode (index: mode number from 1):
        eigenvalue parts, δ, ω_n, ω_d, f_n, f_d, ζ, stability, kind, η, κ, tolerance, dominant
        coordinates.  pandas is optional: ImportError with the install hint when missing."""
        try:
            import pandas as pd
        except ImportError:
            raise ImportError("Modes.to_dataframe needs pandas (pip install pandas)") from None
        n = len(self)
        return pd.DataFrame({
            "re": self.eigenvalues.real, "im": self.eigenvalues.imag, "delta": self.delta,
            "omega_n": self.omega_n, "omega_d": self.omega_d, "freq_n_hz": self.freq_n_hz,
            "freq_hz": self.freq_hz, "zeta": self.zeta, "stability": list(self.stability),
            "kind": list(self.kind), "backward_error": self.backward_error,
            "condition": self.condition, "tolerance": self.tolerance,
            "dominant": [", ".join(nm for nm, _ in d) for d in self.dominant],
        }, index=pd.RangeIndex(1, n + 1, name="mode"))

    def table(self) -> str:
        """Readable fixed-width table of the listed modes."""
        head = (f"{'#':>3} {'Re s':>13} {'Im s':>13} {'delta':>11} {'omega_n':>11} "
                f"{'f_n [Hz]':>11} {'f_d [Hz]':>11} "
                f"{'zeta':>10} {'eta':>8}  {'stability':<9} {'kind':<11} dominant")
        rows = [head, "-" * len(head)]
        for k in range(len(self)):
            s = self.eigenvalues[k]
            dom = ", ".join(f"{nm}" for nm, _ in self.dominant[k][:3])
            note = f"  [{'; '.join(self.flags[k])}]" if self.flags and self.flags[k] else ""
            rows.append(
                f"{k + 1:>3} {s.real:>13.6g} {s.imag:>13.6g} {self.delta[k]:>11.4g} "
                f"{self.omega_n[k]:>11.6g} {self.freq_n_hz[k]:>11.6g} {self.freq_hz[k]:>11.6g} "
                f"{self.zeta[k]:>10.3g} "
                f"{self.backward_error[k]:>8.1e}  {self.stability[k]:<9} {self.kind[k]:<11} {dom}{note}"
            )
        if self.coverage:
            rows.append(f"partial spectrum: {self.coverage}")
        rows.append("f_n = omega_n/2pi = |s|/2pi (natural), f_d = omega_d/2pi (damped; 0 for a "
                    "real eigenvalue)")
        return "\n".join(rows)


def _names(coordinate_names, N, vector, limit=4):
    """Coordinates carrying a null vector: 'x2' or 'x1, x2 (combination 0.707 x1 − 0.707 x2)'."""
    v = np.asarray(vector)
    full = v if N is None else np.asarray(N @ v)
    n = full.size
    names = list(coordinate_names) if coordinate_names is not None else [f"x{k + 1}" for k in range(n)]
    mag = np.abs(full)
    if not mag.size or mag.max() == 0:
        return "?"
    j = int(np.argmax(mag))
    full = full * (np.conj(full[j]) / mag[j]) / np.linalg.norm(full)  # real where it can be
    idx = [i for i in np.argsort(-mag, kind="stable")[:limit] if mag[i] >= 1e-3 * mag.max()]
    if len(idx) == 1:
        return names[idx[0]]
    terms = " ".join(f"{'−' if full[i].real < 0 else '+'} {abs(full[i]):.3g} {names[i]}" for i in idx)
    return f"{', '.join(names[i] for i in idx)} (combination {terms.lstrip('+ ')})"


def modes(M, P=None, Q=None, *, solver: str = "auto", N=None, coordinate_names=None,
          stability_rtol: float = 1e-12, stability_atol: float = 0.0, safety: float = 10.0,
          n_dominant: int = 3, rigid_rank_tol: float = 1e-6, n_modes: int | None = None,
          target: float | None = None, band=None, constraints=None, eta_warn: float = 1e-12,
          **solver_options) -> Modes:
    """Solve and classify the modes of (M s² + P s + Q) x = 0.

    M may be a :class:`~mbseig.linear.LinearModel` instead of a matrix: its M, P, Q, N,
    coordinate names and (large constrained models) constraint Jacobian are used.
    N, coordinate_names : null-space basis and full-coordinate names for mode shapes (q = N x).
    stability_rtol, stability_atol, safety : see the module docstring.
    rigid_rank_tol : relative threshold for counting independent eigenvectors (rigid-body modes,
        Jordan block sizes of clusters).
    n_modes, target, band, constraints : ask for a partial spectrum of sparse matrices (the
        ``partial-*`` paths of :func:`mbseig.eigen.solve_partial`): ``n_modes`` modes nearest the
        angular frequency ``target`` (rad/s, default 0), or every mode with ω_n in
        ``band = (ω_lo, ω_hi)``; ``constraints`` is Φ_q when M, P, Q are in full coordinates.
    eta_warn : a listed mode whose backward errors (normwise and componentwise) both exceed it is
        flagged in :attr:`Modes.flags` and named in a RuntimeWarning.
    Other keywords are the path options of the request (:class:`mbseig.eigen.Request`): those of
    :func:`mbseig.eigen.solve_qep` (``sym_tol``, ``rayleigh_tol``, ``scale``, ``left``,
    ``companion_cond``) or of :func:`mbseig.eigen.solve_partial`.
    """
    if isinstance(M, LinearModel):
        lin = M
        M, P, Q, N, coordinate_names = lin.M, lin.P, lin.Q, lin.N, lin.coordinate_names
        if constraints is None:
            constraints = lin.constraint_jacobian
    if Q is None:
        raise SolverError("modes(M, P, Q) needs Q (or a LinearModel alone)")
    request = Request(solver, n_modes=n_modes, target=target, band=band, options=solver_options)
    problem = Problem(M, P, Q, G=constraints)
    if (band is not None and n_modes is None and target is None and constraints is None
            and Request(solver).family() == "dense"
            and (not sp.issparse(M) or M.shape[0] <= BAND_DENSE_MAX)):
        # a band of a model small enough for the dense path: solve it all, list the band
        full = modes(M, P, Q, solver=solver, N=N, coordinate_names=coordinate_names,
                     stability_rtol=stability_rtol, stability_atol=stability_atol,
                     safety=safety, n_dominant=n_dominant, rigid_rank_tol=rigid_rank_tol,
                     eta_warn=eta_warn, **solver_options)
        return _band(full, band)
    try:
        if (request.family(problem) == "dense" and sp.issparse(M)
                and M.shape[0] > DENSE_MAX):
            raise SolverError(f"{M.shape[0]} unknowns is beyond the dense path (limit "
                              f"{DENSE_MAX}): ask for a partial spectrum (n_modes=, target= or "
                              f"band=; mbseig modes --n-modes K or --band-hz F1 F2)")
        sol = solve(problem, request)
    except SingularPencilError as exc:
        if exc.vector is None:
            raise
        raise SolverError(f"singular pencil: {_names(coordinate_names, N, exc.vector)} "
                          f"has no mass, damping or stiffness (det(M s² + P s + Q) ≡ 0, every s "
                          f"would be an eigenvalue): give it mass or a spring, or remove it") from None
    b = _bounds(sol, safety=safety, stability_rtol=stability_rtol, stability_atol=stability_atol,
                rank_tol=rigid_rank_tol)
    b = _zero_pair_floor(b, sol, M, P, safety)
    return _listing(sol, b, N=N, coordinate_names=coordinate_names, n_dominant=n_dominant,
                    eta_warn=eta_warn,
                    tolerances_used={"stability_rtol": stability_rtol,
                                     "stability_atol": stability_atol, "safety": safety,
                                     "rigid_rank_tol": rigid_rank_tol, "eta_warn": eta_warn})


def _band(md: Modes, band) -> Modes:
    """The modes of a full listing with ω_lo ≤ ω_n ≤ ω_hi: a partial listing (its verdict
    covers those modes only), every eigenvalue of the band found by the dense solve."""
    import dataclasses

    lo, hi = (float(b) for b in band)
    if not (0 <= lo <= hi):
        raise SolverError(f"band must be (ω_lo, ω_hi) with 0 ≤ ω_lo ≤ ω_hi, got {band!r}")
    keep = np.flatnonzero((md.omega_n >= lo) & (md.omega_n <= hi))
    cut = lambda a: None if a is None else (a[..., keep] if np.ndim(a) > 1 else a[keep])
    pick = lambda seq: [seq[k] for k in keep]
    coverage = (f"{keep.size} modes of {md.vectors.shape[0]} DOF; every eigenvalue with "
                f"{lo:.6g} ≤ |s| ≤ {hi:.6g} rad/s found (dense solve of the whole spectrum); "
                f"modes outside were not listed")
    stab = pick(md.stability)
    verdict = Verdict(worst(stab), f"of the modes computed ({coverage})")
    acc = {**md.accounting, "listed_modes": int(keep.size), "band": [lo, hi]}
    return dataclasses.replace(
        md, eigenvalues=cut(md.eigenvalues), delta=cut(md.delta), omega_n=cut(md.omega_n),
        omega_d=cut(md.omega_d), freq_hz=cut(md.freq_hz), zeta=cut(md.zeta), stability=stab,
        kind=pick(md.kind), backward_error=cut(md.backward_error), condition=cut(md.condition),
        error_estimate=cut(md.error_estimate), tolerance=cut(md.tolerance),
        vectors=md.vectors[:, keep], shapes=md.shapes[:, keep], dominant=pick(md.dominant),
        verdict=verdict, left_vectors=None if md.left_vectors is None else md.left_vectors[:, keep],
        multiplicity=None if md.multiplicity is None else md.multiplicity[keep],
        accounting=acc, coverage=coverage, partial=True,
        flags=pick(md.flags) if md.flags else md.flags)


# ---------------------------------------------------------------------------------------------
# error bounds and tolerances
# ---------------------------------------------------------------------------------------------
def _frequency_scale(norms):
    nM, nP, nQ = norms
    if nM > 0 and nQ > 0:
        return math.sqrt(nQ / nM)
    if nM > 0 and nP > 0:
        return nP / nM
    if nP > 0 and nQ > 0:
        return nQ / nP
    return 1.0


def _rank(X, rank_tol):
    """Numerical rank of the columns of X (pivoted QR, relative pivot threshold)."""
    if X.shape[1] == 0:
        return 0
    Xn = X / np.maximum(np.linalg.norm(X, axis=0), np.finfo(float).tiny)
    R = sla.qr(Xn, mode="r", pivoting=True)[0]
    d = np.abs(np.diag(R))
    return int(np.sum(d > rank_tol * d[0])) if d.size and d[0] > 0 else 0


def _nullity(sol, mean, spread, scale, max_order=2000):
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
    a = abs(mu)
    if a > 1:  # reversed: T(μ)/μ² and T′(μ)/μ, the same ratios without overflow
        t = 1.0 / mu
        T, Td, r = M + t * P + (t * t) * Q, 2 * M + t * P, spread / gamma / a
    else:
        T, Td, r = (mu * mu) * M + mu * P + Q, 2 * mu * M + P, spread / gamma
    if not (np.all(np.isfinite(T)) and np.all(np.isfinite(Td))):
        return 0
    sv = np.linalg.svd(T, compute_uv=False)
    thr = 10 * (r + np.sqrt(EPS) * scale / gamma / max(a, 1.0)) * np.linalg.norm(Td) \
        + 1e3 * EPS * sv[0]
    return int(np.sum(sv <= thr))


def _components(n, pairs):
    """Connected components (labels) of the graph on n nodes with the given edges."""
    parent = np.arange(n)

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
class _Bounds:
    err: np.ndarray  # error bound of s
    tol: np.ndarray  # tolerance for the rigid-body and real tests
    tol_re: np.ndarray  # tolerance for the δ test
    rigid: np.ndarray
    cluster: np.ndarray  # cluster label per eigenvalue (its own index when alone)
    block: np.ndarray  # estimated Jordan block size of the eigenvalue's cluster
    geometric: np.ndarray = None  # independent eigenvectors of the eigenvalue's cluster


class _AllPairs:
    """The two cKDTree queries :func:`_bounds` uses, by all pairs: for the few eigenvalues of a
    small model this is faster than importing scipy.spatial (≈ 0.1 s of start-up)."""

    def __init__(self, points):
        self.z = points[:, 0] + 1j * points[:, 1]

    def query(self, points, k=2):
        z = points[:, 0] + 1j * points[:, 1]
        d = np.sort(np.abs(z[:, None] - self.z[None, :]), axis=1)[:, :k]
        return d, None

    def query_ball_point(self, x, r):
        x = np.asarray(x, float)
        single = x.ndim == 1
        x = np.atleast_2d(x)
        d = np.abs((x[:, 0] + 1j * x[:, 1])[:, None] - self.z[None, :])
        r = np.broadcast_to(np.asarray(r, float), (x.shape[0],))
        out = [np.flatnonzero(d[i] <= r[i]).tolist() for i in range(x.shape[0])]
        return out[0] if single else out


def _neighbour_index(points, small=256):
    """Nearest-neighbour queries on the eigenvalues: all pairs for a small spectrum, a k-d tree
    (scipy.spatial, imported here: off the start-up path) above."""
    if points.shape[0] <= small:
        return _AllPairs(points)
    from scipy.spatial import cKDTree

    return cKDTree(points)


def _bounds(sol, *, safety=10.0, stability_rtol=1e-12, stability_atol=0.0, rank_tol=1e-6):
    """Error bounds, tolerances and clusters of every eigenvalue of ``sol`` (module docstring)."""
    s = np.asarray(sol.eigenvalues)
    k = s.size
    eta = np.maximum(np.asarray(sol.backward_error, float), EPS)
    with np.errstate(over="ignore", invalid="ignore"):
        err = np.asarray(sol.condition, float) * eta
    err = np.where(np.isnan(err), np.inf, err)
    scale = _frequency_scale(sol.norms)
    S = np.maximum(np.abs(s), scale)
    holder2 = S * np.sqrt(eta)
    # componentwise bounds where the normwise one does not separate s from 0, from the real axis
    # or from its neighbours (computed only there: they cost a product with |M|, |P|, |Q|)
    if k > 1:  # the tree on s / max|s|: squared distances of |s| ~ 1e300 would overflow
        unit = float(np.max(np.abs(s))) or 1.0
        points = np.column_stack([s.real, s.imag]) / unit
        tree = _neighbour_index(points)
        near = tree.query(points, k=2)[0][:, 1] * unit
    else:
        near = np.full(k, np.inf)
    # (an exactly zero Re s is critical whatever the bound: no need to sharpen it for that)
    gaps = [np.abs(s), np.where(s.real != 0, np.abs(s.real), np.inf),
            np.where(s.imag != 0, np.abs(s.imag), np.inf), near]
    undecided = safety * err >= np.minimum.reduce(gaps)
    idx = np.flatnonzero(undecided)
    if idx.size:
        eta_c, kappa_c = sol.componentwise(idx)
        with np.errstate(over="ignore", invalid="ignore"):
            err_c = kappa_c * np.maximum(eta_c, EPS)
        err_c = np.where(np.isnan(err_c), np.inf, err_c)
        err[idx] = np.minimum(err[idx], err_c)
    # linking radius: the first-order bound, but where other eigenvalues lie within it (first
    # order is then unreliable) no more than the Hölder radius S·η^{1/k} of a block of all k of
    # them; an infinite bound (an exactly defective pair) links within the double's S·√η
    radius = np.where(np.isfinite(err), err, holder2)
    cluster = np.arange(k)
    block = np.ones(k, int)
    if k > 1:
        finite = np.flatnonzero(np.isfinite(err) & (err > 0))
        if finite.size:
            reach = np.minimum(safety * err[finite] / unit, 4.0)
            counts = np.array([len(c) for c in tree.query_ball_point(points[finite], reach)])
            holder_k = S[finite] * eta[finite] ** (1.0 / np.maximum(counts, 1))
            radius[finite] = np.where(counts > 1, np.minimum(err[finite], holder_k), err[finite])
        pairs = set()
        reach = np.minimum(2 * safety * radius / unit, 4.0)  # beyond 4 max|s|: everything
        for i in range(k):  # radius 0 still finds exact duplicates
            for j in tree.query_ball_point(points[i], reach[i]):
                if j != i and abs(s[i] - s[j]) <= safety * (radius[i] + radius[j]):
                    pairs.add((min(i, j), max(i, j)))
        cluster = _components(k, pairs)
    err = err.copy()
    labels, inverse, counts = np.unique(cluster, return_inverse=True, return_counts=True)
    alone = (counts[inverse] == 1) & ~np.isfinite(err)  # κ = ∞ alone: a defective root, Hölder
    err[alone], block[alone] = holder2[alone], 2
    geometric = np.ones(k, int)
    for c in labels[counts > 1]:
        members = np.flatnonzero(cluster == c)
        mean0 = np.mean(s[members])
        spread0 = float(np.max(np.abs(s[members] - mean0)))
        g = max(_rank(sol.vectors[:, members], rank_tol),
                _nullity(sol, mean0, spread0, max(abs(mean0), scale)))
        g = min(g, members.size)
        geometric[members] = g
        b = max(1, math.ceil(members.size / max(g, 1)))
        mean = np.mean(s[members])
        spread = float(np.max(np.abs(s[members] - mean)))
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
        clustered = block > 1  # the path's Re s bound is first order: not inside a defective cluster
        re_bound = np.where(clustered, err, np.minimum(err, re_err))
        tol_re = np.maximum.reduce([safety * re_bound, *floor])
    return _Bounds(err, tol, tol_re, np.abs(s) <= tol, cluster, block, geometric)


def _zero_pair_floor(b, sol, M, P, safety, nQ=None, gamma=1.0):
    """Near s = 0, an undamped eigenvalue comes from s² = −ω² with ω² a small difference of
    stiffness terms: an ε-relative error of Q (its formation Nᵀ K N, rounding of K) moves ω² by
    up to ε‖Q‖‖x‖²/|xᴴMx| and s by the square root of that, which no first-order bound sees.  For
    an eigenvalue whose damping term is below its inertia term (|xᴴPx| ≤ |s||xᴴMx|, the ±√ω²
    structure), the error bound is raised to that Hölder radius,
    h = √(max(η, ε) ‖Q‖_F ‖x‖² / |xᴴMx|),  with the mode's own modal mass (a light body's spin
    has a far larger h than the global √(ε‖Q‖/‖M‖)); s within safety·h of 0 is then rigid-body
    (critical).  An eigenvalue beyond it keeps its verdict."""
    import dataclasses

    s = np.asarray(sol.eigenvalues)
    if s.size == 0 or sol.complex_problem or sol.vectors is None or M is None:
        return b
    scale = _frequency_scale(sol.norms)
    cand = np.flatnonzero(np.abs(s) <= 1e-3 * scale)
    if cand.size == 0:
        return b
    nQ = float(sol.norms[2]) if nQ is None else nQ
    s = s / gamma  # M, P, Q of a problem scaled by s = γ μ: work in μ, radius back in s
    eta = np.maximum(np.asarray(sol.backward_error, float), EPS)
    err, tol, tol_re, rigid = b.err.copy(), b.tol.copy(), b.tol_re.copy(), b.rigid.copy()
    Mm = M if sp.issparse(M) else np.asarray(M)
    Pm = None if P is None else (P if sp.issparse(P) else np.asarray(P))
    for k in cand:
        x = sol.vectors[:, k]
        if x.shape[0] != Mm.shape[0]:
            return b
        mx = abs(np.vdot(x, Mm @ x))
        px = 0.0 if Pm is None else abs(np.vdot(x, Pm @ x))
        if mx == 0 or px > abs(s[k]) * mx:
            continue
        h = math.sqrt(eta[k] * nQ * float(np.vdot(x, x).real) / mx)
        s_k, h = s[k] * gamma, h * gamma
        if abs(s_k) <= safety * h:
            err[k] = max(err[k], h)
            tol[k] = max(tol[k], safety * h)
            tol_re[k] = max(tol_re[k], safety * h)
            rigid[k] = True
    return dataclasses.replace(b, err=err, tol=tol, tol_re=tol_re, rigid=rigid)


def tolerances(sol, *, safety=10.0, stability_rtol=1e-12, stability_atol=0.0, rank_tol=1e-6):
    """(err, tol, tol_re, rigid) per eigenvalue of a :class:`~mbseig.eigen.QEPSolution`.

    err: error bound of s (first order, normwise or componentwise, or the cluster bound of a
    defective or nearly defective cluster: module docstring); tol = max(safety·err,
    stability_rtol·|s|, stability_atol) for the rigid-body and real tests, tol_re the same with
    the path's sharper bound of Re s where it has one (the δ test), rigid: |s| ≤ tol, with the
    zero-pair floor of :func:`_zero_pair_floor` (from the problem the pairs refer to).  The one
    definition used by :func:`modes` and by the sweeps.
    """
    b = _bounds(sol, safety=safety, stability_rtol=stability_rtol, stability_atol=stability_atol,
                rank_tol=rank_tol)
    prob = sol.problem
    if isinstance(prob, tuple) and len(prob) == 4:  # the zero-pair floor, as modes() applies it
        Ms, Ps, Qs, gamma = prob
        nQs = float(np.linalg.norm(Qs.tocsr().data) if sp.issparse(Qs) else np.linalg.norm(Qs))
        b = _zero_pair_floor(b, sol, Ms, Ps, safety, nQ=nQs, gamma=float(gamma))
    return b.err, b.tol, b.tol_re, b.rigid


def stability(delta, tol_re, rigid) -> list:
    """stable / critical / unstable per eigenvalue: δ against its tolerance; rigid-body modes
    (s = 0 within its error) are critical."""
    return ["critical" if r else "stable" if d > t else "unstable" if d < -t else "critical"
            for d, t, r in zip(delta, tol_re, rigid)]


def worst(stabilities) -> str:
    """The verdict over modes: the worst of their stabilities ("stable" for none)."""
    return max(stabilities, key=STABILITY_ORDER.get) if len(stabilities) else "stable"


# ---------------------------------------------------------------------------------------------
# listing
# ---------------------------------------------------------------------------------------------
def _rigid_representatives(sol, rigid_idx, rank_tol):
    """One rigid-body eigenvalue per independent vector, the largest Re s first (greedy)."""
    order = rigid_idx[np.lexsort((-sol.eigenvalues[rigid_idx].imag, -sol.eigenvalues[rigid_idx].real))]
    chosen, basis = [], None
    for i in order:
        v = sol.vectors[:, i]
        v = v / max(np.linalg.norm(v), np.finfo(float).tiny)
        r = v if basis is None else v - basis @ (basis.conj().T @ v)
        if np.linalg.norm(r) > rank_tol:
            chosen.append(i)
            r = r / np.linalg.norm(r)
            basis = r[:, None] if basis is None else np.column_stack([basis, r])
    return np.array(sorted(chosen), int)


def _listing(sol, b, *, N, coordinate_names, n_dominant, eta_warn, tolerances_used):
    s_all = sol.eigenvalues
    err_all, tol_all, tol_re_all, rigid = b.err, b.tol, b.tol_re, b.rigid
    real_problem = not sol.complex_problem
    near_real = (~rigid) & (np.abs(s_all.imag) <= tol_all)
    if real_problem:
        listed = (~rigid) & ((s_all.imag > 0) | near_real)
    else:
        listed = ~rigid
    rigid_idx = np.flatnonzero(rigid)
    rep = _rigid_representatives(sol, rigid_idx, tolerances_used["rigid_rank_tol"]) \
        if rigid_idx.size else np.zeros(0, int)
    listed[rep] = True
    g_rigid = int(np.max(b.geometric[rigid], initial=0)) if b.geometric is not None else 0
    accounting = _account(sol, rigid, near_real, listed, rep, g_rigid)
    sel = np.flatnonzero(listed)
    s = s_all[sel].copy()
    eta, kappa, X = sol.backward_error[sel], sol.condition[sel], sol.vectors[:, sel]
    Y = None if sol.left_vectors is None else sol.left_vectors[:, sel]
    is_rigid, real_listed = rigid[sel], near_real[sel]
    mult = np.where(is_rigid, 0, np.where(real_listed | ~real_problem, 1, 2))
    if rep.size:  # the rigid-body eigenvalues, shared out over the listed rigid modes
        share = np.full(rep.size, accounting["rigid_eigenvalues"] // rep.size)
        share[: accounting["rigid_eigenvalues"] % rep.size] += 1
        mult[is_rigid] = share
    flip = real_problem & (s.imag < 0)  # a rigid or near-real member below the axis
    if np.any(flip):
        s = np.where(flip, np.conj(s), s)
        X = X.astype(complex)
        X[:, flip] = np.conj(X[:, flip])
        if Y is not None:
            Y = Y.astype(complex)
            Y[:, flip] = np.conj(Y[:, flip])
    if real_problem:  # a near-real pair: two real eigenvalues within tolerance, listed with ω = 0
        s = np.where(real_listed, s.real + 0j, s)
    err, tol, tol_s = err_all[sel], tol_all[sel], tol_re_all[sel]
    delta, omega = 0.0 - s.real, s.imag  # 0.0 − x: no negative zeros in reports
    wn = np.abs(s)
    order = np.lexsort((omega, delta, wn))
    s, eta, kappa, X, err, tol, tol_s, delta, omega, wn, is_rigid, mult = (
        a[..., order] for a in (s, eta, kappa, X, err, tol, tol_s, delta, omega, wn, is_rigid, mult))
    sel = sel[order]
    Y = None if Y is None else Y[:, order]
    stability_ = stability(delta, tol_s, is_rigid)
    kind = []
    for k in range(s.size):
        if is_rigid[k]:
            kd = "rigid-body"
        elif abs(omega[k]) <= tol[k]:
            kd = "overdamped" if delta[k] > 0 else "divergence"
        else:
            kd = "flutter" if stability_[k] == "unstable" else "oscillatory"
        kind.append(kd)
    with np.errstate(divide="ignore", invalid="ignore"):
        zeta = np.where((wn > 0) & ~is_rigid, delta / np.where(wn > 0, wn, 1.0), 0.0)
    shapes, dominant = _shapes(X, N, coordinate_names, n_dominant)
    flags = [[] for _ in range(s.size)]
    bad = np.flatnonzero(eta > eta_warn)
    if bad.size:
        eta_c = sol.componentwise(sel[bad])[0]
        bad = bad[eta_c > eta_warn]
    for k in bad:
        flags[k].append(f"η = {eta[k]:.1e} above {eta_warn:g}")
    if bad.size:
        names_ = ", ".join(f"{z.real:.6g}{z.imag:+.6g}j (η={e:.1e})"
                           for z, e in zip(s[bad][:8], eta[bad][:8]))
        warnings.warn(f"{bad.size} eigenvalues miss the backward-error target {eta_warn:g} "
                      f"({sol.solver}): {names_}", RuntimeWarning, stacklevel=3)
    coverage = _coverage_text(sol, len(s)) if sol.partial else ""
    verdict = Verdict(worst(stability_), f"of the modes computed ({coverage})" if sol.partial else "")
    numeric_details = {k: v for k, v in sol.details.items()}
    return Modes(
        eigenvalues=s, delta=delta, omega_n=wn, omega_d=omega, freq_hz=omega / (2 * np.pi),
        zeta=zeta, stability=stability_, kind=kind, backward_error=eta, condition=kappa,
        error_estimate=err, tolerance=tol_s, vectors=X, shapes=shapes, dominant=dominant,
        verdict=verdict, solver=sol.solver, solver_reason=sol.reason, n_infinite=sol.n_infinite,
        all_eigenvalues=s_all, tolerances={**tolerances_used, **numeric_details},
        left_vectors=Y, multiplicity=mult, accounting=accounting, coverage=coverage,
        partial=sol.partial, complex_problem=sol.complex_problem, flags=flags)


def _account(sol, rigid, near_real, listed, rep, g_rigid=0):
    """Every eigenvalue accounted for, or SolverError (a dense listing; module docstring).
    ``g_rigid``: independent eigenvectors of s = 0 from T(0)'s nullity (may exceed the computed
    vectors' rank for a derogatory zero)."""
    s = sol.eigenvalues
    n_rigid = int(np.sum(rigid))
    out = {"eigenvalues": 2 * sol.n_dof if not sol.partial else None,
           "finite": int(s.size), "infinite": int(sol.n_infinite),
           "rigid_eigenvalues": n_rigid, "rigid_modes": int(rep.size), "complete": True}
    g = max(rep.size, g_rigid)
    if n_rigid > 2 * g:
        raise SolverError(
            f"s = 0 has {n_rigid} eigenvalues but only {g} independent rigid-body vectors: "
            f"a zero eigenvalue of higher order than a free motion (secular growth t^k, or a "
            f"degenerate model); no listing can account for it")
    if not sol.complex_problem:
        upper = (~rigid) & (~near_real) & (s.imag > 0)
        lower = (~rigid) & (~near_real) & (s.imag < 0)
        if int(upper.sum()) != int(lower.sum()):
            raise SolverError(f"{int(upper.sum())} eigenvalues above the real axis but "
                              f"{int(lower.sum())} below: the listing of a real problem would "
                              f"not account for every eigenvalue")
    if not sol.partial and s.size + sol.n_infinite != 2 * sol.n_dof:
        out["complete"] = False
        raise SolverError(f"{sol.solver}: {s.size} finite + {sol.n_infinite} infinite eigenvalues "
                          f"for {sol.n_dof} DOF (expected {2 * sol.n_dof}): the listing is "
                          f"incomplete, no verdict")
    out["listed_modes"] = int(np.sum(listed))
    return out


def _coverage_text(sol, n_listed):
    c = sol.coverage or {}
    lo, hi = c.get("omega_n", (math.nan, math.nan))
    what = c.get("measure", "|s|")
    text = f"{n_listed} modes of {c.get('dof', sol.n_dof)} DOF; "
    if c.get("verified", True):
        text += f"every eigenvalue with {lo:.6g} ≤ {what} ≤ {hi:.6g} rad/s found"
    else:
        text += f"the range {lo:.6g} ≤ {what} ≤ {hi:.6g} rad/s could not be verified complete"
    if c.get("note"):
        text += f"; {c['note']}"
    return text + "; modes outside were not computed"


def _shapes(X, N, coordinate_names, n_dominant):
    full = X if N is None else N @ X
    n_full = full.shape[0]
    names = list(coordinate_names) if coordinate_names is not None else [f"q{k + 1}" for k in range(n_full)]
    shapes = np.zeros_like(full)
    dominant = []
    for k in range(full.shape[1]):
        v = full[:, k]
        j = int(np.argmax(np.abs(v)))
        shapes[:, k] = v / v[j] if v[j] != 0 else v
        mag = np.abs(shapes[:, k])
        if mag.size > 4 * n_dominant:  # large models: the top entries without a full sort
            cand = np.argpartition(-mag, n_dominant)[:n_dominant]
            top = cand[np.lexsort((cand, -mag[cand]))]
        else:
            top = np.argsort(-mag, kind="stable")[:n_dominant]
        dominant.append([(names[i], float(mag[i])) for i in top if mag[i] >= 0.05])
    return shapes, dominant
