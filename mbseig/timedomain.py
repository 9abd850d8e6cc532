"""Time-domain cross-check of predicted modes (DESIGN §7).

Each checked mode is proved against a simulation of the *nonlinear* model, not of the linear one
that predicted it, so that a wrong linearization cannot pass.

Forward dynamics
----------------
The constrained equations  M q̈ + Φ_qᵀ λ = g(q, q̇),  Φ(q) = 0  are integrated in index-1 form
(no Baumgarte terms): every right-hand-side evaluation solves

    ┌ M     Φ_qᵀ ┐ ┌ q̈ ┐   ┌ g(q, q̇) ┐
    │            │ │    │ = │         │          γ = −(Φ_q q̇)_q q̇   (Φ_q q̈ = γ)
    └ Φ_q    0   ┘ └ λ  ┘   └ γ(q, q̇) ┘

for q̈ (minimum-norm least squares when constraints are redundant).  The state is the deviation
u = q − q₀, v = q̇ from the equilibrium, so the relative tolerance acts on the perturbation and not
on the coordinates' absolute size.  The run is cut into segments (one period, or a tenth of an
e-folding time, of the checked mode); at every segment end q is projected back onto Φ(q) = 0 and q̇
onto Φ_q q̇ = 0 by minimum-norm corrections.  The largest violation met before a projection is
recorded (``constraint_drift``: max_k |Φ_k| / scale_k, e.g. scale L² for a rigid length, so a
drift d means a length error of about d·L/2, to be compared with the perturbation ε·L) so that
drift can be seen not to fake a decay.  A point may be massless only where the constraints fix
it: the reduced mass Nᵀ M N must be positive definite, otherwise
:class:`~mbseig.errors.SimulationError` names the massless coordinates.  Models with a
configuration-dependent mass (co-rotational beams) are refused with the same error: they would
need the quadratic velocity terms of M(q) and, being stiff in their axial modes, an implicit
integrator.

Integrator
----------
``DOP853`` (Dormand–Prince 8(5,3), scipy.integrate.solve_ivp) with ``ode_rtol = 1e-10``.  An
explicit method of order 8 has no built-in dissipation: its amplification factor per step differs
from 1 by the local error, which the step control holds at 1e-10 of the perturbation.  Measured:
the undamped pendulum shows an apparent δ/ω = 3.0e-12 whether the run lasts 20 or 100 periods
(ω error 6.5e-10), seven orders below the check's ``zero_delta_tol = 1e-5`` (asserted ≤ 1e-8 in
tests/test_timedomain.py).  Implicit L-stable methods (Radau, BDF) damp under-resolved motion;
Radau is offered (``method=``) for stiff models, where it damps only the unresolved fast modes
that the modal projection discards; BDF (variable order 1–5) is offered to measure what a
low-order implicit method does to the measured δ (``mbseig bench``).  A symplectic scheme (RATTLE) would be energy-neutral but is
second order and does not help with the damped and non-conservative forces the check must also
handle.

Initial condition and extraction
--------------------------------
For a listed mode s = −δ + iω with reduced right vector x̂ (normalized so that the largest
component of N x̂ is 1), the start is q = q₀ + a N Re(x̂), q̇ = a N Re(s x̂), projected onto the
constraints, with a = ``amplitude`` · model length scale (growing modes start at a·e^(−efolds), so
they end at a).  The nonlinear terms shift the measured δ and ω by O(ε) relative to the linear
prediction (measured on the finger-exoskeleton case: 9e-4 in ω of its most damped mode at ε = 1e-3,
9e-5 at 1e-4, 9e-6 at 1e-5), hence the default ε = 1e-4; the integration works on the deviation,
so a small ε costs no accuracy.  With the left vector y, yᴴ(s²M + sP + Q) = 0, of the reduced
model and x = Nᵀ(q − q₀), ẋ = Nᵀ q̇, the modal coordinate

    η(t) = yᴴ[(sM + P) x + M ẋ] / yᴴ(2sM + P) x̂

is the projection of the state on the left eigenvector [(sM + P)ᴴ y; y] of the companion pencil:
for the linear model η(t) = η(0) e^{st} exactly, whatever the other modes do.  δ and ω are
fitted by linear least squares, log|η| = c − δ t and unwrap(arg η) = φ + ω t, over the whole run
(≥ ``periods`` periods or ``efolds`` e-folding times).  If the linear model is wrong, the response
is no eigenmotion of it and η carries the true frequency and decay, which is what the fit reports.

Verdict per mode::

    rel_error.omega = |ω_m − ω_p| / ω_p            (|s_p| for a real mode)
    rel_error.delta = |δ_m − δ_p| / max(|δ_p|, (zero_delta_tol / delta_rtol) |s_p|)
    passed          = rel_error.omega ≤ omega_rtol  and  rel_error.delta ≤ delta_rtol

so an undamped mode passes when |δ_m| ≤ zero_delta_tol·|s_p|.  Rigid-body modes (s = 0) are not
fitted (the reason is recorded); instead a static probe of the nonlinear model checks that it
offers no restoring force along them (see :func:`_probe_rigid`), so a linearization that turns an
oscillation into a rigid-body mode cannot pass either.
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass, field, replace

import numpy as np
import scipy.linalg as sla

from .case import LinearCase
from .errors import CaseError, SimulationError

__all__ = [
    "CheckResult",
    "ModeCheck",
    "Simulation",
    "ForwardDynamics",
    "check_modes",
    "simulate",
    "parse_mode_list",
    "reaction_forces",
    "INTEGRATORS",
]

#: integrators offered through ``method=`` (scipy.integrate.solve_ivp names)
INTEGRATORS = ("DOP853", "Radau", "BDF")


# ---------------------------------------------------------------------------------------------
# Forward dynamics
# ---------------------------------------------------------------------------------------------
class ForwardDynamics:
    """Right-hand side and constraint projections of the nonlinear model about q₀.

    State y = [u; v] with q = q₀ + u, q̇ = v.  ``model`` is a :class:`~mbseig.Model` or a
    :class:`~mbseig.LinearCase` (then M ẍ + P ẋ + Q x = 0 is integrated as it stands).
    """

    def __init__(self, model, q0, *, redundant: bool = False, mass_tol: float = 1e-12,
                 projection_tol: float = 1e-14):
        self.model = model
        self.q0 = np.asarray(q0, dtype=float)
        self.mass_tol, self.projection_tol = mass_tol, projection_tol
        self.linear = isinstance(model, LinearCase)
        self.n = model.n
        self.nfev = 0
        if self.linear:
            self.M = _dense(model.M)
            self.P, self.Q = _dense(model.P), _dense(model.Q)
            self.m = 0
            self.constraints = ()
        else:
            if getattr(model, "mass_elements", ()):
                names = ", ".join(str(getattr(e, "name", "?")) for e, _ in model.mass_elements[:3])
                raise SimulationError(
                    f"configuration-dependent mass ({names}): the time-domain check integrates "
                    f"constant-mass models only", element="time-domain check")
            self.M = model.mass.toarray()
            self.constraints = tuple(model.constraints)
            self.m = model.n_constraints
            off = np.cumsum([0] + [c.n_eq for c in self.constraints])
            self.rows = [np.arange(off[k], off[k + 1]) for k in range(len(self.constraints))]
            self.cscale = model.constraint_scales() if self.m else np.zeros(0)
        self.redundant = bool(redundant)
        self._check_mass()
        if self.m == 0:
            self._lu = sla.lu_factor(self.M)

    # -- model pieces (dense, assembled here because the sparse assembly costs ~100 µs) ------
    def phi(self, q):
        return self.model.phi(q) if self.m else np.zeros(0)

    def phi_q(self, q):
        J = np.zeros((self.m, self.n))
        for r, c in zip(self.rows, self.constraints):
            J[np.ix_(r, c.idx)] = c.jac(q)
        return J

    def force(self, q, qd):
        if self.linear:
            return -(self.P @ qd) - self.Q @ q
        return self.model.generalized_force(q, qd)

    def _check_mass(self):
        """The reduced mass Nᵀ M N must be positive definite (no massless free motion)."""
        if self.m:
            J = self.phi_q(self.q0)
            _, s, vt = sla.svd(J)
            rank = int(np.sum(s > 1e-10 * s[0])) if s.size and s[0] > 0 else 0
            N = vt[rank:].T
        else:
            N = np.eye(self.n)
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

    # -- accelerations ----------------------------------------------------------------------
    def acceleration(self, q, qd):
        """(q̈, λ) from the augmented index-1 system."""
        self.nfev += 1
        g = self.force(q, qd)
        if self.m == 0:
            return sla.lu_solve(self._lu, g), np.zeros(0)
        J = self.phi_q(q)
        gam = self.model.gamma(q, qd)
        n = self.n
        A = np.zeros((n + self.m, n + self.m))
        A[:n, :n] = self.M
        A[:n, n:] = J.T
        A[n:, :n] = J
        rhs = np.concatenate([g, gam])
        if self.redundant:
            sol = np.linalg.lstsq(A, rhs, rcond=None)[0]
        else:
            sol = np.linalg.solve(A, rhs)
        return sol[:n], sol[n:]

    def rhs(self, t, y):
        n = self.n
        u, v = y[:n], y[n:]
        qdd, _ = self.acceleration(self.q0 + u, v)
        return np.concatenate([v, qdd])

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
        u = u.copy()
        du_total = np.zeros_like(u)
        for _ in range(max_iter):
            q = self.q0 + u
            r = self.phi(q)
            if np.max(np.abs(r) / self.cscale) <= self.projection_tol:
                break
            du = -np.linalg.lstsq(self.phi_q(q), r, rcond=None)[0]
            u += du
            du_total += du
        else:
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


def simulate(dynamics: ForwardDynamics, u0, v0, t_eval, *, segment_samples: int,
             method: str = "DOP853", rtol: float = 1e-10, atol_position: float,
             atol_velocity: float) -> Simulation:
    """Integrate from (u0, v0) through the sample times ``t_eval`` (t_eval[0] = 0), projecting
    onto the constraints every ``segment_samples`` samples."""
    from scipy.integrate import solve_ivp  # imported here: it costs ~0.2 s at import mbseig

    if method not in INTEGRATORS:
        raise CaseError(f"unknown integrator {method!r} (one of {', '.join(INTEGRATORS)})",
                        element="method")
    n = dynamics.n
    atol = np.concatenate([np.full(n, atol_position), np.full(n, atol_velocity)])
    u, v, _, _ = dynamics.project(np.asarray(u0, float), np.asarray(v0, float))
    U, V = [u], [v]
    drift = vdrift = proj = vproj = 0.0
    n_seg = 0
    k = 0
    nfev0 = dynamics.nfev
    while k < len(t_eval) - 1:
        k1 = min(k + segment_samples, len(t_eval) - 1)
        ts = t_eval[k:k1 + 1]
        sol = solve_ivp(dynamics.rhs, (ts[0], ts[-1]), np.concatenate([u, v]), method=method,
                        t_eval=ts[1:], rtol=rtol, atol=atol)
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
                      velocity_drift=vdrift, max_projection=proj, max_velocity_projection=vproj)


# ---------------------------------------------------------------------------------------------
# Results
# ---------------------------------------------------------------------------------------------
@dataclass(frozen=True, eq=False)
class ModeCheck:
    """Predicted vs measured δ, ω of one listed mode (1-based ``index`` as in the modes table).

    ``skipped`` holds the reason when the mode was not simulated; a rigid-body mode is then
    probed statically (``probe_omega`` = ω_eff against ``probe_reference`` = ω_ref) and
    ``passed`` is the probe's verdict (None for a mode neither simulated nor probed).
    Arrays ``t``, ``eta`` (modal coordinate) and ``response`` (the dominant coordinate's
    deviation, named ``coordinate``) are kept for plots.
    """

    index: int
    kind: str
    eigenvalue: complex
    predicted_delta: float
    predicted_omega: float
    measured_delta: float = math.nan
    measured_omega: float = math.nan
    rel_error_delta: float = math.nan
    rel_error_omega: float = math.nan
    passed: bool | None = None
    skipped: str = ""
    duration: float = 0.0
    periods: float = 0.0
    efolds: float = 0.0
    amplitude: float = 0.0
    fit_residual: float = math.nan
    fit_amplitude: float = math.nan
    constraint_drift: float = 0.0
    velocity_drift: float = 0.0
    max_projection: float = 0.0
    nfev: int = 0
    elapsed: float = 0.0
    coordinate: str = ""
    probe_omega: float = math.nan
    probe_reference: float = math.nan
    t: np.ndarray = field(default_factory=lambda: np.zeros(0))
    eta: np.ndarray = field(default_factory=lambda: np.zeros(0, complex))
    response: np.ndarray = field(default_factory=lambda: np.zeros(0))

    def to_dict(self) -> dict:
        skipped = bool(self.skipped)
        num = (lambda x: None) if skipped else float
        return {
            "index": self.index,
            "kind": self.kind,
            "eigenvalue": [float(self.eigenvalue.real), float(self.eigenvalue.imag)],
            "predicted": {"delta": float(self.predicted_delta),
                          "omega": float(self.predicted_omega)},
            "measured": {"delta": num(self.measured_delta), "omega": num(self.measured_omega)},
            "rel_error": {"delta": num(self.rel_error_delta), "omega": num(self.rel_error_omega)},
            "passed": self.passed,
            "skipped": self.skipped or None,
            "duration": float(self.duration),
            "periods": float(self.periods),
            "efolds": float(self.efolds),
            "amplitude": float(self.amplitude),
            "fit_residual": num(self.fit_residual),
            "constraint_drift": float(self.constraint_drift),
            "velocity_drift": float(self.velocity_drift),
            "max_projection": float(self.max_projection),
            "nfev": int(self.nfev),
            "elapsed": float(self.elapsed),
            "coordinate": self.coordinate,
            "probe": None if math.isnan(self.probe_omega) else {
                "omega_eff": float(self.probe_omega), "omega_ref": float(self.probe_reference)},
        }


@dataclass(frozen=True, eq=False)
class CheckResult:
    """Outcome of :func:`check_modes`: one :class:`ModeCheck` per requested mode.

    ``passed`` is True when no mode failed (neither a fit nor a rigid-body probe); ``tolerances``
    records every tolerance and option used; ``reactions`` are the equilibrium constraint
    reactions (see :func:`reaction_forces`) and ``actuators`` the inverse-statics driver records
    (effort per actuator, :mod:`mbseig.inverse_statics`) of the model, if it has any.
    """

    name: str
    parameters: dict
    modes: tuple
    tolerances: dict
    integrator: str
    elapsed: float
    reactions: tuple = ()
    constraint_stiffness: bool = True
    actuators: tuple = ()

    @property
    def passed(self) -> bool:
        return not any(m.passed is False for m in self.modes)

    @property
    def failed(self) -> list:
        return [m.index for m in self.modes if m.passed is False]

    def to_dict(self) -> dict:
        per_mode = {k: self.tolerances[k] for k in ("delta_rtol", "omega_rtol", "zero_delta_tol")}
        return {
            "case": self.name,
            "parameters": dict(self.parameters),
            "passed": self.passed,
            "integrator": self.integrator,
            "constraint_stiffness": self.constraint_stiffness,
            "tolerances": dict(self.tolerances),
            "elapsed": float(self.elapsed),
            "modes": [{**m.to_dict(), "tolerances": per_mode} for m in self.modes],
            "reactions": [dict(r) for r in self.reactions],
            "actuators": [dict(r) for r in self.actuators],
        }

    def table(self) -> str:
        head = (f"{'#':>3} {'kind':<11} {'delta pred':>12} {'delta meas':>12} {'err':>9} "
                f"{'omega pred':>12} {'omega meas':>12} {'err':>9}  {'result':<6} {'periods':>7}")
        rows = [head, "-" * len(head)]
        for m in self.modes:
            if m.skipped:
                if math.isnan(m.probe_omega):
                    rows.append(f"{m.index:>3} {m.kind:<11} {m.predicted_delta:>12.6g} {'':>12} "
                                f"{'':>9} {m.predicted_omega:>12.6g} {'':>12} {'':>9}  skip    "
                                f"({m.skipped})")
                else:
                    rel = m.probe_omega / m.probe_reference if m.probe_reference else math.inf
                    rows.append(f"{m.index:>3} {m.kind:<11} {m.predicted_delta:>12.6g} {'':>12} "
                                f"{'':>9} {m.predicted_omega:>12.6g} {m.probe_omega:>12.6g} "
                                f"{rel:>9.2e}  {'pass' if m.passed else 'FAIL':<6}  (static "
                                f"probe: restoring ω_eff vs ω_ref {m.probe_reference:.4g})")
                continue
            rows.append(
                f"{m.index:>3} {m.kind:<11} {m.predicted_delta:>12.6g} {m.measured_delta:>12.6g} "
                f"{m.rel_error_delta:>9.2e} {m.predicted_omega:>12.6g} {m.measured_omega:>12.6g} "
                f"{m.rel_error_omega:>9.2e}  {'pass' if m.passed else 'FAIL':<6} {m.periods:>7.1f}")
        return "\n".join(rows)

    def plot(self, directory) -> list:
        """Write one PNG per simulated mode to ``directory``; returns the paths."""
        from .checkplot import plot_check

        return plot_check(self, directory)


# ---------------------------------------------------------------------------------------------
# The check
# ---------------------------------------------------------------------------------------------
def parse_mode_list(text: str, n_modes: int) -> list:
    """'1,3-5' → [1, 3, 4, 5] (1-based, as in the modes table)."""
    out = []
    for part in str(text).split(","):
        part = part.strip()
        if not part:
            continue
        try:
            if "-" in part:
                a, b = (int(x) for x in part.split("-", 1))
                out.extend(range(a, b + 1))
            else:
                out.append(int(part))
        except ValueError:
            raise CaseError(f"mode list must be integers like 1,2,4-6, got {text!r}",
                            element="--modes") from None
    bad = [k for k in out if not 1 <= k <= n_modes]
    if bad or not out:
        raise CaseError(f"mode numbers must lie in 1..{n_modes}, got {text!r}", element="--modes")
    return list(dict.fromkeys(out))


def check_modes(model, eq, lin, modes, *, indices=None, amplitude: float = 1e-4,
                periods: float = 20.0, efolds: float = 3.0, samples_per_period: int = 40,
                min_samples: int = 400, delta_rtol: float = 1e-2, omega_rtol: float = 1e-3,
                zero_delta_tol: float = 1e-5, rigid_tol: float = 1e-3, method: str = "DOP853",
                ode_rtol: float = 1e-10, mass_tol: float = 1e-12) -> CheckResult:
    """Prove the listed ``modes`` (predicted from ``lin``) against the nonlinear ``model``.

    indices : 1-based mode numbers (default: all listed modes).
    amplitude : ε, the largest coordinate deviation relative to the model's length scale.
    periods, efolds : the run lasts ``periods`` periods of an oscillatory mode, cut short at
        ``efolds`` e-folding times 1/|δ|; a real mode runs ``efolds`` e-folding times 1/|s|.
    samples_per_period, min_samples : output sampling of the modal coordinate.
    delta_rtol, omega_rtol, zero_delta_tol : pass/fail tolerances (see the module docstring).
    rigid_tol : a rigid-body mode passes when the probed ω_eff ≤ rigid_tol · ω_ref.
    method, ode_rtol : integrator and its relative tolerance; absolute tolerances are ode_rtol
        times the smallest expected deviation.
    mass_tol : relative eigenvalue of Nᵀ M N below which the model counts as massless.
    """
    t_start = time.perf_counter()
    for nm, val in (("amplitude", amplitude), ("periods", periods), ("efolds", efolds),
                    ("delta_rtol", delta_rtol), ("omega_rtol", omega_rtol),
                    ("zero_delta_tol", zero_delta_tol), ("rigid_tol", rigid_tol),
                    ("ode_rtol", ode_rtol)):
        if not (isinstance(val, (int, float)) and math.isfinite(val) and val > 0):
            raise CaseError(f"must be a positive number, got {val!r}", element=nm)
    n_modes = len(modes)
    idx = list(range(1, n_modes + 1)) if indices is None else [int(k) for k in indices]
    bad = [k for k in idx if not 1 <= k <= n_modes]
    if bad:
        raise CaseError(f"mode numbers must lie in 1..{n_modes}, got {bad}", element="modes")
    redundant = bool(getattr(eq, "n_redundant", 0))
    try:
        dyn = ForwardDynamics(model, lin.q0, redundant=redundant, mass_tol=mass_tol)
    except SimulationError as exc:
        raise exc.located(file=getattr(model, "source", None)) from None
    length = 1.0 if isinstance(model, LinearCase) else float(model.length_scale)
    Mr, Pr, Qr, N = (np.asarray(lin.M, float), np.asarray(lin.P, float), np.asarray(lin.Q, float),
                     np.asarray(lin.N, float))
    names = list(model.coordinate_names)
    opts = dict(amplitude=amplitude, periods=periods, efolds=efolds,
                samples_per_period=samples_per_period, min_samples=min_samples, method=method,
                ode_rtol=ode_rtol, length=length)
    results = []
    for k in idx:
        j = k - 1
        s = complex(modes.eigenvalues[j])
        kind = modes.kind[j]
        base = dict(index=k, kind=kind, eigenvalue=s, predicted_delta=float(modes.delta[j]),
                    predicted_omega=float(modes.omega_d[j]))
        if kind == "rigid-body":
            w_eff, w_ref = _probe_rigid(dyn, Mr, N, modes.vectors[:, j], amplitude * length,
                                        modes, eq, length)
            results.append(ModeCheck(
                **base, skipped="rigid-body mode (s = 0): no decay rate or frequency to fit; "
                                "probed statically", probe_omega=w_eff, probe_reference=w_ref,
                passed=bool(w_eff <= rigid_tol * w_ref)))
            continue
        t0 = time.perf_counter()
        try:
            mc = _check_one(dyn, Mr, Pr, Qr, N, s, modes.vectors[:, j], names, base, opts)
        except SimulationError as exc:
            raise exc.located(file=getattr(model, "source", None), element=f"mode {k}") from None
        dscale = max(abs(mc.predicted_delta), (zero_delta_tol / delta_rtol) * abs(s))
        err_d = abs(mc.measured_delta - mc.predicted_delta) / dscale
        passed = bool(err_d <= delta_rtol and mc.rel_error_omega <= omega_rtol)
        results.append(replace(mc, rel_error_delta=err_d, passed=passed,
                               elapsed=time.perf_counter() - t0))
    reactions = () if isinstance(model, LinearCase) else tuple(reaction_forces(model, eq))
    return CheckResult(
        name=model.name, parameters=dict(model.parameters), modes=tuple(results),
        tolerances={"delta_rtol": delta_rtol, "omega_rtol": omega_rtol,
                    "zero_delta_tol": zero_delta_tol, "rigid_tol": rigid_tol,
                    "amplitude": amplitude, "periods": periods,
                    "efolds": efolds, "samples_per_period": samples_per_period,
                    "min_samples": min_samples, "ode_rtol": ode_rtol, "mass_tol": mass_tol,
                    "projection_tol": dyn.projection_tol, "length_scale": length},
        integrator=method, elapsed=time.perf_counter() - t_start, reactions=reactions,
        constraint_stiffness=bool(getattr(lin, "constraint_stiffness", True)),
        actuators=tuple(dict(r) for r in getattr(model, "drivers", ()) or ()))


def _left_vector(Mr, Pr, Qr, s, x, rtol=1e-8):
    """y with yᴴ(s²M + sP + Q) = 0 and yᴴ(2sM + P)x real positive (largest over a repeated
    eigenvalue's left null space)."""
    T = s * s * Mr + s * Pr + Qr
    U, sv, _ = np.linalg.svd(T)
    k = max(1, int(np.sum(sv <= rtol * max(sv[0], 1e-300))))
    Y = U[:, -k:]
    b = Y.conj().T @ ((2 * s * Mr + Pr) @ x)
    if np.linalg.norm(b) == 0:
        raise SimulationError(f"eigenvalue {s:.6g} is defective (yᴴ(2sM + P)x = 0): its modal "
                              f"coordinate is undefined")
    return Y @ b


def _check_one(dyn, Mr, Pr, Qr, N, s, x, names, base, o):
    delta, omega = -s.real, abs(s.imag)
    real_mode = base["kind"] in ("overdamped", "divergence")
    if real_mode:
        s = complex(s.real, 0.0)
        x = x.real if np.linalg.norm(x.real) >= np.linalg.norm(x.imag) else x.imag
        x = np.asarray(x, complex)
        T = o["efolds"] / abs(s)
        n_per = 0.0
        n_samples = o["min_samples"]
        seg_len = 0.1 / abs(s)
    else:
        T = o["periods"] * 2 * np.pi / omega
        if delta != 0:
            T = min(T, o["efolds"] / abs(delta))
        n_per = T * omega / (2 * np.pi)
        n_samples = max(o["min_samples"], int(math.ceil(o["samples_per_period"] * n_per)))
        seg_len = min(2 * np.pi / omega, 0.1 / abs(delta) if delta else np.inf)
    # shape normalized: largest component of N x is 1 (real)
    full = N @ x
    jmax = int(np.argmax(np.abs(full)))
    x = x / full[jmax]
    growth = max(0.0, -delta) * T
    a = o["amplitude"] * o["length"] * math.exp(-growth)
    smallest = a * math.exp(-max(0.0, delta) * T)  # smallest expected deviation over the run
    u0 = a * (N @ x).real
    v0 = a * (N @ (s * x)).real
    t_eval = np.linspace(0.0, T, n_samples + 1)
    seg = max(1, int(round(seg_len / (T / n_samples))))
    sim = simulate(dyn, u0, v0, t_eval, segment_samples=seg, method=o["method"], rtol=o["ode_rtol"],
                   atol_position=o["ode_rtol"] * smallest,
                   atol_velocity=o["ode_rtol"] * smallest * abs(s))
    # modal coordinate from the reduced state x = Nᵀ u, ẋ = Nᵀ v
    y = _left_vector(Mr, Pr, Qr, s, x)
    X, Xd = N.T @ sim.u, N.T @ sim.v
    den = y.conj() @ ((2 * s * Mr + Pr) @ x)
    eta = (y.conj() @ ((s * Mr + Pr) @ X + Mr @ Xd)) / den
    meas_delta, meas_omega, resid, eta0 = _fit_exponential(sim.t, eta)
    if real_mode:  # η is real: its phase is constant (0 or π), the fitted slope a residue
        meas_omega = abs(meas_omega)
    # an oscillatory mode keeps the sign of its phase slope: a response turning the other way
    # than e^{st} must not pass
    pred_omega = abs(s.imag)
    scale_w = pred_omega if pred_omega > 0 else abs(s)
    err_w = abs(meas_omega - pred_omega) / scale_w
    return ModeCheck(
        **base, measured_delta=meas_delta, measured_omega=meas_omega,
        rel_error_delta=math.nan, rel_error_omega=err_w, duration=T, periods=n_per,
        efolds=abs(delta) * T if not real_mode else abs(s) * T, amplitude=a,
        fit_residual=resid, fit_amplitude=eta0, constraint_drift=sim.constraint_drift,
        velocity_drift=sim.velocity_drift, max_projection=sim.max_projection, nfev=sim.nfev,
        coordinate=names[jmax], t=sim.t, eta=eta, response=sim.u[jmax])


def _probe_rigid(dyn, Mr, N, x, a, modes, eq, length):
    """(ω_eff, ω_ref) for a listed rigid-body mode: does the nonlinear model really offer no
    restoring force along it?

    The reduced accelerations at q₀ ± a N x̂ (projected onto the constraints, q̇ = 0) give by
    central differences k_eff = −x̂ᵀM_r(ẍ₊ − ẍ₋) / (2a x̂ᵀM_r x̂) and ω_eff = √|k_eff|; the
    O(a²) offset of the projected start from a curved rigid motion is even in a and cancels.
    ω_ref, the model's own frequency scale, is the largest |s| of its other listed modes or
    √(force scale / (length · largest mass)), whichever is larger.  A linearization that drops a
    stiffness (the pendulum without Σλ∇²Φ) reports a rigid-body mode that fails this probe.
    """
    x = x.real if np.linalg.norm(x.real) >= np.linalg.norm(x.imag) else x.imag
    full = N @ x
    x = x / full[int(np.argmax(np.abs(full)))]
    acc = []
    for sign in (1.0, -1.0):
        u, _, _, _ = dyn.project(sign * a * (N @ x), np.zeros(dyn.n))
        qdd, _ = dyn.acceleration(dyn.q0 + u, np.zeros(dyn.n))
        acc.append(N.T @ qdd)
    k_eff = -(x @ Mr @ (acc[0] - acc[1])) / (2 * a * (x @ Mr @ x))
    w_eff = math.sqrt(abs(k_eff))
    others = [abs(s) for s, kd in zip(modes.eigenvalues, modes.kind) if kd != "rigid-body"]
    m_max = float(np.max(np.abs(np.diag(dyn.M)), initial=0.0)) or 1.0
    f_scale = float(getattr(eq, "tolerances", {}).get("force_scale", 0.0) or 0.0)
    w_ref = max(max(others, default=0.0), math.sqrt(f_scale / (length * m_max)))
    return w_eff, w_ref


def _fit_exponential(t, eta):
    """Least-squares fit of η(t) = η₀ e^{(−δ + iω) t}: log|η| and unwrapped arg η linear in t.

    Returns (δ, ω, rms residual of log η, fitted |η₀|).
    """
    mag = np.abs(eta)
    if np.any(mag == 0) or not np.all(np.isfinite(mag)):
        raise SimulationError("the modal coordinate vanished or overflowed during the run")
    logm = np.log(mag)
    ph = np.unwrap(np.angle(eta))
    A = np.column_stack([np.ones_like(t), t])
    (c0, c1), *_ = np.linalg.lstsq(A, logm, rcond=None)
    (p0, p1), *_ = np.linalg.lstsq(A, ph, rcond=None)
    res = np.sqrt(np.mean((logm - c0 - c1 * t) ** 2 + (ph - p0 - p1 * t) ** 2))
    return float(-c1), float(p1), float(res), float(np.exp(c0))


# ---------------------------------------------------------------------------------------------
# Reactions (inverse statics at the equilibrium)
# ---------------------------------------------------------------------------------------------
def reaction_forces(model, eq) -> list:
    """Per constraint element: its multipliers λ and the reaction −Φ_qᵀλ it exerts on each point.

    Returns a list of ``{"element", "multipliers", "forces": {point: [fx, fy, ...]}}``; a
    distance constraint (a rod or a body's rigid length) with λ > 0 is in tension 2λL.
    """
    if isinstance(model, LinearCase) or not model.n_constraints:
        return []
    names = model.coordinate_names
    out, k = [], 0
    for c in model.constraints:
        lam = np.asarray(eq.lam[k:k + c.n_eq], float)
        k += c.n_eq
        f_local = -(c.jac(eq.q).T @ lam)
        forces: dict = {}
        for i, val in zip(c.idx, f_local):
            point, _, axis = names[i].rpartition(".")
            forces.setdefault(point, {})[axis] = float(val) + 0.0  # + 0.0: no "-0" in reports
        out.append({"element": c.name, "multipliers": [float(x) for x in lam],
                    "forces": {p: [v.get(ax, 0.0) for ax in "xyz"[:model.dimension]]
                               for p, v in forces.items()}})
    return out


def _dense(A):
    return A.toarray() if hasattr(A, "toarray") else np.asarray(A, dtype=float)
