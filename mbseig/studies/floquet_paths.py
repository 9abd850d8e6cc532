"""Constrained linearizations along a periodic motion and periodic responses by shooting.

The null-space path N(t) of Φ_q(t) (Procrustes continuation), the projected first-order system
of M δq̈ + C δq̇ + K δq + Φ_qᵀ δλ = 0, Φ_q δq = 0 (:func:`constrained_system`), and Newton on
the state after one period (:func:`periodic_orbit`).  Numerics of :mod:`mbseig.studies.floquet`.
"""

from __future__ import annotations

import functools
import math
from collections.abc import Callable
from dataclasses import dataclass, field

import numpy as np
import scipy.linalg as la
import scipy.sparse as sp
import scipy.sparse.linalg as spla
from scipy.integrate import quad, solve_ivp

from ..errors import CaseError
from .floquet import (
    ATOL_FACTOR,
    DEFAULT_RTOLS,
    FloquetError,
    LinearPeriodicSystem,
    analyze,
    positive_period,
)

__all__ = ["first_order", "ConstrainedLinearization", "constrained_system", "null_space_path",
           "NullSpacePath", "PeriodicOrbit", "periodic_orbit", "floquet_of_orbit"]


# ---- constrained second-order linearization ----------------------------------------------------
def _jacobian(J, n):
    """Φ_q (or Φ̇_q) as an m×n array or CSR matrix (m = 0 allowed; None: no rows)."""
    if J is None:
        return np.zeros((0, n))
    if sp.issparse(J):
        return sp.csr_matrix(J)
    J = np.asarray(J, dtype=float)
    return J.reshape(-1, n) if J.size else np.zeros((0, n))


def _dense(J, n):
    J = _jacobian(J, n)
    return J.toarray() if sp.issparse(J) else J


@dataclass(frozen=True)
class NullSpacePath:
    """A smooth orthonormal basis N(t) of null Φ_q(t) over one period, continued piecewise.

    On segment k, N(t) = P(t) B_k (B_kᵀ P(t) B_k)^(−1/2), P = I − Φ_q⁺ Φ_q: the orthogonal
    Procrustes alignment of the null space at t to the basis B_k at the segment's start (the polar
    factor is independent of how the null space at t was computed, so N is as smooth as Φ_q).
    B_{k+1} = N(t_{k+1}); ``holonomy`` R = B_0ᵀ B_K (orthogonal) says how the basis came back
    after one period.  ``derivative(t)`` gives Ṅ from Ṗ = −(Φ_q⁺ Φ̇_q P + (Φ_q⁺ Φ̇_q P)ᵀ) and
    the Daleckii–Krein formula for d(S^(−1/2)), S = BᵀPB.
    """

    phi_q: Callable
    phi_q_dot: Callable
    nodes: np.ndarray
    bases: tuple
    holonomy: np.ndarray
    min_overlap: float = 0.3

    def segment(self, t):
        k = int(np.searchsorted(self.nodes, t, side="right") - 1)
        return min(max(k, 0), len(self.nodes) - 2)

    def _parts(self, t, k):
        J = _jacobian(self.phi_q(t), self.bases[0].shape[0])
        if J.shape[0]:
            # Φ_q⁺ = Φ_qᵀ (Φ_q Φ_qᵀ)⁻¹ applied through a factor of Φ_q Φ_qᵀ (m × m; Φ_q sparse
            # or dense): Φ_q⁺ Y = Φ_qᵀ solve(Y)
            JJ = J @ J.T
            try:  # a sparse Φ_q Φ_qᵀ (chains: banded) by sparse LU, else Cholesky
                if sp.issparse(JJ) and JJ.nnz <= 0.25 * JJ.shape[0] ** 2:
                    solve = spla.splu(sp.csc_matrix(JJ)).solve
                else:
                    factor = la.cho_factor(JJ.toarray() if sp.issparse(JJ) else JJ)
                    solve = functools.partial(la.cho_solve, factor)
            except (la.LinAlgError, RuntimeError):
                raise FloquetError(f"Φ_q loses rank at t = {t:g} (redundant or singular "
                                   "constraints along the motion)",
                                   element="null space") from None
        else:  # no rows: no constraints, P = I
            def solve(Y):
                return Y
        B = self.bases[k]
        PB = B - J.T @ solve(J @ B)  # P B without forming the n×n projector: O(n m r)
        S = B.T @ PB
        s, V = np.linalg.eigh(S)
        if s[0] < self.min_overlap ** 2:
            raise FloquetError(f"the null space turned too far within segment {k} at t = {t:g} "
                               f"(overlap {math.sqrt(max(s[0], 0)):.2g}); use more segments",
                               element="null space")
        r = 1.0 / np.sqrt(s)
        return J, solve, PB, B, s, V, r

    def basis(self, t, k=None):
        k = self.segment(t) if k is None else k
        _, _, PB, _, _, V, r = self._parts(t, k)
        return PB @ ((V * r) @ V.T)

    def derivative(self, t, k=None):
        """(N, Ṅ) at t on segment k (products with the thin factors only: O(n m r + n r²))."""
        k = self.segment(t) if k is None else k
        J, solve, PB, B, s, V, r = self._parts(t, k)
        Jd = _jacobian(self.phi_q_dot(t), J.shape[1])
        # Ṗ B = −(E + Eᵀ) B with E = Φ_q⁺ Φ̇_q P:  E B = Φ_q⁺ (Φ̇_q P B),  Eᵀ B = P Φ̇_qᵀ Φ_q⁺ᵀ B
        X = Jd.T @ solve(J @ B)
        PdB = -(J.T @ solve(Jd @ PB) + X - J.T @ solve(J @ X))
        Sd = V.T @ (B.T @ PdB) @ V
        sq = np.sqrt(s)
        dk = -1.0 / (sq[:, None] * sq[None, :] * (sq[:, None] + sq[None, :]))
        Rinv = (V * r) @ V.T
        Rinv_dot = V @ (Sd * dk) @ V.T
        N = PB @ Rinv
        Nd = PdB @ Rinv + PB @ Rinv_dot
        return N, Nd


def null_space_path(phi_q, phi_q_dot, period, *, segments=16, start=None, periodic_tol=1e-9):
    """Continue an orthonormal null-space basis of Φ_q(t) over one period (:class:`NullSpacePath`).

    ``phi_q(t)`` is the m×n constraint Jacobian along the reference motion (full row rank) and
    ``phi_q_dot(t)`` its total time derivative. ``start`` is the basis at t = 0 (default: from
    the SVD).  Raises FloquetError if Φ_q(T) ≠ Φ_q(0) (the motion does not repeat with T).
    """
    T = positive_period(period)
    J0 = phi_q(0.0)
    n = J0.shape[-1]
    J0, JT = _dense(J0, n), _dense(phi_q(T), n)
    if np.linalg.norm(JT - J0) > periodic_tol * max(1.0, np.linalg.norm(J0)):
        raise FloquetError(f"Φ_q(T) differs from Φ_q(0) by {np.linalg.norm(JT - J0):.3g}: the "
                           f"motion does not repeat with period {T:g}", element="motion.period")
    if start is None:
        start = la.null_space(J0) if J0.shape[0] else np.eye(n)
    nodes = np.linspace(0.0, T, int(segments) + 1)
    bases = [np.asarray(start, dtype=float)]
    path = NullSpacePath(phi_q, phi_q_dot, nodes, tuple(bases), np.eye(start.shape[1]))
    for k in range(int(segments)):
        path = NullSpacePath(phi_q, phi_q_dot, nodes, tuple(bases), path.holonomy)
        bases.append(path.basis(nodes[k + 1], k))
    R = bases[0].T @ bases[-1]
    return NullSpacePath(phi_q, phi_q_dot, nodes, tuple(bases), R)


def _operator(A):
    """A coefficient matrix as given (CSR or dense); None or an all-zero sparse one as None."""
    if A is None:
        return None
    if sp.issparse(A):
        return A if A.nnz else None
    return np.asarray(A, dtype=float)


def first_order(M, C, K):
    """A(t) of M q̈ + C q̇ + K q = 0 without constraints (callables of t), state [q; q̇]:

        A = ┌ 0        I      ┐
            └ −M⁻¹K   −M⁻¹C  ┘
    """
    def A(t):
        Mt = np.asarray(M(t), dtype=float)
        n = Mt.shape[0]
        out = np.zeros((2 * n, 2 * n))
        out[:n, n:] = np.eye(n)
        out[n:, :n] = -np.linalg.solve(Mt, np.asarray(K(t), dtype=float))
        out[n:, n:] = -np.linalg.solve(Mt, np.asarray(C(t), dtype=float))
        return out
    return A


@dataclass(frozen=True)
class ConstrainedLinearization:
    """The linearized constrained equations along a T-periodic reference motion q*(t):

        M(t) δq̈ + C(t) δq̇ + K(t) δq + Φ_q(t)ᵀ δλ = 0,      Φ_q(t) δq = 0

    (C = −∂g/∂q̇, K = −∂g/∂q + Σ λ*_k ∇²Φ_k, both along q*(t); a rheonomic Φ(q, t) enters the
    reference motion through Φ_t, Φ_tt but its variation is Φ_q δq), reduced on the null space
    and written first order in (y, p) (:func:`constrained_system`)."""

    system: LinearPeriodicSystem
    path: NullSpacePath
    dof: int


def constrained_system(M, C, K, phi_q, phi_q_dot, period, *, M_dot=None, segments=16,
                       start=None):
    """The projected first-order periodic system of a constrained linearization.

    Derivation.  Let N(t) (n×r, r = n − m) be an orthonormal basis of null Φ_q(t)
    (:func:`null_space_path`).  Every δq with Φ_q δq = 0 is δq = N y, hence

        δq̇ = N ẏ + Ṅ y.

    Premultiplying the equations of motion by Nᵀ removes Φ_qᵀ δλ (Nᵀ Φ_qᵀ = 0).  Rather than
    the second-order form (which needs N̈) take the momentum-like coordinate

        p = Nᵀ M δq̇ = M_r ẏ + Nᵀ M Ṅ y,          M_r = Nᵀ M N,

    whose derivative is  ṗ = (Ṅᵀ M + Nᵀ Ṁ − Nᵀ C) δq̇ − Nᵀ K N y.  With G = M_r⁻¹, H = Nᵀ M Ṅ,
    W = Ṅᵀ M + Nᵀ Ṁ − Nᵀ C:

        ẏ  = −G H y + G p
        δq̇ = (Ṅ − N G H) y + N G p            = V_y y + V_p p
        ṗ  = (W V_y − Nᵀ K N) y + W V_p p

        ┌ ẏ ┐   ┌ −G H             G     ┐ ┌ y ┐
        └ ṗ ┘ = └ W V_y − NᵀKN     W V_p ┘ └ p ┘        (2r × 2r)

    The state has 2r = 2(n − m) entries: the constraints add no multipliers (a first-order form
    in all 2n coordinates would add 2m spurious ones at μ = 1 or wherever the drift goes).
    N is continued in segments (Procrustes); y and p = Nᵀ M δq̇ depend on N only, not on Ṅ, so
    they are continuous where the segment's base basis changes and the monodromy is the product
    of the segments' transition matrices, closed by diag(R, R) with R = B_0ᵀ N(T) the holonomy
    of the basis (δq(T) = N(0) R y(T) and likewise for p).  tr A = tr(M_r⁻¹ (Nᵀ Ṁ N − Nᵀ C N)).
    ``start``: the basis at t = 0 (default from the SVD), so that two linearizations of one
    motion share their coordinates.
    """
    T = positive_period(period)
    path = null_space_path(phi_q, phi_q_dot, T, segments=segments, start=start)
    r = path.bases[0].shape[1]
    if r == 0:
        raise CaseError("the constraints leave no degree of freedom: the reference motion is "
                        "fully prescribed and has no Floquet multipliers", element="motion")

    def make(k):
        def A(t):
            N, Nd = path.derivative(t, k)
            Mt = _operator(M(t))
            MN = Mt @ N
            G = np.linalg.inv(N.T @ MN)
            H = MN.T @ Nd  # Nᵀ M Ṅ (M symmetric)
            Wt = Mt @ Nd  # Wᵀ = M Ṅ − Cᵀ N + Ṁ N
            Ct = _operator(C(t))
            if Ct is not None:
                Wt = Wt - Ct.T @ N
            if M_dot is not None:
                Md = _operator(M_dot(t))
                if Md is not None:
                    Wt = Wt + Md @ N
            WN = Wt.T @ np.hstack([N, Nd])  # [W N, W Ṅ]: W V_y = W Ṅ − W N G H, W V_p = W N G
            Kt = _operator(K(t))
            Kr = N.T @ (Kt @ N) if Kt is not None else 0.0
            GH = G @ H
            out = np.empty((2 * r, 2 * r))
            out[:r, :r] = -GH
            out[:r, r:] = G
            out[r:, :r] = WN[:, r:] - WN[:, :r] @ GH - Kr
            out[r:, r:] = WN[:, :r] @ G
            return out
        return A

    def trace(t):
        Ct = _operator(C(t))
        Md = _operator(M_dot(t)) if M_dot is not None else None
        if Ct is None and Md is None:
            return 0.0  # tr A = tr(M_r⁻¹ Nᵀ(Ṁ − C)N) vanishes
        N = path.basis(t)
        Mt = _operator(M(t))
        DN = (-(Ct @ N) if Ct is not None else 0.0) + (Md @ N if Md is not None else 0.0)
        return float(np.trace(la.solve(N.T @ (Mt @ N), N.T @ DN)))

    segs = tuple((path.nodes[k], path.nodes[k + 1], make(k)) for k in range(len(path.nodes) - 1))
    R = path.holonomy
    closing = la.block_diag(R, R)
    return ConstrainedLinearization(LinearPeriodicSystem(segs, 2 * r, closing, trace), path, r)


# ---- periodic response by shooting --------------------------------------------------------------
@dataclass(frozen=True)
class PeriodicOrbit:
    """A T-periodic solution x*(t) of x' = f(x, t): its state at t = 0, the Newton record
    (residual ‖x(T) − x(0)‖ per iteration) and the monodromy of the last iterate."""

    x0: np.ndarray
    period: float
    residual: float
    iterations: int
    history: tuple
    monodromy: np.ndarray = field(repr=False)
    tol: float
    rtol: float


def _fd_jacobian(f):
    def jac(x, t):
        n = x.size
        J = np.empty((n, n))
        for j in range(n):
            h = 1e-6 * max(1.0, abs(x[j]))
            e = np.zeros(n)
            e[j] = h
            J[:, j] = (np.asarray(f(x + e, t)) - np.asarray(f(x - e, t))) / (2 * h)
        return J
    return jac


def _flow(f, jac, x0, T, *, method, rtol, t0=0.0):
    """(x(T), X(T)): the state and its sensitivity ∂x(T)/∂x(0) in one integration."""
    n = x0.size

    def rhs(t, z):
        x = z[:n]
        X = z[n:].reshape(n, n)
        return np.concatenate([np.asarray(f(x, t), dtype=float), (jac(x, t) @ X).ravel()])

    z0 = np.concatenate([x0, np.eye(n).ravel()])
    scale = np.concatenate([np.full(n, max(1.0, np.max(np.abs(x0)))), np.ones(n * n)])
    sol = solve_ivp(rhs, (t0, t0 + T), z0, method=method, rtol=rtol,
                    atol=ATOL_FACTOR * rtol * scale)
    if not sol.success:
        raise FloquetError(f"integration from x(0) = {np.array2string(x0, precision=4)} failed "
                           f"at t = {sol.t[-1]:g}: {sol.message}", element="shooting")
    return sol.y[:n, -1], sol.y[n:, -1].reshape(n, n)


def periodic_orbit(f, x0, period, *, jac=None, tol=1e-10, max_iter=40, method="DOP853",
                   rtol=1e-12, max_step=None, min_step=2.0 ** -20):
    """The T-periodic response of x' = f(x, t) by shooting from ``x0``.

    Newton on F(x) = x(T; x) − x with Jacobian Φ(x) − I (Φ the monodromy, integrated with the
    state), a backtracking line search on ‖F‖ (steps down to ``min_step``; a Newton step
    longer than ``max_step``, default max(1, ‖x‖), is first shortened to it: far from the orbit
    Φ − I can be nearly singular), converged when ‖F‖ ≤ tol · max(1, ‖x‖).
    ``jac(x, t)`` = ∂f/∂x (central differences of f if None).  Raises FloquetError naming what
    did not converge, from where, and the residual.
    """
    T = positive_period(period)
    jac = jac or _fd_jacobian(f)
    x = np.array(x0, dtype=float)
    start = x.copy()
    xT, Phi = _flow(f, jac, x, T, method=method, rtol=rtol)
    F = xT - x
    history = [float(np.linalg.norm(F))]
    for it in range(1, max_iter + 1):
        if history[-1] <= tol * max(1.0, np.linalg.norm(x)):
            return PeriodicOrbit(x, T, history[-1], it - 1, tuple(history), Phi, tol, rtol)
        Jn = Phi - np.eye(x.size)
        try:
            dx = la.solve(Jn, -F)
        except la.LinAlgError:
            dx = la.lstsq(Jn, -F)[0]
        cap = max_step if max_step is not None else max(1.0, float(np.linalg.norm(x)))
        if np.linalg.norm(dx) > cap:
            dx = dx * (cap / np.linalg.norm(dx))
        step, accepted = 1.0, False
        while step >= min_step:
            xn = x + step * dx
            try:
                xTn, Phin = _flow(f, jac, xn, T, method=method, rtol=rtol)
            except FloquetError:
                step /= 2
                continue
            Fn = xTn - xn
            if np.linalg.norm(Fn) < (1 - 1e-4 * step) * history[-1]:
                accepted = True
                break
            step /= 2
        if not accepted:
            raise FloquetError(
                f"shooting did not converge: no step along the Newton direction reduces "
                f"‖x(T) − x(0)‖ = {history[-1]:.3g} at iteration {it} (started from "
                f"{np.array2string(start, precision=4)}; Φ − I has condition "
                f"{np.linalg.cond(Jn):.2g}: a multiplier near +1?)", element="shooting")
        x, F, Phi = xn, Fn, Phin
        history.append(float(np.linalg.norm(F)))
    if history[-1] <= tol * max(1.0, np.linalg.norm(x)):
        return PeriodicOrbit(x, T, history[-1], max_iter, tuple(history), Phi, tol, rtol)
    raise FloquetError(f"shooting did not converge in {max_iter} iterations from "
                       f"{np.array2string(start, precision=4)}: residual ‖x(T) − x(0)‖ = "
                       f"{history[-1]:.3g} > {tol:g}", element="shooting")


def floquet_of_orbit(f, orbit, *, jac=None, method="DOP853", rtols=DEFAULT_RTOLS):
    """Floquet multipliers of the periodic orbit: the variational equations integrated with the
    state from x*(0) at two tolerances; tr ∂f/∂x along the orbit from the dense output."""
    jac = jac or _fd_jacobian(f)
    rtols = tuple(sorted(rtols, reverse=True))
    T = orbit.period
    _, Phi = _flow(f, jac, orbit.x0, T, method=method, rtol=rtols[1])
    _, Phi2 = _flow(f, jac, orbit.x0, T, method=method, rtol=rtols[0])
    sol = solve_ivp(lambda t, x: f(x, t), (0, T), orbit.x0, method=method, rtol=rtols[1],
                    atol=ATOL_FACTOR * rtols[1], dense_output=True)
    tr, _ = quad(lambda t: float(np.trace(jac(sol.sol(t), t))), 0, T, epsabs=1e-13,
                 epsrel=1e-13, limit=400)
    return analyze(Phi, Phi2, T, tr, method=f"variational equations along the orbit, {method}",
                   tolerances=rtols[::-1])


