"""The periodic reference motion of a driven case: kinematics, shooting, nonlinear simulation.

Coordinate partitioning (Wehage and Haug): a pivoted QR of Φ_q at t = 0 splits q into m
dependent coordinates q_d and d = n − m independent ones q_i.  Given (q_i, q̇_i, t):

    Φ(q, t) = 0                          → q_d (Newton, from the last solution)
    Φ_q q̇ = −Φ_t                         → q̇_d
    ┌ M    Φ_qᵀ ┐ ┌ q̈ ┐   ┌ g(q, q̇, t)                   ┐
    └ Φ_q  0    ┘ └ λ  ┘ = └ γ(q, q̇) − 2 Φ_qt q̇ − Φ_tt    ┘

so the state x = (q_i, q̇_i) obeys x' = f(x, t) on the constraint manifold without drift.
Fully driven (d = 0): the reference is the prescribed motion itself.  Otherwise the
T-periodic response is found by shooting (:func:`mbseig.studies.floquet_paths.periodic_orbit`,
Newton on x(T) − x(0)) started from the case's positions at rest relative to the drive.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
import scipy.linalg as la
import scipy.sparse as sp
import scipy.sparse.linalg as spla
from scipy.integrate import solve_ivp

from ..errors import CaseError
from .floquet import FloquetError

_MARCH = 64  # instants of the marched assembly
#: systems at least this large and at most SPARSE_FILL full are solved by sparse LU (the same
#: solution to rounding; below, dense LU keeps small models' numbers as they were)
SPARSE_FROM = 200
SPARSE_FILL = 0.05


def _solve(A, b):
    """A⁻¹ b, by sparse LU where A is large and sparse (chains: banded), else dense."""
    if A.shape[0] >= SPARSE_FROM and np.count_nonzero(A) <= SPARSE_FILL * A.size:
        return _sparse_solve(sp.csc_matrix(A), b)
    return np.linalg.solve(A, b)


def _sparse_solve(A, b):
    """A⁻¹ b by SuperLU; a singular A raises LinAlgError, as the dense solve does (the callers
    report it)."""
    try:
        return spla.splu(A).solve(b)
    except RuntimeError as exc:  # SuperLU: "Factor is exactly singular"
        raise np.linalg.LinAlgError(str(exc)) from None

__all__ = ["Partitioned", "ReferenceMotion", "reference_motion", "sample_linearization", "shoot",
           "simulate"]


class Partitioned:
    """The equations of a :class:`~mbseig.model.timed.TimedModel` in independent coordinates
    (module docstring); ``state(xi, t)`` gives (q, q̇, q̈, λ) on the manifold."""

    def __init__(self, timed, q_start, *, tol=1e-13):
        self.timed, self.tol = timed, tol
        base = timed.base
        self.M = base.mass.toarray()
        self._M_sparse = None  # M as CSC, made on the first sparse solve (state)
        self.scales = base.constraint_scales()
        q = self.position(np.asarray(q_start, dtype=float), 0.0, dep=None)
        J = timed.phi_q(q, 0.0)
        m = J.shape[0]
        if m:
            _, R, piv = la.qr(J, pivoting=True, mode="economic")
            diag = np.abs(np.diag(R))
            rank = int(np.sum(diag > 1e-10 * max(diag[0], 1e-300)))
            if rank < m:
                rows = base.constraint_row_names()
                raise CaseError(f"the constraints are redundant along the motion (rank {rank} of "
                                f"{m} at t = 0); a periodic case needs independent constraints "
                                f"({', '.join(dict.fromkeys(rows))})", element="motion")
            self.dep, self.ind = np.sort(piv[:m]), np.sort(piv[m:])
        else:
            self.dep, self.ind = np.zeros(0, int), np.arange(base.n)
        self.q0 = q
        self._last = (0.0, q.copy(), np.zeros(q.size))
        # the assembly along one period, marched in small steps from t = 0: the first guess
        # wherever a flow jumps in time (never a different assembly mode of the mechanism)
        self._march = [q]
        if self.dep.size:
            for j in range(1, _MARCH):
                self._march.append(self.position(self._march[-1], j * timed.period / _MARCH))

    @property
    def dof(self):
        return self.ind.size

    def position(self, q, t, *, dep="auto"):
        """q on Φ(q, t) = 0 by Newton on the dependent coordinates (all coordinates, least-norm
        steps, when ``dep`` is None: the first projection of the case's positions)."""
        q = q.copy()
        model = self.timed.at(t)
        if model.n_constraints == 0:
            return q
        cols = self.dep if dep == "auto" else None
        small = 0.0
        for _ in range(40):
            r = model.phi(q)
            if np.max(np.abs(r) / self.scales) <= 0.1 * self.tol or small:
                return q
            J = self.timed.phi_q(q, t)
            if cols is None:
                step = -np.linalg.lstsq(J, r, rcond=None)[0]
                q += step
            else:
                step = -_solve(J[:, cols], r)
                q[cols] += step
            # a step this small leaves a rounding-level residual: one more evaluation
            small = np.max(np.abs(step)) <= self.tol * max(1.0, self.timed.base.length_scale)
        raise FloquetError(f"the constraints cannot be satisfied at t = {t:.6g}: residual "
                           f"{np.max(np.abs(model.phi(q)) / self.scales):.3g} after 40 Newton "
                           "steps", element="motion")

    def state(self, xi, t):
        """(q, q̇, q̈, λ) at t from the independent state xi = (q_i, q̇_i)."""
        d = self.dof
        t_last, q_last, qd_last = self._last
        if abs(t - t_last) <= 0.02 * self.timed.period:
            guess = q_last + (t - t_last) * qd_last  # predictor along the last velocity
        else:
            j = int(round((t % self.timed.period) / self.timed.period * _MARCH)) % _MARCH
            guess = self._march[j].copy()
        guess[self.ind] = xi[:d]
        q = self.position(guess, t)
        model = self.timed.at(t)
        qd = np.zeros(q.size)
        qd[self.ind] = xi[d:]
        m = model.n_constraints
        if m:
            _, phit, phitt = self.timed.phi_time(q, t)
            J = self.timed.phi_q(q, t)
            qd[self.dep] = _solve(J[:, self.dep], -phit - J[:, self.ind] @ xi[d:])
            rhs2 = model.gamma(q, qd) - 2.0 * self.timed.phi_qt(q, t) @ qd - phitt
        else:
            J, rhs2 = np.zeros((0, q.size)), np.zeros(0)
        self._last = (t, q, qd)
        n = q.size
        rhs = np.concatenate([model.generalized_force(q, qd), rhs2])
        if n + m >= SPARSE_FROM and np.count_nonzero(J) <= SPARSE_FILL * J.size:
            if self._M_sparse is None:
                self._M_sparse = sp.csc_matrix(self.M)
            Js = sp.csr_matrix(J)
            sol = _sparse_solve(sp.bmat([[self._M_sparse, Js.T], [Js, None]], format="csc"), rhs)
        else:
            A = np.block([[self.M, J.T], [J, np.zeros((m, m))]])
            sol = np.linalg.solve(A, rhs)
        return q, qd, sol[:n], sol[n:]

    budget = 10_000  # right-hand sides per integration (a period far longer than the motion)

    def rhs(self, x, t):
        self.calls = getattr(self, "calls", 0) + 1
        if self.calls > self.budget:
            self.calls = 0
            raise FloquetError(f"the integration over one period (T = {self.timed.period:.6g}) "
                               f"needs more than {self.budget} evaluations: is the period far "
                               "longer than the motion's time scale?", element="motion.period")
        _, qd, qdd, _ = self.state(x, t)
        return np.concatenate([qd[self.ind], qdd[self.ind]])

    def independent(self, q, qd):
        return np.concatenate([q[self.ind], qd[self.ind]])


@dataclass(frozen=True)
class ReferenceMotion:
    """The T-periodic reference: its independent state at t = 0, how it was found (kinematics
    or shooting: residual ‖x(T) − x(0)‖, Newton iterations, where it started) and the dense
    solution of one period (None when fully driven)."""

    #: the reference motion this belongs to (mbseig.studies.reference): a periodic orbit
    kind = "periodic"

    partition: Partitioned = field(repr=False)
    period: float
    x0: np.ndarray
    method: str
    residual: float
    iterations: int
    start: np.ndarray
    dense: object = field(repr=False, default=None)

    def at(self, t):
        """(q, q̇, q̈, λ) of the reference at t."""
        t = float(t) % self.period
        xi = self.dense(t) if self.dense is not None else np.zeros(0)
        return self.partition.state(xi, t)


def _flow(part, x0, T, rtol):
    """The solution over one period from x0 (dense output kept for the reference)."""
    part.calls = 0
    sol = solve_ivp(lambda t, x: part.rhs(x, t), (0.0, T), x0, method="DOP853", rtol=rtol,
                    atol=1e-3 * rtol * max(1.0, float(np.max(np.abs(x0)))), dense_output=True)
    if not sol.success:
        raise FloquetError(f"integration from x(0) = {np.array2string(x0, precision=4)} failed "
                           f"at t = {sol.t[-1]:g}: {sol.message}", element="shooting")
    return sol


def shoot(part, x0, T, *, tol=1e-10, rtol=1e-11, max_iter=30, jac_rtol=1e-8):
    """The T-periodic state by a chord Newton on F(x) = x(T; x) − x: the Jacobian Φ − I from
    one variational flow at ``jac_rtol`` (refreshed when a step does not halve ‖F‖), each F
    from one flow at ``rtol`` (a step that does not reduce ‖F‖ is cut by 4, down to 1e-3).
    Returns (x, ‖F‖, iterations, the last flow); FloquetError naming what did not converge,
    where it started and the residual."""
    x = np.array(x0, dtype=float)
    n = x.size

    def jacobian(x):
        _, Phi = _variational(part, x, T, jac_rtol)
        return Phi - np.eye(n)

    tol_x = tol * max(1.0, float(np.linalg.norm(x)))
    sol = _flow(part, x, T, rtol)
    F = sol.y[:, -1] - x
    history = [float(np.linalg.norm(F))]
    J = None  # (a start already periodic needs none)
    it = 0
    while it < max_iter:
        if history[-1] <= tol_x:
            return x, history[-1], it, sol
        it += 1
        if J is None:
            J = jacobian(x)
        dx = -np.linalg.lstsq(J, F, rcond=None)[0]
        step = 1.0
        while True:
            xn = x + step * dx
            soln = _flow(part, xn, T, rtol)
            Fn = soln.y[:, -1] - xn
            if np.linalg.norm(Fn) < history[-1] or step < 1e-3:
                break
            step /= 4
        if np.linalg.norm(Fn) > 0.5 * history[-1]:
            J = None  # the chord lost its way: a fresh Jacobian
        x, F, sol = xn, Fn, soln
        history.append(float(np.linalg.norm(F)))
        if not np.isfinite(history[-1]):
            break
    raise FloquetError(f"shooting did not converge in {it} iterations from "
                       f"{np.array2string(np.asarray(x0), precision=4)}: residual "
                       f"‖x(T) − x(0)‖ = {history[-1]:.3g} > {tol_x:.3g}", element="shooting")


def _variational(part, x0, T, rtol):
    """(x(T), ∂x(T)/∂x(0)) by forward differences of f in the variational equations."""
    n = x0.size

    def rhs(t, z):
        x, X = z[:n], z[n:].reshape(n, n)
        f0 = part.rhs(x, t)
        Jf = np.empty((n, n))
        for j in range(n):
            h = 1e-7 * max(1.0, abs(x[j]))
            e = np.zeros(n)
            e[j] = h
            Jf[:, j] = (part.rhs(x + e, t) - f0) / h
        return np.concatenate([f0, (Jf @ X).ravel()])

    z0 = np.concatenate([x0, np.eye(n).ravel()])
    part.calls = 0
    sol = solve_ivp(rhs, (0.0, T), z0, method="DOP853", rtol=rtol,
                    atol=1e-3 * rtol * max(1.0, float(np.max(np.abs(x0)))))
    if not sol.success:
        raise FloquetError(f"integration from x(0) = {np.array2string(x0, precision=4)} failed "
                           f"at t = {sol.t[-1]:g}: {sol.message}", element="shooting")
    return sol.y[:n, -1], sol.y[n:, -1].reshape(n, n)


def _quasi_static(part):
    """The start of the shooting: the independent coordinates where their acceleration
    vanishes at t = 0 with q̇_i = 0 (the static equilibrium at the drive's initial state),
    by damped Newton from the case's positions; the case's positions if that fails."""
    d = part.dof
    qi = part.q0[part.ind].copy()

    def acc(qi):
        return part.rhs(np.concatenate([qi, np.zeros(d)]), 0.0)[d:]

    a = acc(qi)
    if not np.any(a):  # already at rest: no Jacobian (its Newton step would be zero)
        return np.concatenate([qi, np.zeros(d)])
    for _ in range(30):
        J = np.empty((d, d))
        for j in range(d):
            h = 1e-7 * max(1.0, abs(qi[j]))
            e = np.zeros(d)
            e[j] = h
            J[:, j] = (acc(qi + e) - a) / h
        step = -np.linalg.lstsq(J, a, rcond=None)[0]
        lam = 1.0
        while lam > 1e-3:
            try:
                an = acc(qi + lam * step)
            except FloquetError:
                an = None
            if an is not None and np.linalg.norm(an) < np.linalg.norm(a):
                break
            lam /= 4
        else:
            break
        qi, a = qi + lam * step, an
        if np.linalg.norm(lam * step) <= 1e-12 * max(1.0, np.linalg.norm(qi)):
            return np.concatenate([qi, np.zeros(d)])
    return np.concatenate([part.q0[part.ind], np.zeros(d)])


def start_note(start, part):
    return (f"q_i = {np.array2string(start[:part.dof], precision=4)} at rest, the static "
            "equilibrium at t = 0 or else the case's positions")


def reference_motion(timed, *, tol=1e-10, rtol=1e-11, max_iter=30) -> ReferenceMotion:
    """The periodic reference motion of a driven case (module docstring)."""
    part = Partitioned(timed, timed.base.q_init)
    T = timed.period
    if part.dof == 0:
        return ReferenceMotion(part, T, np.zeros(0), "the prescribed motion (fully driven)",
                               0.0, 0, np.zeros(0))
    start = _quasi_static(part)
    try:
        x0, residual, iterations, sol = shoot(part, start, T, tol=tol, rtol=rtol,
                                             max_iter=max_iter)
    except FloquetError as exc:
        names = ", ".join(timed.base.coordinate_names[i] for i in part.ind)
        raise FloquetError(f"periodic response not found: {exc.message} (independent "
                           f"coordinates {names}, started from {start_note(start, part)})",
                           element="shooting") from None
    return ReferenceMotion(part, T, x0, "shooting (chord Newton on x(T) − x(0), DOP853)",
                           residual, iterations, start, sol.sol)


def simulate(reference, x_start, periods, *, rtol=1e-11):
    """The independent state x(kT), k = 0 … periods, of the nonlinear model from x_start."""
    part, T = reference.partition, reference.period
    part.calls = -periods * part.budget // 4  # a longer run: periods/4 budgets
    sol = solve_ivp(lambda t, x: part.rhs(x, t), (0.0, periods * T), x_start, method="DOP853",
                    rtol=rtol, atol=1e-3 * rtol * max(1.0, np.max(np.abs(x_start))),
                    t_eval=np.arange(periods + 1) * T)
    if not sol.success:
        raise FloquetError(f"the nonlinear simulation failed at t = {sol.t[-1]:g}: {sol.message}",
                           element="check")
    return sol.y.T


def sample_linearization(reference, N, offset, *, sparse=False):
    """The damping, stiffness and constraint Jacobian along the reference motion at N instants
    of its period from ``offset``, fitted as trigonometric series (each entry's pattern
    kept with ``sparse``): [C(t), K(t) + Σλ∇²Φ, Φ_q(t)]."""
    from ..model.timed import TrigSeries
    from .floquet_sparse import pattern_series

    T = reference.period
    model = reference.partition.timed
    Cs, Ks, Js = [], [], []
    for j in range(N):
        t = offset + j * T / N
        q, qd, _, lam = reference.at(t)
        m = model.at(t)
        K, C = m.force_jacobians(q, qd, dense=True)
        K = np.asarray(K) + (np.asarray(m.constraint_hessian(q, lam, dense=True))
                             if m.n_constraints else 0.0)
        Cs.append(np.asarray(C))
        Ks.append(K)
        Js.append(model.phi_q(q, t))
    if not sparse:
        return [TrigSeries.fit(np.array(v), T, offset=offset) for v in (Cs, Ks, Js)]
    return [pattern_series(v, T, offset=offset) for v in (Cs, Ks, Js)]
