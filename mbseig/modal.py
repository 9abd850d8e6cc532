"""Stage 4: modes and their stability (docs/design.md, "Tolerances").

For an eigenvalue s_k = −δ_k + iω_k:  ω_n = |s|,  ζ = δ/|s|,  f = ω/2π, and

    δ > tol_k  stable,   |δ| ≤ tol_k  critical,   δ < −tol_k  unstable,

    tol_k = max(safety · κ_k · max(η_k, ε),  stability_rtol · |s_k|,  stability_atol)

where κ_k·η_k is the first-order error bound of s_k (absolute condition number times backward
error, see :mod:`mbseig.eigen.measures`).  The structured paths (``eigh``, ``proportional``) compute
δ = (α + βω²)/2 from an accurate ω² and supply a sharper bound of the error of Re s, which
replaces κ·η in the δ test (not in the rigid-body and real tests).  So "δ = 0" means "zero within
the numerical error of this eigenvalue", and the tolerance of each verdict is recorded per mode.  Kinds: ``rigid-body`` (|s| ≤ tol),
``oscillatory`` (complex, δ ≥ −tol), ``flutter`` (complex, δ < −tol), ``overdamped`` (real,
negative), ``divergence`` (real, positive); |ω| ≤ tol counts as real.

Listing: a complex-conjugate pair once (ω > 0), real eigenvalues each (a pair with |ω| within
its tolerance, e.g. critical damping, counts as two real eigenvalues), a rigid-body mode once per
independent vector; sorted by ω_n, then δ, then ω (deterministic).
"""

from __future__ import annotations

import warnings
from dataclasses import dataclass, field

import numpy as np
import scipy.linalg as sla
import scipy.sparse as sp

from .eigen import EPS, SOLVERS, solve_partial, solve_qep
from .errors import SolverError
from .linear import LinearModel

__all__ = ["Modes", "modes", "STABILITY_ORDER", "tolerances", "stability", "worst"]

STABILITY_ORDER = {"stable": 0, "critical": 1, "unstable": 2}
DENSE_MAX = 5000  # sparse input above this size needs a partial-spectrum request


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

    def __len__(self):
        return self.eigenvalues.size

    def table(self) -> str:
        """Readable fixed-width table of the listed modes."""
        head = (f"{'#':>3} {'Re s':>13} {'Im s':>13} {'delta':>11} {'omega_n':>11} {'f [Hz]':>11} "
                f"{'zeta':>10} {'eta':>8}  {'stability':<9} {'kind':<11} dominant")
        rows = [head, "-" * len(head)]
        for k in range(len(self)):
            s = self.eigenvalues[k]
            dom = ", ".join(f"{nm}" for nm, _ in self.dominant[k][:3])
            rows.append(
                f"{k + 1:>3} {s.real:>13.6g} {s.imag:>13.6g} {self.delta[k]:>11.4g} "
                f"{self.omega_n[k]:>11.6g} {self.freq_hz[k]:>11.6g} {self.zeta[k]:>10.3g} "
                f"{self.backward_error[k]:>8.1e}  {self.stability[k]:<9} {self.kind[k]:<11} {dom}"
            )
        return "\n".join(rows)


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
    rigid_rank_tol : relative pivot threshold for counting independent rigid-body vectors.
    n_modes, target, band, constraints : ask for a partial spectrum of sparse matrices (the
        ``partial-*`` paths of :func:`mbseig.eigen.solve_partial`): ``n_modes`` modes nearest the
        angular frequency ``target`` (rad/s, default 0), or every mode with ω_n in
        ``band = (ω_lo, ω_hi)``; ``constraints`` is Φ_q when M, P, Q are in full coordinates.
    eta_warn : a listed mode whose backward error exceeds it is named in a RuntimeWarning.
    Other keywords go to :func:`mbseig.eigen.solve_qep` (``sym_tol``, ``rayleigh_tol``, ``scale``,
    ``left``) or to :func:`mbseig.eigen.solve_partial`.
    """
    if isinstance(M, LinearModel):
        lin = M
        M, P, Q, N, coordinate_names = lin.M, lin.P, lin.Q, lin.N, lin.coordinate_names
        if constraints is None:
            constraints = lin.constraint_jacobian
    if Q is None:
        raise SolverError("modes(M, P, Q) needs Q (or a LinearModel alone)")
    path = SOLVERS.get(solver)
    partial = (n_modes is not None or target is not None or band is not None
               or constraints is not None or (path is not None and path.partial))
    if partial:
        sol = solve_partial(M, P, Q, n_modes=n_modes, target=target, band=band, G=constraints,
                            solver=solver, **solver_options)
    else:
        if sp.issparse(M) and M.shape[0] > DENSE_MAX:
            raise SolverError(f"{M.shape[0]} unknowns is beyond the dense path (limit {DENSE_MAX}): "
                              f"ask for a partial spectrum (n_modes=, target= or band=; "
                              f"mbseig modes --n-modes K or --band-hz F1 F2)")
        sol = solve_qep(M, P, Q, solver=solver, **solver_options)
    s_all = sol.eigenvalues
    err_all, tol_all, tol_re, rigid = tolerances(sol, safety=safety, stability_rtol=stability_rtol,
                                                 stability_atol=stability_atol)
    # a complex pair is listed once (ω > 0; real LAPACK drivers return exact conjugates) and a
    # real eigenvalue on its own; a rigid-body mode (s = 0, double when P x = 0) is listed once
    # per independent vector: as many as the rank of the rigid eigenvectors.
    # a pair whose |ω| is within its tolerance counts as two real eigenvalues (a defective or
    # nearly defective double root, e.g. critical damping) and is listed twice, ω ≥ 0 each
    listed = (~rigid) & ((s_all.imag >= 0) | (np.abs(s_all.imag) <= tol_all))
    rigid_idx = np.flatnonzero(rigid)
    if rigid_idx.size:
        R = sol.vectors[:, rigid_idx]
        _, sv, piv = sla.qr(R, mode="economic", pivoting=True)
        d = np.abs(np.diag(sv))
        r = int(np.sum(d > rigid_rank_tol * d[0])) if d.size and d[0] > 0 else 0
        listed[rigid_idx[np.sort(piv[:r])]] = True
    sel = np.flatnonzero(listed)
    s = s_all[sel]
    eta, kappa, X = sol.backward_error[sel], sol.condition[sel], sol.vectors[:, sel]
    Y = None if sol.left_vectors is None else sol.left_vectors[:, sel]
    flip = s.imag < 0  # the lower member of a near-real pair: listed as its conjugate
    if np.any(flip):
        s = np.where(flip, np.conj(s), s)
        X = X.astype(complex)
        X[:, flip] = np.conj(X[:, flip])
        if Y is not None:
            Y = Y.astype(complex)
            Y[:, flip] = np.conj(Y[:, flip])
    err, tol, tol_s, is_rigid = err_all[sel], tol_all[sel], tol_re[sel], rigid[sel]
    delta, omega = 0.0 - s.real, s.imag  # 0.0 − x: no negative zeros in reports
    wn = np.abs(s)
    order = np.lexsort((omega, delta, wn))
    s, eta, kappa, X, err, tol, tol_s, delta, omega, wn, is_rigid = (
        a[..., order] for a in (s, eta, kappa, X, err, tol, tol_s, delta, omega, wn, is_rigid))
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
        zeta = np.where(wn > 0, delta / wn, 0.0)
    n_full = X.shape[0] if N is None else N.shape[0]
    full = X if N is None else N @ X
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
    verdict = worst(stability_)
    missed = np.flatnonzero(eta > eta_warn)
    if missed.size:
        names_ = ", ".join(f"{z.real:.6g}{z.imag:+.6g}j (η={e:.1e})"
                           for z, e in zip(s[missed][:8], eta[missed][:8]))
        warnings.warn(f"{missed.size} eigenvalues miss the backward-error target {eta_warn:g} "
                      f"({sol.solver}): {names_}", RuntimeWarning, stacklevel=2)
    return Modes(
        eigenvalues=s, delta=delta, omega_n=wn, omega_d=omega, freq_hz=omega / (2 * np.pi),
        zeta=zeta, stability=stability_, kind=kind, backward_error=eta, condition=kappa,
        error_estimate=err, tolerance=tol_s, vectors=X, shapes=shapes, dominant=dominant,
        verdict=verdict, solver=sol.solver, solver_reason=sol.reason, n_infinite=sol.n_infinite,
        all_eigenvalues=s_all,
        tolerances={"stability_rtol": stability_rtol, "stability_atol": stability_atol,
                    "safety": safety, "rigid_rank_tol": rigid_rank_tol, "eta_warn": eta_warn, **{k: v for k, v in sol.details.items()}},
        left_vectors=Y,
    )


def tolerances(sol, *, safety=10.0, stability_rtol=1e-12, stability_atol=0.0):
    """(err, tol, tol_re, rigid) per eigenvalue of a :class:`~mbseig.eigen.QEPSolution`.

    err = κ·max(η, ε) (first-order error bound), tol = max(safety·err, stability_rtol·|s|,
    stability_atol) for the rigid-body and real tests, tol_re the same with the path's sharper
    bound of Re s where it has one (the δ test), rigid: |s| ≤ tol.  The one definition used by
    :func:`modes` and by the sweeps (module docstring).
    """
    s = sol.eigenvalues
    err = sol.condition * np.maximum(sol.backward_error, EPS)
    floor = [stability_rtol * np.abs(s), np.full(s.size, stability_atol)]
    tol = np.maximum.reduce([safety * err, *floor])
    re_err = sol.real_error
    tol_re = tol if re_err is None else np.maximum.reduce([safety * np.minimum(err, re_err), *floor])
    return err, tol, tol_re, np.abs(s) <= tol


def stability(delta, tol_re, rigid) -> list:
    """stable / critical / unstable per eigenvalue: δ against its tolerance; rigid-body modes
    (s = 0 within its error) are critical."""
    return ["critical" if r else "stable" if d > t else "unstable" if d < -t else "critical"
            for d, t, r in zip(delta, tol_re, rigid)]


def worst(stabilities) -> str:
    """The verdict over modes: the worst of their stabilities ("stable" for none)."""
    return max(stabilities, key=STABILITY_ORDER.get) if len(stabilities) else "stable"
