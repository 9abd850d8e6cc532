"""Products with the monodromy of a constrained periodic linearization in its own sparse
coordinates (the partial Floquet method's operator, :mod:`mbseig.studies.periodic_partial`).

The projected first-order system (:func:`mbseig.studies.floquet_paths.constrained_system`) needs
the dense null-space basis N(t) and its derivative: a product with it costs O((2r)²) a stage
(through the Chebyshev interpolants of A(t)), as much as a column of the full monodromy.  A
product does not need N.  In the coordinates of the model, the linearized equations along the
reference motion,

    M δq̈ + C(t) δq̇ + K(t) δq + Φ_q(t)ᵀ δλ = 0,      Φ_q(t) δq = 0,

differentiated twice in the constraint, give at every instant the accelerations from one sparse
symmetric solve

    ┌ M     Φ_qᵀ ┐ ┌ δq̈ ┐   ┌ −C δq̇ − K δq         ┐
    └ Φ_q   0    ┘ └ δλ ┘ = └ −2 Φ̇_q δq̇ − Φ̈_q δq  ┘

(Φ̇_q, Φ̈_q the derivatives of the sampled series, as the projected system uses Φ̇_q).  The states
that satisfy Φ_q δq = 0 and Φ_q δq̇ + Φ̇_q δq = 0 at t = 0 form a subspace of dimension 2r that
the flow maps onto itself after one period (Φ_q is T-periodic); on it the flow is the monodromy
of the projected system in other coordinates, so it has the same multipliers.  The operator

    v ↦ Π Φ_T Π v,    Π: δq ← δq − Φ_q⁺ Φ_q δq,  δq̇ ← δq̇ − Φ_q⁺ (Φ_q δq̇ + Φ̇_q δq)   (at t = 0)

has those 2r multipliers and 2m zeros (the directions Π removes; they also absorb the drift of
the constraint, which the index-1 form lets grow linearly), so ARPACK's largest |μ| are the
model's.

The integration uses fixed steps of Butcher's explicit Runge–Kutta method of order 6 (seven
stages at c = 0, 1/3, 2/3, 1/3, 1/2, 1/2, 1: four new instants a step; Butcher 1964, and
Butcher, *Numerical Methods for Ordinary Differential Equations*, 2016, §325), so that every
product meets the same instants: the solve's factorization and the sparse C, K, Φ̇_q, Φ̈_q are made
once per instant and reused by every product, with the right-hand side's four blocks as one
sparse matrix of the state.  A stage then costs a sparse solve and one sparse product, O(nnz).
The step count is doubled from ``START_STEPS`` until the product of a probe vector with n and
2n steps differs by at most 63 rtol ‖Φ v‖ (the order-6 error of the finer run is about the
difference over 2⁶ − 1).
"""

from __future__ import annotations

from fractions import Fraction

import numpy as np
import scipy.sparse as sp
import scipy.sparse.linalg as spla
from scipy.sparse.linalg import LinearOperator, eigs

from .floquet import FloquetError, PartialFloquetResult

__all__ = ["BUTCHER6", "BudgetSpent", "DescriptorFlow", "FULL_MAX_STEPS", "StepsNotSettled",
           "consistent_start", "descriptor_flow", "descriptor_monodromy", "descriptor_partial",
           "rk_fixed"]

# Butcher's 7-stage, order-6 explicit method: (c, A rows, b)
BUTCHER6 = (
    np.array([0.0, 1 / 3, 2 / 3, 1 / 3, 1 / 2, 1 / 2, 1.0]),
    (np.array([]), np.array([1 / 3]), np.array([0.0, 2 / 3]),
     np.array([1 / 12, 1 / 3, -1 / 12]), np.array([-1 / 16, 9 / 8, -3 / 16, -3 / 8]),
     np.array([0.0, 9 / 8, -3 / 8, -3 / 4, 1 / 2]),
     np.array([9 / 44, -9 / 11, 63 / 44, 18 / 11, 0.0, -16 / 11])),
    np.array([11 / 120, 0.0, 27 / 40, 27 / 40, -4 / 15, -4 / 15, 11 / 120]),
)
START_STEPS = 32
MAX_STEPS = 8192


class StepsNotSettled(FloquetError):
    """The fixed-step products did not settle within ``MAX_STEPS`` steps a period (a model too
    stiff for explicit steps)."""


class BudgetSpent(FloquetError):
    """ARPACK did not converge within the products it was given (:func:`descriptor_partial`
    ``budget``): the largest |μ| are clustered, or too many were asked."""


def _inner(c):
    """The distinct stage abscissae of a step below 1 (c = 1 is the next step's first)."""
    return sorted({float(x) for x in c if x < 1.0})


def rk_fixed(f, x, h, steps, tableau=BUTCHER6):
    """x after ``steps`` fixed steps of length h of x′ = f(k, x, out) from t = 0: f writes the
    rate at the stage's state into ``out`` and is called with the index k of the stage's instant
    in :func:`_instants`' order (its operators).  x may be a vector or a matrix of columns; the
    stage combinations are one product with the stacked rates each (few passes over memory)."""
    c, rows, b = tableau
    inner = _inner(c)
    per = len(inner)
    idx = [inner.index(float(x)) if x < 1.0 else per for x in c]
    K = np.empty((len(rows),) + np.shape(x))
    flat = K.reshape(len(rows), -1)
    for s in range(steps):
        for i, row in enumerate(rows):
            if i == 0:
                xi = x
            else:
                xi = (h * row) @ flat[:i]
                xi = xi.reshape(np.shape(x))
                xi += x
            f(s * per + idx[i], xi, K[i])
        step = (h * b) @ flat
        x = x + step.reshape(np.shape(x))
    return x


def _instants(steps, c):
    """The distinct stage instants of ``steps`` fixed steps over one period, as exact fractions
    of the period (the last is 1): a grid's instants are among those of twice its steps, so
    their operators are shared (:class:`DescriptorFlow` ``cache``)."""
    inner = [Fraction(x).limit_denominator(12) for x in _inner(c)]
    out = [(s + x) / steps for s in range(steps) for x in inner]
    out.append(Fraction(1))
    return out


def _csr(A, shape):
    if A is None:
        return None
    if sp.issparse(A):
        return sp.csr_matrix(A)
    A = np.asarray(A, dtype=float)
    return sp.csr_matrix(A) if A.size else sp.csr_matrix(shape)


class DescriptorFlow:
    """v ↦ Π Φ_T Π v for one sampling of the linearization (module docstring); ``products``
    counts the integrations."""

    def __init__(self, M, fit, period, steps, cache=None):
        C, K, J = fit
        self.M = sp.csc_matrix(M)
        n = self.M.shape[0]
        self.n, self.T, self.steps = n, float(period), int(steps)
        self.h = self.T / self.steps
        self._J = J
        J0 = self._jacobian(0.0, 0)
        self.m = J0.shape[0]
        cache = {} if cache is None else cache  # operators by instant (a fraction of T)
        self.ops = []
        for x in _instants(self.steps, BUTCHER6[0]):
            if x not in cache:
                cache[x] = self._operators(C, K, self.T * float(x))
            self.ops.append(cache[x])
        self.products = 0
        self.budget = None  # products allowed (None: no limit), BudgetSpent past it
        # the projection at t = 0
        self._J0, self._Jd0 = J0, self._jacobian(0.0, 1)
        if self.m:
            try:
                self._JJ = spla.splu(sp.csc_matrix(J0 @ J0.T))
            except RuntimeError as exc:  # SuperLU: "Factor is exactly singular"
                raise FloquetError(f"Φ_q loses rank at t = 0 ({exc}): redundant constraints",
                                   element="monodromy") from None

    def _jacobian(self, t, order):
        """Φ_q(t) (or its derivative of that order) as CSR; the series gives None for a pattern
        with no entries: zero rows of its shape."""
        got = self._J(t, order)
        return sp.csr_matrix(self._J.shape) if got is None else _csr(got, self._J.shape)

    def _operators(self, C, K, t):
        n = self.n
        Jt = self._jacobian(t, 0)
        m = Jt.shape[0]
        if m:
            kkt = sp.bmat([[self.M, Jt.T], [Jt, None]], format="csc")
        else:
            kkt = self.M
        try:
            lu = spla.splu(kkt)
        except RuntimeError as exc:  # SuperLU: "Factor is exactly singular"
            raise FloquetError(f"the mass-constraint matrix [M, Φ_qᵀ; Φ_q, 0] is singular at "
                               f"t = {t:g} ({exc}): a coordinate without mass or redundant "
                               "constraints along the motion", element="monodromy") from None
        # the right-hand side as one sparse product with the state (q, v):
        # [−K, −C; −Φ̈_q, −2 Φ̇_q] (an empty block where the model has no such term)
        zero = sp.csr_matrix((n, n))
        Kt, Ct = _csr(K(t), (n, n)), _csr(C(t), (n, n))
        rows = [[zero if Kt is None else -Kt, zero if Ct is None else -Ct]]
        if m:
            rows.append([-self._jacobian(t, 2), -2.0 * self._jacobian(t, 1)])
        rhs = sp.bmat(rows, format="csr")
        return lu.solve, rhs

    def _rate(self, k, x, out):
        """out ← (v, a): the rate at the stage's state x = (q, v) (vector or columns)."""
        solve, rhs = self.ops[k]
        n = self.n
        out[:n] = x[n:]
        out[n:] = solve(rhs @ x)[:n]

    def project(self, x):
        """Π x: the nearest state (in each half) that keeps the constraints at t = 0."""
        if not self.m:
            return x
        n = self.n
        q, v = x[:n], x[n:]
        J0, Jd0 = self._J0, self._Jd0
        q = q - J0.T @ self._JJ.solve(J0 @ q)
        v = v - J0.T @ self._JJ.solve(J0 @ v + Jd0 @ q)
        return np.concatenate([q, v])

    def __call__(self, x):
        """Π Φ_T Π x (real x of length 2n)."""
        if self.budget is not None and self.products >= self.budget:
            raise BudgetSpent(f"Arnoldi did not converge within {self.budget} products",
                              element="monodromy")
        self.products += 1
        y = rk_fixed(self._rate, self.project(np.asarray(x, dtype=float)), self.h, self.steps)
        return self.project(y)


def consistent_start(flow):
    """A unit state that keeps the constraints at t = 0: a fixed pseudo-random vector (seeded:
    the runs repeat) projected by Π.  A structured vector such as all ones can lie wholly in the
    constraint directions (the spatial pendulum's unit-vector conditions) and project to 0."""
    x = np.random.default_rng(45).standard_normal(2 * flow.n)
    v = flow.project(x)
    norm = float(np.linalg.norm(v))
    if not norm > 1e-8 * float(np.linalg.norm(x)):
        raise FloquetError("no state keeps the constraints at t = 0 (the projection removed "
                           "a random start vector): the motion leaves no degree of freedom",
                           element="monodromy")
    return v / norm


def descriptor_flow(M, fit, period, *, rtol, start=START_STEPS, max_steps=None):
    """The :class:`DescriptorFlow` whose product of a probe vector agrees with the one at half
    its step count to 63 rtol (module docstring); returns (flow, record) with the step counts
    tried, their differences and the probe products (one per step count); the returned flow's
    own ``products`` restart at 0."""
    max_steps = MAX_STEPS if max_steps is None else max_steps
    steps = int(start)
    cache = {}
    coarse = DescriptorFlow(M, fit, period, steps, cache)
    probe = consistent_start(coarse)
    x_coarse = coarse(probe)
    history = []
    while True:
        fine = DescriptorFlow(M, fit, period, 2 * steps, cache)
        x_fine = fine(probe)
        diff = float(np.linalg.norm(x_fine - x_coarse)) / max(float(np.linalg.norm(x_fine)),
                                                              1e-300)
        history.append((2 * steps, diff))
        probes = len(history) + 1  # one product per step count tried
        if diff <= 63.0 * rtol:
            fine.products = 0
            return fine, {"steps": 2 * steps, "history": history, "probe_products": probes}
        if 4 * steps > max_steps or not np.isfinite(diff):
            raise StepsNotSettled(
                f"the fixed-step products did not settle: {2 * steps} steps a period still "
                f"change a product by {diff:.2g} relative (asked {63 * rtol:.2g}); the model "
                "is too stiff for the explicit steps of the partial method: use --floquet full",
                element="monodromy")
        steps, coarse, x_coarse = 2 * steps, fine, x_fine


def descriptor_partial(M, fit, period, *, k, rtol, tol, steps=None, budget=None, start=None,
                       ncv=None, max_steps=None):
    """(result, steps, vectors): the ``k`` multipliers of largest modulus by ARPACK on
    :class:`DescriptorFlow` (a :class:`~mbseig.studies.floquet.PartialFloquetResult`;
    ``products`` counts every integration, the step probes included), the steps a period it
    used (chosen for ``rtol`` by :func:`descriptor_flow` within ``max_steps``, or ``steps`` as
    given) and the Ritz vectors (columns, in the result's order).  ARPACK starts from ``start``
    projected by Π (a previous estimate's vectors, summed) or from :func:`consistent_start`,
    with ``ncv`` basis vectors (None: ARPACK's default); past ``budget`` products it stops with
    :class:`BudgetSpent`.  A Ritz value at the rounding level of the largest is one of the 2m
    zeros the projection adds, not a multiplier: asking that many is refused."""
    if steps is None:
        flow, rec = descriptor_flow(M, fit, period, rtol=rtol, max_steps=max_steps)
    else:
        flow, rec = DescriptorFlow(M, fit, period, steps), {"steps": steps, "probe_products": 0}
    size = 2 * flow.n
    op = LinearOperator((size, size), matvec=flow, dtype=float)
    v0 = consistent_start(flow)
    if start is not None:
        warm = flow.project(np.asarray(start, dtype=complex).reshape(size, -1).sum(axis=1).real)
        if np.linalg.norm(warm) > 0.0:
            v0 = warm / np.linalg.norm(warm)
    flow.budget = budget
    mu, V = eigs(op, k=k, which="LM", tol=tol, v0=v0, ncv=ncv)
    flow.budget = None  # the residual products below are part of the answer, not the search
    floor = 64 * np.finfo(float).eps * float(np.max(np.abs(mu)))
    if np.any(np.abs(mu) <= floor):
        raise FloquetError(f"the {k} largest multipliers reach the rounding level of the largest "
                           f"({floor:.2g}): ask fewer (--n-modes) or use --floquet full",
                           element="monodromy")
    res = np.array([np.linalg.norm((flow(V[:, j].real) + 1j * flow(V[:, j].imag))
                                   - mu[j] * V[:, j]) / np.linalg.norm(V[:, j])
                    for j in range(k)])
    order = np.lexsort((np.angle(mu), -np.abs(mu)))
    method = (f"Arnoldi (ARPACK) on the monodromy operator in the model's coordinates (index-1 "
              f"form, projected on the constraints at t = 0), Butcher's order-6 Runge–Kutta, "
              f"{rec['steps']} fixed steps a period")
    return (PartialFloquetResult(period, mu[order], res[order],
                                 flow.products + rec["probe_products"], method, rtol),
            flow.steps, V[:, order])


#: the full monodromy in the model's coordinates stops doubling here (each step integrates 2r
#: columns): a model that needs more is left to the projected system's adaptive integration
FULL_MAX_STEPS = 512


def descriptor_monodromy(M, fits, period, basis, *, rtol, max_steps=None):
    """(Φ, Φ̃, steps): the monodromy on the coordinates of ``basis`` (2n × 2r, states that keep
    the constraints at t = 0, e.g. (y, p) ↦ (δq, δq̇) of the projected system) from every
    column integrated at once, Φ = basis⁺ Π Φ_T basis, on the first sampling with the steps
    that meet ``rtol`` (:func:`descriptor_flow`) and, as the check, on the shifted sampling at
    half those steps (so that Φ − Φ̃ holds the first one's discretization error as well as the
    sampling's).  Raises :class:`StepsNotSettled` past ``max_steps`` (default
    :data:`FULL_MAX_STEPS`)."""
    max_steps = FULL_MAX_STEPS if max_steps is None else max_steps
    flow, rec = descriptor_flow(M, fits[0], period, rtol=rtol, max_steps=max_steps)
    half = DescriptorFlow(M, fits[1], period, max(rec["steps"] // 2, 1))
    basis = np.asarray(basis, dtype=float)
    Phi = np.linalg.lstsq(basis, flow(basis), rcond=None)[0]
    Phi2 = np.linalg.lstsq(basis, half(basis), rcond=None)[0]
    return Phi, Phi2, rec["steps"]
