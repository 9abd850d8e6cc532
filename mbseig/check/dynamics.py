"""The nonlinear constrained equations of motion in index-1 form, integrated with projection.

    ┌ M     Φ_qᵀ ┐ ┌ q̈ ┐   ┌ g(q, q̇) ┐
    └ Φ_q    0   ┘ └ λ  ┘ = └    γ     ┘

about the equilibrium q₀ (state u = q − q₀, v = q̇), DOP853 by default (explicit: no numerical
damping), q and v projected back onto Φ = 0, Φ_q q̇ = 0 at the end of every segment so that
constraint drift cannot fake a decay (docs/design.md, "Time-domain check").

Configuration-dependent mass (co-rotational beams, 2-D and 3-D: ``model.mass_elements``).  The
equations are Lagrange's with M(q):

    M(q) q̈ + h(q, q̇) + Φ_qᵀ λ = g(q, q̇),    h = Ṁ q̇ − ½ ∂(q̇ᵀ M q̇)/∂q,

M(q) = ``model.mass_matrix(q)`` at every evaluation.  h is formed element by element: in closed
form where the element gives ``velocity_terms(q, q̇)`` (the 3-D beams,
:mod:`mbseig.model.beam_whirl`), otherwise from the element's own ``mass(q)`` (the
:class:`~mbseig.model.base.ConfigurationMass` contract): Ṁ q̇ by a central difference along q̇ and
each component of ½ ∂(q̇ᵀ M_e q̇)/∂q_j by a central difference along q_j (step ``MASS_STEP`` ×
max(|q_j|, length scale): truncation error ~1e-12 of h, which is itself of second order in the
perturbation).  The augmented system is then solved sparse (SuperLU: one thread, no BLAS
contention).  Such models carry axial modes orders of magnitude stiffer than the bending modes
that are checked, so where DOP853 is asked :func:`simulate` integrates them in the tangent
coordinates of their constraints (:mod:`mbseig.check.tangent`: why the full state fails there
is measured in its docstring) with the exponential Adams integrator
(:mod:`mbseig.check.exponential`: the linearization at the equilibrium integrated exactly, only
the nonlinear remainder stepped), or with Radau IIA (order 5, implicit, the exact Jacobian at the
equilibrium as Newton matrix) where that Jacobian has no well-conditioned eigenvector basis or
Radau is asked (an explicit method would need steps below the axial period;
``Simulation.method`` records the one used, and why where the exponential one did not apply).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import scipy.linalg as sla
import scipy.sparse as sp
import scipy.sparse.linalg as spla

from ..errors import CaseError, SimulationError
from ..model.base import Force
from ..model.linear_case import LinearCase
from ..numerics import dense, min_norm_projection, null_space_basis
from .augmented import AugmentedPattern

__all__ = ["INTEGRATORS", "ForwardDynamics", "Simulation", "simulate"]

#: integrators offered through ``method=`` (scipy.integrate.solve_ivp names)
INTEGRATORS = ("DOP853", "Radau", "BDF", "exponential")
#: relative central-difference step of the mass derivatives (module docstring)
MASS_STEP = 1e-6
#: stiff models: absolute tolerances at least this many noise levels per sample interval,
#: relative tolerance at least STIFF_RTOL, absolute ones at least STIFF_RTOL × the
#: perturbation (simulate): the rounding noise of the unresolved stiff modes reaches the
#: resolved ones through the geometric coupling inside Radau's Newton iteration
#: (mbseig.check.tangent), which does not converge to tighter tolerances
NOISE_FACTOR = 10.0
STIFF_RTOL = 1e-6
#: stiff models: modes above FAST_FACTOR × the checked |s| are left unresolved (simulate)
FAST_FACTOR = 10.0
#: their absolute tolerance, relative to the perturbation (they carry ~ε² of it)
FAST_ATOL = 1e-2


class ForwardDynamics:
    """Right-hand side and constraint projections of the nonlinear model about q₀.

    State y = [u; v] with q = q₀ + u, q̇ = v.  ``model`` is a :class:`~mbseig.Model` or a
    :class:`~mbseig.LinearCase` (then M ẍ + P ẋ + Q x = 0 is integrated as it stands).
    """

    def __init__(self, model, q0, *, redundant: bool = False, mass_tol: float = 1e-12,
                 projection_tol: float = 1e-14, rank_tol: float = 1e-10):
        self.model = model
        self.q0 = np.asarray(q0, dtype=float)
        self.mass_tol, self.projection_tol, self.rank_tol = mass_tol, projection_tol, rank_tol
        self.linear = isinstance(model, LinearCase)
        self.n = model.n
        self.nfev = 0
        self._pattern = None  # of the augmented matrix (_augmented)
        if self.linear:
            self.M = dense(model.M)
            self.P, self.Q = dense(model.P), dense(model.Q)
            self.m = 0
            self.constraints = ()
        else:
            self.mass_elements = tuple(getattr(model, "mass_elements", ()) or ())
            self.M = model.mass.toarray()
            self.constraints = tuple(model.constraints)
            self.m = model.n_constraints
            off = np.cumsum([0] + [c.n_eq for c in self.constraints])
            self.rows = [np.arange(off[k], off[k + 1]) for k in range(len(self.constraints))]
            self.cscale = model.constraint_scales() if self.m else np.zeros(0)
        if self.linear:
            self.mass_elements = ()
        # configuration-dependent mass or stiff structural elements: integrated as stiff
        # (simulate)
        self.stiff = bool(self.mass_elements) or (not self.linear and any(
            isinstance(f, Force) and f.stiff_structure for f in model.forces))
        self._step = MASS_STEP * (1.0 if self.linear else float(model.length_scale))
        self.redundant = bool(redundant)
        self._check_mass()
        if self.m == 0 and not self.stiff:
            self._lu = sla.lu_factor(self.M)

    # -- model pieces (dense, assembled here because the sparse assembly costs ~100 µs) ------
    def phi(self, q):
        return self.model.phi(q) if self.m else np.zeros(0)

    def phi_q(self, q):
        J = np.zeros((self.m, self.n))
        for r, c in zip(self.rows, self.constraints, strict=True):
            J[np.ix_(r, c.idx)] = c.jac(q)
        return J

    def force(self, q, qd):
        if self.linear:
            return -(self.P @ qd) - self.Q @ q
        return self.model.generalized_force(q, qd)

    def _check_mass(self):
        """The reduced mass Nᵀ M N must be positive definite (no massless free motion)."""
        N = (null_space_basis(self.phi_q(self.q0), self.n, self.rank_tol)[0] if self.m
             else np.eye(self.n))
        if N.shape[1] == 0:
            return
        Mr = N.T @ self.M @ N
        w, V = np.linalg.eigh(0.5 * (Mr + Mr.T))
        scale = max(float(np.max(np.abs(np.diag(self.M)), initial=0.0)), 1e-300)
        if w[0] <= self.mass_tol * scale:
            v = N @ V[:, 0]
            names = [self.model.coordinate_names[i] for i in np.argsort(-np.abs(v))[:3]
                     if abs(v[i]) >= 0.1 * np.abs(v).max()]
            raise SimulationError(
                f"the mass matrix is singular on the constraint null space (massless free motion "
                f"of {', '.join(names)}): the forward dynamics are not an ODE; give these points "
                f"mass or constrain them", element="time-domain check")

    # -- configuration-dependent mass (module docstring) -------------------------------------
    def mass(self, q):
        """M(q), dense: the constant part plus every element's mass(q) − its reference."""
        if not self.mass_elements:
            return self.M
        M = self.M.copy()
        for el, M_ref in self.mass_elements:
            M[np.ix_(el.idx, el.idx)] += el.mass(q) - M_ref
        return M

    def velocity_terms(self, q, qd):
        """h(q, q̇) = Ṁ q̇ − ½ ∂(q̇ᵀ M q̇)/∂q (zeros for a constant mass)."""
        h = np.zeros(self.n)
        if not self.mass_elements or not np.any(qd):
            return h
        for el, _ in self.mass_elements:
            idx = el.idx
            v = qd[idx]
            vmax = float(np.max(np.abs(v)))
            if vmax == 0.0:
                continue
            closed = el.velocity_terms  # declared on the element's class (mbseig.model.base)
            if closed is not None:
                h[idx] += closed(q, qd)
                continue
            e = self._step / vmax
            dq = np.zeros_like(q)
            dq[idx] = e * v
            Mdot_v = ((el.mass(q + dq) - el.mass(q - dq)) @ v) / (2.0 * e)
            grad = np.empty(idx.size)
            for k, j in enumerate(idx):
                hj = self._step * max(abs(q[j]), 1.0)
                qp, qm = q.copy(), q.copy()
                qp[j] += hj
                qm[j] -= hj
                grad[k] = v @ ((el.mass(qp) - el.mass(qm)) @ v) / (4.0 * hj)
            h[idx] += Mdot_v - grad
        return h

    # -- accelerations ----------------------------------------------------------------------
    def acceleration(self, q, qd):
        """(q̈, λ) from the augmented index-1 system."""
        self.nfev += 1
        g = self.force(q, qd)
        if self.stiff:
            g = g - self.velocity_terms(q, qd)
        if self.m == 0:
            if self.stiff:
                return spla.spsolve(sp.csc_matrix(self.model.mass_matrix(q)), g), np.zeros(0)
            return sla.lu_solve(self._lu, g), np.zeros(0)
        gam = self.model.gamma(q, qd)
        n = self.n
        if self.stiff and not self.redundant:  # sparse: M(q) and Φ_q are banded for beams
            A = self._augmented(q)
            sol = spla.splu(A).solve(np.concatenate([g, gam]))
            return sol[:n], sol[n:]
        M = self.mass(q) if self.stiff else self.M
        J = self.phi_q(q)
        A = np.zeros((n + self.m, n + self.m))
        A[:n, :n] = M
        A[:n, n:] = J.T
        A[n:, :n] = J
        rhs = np.concatenate([g, gam])
        if self.redundant:
            sol = np.linalg.lstsq(A, rhs, rcond=None)[0]
        else:
            sol = np.linalg.solve(A, rhs)
        return sol[:n], sol[n:]

    def _augmented(self, q):
        """[[M(q), Φ_qᵀ], [Φ_q, 0]] (CSC) as ``sp.bmat`` forms it from ``mass_matrix(q)`` and
        ``phi_q(q)``: the same entries, order and stored zeros (none of M's, Φ_q's kept), so
        that SuperLU orders and factors the very same matrix; filled into the pattern of the
        first call (``AugmentedPattern``) while M(q) and Φ_q keep their patterns."""
        Mf, Js = self.model.mass_matrix(q, fixed=True), self.model.phi_q(q)
        if self._pattern is None:
            self._pattern = AugmentedPattern(Mf, Js)
        elif not self._pattern.matches(Mf, Js):  # patterns that change (large models): bmat
            Mf = Mf.copy()
            Mf.eliminate_zeros()
            return sp.bmat([[Mf, Js.T], [Js, None]], format="csc")
        return self._pattern.fill(Mf, Js)

    def rhs(self, t, y):
        n = self.n
        u, v = y[:n], y[n:]
        qdd, _ = self.acceleration(self.q0 + u, v)
        return np.concatenate([v, qdd])

    def acceleration_noise(self, y, scale_u: float) -> float:
        """Rounding noise of q̈ near the state y: the largest second difference of q̈ over
        eleven points 1e-8 of the perturbation apart (a smooth q̈ gives ~0 there)."""
        n = self.n
        rng = np.random.default_rng(0)
        dy = np.concatenate([rng.standard_normal(n), np.zeros(n)]) * (1e-8 * scale_u)
        acc = np.array([self.rhs(0.0, y + t * dy)[n:] for t in range(11)])
        return float(np.max(np.abs(np.diff(acc, 2, axis=0)), initial=0.0)) / 4.0

    def state_jacobian(self):
        """∂(rhs)/∂y at the equilibrium, exact: the constant Newton matrix Radau uses for a
        configuration-dependent mass (the motion stays within the perturbation of q₀).  At
        (q₀, q̇ = 0) q̈ = 0 and h, γ are quadratic in q̇, so

            ┌ M   Φ_qᵀ ┐ ┌ ∂q̈/∂u  ∂q̈/∂v ┐   ┌ −(K + H(λ₀))  −C ┐
            └ Φ_q   0  ┘ └   ·       ·    ┘ = └      0         0 ┘

        with (K, C) = −(∂g/∂q, ∂g/∂q̇) and H(λ₀) = ∂(Φ_qᵀλ₀)/∂q of the reactions λ₀ at q₀."""
        n, m, q0 = self.n, self.m, self.q0
        K, C = self.model.force_jacobians(q0, np.zeros(n))
        K, C = sp.csc_matrix(K), sp.csc_matrix(C)
        if m:
            lam0 = self.acceleration(q0, np.zeros(n))[1]
            K = K + sp.csc_matrix(self.model.constraint_hessian(q0, lam0))
            Js = self.model.phi_q(q0)
            A = sp.bmat([[self.model.mass_matrix(q0), Js.T], [Js, None]], format="csc")
        else:
            A = sp.csc_matrix(self.model.mass_matrix(q0))
        rhs = np.zeros((n + m, 2 * n))
        rhs[:n, :n], rhs[:n, n:] = -K.toarray(), -C.toarray()
        X = spla.splu(A).solve(rhs)[:n]
        return np.block([[np.zeros((n, n)), np.eye(n)], [X]])

    # -- projections ------------------------------------------------------------------------
    def constraint_violation(self, u, v):
        """(max |Φ_k|/scale_k, max |Φ_q q̇|) at q = q₀ + u."""
        if self.m == 0:
            return 0.0, 0.0
        q = self.q0 + u
        pos = float(np.max(np.abs(self.phi(q)) / self.cscale))
        vel = float(np.max(np.abs(self.phi_q(q) @ v)))
        return pos, vel

    def project(self, u, v, *, max_iter: int = 10):
        """Minimum-norm corrections onto Φ(q₀ + u) = 0 and Φ_q v = 0; returns (u, v, |Δu|, |Δv|)."""
        if self.m == 0:
            return u, v, 0.0, 0.0
        u, _, converged, du_total = min_norm_projection(
            lambda x: self.phi(self.q0 + x), lambda x: self.phi_q(self.q0 + x), u, self.cscale,
            tol=self.projection_tol, max_iter=max_iter)
        if not converged:
            raise SimulationError(
                "position projection onto the constraints did not converge (the motion left the "
                "region where the constraints can be satisfied)", element="time-domain check")
        J = self.phi_q(self.q0 + u)
        dv = -np.linalg.lstsq(J, J @ v, rcond=None)[0]
        return u, v + dv, float(np.linalg.norm(du_total)), float(np.linalg.norm(dv))


@dataclass(frozen=True, eq=False)
class Simulation:
    """Samples of a forward-dynamics run: q(t) = q₀ + u(t), q̇(t) = v(t).

    ``constraint_drift``: largest max_k |Φ_k|/scale_k met before a projection;
    ``velocity_drift``: largest |Φ_q q̇|; ``max_projection``: largest position correction.
    """

    t: np.ndarray
    u: np.ndarray  # n × len(t)
    v: np.ndarray
    method: str
    rtol: float
    atol_position: float
    atol_velocity: float
    n_segments: int
    nfev: int
    constraint_drift: float
    velocity_drift: float
    max_projection: float
    max_velocity_projection: float
    fast_modes: int = 0  # modes integrated unresolved (stiff models: simulate's ``cut``)


def simulate(dynamics: ForwardDynamics, u0, v0, t_eval, *, segment_samples: int,
             method: str = "DOP853", rtol: float = 1e-10, atol_position: float,
             atol_velocity: float, cut: float | None = None, tangent=None) -> Simulation:
    """Integrate from (u0, v0) through the sample times ``t_eval`` (t_eval[0] = 0), projecting
    onto the constraints every ``segment_samples`` samples.

    A model with a configuration-dependent mass (``dynamics.stiff``) runs the exponential
    integrator (Radau where it does not apply, and for redundant constraints) where DOP853 is
    asked, at a relative tolerance of at least ``STIFF_RTOL`` that also bounds the absolute
    ones relative to the perturbation, in the tangent coordinates of its constraints
    (:class:`~mbseig.check.tangent.TangentCoordinates`, ``tangent`` if given, built otherwise;
    redundant constraints: the full state with projections, as other models).  There the modes
    of the model's own linearization above ``cut`` (rad/s) are left unresolved with the
    absolute tolerance ``FAST_ATOL`` × the perturbation (× ω for velocities): the nonlinear
    terms excite the stiff axial modes at second order; resolving them would cost thousands
    of steps per period of the checked mode, while Radau (L-stable) damps them unresolved and
    the modal coordinate of the checked mode is blind to them to first order."""
    from scipy.integrate import (
        solve_ivp,  # imported here: it costs ~0.2 s at import mbseig
    )

    if method not in INTEGRATORS:
        raise CaseError(f"unknown integrator {method!r} (one of {', '.join(INTEGRATORS)})",
                        element="method")
    n = dynamics.n
    extra = {}
    stiff = getattr(dynamics, "stiff", False)
    if method == "exponential" and not (stiff and not dynamics.redundant):
        raise CaseError("the exponential integrator runs in the tangent coordinates of a stiff "
                        "model (a configuration-dependent mass, independent constraints); this "
                        "model is not one: use DOP853, Radau or BDF", element="method")
    if stiff:
        if method == "DOP853":  # stiff axial modes (module docstring)
            method = "Radau" if dynamics.redundant else "exponential"
        rtol = max(rtol, STIFF_RTOL)
        amp = max(float(np.max(np.abs(u0), initial=0.0)), atol_position / rtol)
        speed = atol_velocity / atol_position if atol_position > 0 else 1.0
        atol_position = max(atol_position, rtol * amp)
        atol_velocity = max(atol_velocity, rtol * amp * speed)
        if not dynamics.redundant:
            from .tangent import TangentCoordinates

            tc = TangentCoordinates(dynamics) if tangent is None else tangent
            out = tc.simulate(np.asarray(u0, float), np.asarray(v0, float), t_eval,
                              method=method, rtol=rtol, atol_position=atol_position,
                              atol_velocity=atol_velocity,
                              cut=np.inf if cut is None else float(cut), fast_atol=FAST_ATOL,
                              noise_factor=NOISE_FACTOR)
            return Simulation(t=np.asarray(t_eval, float), **out)
        if method in ("Radau", "BDF"):
            extra["jac"] = dynamics.state_jacobian()
        # the stiff forces are computed from absolute coordinates: their rounding noise σ (in q̈)
        # bounds what any step can resolve; tolerances below it would shrink the steps to
        # nothing, so the absolute tolerances are floored at NOISE_FACTOR σ per sample interval
        dt = float(t_eval[1] - t_eval[0]) if len(t_eval) > 1 else 1.0
        sigma = dynamics.acceleration_noise(np.concatenate([u0, v0]), amp)
        atol_velocity = max(atol_velocity, NOISE_FACTOR * sigma * dt)
        atol_position = max(atol_position, atol_velocity * dt)
    atol = np.concatenate([np.full(n, atol_position), np.full(n, atol_velocity)])
    u, v, _, _ = dynamics.project(np.asarray(u0, float), np.asarray(v0, float))
    fun = dynamics.rhs
    U, V = [u], [v]
    drift = vdrift = proj = vproj = 0.0
    n_seg = 0
    k = 0
    nfev0 = dynamics.nfev
    while k < len(t_eval) - 1:
        k1 = min(k + segment_samples, len(t_eval) - 1)
        ts = t_eval[k:k1 + 1]
        y0 = np.concatenate([u, v])
        try:
            sol = solve_ivp(fun, (ts[0], ts[-1]), y0, method=method, t_eval=ts[1:], rtol=rtol,
                            atol=atol, **extra)
        except np.linalg.LinAlgError as exc:  # a state where [M Φ_qᵀ; Φ_q 0] is singular
            raise SimulationError(
                f"integration ({method}) failed between t = {ts[0]:.6g} and {ts[-1]:.6g}: the "
                f"mass-constraint matrix [M, Phi_q^T; Phi_q, 0] was singular at a state the "
                f"integrator tried ({exc})", element="time-domain check") from exc
        if sol.status != 0:
            t_fail = sol.t[-1] if sol.t.size else ts[0]
            raise SimulationError(f"integration failed at t = {t_fail:.6g}: {sol.message}",
                                  element="time-domain check")
        n_seg += 1
        u, v = sol.y[:n, -1], sol.y[n:, -1]
        d, dv = dynamics.constraint_violation(u, v)
        drift, vdrift = max(drift, d), max(vdrift, dv)
        u, v, du, dvv = dynamics.project(u, v)
        proj, vproj = max(proj, du), max(vproj, dvv)
        U.extend(sol.y[:n, :-1].T)
        V.extend(sol.y[n:, :-1].T)
        U.append(u)
        V.append(v)
        k = k1
    return Simulation(t=np.asarray(t_eval, float), u=np.array(U).T, v=np.array(V).T, method=method,
                      rtol=rtol, atol_position=atol_position, atol_velocity=atol_velocity,
                      n_segments=n_seg, nfev=dynamics.nfev - nfev0, constraint_drift=drift,
                      velocity_drift=vdrift, max_projection=proj, max_velocity_projection=vproj,
                      fast_modes=0)
