"""Floquet analysis of time-periodic linear systems: monodromy, multipliers, error bounds, verdict.

The constrained reduction and the shooting are in :mod:`mbseig.studies.floquet_paths`, the
verdict changes along a parameter and the stability chart in :mod:`mbseig.studies.floquet_sweep`.

A linear system with T-periodic coefficients

    x'(t) = A(t) x(t),      A(t + T) = A(t),      x ∈ Rⁿ

has the fundamental matrix X(t) (X' = A X, X(0) = I); its value after one period, the monodromy
matrix Φ = X(T), maps the state at t to the state at t + T.  Its eigenvalues μ are the Floquet
multipliers; every solution grows like |μ|^(t/T) along its Floquet vector.  Eigenvalues of A(t)
frozen at an instant say nothing reliable about stability (a pendulum on a pivot shaken at twice
its natural frequency is stable at every frozen instant and unstable in fact).

Method: the variational equations X' = A(t) X are integrated over one period by
``scipy.integrate.solve_ivp`` (DOP853, or Radau for stiff systems) twice, at two tolerances, as
two independent estimates of Φ.  A Hill (harmonic-balance) determinant would be sharper for
smooth, nearly harmonic coefficients and small n, but it needs A(t) as a Fourier series and
converges slowly for the kinks of a piecewise coefficient (a contact, a Procrustes segment);
direct integration works for any callable A(t) and gives the error estimates used below.
Cost: the state holds n² numbers and a dense A(t) X costs n³ per right-hand side, so one
period costs O(steps · n³) beside the evaluations of A (a periodic case integrates Chebyshev
interpolants of A, :mod:`mbseig.studies.floquet_chebyshev`, so those are few);
:func:`floquet_partial` (Arnoldi on the monodromy operator, one integration of n numbers per
product) costs O(steps · n²) per product and needs p ≥ 2k + 1
products for the k largest |μ|, each of which evaluates A(t) again at every stage: it is faster
only where evaluating A(t) is cheap beside n³ (measured for the projected systems of periodic
cases in benchmarks/periodic_scaling.py and docs/periodic.md).

Error bound of multiplier k (:class:`FloquetResult`, ``error_bounds``) is the largest of

(i)   |μ_k − μ̃_k|, the difference between the two estimates (matched by assignment);
(ii)  κ_k ‖Φ − Φ̃‖₂, the first-order eigenvalue perturbation bound, κ_k = ‖y_k‖‖x_k‖/|y_kᴴ x_k|
      the condition number of μ_k (left and right eigenvectors y_k, x_k);
(iii) |μ_k| ε_L, with ε_L = |det Φ / exp(∫₀ᵀ tr A dt) − 1| the relative mismatch of Liouville's
      identity (the trace integral by adaptive quadrature, independent of the ODE integrator):
      it catches an error common to both estimates;

and a rounding floor 64 ε_mach κ_k ‖Φ‖₂.  A multiplier at a collision (μ = ±1 double, a Jordan
block) has an unbounded κ_k: its bound is then large and the verdict honestly critical.

Verdict: stable when every |μ_k| + b_k < 1, unstable when some |μ_k| − b_k > 1, critical
otherwise; the multiplier that decided it and its margin are recorded.
"""

from __future__ import annotations

import json
import math
from collections.abc import Callable
from dataclasses import dataclass, field

import numpy as np
import scipy.linalg as la
from scipy.integrate import quad, solve_ivp
from scipy.optimize import linear_sum_assignment
from scipy.sparse.linalg import LinearOperator, eigs

from ..errors import CaseError, MbseigError

__all__ = [
    "FloquetError", "LinearPeriodicSystem", "FloquetResult", "monodromy", "floquet",
    "floquet_partial", "PartialFloquetResult", "frozen_time_eigenvalues",
    "DEFAULT_RTOLS", "ATOL_FACTOR",
]

DEFAULT_RTOLS = (1e-10, 1e-12)
MAX_EVALUATIONS = 50_000  # right-hand sides of one integration of the variational equations
ATOL_FACTOR = 1e-3  # atol = ATOL_FACTOR · rtol on the entries of X (|X(0)| = 1)


class FloquetError(MbseigError, RuntimeError):
    """A periodic computation failed: an integration, a shooting Newton, a basis continuation."""


def positive_period(period, what="period"):
    try:
        T = float(period)
    except (TypeError, ValueError):
        raise CaseError(f"{what} must be a positive number, got {period!r}",
                        element="motion.period") from None
    if not (math.isfinite(T) and T > 0):
        raise CaseError(f"{what} must be a positive number, got {period!r}",
                        element="motion.period")
    return T


# ---- the linear periodic system -------------------------------------------------------------
@dataclass(frozen=True)
class LinearPeriodicSystem:
    """x' = A_k(t) x on the segments [t_k, t_{k+1}] of one period, then x ← closing · x.

    One segment and ``closing = None`` is the plain system x' = A(t) x.  Several segments arise
    from a null-space basis continued piecewise (:func:`constrained_system`); ``closing`` is the
    change of basis after one period (the holonomy of the basis), so that

        Φ = closing · X_K(t_K) ··· X_1(t_1)

    maps the state at 0 to the state at T in the same coordinates.  ``trace(t)`` gives tr A(t) for
    Liouville's identity (default: the trace of the segment's A).
    """

    segments: tuple  # ((t0, t1, A), ...), A: t -> (n, n) ndarray
    size: int
    closing: np.ndarray | None = None
    trace: Callable | None = None

    @property
    def period(self) -> float:
        return self.segments[-1][1] - self.segments[0][0]

    @classmethod
    def from_callable(cls, A, period, *, size=None, trace=None):
        T = positive_period(period)
        if size is None:
            A0 = np.asarray(A(0.0), dtype=float)
            if A0.ndim != 2 or A0.shape[0] != A0.shape[1]:
                raise CaseError(f"A(t) must be a square matrix, got shape {A0.shape}",
                                element="A")
            size = A0.shape[0]
        return cls(((0.0, T, A),), int(size), None, trace)

    def trace_integral(self, *, epsabs=1e-13, epsrel=1e-13) -> float:
        """∫₀ᵀ tr A dt by adaptive Gauss–Kronrod quadrature, segment by segment."""
        total = 0.0
        for t0, t1, A in self.segments:
            fn = self.trace if self.trace is not None else (lambda t, A=A: float(np.trace(A(t))))
            val, _ = quad(fn, t0, t1, epsabs=epsabs, epsrel=epsrel, limit=400)
            total += val
        return total


def _as_system(A, period):
    if isinstance(A, LinearPeriodicSystem):
        if period is not None and not math.isclose(float(period), A.period, rel_tol=1e-14):
            raise CaseError(f"period {period!r} differs from the system's {A.period!r}",
                            element="motion.period")
        return A
    if not callable(A):
        raise CaseError("A must be a callable A(t) or a LinearPeriodicSystem", element="A")
    return LinearPeriodicSystem.from_callable(A, period)


def _propagate(A, t0, t1, X0, *, method, rtol):
    """X(t1) for X' = A(t) X, X(t0) = X0 (n×k): one solve_ivp on the flattened matrix."""
    n, k = X0.shape

    calls = [0]

    def rhs(t, y):
        calls[0] += 1
        if calls[0] > MAX_EVALUATIONS:
            raise FloquetError(f"the variational equations from t = {t0:g} to {t1:g} need more "
                               f"than {MAX_EVALUATIONS} evaluations: is the period far longer "
                               "than the motion's time scale?", element="motion.period")
        return (A(t) @ y.reshape(n, k)).ravel()

    jac = None
    if method in ("Radau", "BDF", "LSODA"):
        def jac(t, y):
            return np.kron(np.asarray(A(t), dtype=float), np.eye(k))

    extra = {"jac": jac} if jac is not None else {}
    sol = solve_ivp(rhs, (t0, t1), X0.ravel(), method=method, rtol=rtol,
                    atol=ATOL_FACTOR * rtol, **extra)
    if not sol.success:
        raise FloquetError(f"integration of the variational equations from t = {t0:g} to "
                           f"{t1:g} failed at t = {sol.t[-1]:g}: {sol.message}",
                           element="monodromy")
    return sol.y[:, -1].reshape(n, k), sol.nfev


def monodromy(A, period=None, *, method="DOP853", rtol=1e-12):
    """The monodromy matrix Φ = X(T) of x' = A(t) x (one estimate; :func:`floquet` makes two)."""
    system = _as_system(A, period)
    X = np.eye(system.size)
    for t0, t1, Ak in system.segments:
        X, _ = _propagate(Ak, t0, t1, X, method=method, rtol=rtol)
    if system.closing is not None:
        X = system.closing @ X
    return X


# ---- the result -----------------------------------------------------------------------------
@dataclass(frozen=True)
class FloquetResult:
    """Floquet multipliers of a T-periodic linear system, with error bounds and the verdict.

    multipliers : μ_k, eigenvalues of the monodromy matrix, sorted by |μ| descending, then by
        arg μ ascending (a conjugate pair is listed in full, both members).
    exponents : ln(μ_k)/T, imaginary parts in (−π/T, π/T] (reduced modulo 2π/T).
    error_bounds : b_k per multiplier (module docstring: the largest of the estimate difference,
        the condition-number bound and the Liouville mismatch); ``error_bound`` = max_k b_k.
    verdict : stable / critical / unstable; ``decided_by`` = (k, |μ_k|, b_k, margin) with margin
        = 1 − |μ_k| − b_k (stable, smallest), |μ_k| − b_k − 1 (unstable, largest) or the
        distance of 1 from the interval |μ_k| ± b_k (critical).
    det_check : relative mismatch ε_L = |det Φ / exp ∫ tr A − 1| (Liouville's identity).
    monodromy, monodromy_check : the two estimates (the second at the looser tolerance).
    """

    period: float
    multipliers: np.ndarray
    exponents: np.ndarray
    error_bounds: np.ndarray
    verdict: str
    decided_by: tuple
    det_check: float
    method: str
    tolerances: tuple
    condition: np.ndarray
    estimate_difference: float
    trace_integral: float
    monodromy: np.ndarray = field(repr=False)
    monodromy_check: np.ndarray = field(repr=False)
    floquet_vectors: np.ndarray = field(repr=False, default=None)

    @property
    def error_bound(self) -> float:
        return float(np.max(self.error_bounds)) if self.error_bounds.size else 0.0

    @property
    def spectral_radius(self) -> float:
        return float(np.max(np.abs(self.multipliers)))

    def to_dict(self) -> dict:
        """DESIGN §8 ``"floquet"`` object (and extras: per-multiplier bounds, the checks)."""
        return {
            "period": self.period,
            "multipliers": [[float(m.real), float(m.imag)] for m in self.multipliers],
            "exponents": [[float(e.real), float(e.imag)] for e in self.exponents],
            "error_bound": self.error_bound,
            "verdict": self.verdict,
            "error_bounds": [float(b) for b in self.error_bounds],
            "decided_by": {"index": int(self.decided_by[0]), "modulus": self.decided_by[1],
                           "bound": self.decided_by[2], "margin": self.decided_by[3]},
            "det_check": self.det_check,
            "method": self.method,
            "tolerances": list(self.tolerances),
        }

    def to_json(self, **kw) -> str:
        return json.dumps({"floquet": self.to_dict()}, **kw)


def _sort_order(mu):
    return np.lexsort((np.angle(mu), -np.abs(mu)))


def _verdict(mu, bounds):
    """The verdict of the multipliers (:func:`mbseig.modal.scope.verdict` over each one's
    stability: unstable when |μ| − b > 1, stable when |μ| + b < 1, else critical) and the
    multiplier that decides it, (k, |μ_k|, b_k, margin)."""
    from ..modal.rules import classify
    from ..modal.scope import verdict

    mod = np.abs(mu)
    upper, lower = mod + bounds, mod - bounds
    stab = classify(1.0 - mod, bounds)  # the one rule: margin 1 − |μ| against its bound
    word = verdict(stab).word
    if word == "unstable":
        k = int(np.argmax(lower))
        return word, (k, float(mod[k]), float(bounds[k]), float(lower[k] - 1.0))
    k = int(np.argmax(upper))
    if word == "stable":
        return word, (k, float(mod[k]), float(bounds[k]), float(1.0 - upper[k]))
    return word, (k, float(mod[k]), float(bounds[k]),  # the interval that contains 1
                  float(min(upper[k] - 1.0, 1.0 - lower[k])))


def analyze(Phi, Phi_check, period, trace_integral, *, method, tolerances):
    """FloquetResult from two monodromy estimates (the first the more accurate one)."""
    mu, vl, vr = la.eig(Phi, left=True, right=True)
    mu2 = la.eigvals(Phi_check)
    cost = np.abs(mu[:, None] - mu2[None, :])
    rows, cols = linear_sum_assignment(cost)
    diff = np.empty(mu.size)
    diff[rows] = cost[rows, cols]
    denom = np.abs(np.einsum("ij,ij->j", vl.conj(), vr))
    with np.errstate(divide="ignore"):
        kappa = np.where(denom > 0, np.linalg.norm(vl, axis=0) * np.linalg.norm(vr, axis=0)
                         / denom, np.inf)
    dPhi = float(np.linalg.norm(Phi - Phi_check, 2))
    nPhi = float(np.linalg.norm(Phi, 2))
    sign, logdet = np.linalg.slogdet(Phi)
    det_check = float(abs(sign * math.exp(logdet - trace_integral) - 1.0)) if sign != 0 else 1.0
    bounds = np.maximum.reduce([diff, kappa * dPhi, np.abs(mu) * det_check,
                                64 * np.finfo(float).eps * kappa * nPhi])
    order = _sort_order(mu)
    mu, bounds, kappa, vr = mu[order], bounds[order], kappa[order], vr[:, order]
    verdict, decided = _verdict(mu, bounds)
    with np.errstate(divide="ignore"):
        exps = np.log(mu.astype(complex)) / period
    return FloquetResult(period=float(period), multipliers=mu, exponents=exps,
                         error_bounds=bounds, verdict=verdict, decided_by=decided,
                         det_check=det_check, method=method, tolerances=tuple(tolerances),
                         condition=kappa, estimate_difference=dPhi,
                         trace_integral=float(trace_integral), monodromy=Phi,
                         monodromy_check=Phi_check, floquet_vectors=vr)


def floquet(A, period=None, *, method="DOP853", rtols=DEFAULT_RTOLS, check_method=None):
    """Floquet multipliers of x' = A(t) x (A a callable of t and ``period`` T, or a
    :class:`LinearPeriodicSystem`) with error bounds and the verdict (module docstring).

    Two estimates of Φ: ``method`` at the tighter of ``rtols`` and ``check_method`` (default the
    same method) at the looser one.  Radau (implicit, for stiff systems) receives the Jacobian
    kron(A, I) of the flattened variational equations.
    """
    system = _as_system(A, period)
    rtols = tuple(sorted((float(r) for r in rtols), reverse=True))
    if len(rtols) != 2 or not all(0 < r < 1 for r in rtols) or rtols[0] == rtols[1]:
        raise CaseError(f"rtols must be two different tolerances in (0, 1), got {rtols!r}",
                        element="rtols")
    check_method = check_method or method
    Phi = monodromy(system, method=method, rtol=rtols[1])
    Phi_check = monodromy(system, method=check_method, rtol=rtols[0])
    label = method if check_method == method else f"{method} / {check_method}"
    return analyze(Phi, Phi_check, system.period, system.trace_integral(),
                   method=f"variational equations, {label}", tolerances=rtols[::-1])


def frozen_time_eigenvalues(A, period, *, samples=64):
    """(times, eigenvalues) of A(t) frozen at ``samples`` instants of one period: what a
    frozen-time analysis would report (not a stability criterion of a periodic system)."""
    T = positive_period(period)
    times = np.linspace(0.0, T, samples, endpoint=False)
    return times, np.array([la.eigvals(np.asarray(A(t), dtype=float)) for t in times])


# ---- partial method: Arnoldi on the monodromy operator ----------------------------------------
@dataclass(frozen=True)
class PartialFloquetResult:
    """The k multipliers of largest modulus (Arnoldi on v ↦ Φ v) and their residuals
    ‖Φ v − μ v‖/‖v‖ (each Φ v a fresh integration)."""

    period: float
    multipliers: np.ndarray
    residuals: np.ndarray
    products: int
    method: str
    rtol: float


def floquet_partial(A, period=None, *, k=4, method="DOP853", rtol=1e-11, tol=1e-10):
    """The ``k`` Floquet multipliers of largest modulus without forming Φ: scipy's ARPACK
    ``eigs`` on a LinearOperator whose product integrates x' = A(t) x for one vector."""
    system = _as_system(A, period)
    n = system.size
    if not 0 < k < n - 1:
        raise CaseError(f"k must be between 1 and n − 2 = {n - 2}, got {k}", element="k")
    count = [0]

    def matvec(v):
        count[0] += 1
        X = np.asarray(v, dtype=float).reshape(n, 1)
        for t0, t1, Ak in system.segments:
            X, _ = _propagate(Ak, t0, t1, X, method=method, rtol=rtol)
        if system.closing is not None:
            X = system.closing @ X
        return X.ravel()

    op = LinearOperator((n, n), matvec=matvec, dtype=float)
    mu, V = eigs(op, k=k, which="LM", tol=tol, v0=np.ones(n) / math.sqrt(n))
    res = np.array([np.linalg.norm((matvec(V[:, j].real) + 1j * matvec(V[:, j].imag))
                                   - mu[j] * V[:, j]) / np.linalg.norm(V[:, j])
                    for j in range(k)])
    order = _sort_order(mu)
    return PartialFloquetResult(system.period, mu[order], res[order], count[0],
                                f"Arnoldi (ARPACK) on the monodromy operator, {method}", rtol)
