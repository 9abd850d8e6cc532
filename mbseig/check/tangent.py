"""Stiff models (configuration-dependent mass: co-rotational beams) integrated in tangent
coordinates of the constraint manifold (coordinate partitioning by a local parametrization).

With N (n × k) an orthonormal basis of null Φ_q(q₀) and R (n × m) of its complement, every
configuration near q₀ on Φ = 0 is

    q(x) = q₀ + N x + R b(x),        Φ(q(x)) = 0   (b by Newton, b = O(|x|²)),
    q̇ = N ẋ + R c,                   Φ_q R c = −Φ_q N ẋ,

and the state integrated is (x, ẋ) ∈ R²ᵏ with ẍ = Nᵀ q̈, q̈ from the index-1 system of
:class:`~mbseig.check.dynamics.ForwardDynamics` at (q(x), q̇) (Nᵀ R = 0).  The constraints then
hold at every evaluation to the Newton tolerance: nothing drifts, nothing is projected, and no
direction normal to the constraints is in the state.

Why (measured on cases/cantilever_3d_oblique.toml, 24 elements): integrating the full state
(u, v) ∈ R²ⁿ with a constant Newton matrix (the exact Jacobian at q₀) fails, because off q₀ the
accelerations normal to the constraints follow Φ_q(q) N ≠ 0 times the stiff tangential
accelerations: ∂q̈_R/∂u has entries ~ε ω_max² (3·10⁷ and 7·10⁷ found by finite differences at
ε = 1e-4, where the constant matrix has 0 and 1e-3), so Radau's Newton iteration contracts only
at a rate ≈ 0.4–0.5 at the steps the accuracy asks (spectral radius of (μ/h − J₀)⁻¹ΔJ = 0.39 at
h = 0.0147), halves its steps, and at a segment end ended on a step of one ulp whose Newton
iteration could not converge in rounding ("Required step size is less than spacing between
numbers").  The rounding noise of the accelerations (1.6e-3 in the tip triad's q̈, in the
unresolved fast modes) also floored every absolute tolerance at 3e-3 of the motion.  In tangent
coordinates the Jacobian at q₀ is the reduced linear model (−M_r⁻¹K_r, −M_r⁻¹C_r), exact there and
off only by the O(ε) change of the physics along the motion (spectral radius of the same
operator ≤ 1e-2 at the start of the run); the noise floor is measured on the resolved modes
alone (7e-11 of 0.73 there).  What still limits the tolerances: the unresolved modes' rounding
noise (~1e-3 in their accelerations) reaches the resolved ones through the geometric coupling
(∂ẅ_slow/∂w_fast ~ 4.5e5 in modal units at ε = 1e-4) inside the Newton iteration, which then
stalls at absolute tolerances of 1e-10 of the perturbation; ``STIFF_RTOL`` = 1e-6 (relative and
× the perturbation) is what it reaches (measured: δ = 7e-6 rad/s, ω to 1.4e-9 on that case,
20 periods).

The state is integrated in the undamped modes of the model's own reduced linearization
(x = X w; ``basis``), the modes above ``cut`` unresolved (absolute tolerance ``FAST_ATOL`` × the
perturbation): see :func:`mbseig.check.dynamics.simulate`.  The default integrator is the
exponential Adams one (:mod:`mbseig.check.exponential`) on the Jacobian at q₀ in these modal
coordinates, velocities in units of their mode's ω (so that J's eigenvectors are judged for
what they are, not for the units); where they are not well conditioned (a nearly defective J),
or where a run needs more than ``EXPONENTIAL_BUDGET`` right-hand sides a sample (undamped fast
modes ringing into the checked one), Radau runs and the result says why.  Radau (or BDF) is
driven step by step to beyond the last sample and read by its dense output, so no step is ever
cut to a sliver at the end of the run.
"""

from __future__ import annotations

import numpy as np
import scipy.linalg as sla
import scipy.sparse as sp

from ..errors import CaseError, SimulationError
from .exponential import ExponentialAdams, ExponentialUnusable

__all__ = ["TangentCoordinates"]

#: Newton iterations of b(x) before the motion counts as having left the parametrized region
NEWTON_MAX = 12
#: constraint residual (max |Φ_k|/scale_k) accepted when Newton stalls in rounding
RESIDUAL_MAX = 1e-10
#: a chord step of lift (Φ_q(q₀) R's factors) must shrink the residual at least this much
CHORD_RATE = 0.1
#: right-hand sides a sample above which the exponential run gives way to Radau: the bundled 3-D
#: beams and rotors need 0.1–1 (docs/beams3d.md); the flexible four-bar needs 116, where the
#: unresolved fast modes, integrated exactly and so undamped, ring into the checked mode's
#: remainder (Radau, L-stable, damps them: 24 a sample there)
EXPONENTIAL_BUDGET = 5


class TangentCoordinates:
    """Tangent-coordinate integration of a :class:`ForwardDynamics` (module docstring)."""

    def __init__(self, dyn):
        self.dyn = dyn
        n, q0 = dyn.n, dyn.q0
        if dyn.m:
            _, sv, vt = sla.svd(dyn.phi_q(q0), full_matrices=True)
            rank = int(np.sum(sv > dyn.rank_tol * max(sv[0], 1e-300)))
            if rank != dyn.m:
                raise SimulationError("tangent coordinates need independent constraints",
                                      element="time-domain check")
            self.N, self.R = vt[rank:].T.copy(), vt[:rank].T.copy()
        else:
            self.N, self.R = np.eye(n), np.zeros((n, 0))
        self.k = self.N.shape[1]
        self.Mr, self.Kr, self.Cr = self._reduced_linear()
        self._basis = self._lu_q0 = None
        self.used = set()  # the integrators the runs took (one, unless one fell back)

    # -- the model's own linearization in x --------------------------------------------------
    def _reduced_linear(self):
        """(M_r, K_r, C_r) = Nᵀ(M, K + H(λ₀), C)N at q₀ from the model itself (not from the
        linearization under check, so that a wrong prediction cannot shape its own run)."""
        dyn, N, q0 = self.dyn, self.N, self.dyn.q0
        K, C = dyn.model.force_jacobians(q0, np.zeros(dyn.n))
        K = sp.csr_matrix(K)
        if dyn.m:
            lam0 = dyn.acceleration(q0, np.zeros(dyn.n))[1]
            K = K + sp.csr_matrix(dyn.model.constraint_hessian(q0, lam0))
        M = sp.csr_matrix(dyn.model.mass_matrix(q0))
        return N.T @ (M @ N), N.T @ (K @ N), N.T @ (sp.csr_matrix(C) @ N)

    def jacobian(self):
        """∂(ẋ, ẍ)/∂(x, ẋ) at q₀: exact (the reduced linear model)."""
        k = self.k
        A = np.linalg.solve(self.Mr, np.hstack([self.Kr, self.Cr]))
        return np.block([[np.zeros((k, k)), np.eye(k)], [-A[:, :k], -A[:, k:]]])

    def basis(self):
        """(X, ω): undamped modes of (sym K_r, sym M_r), x = X w, columns scaled so that N X has
        a largest entry of 1 (a component is a length like u); ω = √|λ|."""
        lam, X = sla.eigh(0.5 * (self.Kr + self.Kr.T), 0.5 * (self.Mr + self.Mr.T))
        X = X / np.abs(self.N @ X).max(axis=0)
        return X, np.sqrt(np.abs(lam))

    # -- lifting x to q ----------------------------------------------------------------------
    def _lu0(self):
        """LU of Φ_q(q₀) R, the chord matrix of :meth:`lift` (factored once per integration)."""
        if self._lu_q0 is None:
            self._lu_q0 = sla.lu_factor(self.dyn.model.phi_q(self.dyn.q0) @ self.R)
        return self._lu_q0

    def lift(self, x, xd=None):
        """(u, v, residual, |R b|): q = q₀ + u on Φ = 0 and q̇ = v with Φ_q q̇ = 0.

        Both solves iterate with the factors of Φ_q(q₀) R (chord steps) instead of refactoring
        Φ_q(q) R at each q: their fixed points are those of Newton's method (Φ(q) = 0 to the
        same ``projection_tol``; Φ_q(q) v = 0 to rounding), reached at a rate |Φ_q(q) − Φ_q(q₀)|
        / |Φ_q(q₀)| ~ |u|/L (1e-4 at the check's perturbations: one or two steps more, each a
        back substitution).  A step that contracts by less than ``CHORD_RATE`` switches to
        Newton at the current q (motions far from q₀)."""
        dyn, N, R = self.dyn, self.N, self.R
        u = N @ x
        v = None if xd is None else N @ xd
        if not dyn.m:
            return u, v, 0.0, 0.0
        b = np.zeros(R.shape[1])
        res_old, lu = np.inf, self._lu0()
        for _ in range(NEWTON_MAX):
            q = dyn.q0 + u + R @ b
            r = dyn.model.phi(q)
            res = float(np.max(np.abs(r) / dyn.cscale))
            if res <= dyn.projection_tol or (res >= res_old and res <= RESIDUAL_MAX):
                break
            if res > CHORD_RATE * res_old:  # slow or no contraction: Newton at q
                lu = sla.lu_factor(dyn.model.phi_q(q) @ R)
            res_old = res
            b = b - sla.lu_solve(lu, r)
        else:
            if res > RESIDUAL_MAX:
                raise SimulationError(
                    f"the motion left the region where tangent coordinates parametrize the "
                    f"constraints (residual {res:.2g} after {NEWTON_MAX} Newton steps)",
                    element="time-domain check")
        if v is not None:
            v = self._tangent_velocity(dyn.model.phi_q(q), v)
        return u + R @ b, v, res, float(np.linalg.norm(b))

    def _tangent_velocity(self, Jq, v):
        """v − R c with Φ_q R c = Φ_q v, by chord steps with Φ_q(q₀) R's factors until a step
        no longer changes v (below 1e-16 of it), Newton's solve if they do not contract."""
        R, lu, last = self.R, self._lu0(), np.inf
        scale = float(np.max(np.abs(v), initial=0.0))
        for _ in range(NEWTON_MAX):
            d = sla.lu_solve(lu, Jq @ v)
            step = R @ d
            v = v - step
            size = float(np.max(np.abs(step), initial=0.0))
            if size <= 1e-16 * scale or size >= last:
                return v
            # a slow step far above rounding: Newton's matrix (near rounding the steps stall
            # whatever the matrix, and the next test ends the loop)
            if size > CHORD_RATE * last and size > 1e-12 * scale:
                lu = sla.lu_factor(Jq @ R)
            last = size
        return v

    @staticmethod
    def _exponential(fun, jac, w0, t_eval, rtol, atol, dt, units, loose):
        """w at t_eval by :class:`~mbseig.check.exponential.ExponentialAdams` from the
        Jacobian at q₀, first step two sample intervals."""
        integrator = ExponentialAdams(fun, jac, rtol=rtol, atol=atol, scale=units, loose=loose)
        try:
            return integrator.run(w0, t_eval, 2.0 * dt, budget=EXPONENTIAL_BUDGET)
        except ArithmeticError as exc:
            raise SimulationError(f"integration failed: {exc}",
                                  element="time-domain check") from None

    def rhs(self, t, y):
        """(ẋ, ẍ) at (x, ẋ) = y."""
        k, n = self.k, self.dyn.n
        u, v, _, _ = self.lift(y[:k], y[k:])
        qdd = self.dyn.rhs(t, np.concatenate([u, v]))[n:]
        return np.concatenate([y[k:], self.N.T @ qdd])

    # -- integration ---------------------------------------------------------------------
    def simulate(self, u0, v0, t_eval, *, method, rtol, atol_position, atol_velocity, cut,
                 fast_atol, noise_factor):
        """Integrate from (u0, v0) (tangent parts Nᵀu0, Nᵀv0) through ``t_eval``; returns the
        ``Simulation`` fields as a dict (mbseig.check.dynamics.simulate assembles it)."""
        from scipy.integrate import BDF, OdeSolution, Radau

        solvers = {"Radau": Radau, "BDF": BDF}
        if method not in solvers and method != "exponential":
            raise CaseError(f"a stiff model runs the exponential integrator, Radau or BDF, not "
                            f"{method!r}", element="method")
        k, dyn = self.k, self.dyn
        if self._basis is None:
            self._basis = self.basis()
        X, omega = self._basis
        Xi = np.linalg.inv(X)
        fast = omega > cut
        amp = max(float(np.max(np.abs(u0), initial=0.0)), atol_position)
        W = sla.block_diag(X, X)
        Wi = sla.block_diag(Xi, Xi)

        def fun(t, w):
            return Wi @ self.rhs(t, W @ w)

        w0 = Wi @ np.concatenate([self.N.T @ u0, self.N.T @ v0])
        # rounding noise of the resolved modes' accelerations (their rows of fun) near w0
        dt = float(t_eval[1] - t_eval[0]) if len(t_eval) > 1 else 1.0
        rng = np.random.default_rng(0)
        dw = np.concatenate([rng.standard_normal(k), np.zeros(k)]) * (1e-8 * amp)
        dw[:k][fast] = 0.0
        acc = np.array([fun(0.0, w0 + j * dw)[k:] for j in range(11)])
        noise = np.max(np.abs(np.diff(acc, 2, axis=0)), axis=0) / 4.0
        sigma = float(np.max(noise[~fast], initial=0.0))
        atol_velocity = max(atol_velocity, noise_factor * sigma * dt)
        atol_position = max(atol_position, atol_velocity * dt)
        atol = np.concatenate([np.full(k, atol_position), np.full(k, atol_velocity)])
        atol[:k][fast] = fast_atol * amp
        atol[k:][fast] = fast_atol * amp * omega[fast]
        nfev0 = dyn.nfev
        T = float(t_eval[-1])
        jac = Wi @ self.jacobian() @ W
        used = method
        if method == "exponential":
            try:
                units = np.concatenate([np.ones(k), np.where(omega > 0, omega, 1.0)])
                loose = np.concatenate([fast, fast])
                Y = self._exponential(fun, jac, w0, t_eval, rtol, atol, dt, units, loose)
            except ExponentialUnusable as exc:
                used = f"Radau (the exponential integrator does not apply: {exc})"
                method = "Radau"
        if method != "exponential":
            solver = solvers[method](fun, 0.0, w0, 2.0 * T + 1.0, rtol=rtol, atol=atol, jac=jac)
            ts, pieces = [0.0], []
            while solver.t < T:
                msg = solver.step()
                if solver.status == "failed":
                    raise SimulationError(f"integration failed at t = {solver.t:.6g}: {msg}",
                                          element="time-domain check")
                ts.append(solver.t)
                pieces.append(solver.dense_output())
            Y = OdeSolution(ts, pieces)(np.asarray(t_eval, float))
        self.used.add(used)
        Y = W @ Y
        Y[:, 0] = W @ w0
        U, V = np.empty((dyn.n, Y.shape[1])), np.empty((dyn.n, Y.shape[1]))
        drift = vdrift = proj = 0.0
        for j in range(Y.shape[1]):
            U[:, j], V[:, j], res, nb = self.lift(Y[:k, j], Y[k:, j])
            drift, proj = max(drift, res), max(proj, nb)
            if dyn.m:
                vdrift = max(vdrift, float(np.max(np.abs(dyn.model.phi_q(dyn.q0 + U[:, j])
                                                         @ V[:, j]))))
        return {"u": U, "v": V, "method": used, "rtol": rtol, "atol_position": atol_position,
                "atol_velocity": atol_velocity, "n_segments": 1, "nfev": dyn.nfev - nfev0,
                "constraint_drift": drift, "velocity_drift": vdrift, "max_projection": proj,
                "max_velocity_projection": 0.0, "fast_modes": int(fast.sum())}
