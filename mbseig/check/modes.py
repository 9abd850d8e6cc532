"""Time-domain cross-check of predicted modes (docs/design.md, "Time-domain check").

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
configuration-dependent mass (co-rotational beams) are integrated with M(q) and its velocity
terms, and, being stiff in their axial modes, by Radau where DOP853 is asked
(:mod:`mbseig.check.dynamics`); the result records the integrator that ran.

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
low-order implicit method does to the measured δ (``mbseig bench``).
A symplectic scheme (RATTLE) would be energy-neutral but is
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

Verdict per mode: the tolerances are tied to what the run resolves.  The fit gives standard
errors σ_δ, σ_ω of the slopes; with the integrator's own floor (an explicit method at ode_rtol
adds an apparent δ, ω of order ode_rtol·|s|, measured far below that), the measurement resolves

    u_δ = max(resolution_k · σ_δ, ode_rtol·|s_p|),   u_ω = max(resolution_k · σ_ω, ode_rtol·|s_p|)

(ode_rtol is the relative tolerance the run kept: for a stiff model, whose absolute
tolerances are floored at the rounding noise of its forces, the floored atol over the
perturbation when larger) and a mode passes when

    |δ_m − δ_p| ≤ max(delta_rtol·|δ_p|, u_δ)   and   |ω_m − ω_p| ≤ max(omega_rtol·ω_p, u_ω)

(ω_p = |s_p| for a real mode); ``rel_error`` reports the two errors divided by
max(|δ_p|, u_δ/delta_rtol) and max(ω_p, u_ω/omega_rtol), so that passing means
rel_error ≤ the rtol.  Hence a δ of the wrong sign fails whenever the run resolves δ (the
pendulum with ζ = 2·10⁻⁶ and its damping flipped: predicted δ = −6.3·10⁻⁶, measured +6.3·10⁻⁶,
resolved to 10⁻¹¹), and an undamped mode passes only when its measured |δ| is within the run's
resolution.  What the run could not resolve is said in ``unresolved``: δ resolved only beyond
``zero_delta_tol``·|s|, or ω resolved only beyond ``omega_rtol``·ω_p (a mode near critical
damping turns through a few microradians of phase in its 3 e-folding times: its damped
frequency is then judged to the run's resolution, not to omega_rtol, and said to be so).

Run length: at most ``max_fast_periods`` = 200 periods of the fastest listed mode (an explicit
integrator's step follows the fastest motion, excited or not, so this caps the work whatever the
checked mode's own period: measured, a pendulum beside a 10⁷ N/m spring took 4·10⁵ force
evaluations, 158 s, for 20 of its periods; capped, 2 % of that); a capped run says so in
``unresolved`` and its resolutions u_δ, u_ω widen accordingly.

Rigid-body modes (s = 0) are not fitted (the reason is recorded); instead a static probe of the
nonlinear model checks that it offers no restoring force along them (see :func:`probe_rigid`),
compared with the force and stiffness scale of the points that mode moves, so a linearization
that turns an oscillation into a rigid-body mode cannot pass either, whatever else the model
holds.
"""

from __future__ import annotations

import math
import time
from dataclasses import replace

import numpy as np

from ..arguments import check
from ..errors import CaseError, SimulationError
from ..model.linear_case import LinearCase
from ..statics import solved
from ..statics.reactions import reaction_forces
from .dynamics import FAST_FACTOR, STIFF_RTOL, ForwardDynamics, simulate
from .fit import (
    amplification,
    fit_exponential,
    judge,
    left_row,
    probe_rigid,
    smaller_amplitude,
)
from .result import CheckResult, ModeCheck

__all__ = ["CheckResult", "ModeCheck", "check_modes", "parse_mode_list"]


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
                ode_rtol: float = 1e-10, mass_tol: float = 1e-12, resolution_k: float = 3.0,
                max_fast_periods: float = 200.0, recheck_amplification: float = 30.0,
                defective_amplification: float = 1e8, progress=None) -> CheckResult:
    """Prove the listed ``modes`` (predicted from ``lin``) against the nonlinear ``model``.

    Each mode is simulated from the equilibrium displaced along its shape; its measured decay
    rate δ and frequency ω are compared with the prediction.

    Parameters
    ----------
    model : Model
        The nonlinear model (``eq.model`` when it had commands).
    eq : Equilibrium
        Its equilibrium (:func:`mbseig.equilibrium`).
    lin : LinearModel
        The linearization the modes came from (:func:`mbseig.linearize`).
    modes : Modes
        The listed modes (:func:`mbseig.modes`).
    indices : sequence of int, optional
        1-based mode numbers (default: all listed modes).
    amplitude : float
        ε, the largest coordinate deviation relative to the model's length scale.
    periods, efolds : float
        The run lasts ``periods`` periods of an oscillatory mode, cut short at ``efolds``
        e-folding times 1/|δ|; a real mode runs ``efolds`` e-folding times 1/|s|.
    samples_per_period, min_samples : int
        Output sampling of the modal coordinate.
    delta_rtol, omega_rtol : float
        Relative tolerances, widened to the run's resolution u_δ, u_ω only (module docstring).
    zero_delta_tol : float
        A δ resolved no better than zero_delta_tol·|s| is reported in ``unresolved``.
    rigid_tol : float
        A rigid-body mode passes when the probed ω_eff ≤ rigid_tol · ω_ref.
    method : str
        The integrator (:data:`mbseig.check.INTEGRATORS`).
    ode_rtol : float
        Its relative tolerance; absolute tolerances are ode_rtol times the smallest expected
        deviation.
    mass_tol : float
        Relative eigenvalue of Nᵀ M N below which the model counts as massless.
    resolution_k : float
        Standard errors of the fitted slopes counted as the run's resolution.
    max_fast_periods : float
        Cap of the run length in periods of the fastest listed mode (explicit integration only:
        a model with a configuration-dependent mass runs implicit, uncapped).
    recheck_amplification, defective_amplification : float
        A mode whose modal coordinate amplifies state errors by more than the first (a nearly
        defective pair, near critical damping) is run again at a tenth of the amplitude, the
        difference counted into its resolution; above the second it is a Jordan block and is
        not simulated (the reason is recorded).
    progress : callable, optional
        A callback ``(label, done, total)`` called with "modes" before each mode and once after
        the last (the CLI's progress bar: a stiff model's mode takes tens of seconds).

    Returns
    -------
    CheckResult
        Per mode a :class:`ModeCheck` (predicted and measured δ and ω, their resolution, passed
        or the reason it was not simulated) and whether all passed.

    Examples
    --------
    >>> import mbseig
    >>> from mbseig.casefile.examples import damped_pendulum
    >>> model = damped_pendulum(c=0.5).build()
    >>> eq = mbseig.equilibrium(model)
    >>> lin = mbseig.linearize(model, eq)
    >>> res = check_modes(model, eq, lin, mbseig.modes(lin), periods=5)
    >>> res.passed
    True
    """
    check("check_modes", locals())
    t_start = time.perf_counter()
    for nm, val in (("amplitude", amplitude), ("periods", periods), ("efolds", efolds),
                    ("delta_rtol", delta_rtol), ("omega_rtol", omega_rtol),
                    ("zero_delta_tol", zero_delta_tol), ("rigid_tol", rigid_tol),
                    ("ode_rtol", ode_rtol), ("resolution_k", resolution_k),
                    ("max_fast_periods", max_fast_periods)):
        if not (isinstance(val, (int, float)) and math.isfinite(val) and val > 0):
            raise CaseError(f"must be a positive number, got {val!r}", element=nm)
    n_modes = len(modes)
    idx = list(range(1, n_modes + 1)) if indices is None else [int(k) for k in indices]
    bad = [k for k in idx if not 1 <= k <= n_modes]
    if bad:
        raise CaseError(f"mode numbers must lie in 1..{n_modes}, got {bad}", element="modes")
    model = solved(model, eq)
    redundant = bool(getattr(eq, "n_redundant", 0))
    try:
        dyn = ForwardDynamics(model, lin.q0, redundant=redundant, mass_tol=mass_tol,
                              rank_tol=float(lin.tolerances.get("rank_tol", 1e-10)))
    except SimulationError as exc:
        raise exc.located(file=model.source) from None
    length = 1.0 if isinstance(model, LinearCase) else float(model.length_scale)
    Mr, Pr, Qr, N = (np.asarray(lin.M, float), np.asarray(lin.P, float), np.asarray(lin.Q, float),
                     np.asarray(lin.N, float))
    names = list(model.coordinate_names)
    fastest = float(np.max(np.abs(modes.eigenvalues), initial=0.0))
    # the cap bounds an explicit method's cost; an implicit one (stiff models) steps over the
    # fast modes, so the run keeps its asked length there
    t_cap = (max_fast_periods * 2 * np.pi / fastest if fastest > 0 and not dyn.stiff
             else np.inf)
    opts = dict(amplitude=amplitude, periods=periods, efolds=efolds,
                samples_per_period=samples_per_period, min_samples=min_samples, method=method,
                ode_rtol=ode_rtol, length=length, t_cap=t_cap,
                tangent=_tangent(dyn, redundant, model))
    results = []
    for k in idx:
        if progress is not None:
            progress("modes", len(results), len(idx))
        j = k - 1
        s = complex(modes.eigenvalues[j])
        kind = modes.kind[j]
        bre, bim = modes.zero_bounds()
        base = dict(index=k, kind=kind, eigenvalue=s, predicted_delta=float(modes.delta[j]),
                    predicted_omega=float(modes.omega_d[j]), bound_delta=float(bre[j]),
                    bound_omega=float(bim[j]))
        if kind == "rigid-body":
            w_eff, w_ref = probe_rigid(dyn, Mr, N, modes.vectors[:, j], amplitude * length,
                                        modes, eq, length, names)
            results.append(ModeCheck(
                **base, skipped="rigid-body mode (s = 0): no decay rate or frequency to fit; "
                                "probed statically", probe_omega=w_eff, probe_reference=w_ref,
                passed=bool(w_eff <= rigid_tol * w_ref)))
            continue
        t0 = time.perf_counter()
        x, yh = modes.vectors[:, j], left_row(modes, j, Mr, Pr, Qr)
        amp = amplification(Mr, Pr, s, x, yh)
        if not amp <= defective_amplification:
            results.append(ModeCheck(
                **base, amplification=amp,
                skipped=f"defective eigenvalue (a Jordan block: modal-coordinate amplification "
                        f"{amp:.2g}): no modal coordinate isolates it, not simulated"))
            continue
        try:
            mc, eff = _check_one(dyn, Mr, Pr, N, s, x, yh, names, base, opts)
            if amp > recheck_amplification:  # nearly defective: the amplitude's share, measured
                small, eff_small = _check_one(dyn, Mr, Pr, N, s, x, yh, names, base,
                                              {**opts, "amplitude": opts["amplitude"] / 10})
                mc, eff = smaller_amplitude(mc, small), max(eff, eff_small)
        except SimulationError as exc:
            raise exc.located(file=model.source, element=f"mode {k}") from None
        results.append(replace(judge(replace(mc, amplification=amp), s, delta_rtol, omega_rtol,
                                      zero_delta_tol, resolution_k, eff),
                               elapsed=time.perf_counter() - t0))
    if progress is not None:
        progress("modes", len(results), len(idx))
    reactions = tuple(reaction_forces(model, eq))
    return CheckResult(
        name=model.name, parameters=dict(model.parameters), modes=tuple(results),
        tolerances={"delta_rtol": delta_rtol, "omega_rtol": omega_rtol,
                    "zero_delta_tol": zero_delta_tol, "rigid_tol": rigid_tol,
                    "amplitude": amplitude, "periods": periods,
                    "efolds": efolds, "samples_per_period": samples_per_period,
                    "min_samples": min_samples, "mass_tol": mass_tol,
                    # the rtol the runs kept (a stiff model's floor) and the one asked for
                    "ode_rtol": max(ode_rtol, STIFF_RTOL) if dyn.stiff else ode_rtol,
                    "ode_rtol_asked": ode_rtol,
                    "resolution_k": resolution_k, "max_fast_periods": max_fast_periods,
                    "recheck_amplification": recheck_amplification,
                    "defective_amplification": defective_amplification,
                    "projection_tol": dyn.projection_tol, "length_scale": length},
        integrator=_integrator(dyn, method, opts["tangent"]),
        elapsed=time.perf_counter() - t_start, reactions=reactions,
        constraint_stiffness=bool(getattr(lin, "constraint_stiffness", True)),
        actuators=tuple(dict(r) for r in getattr(model, "drivers", ()) or ()))


def _integrator(dyn, method, tangent):
    """The integrator the runs took: a stiff model's tangent runs record theirs (the
    exponential one, or Radau where it does not apply, with the reason)."""
    if tangent is not None and tangent.used:
        return "; ".join(sorted(tangent.used))
    return "Radau" if dyn.stiff and method == "DOP853" else method


def _tangent(dyn, redundant, model):
    """The tangent coordinates a stiff model is integrated in (built once for all its modes)."""
    if not dyn.stiff or redundant:
        return None
    from .tangent import TangentCoordinates

    try:
        return TangentCoordinates(dyn)
    except SimulationError as exc:
        raise exc.located(file=model.source) from None


def _check_one(dyn, Mr, Pr, N, s, x, yh, names, base, o):
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
    capped = T > o["t_cap"]
    unresolved = ""
    if capped:
        unresolved = (f"run capped at T = {o['t_cap']:.4g} s ({T:.4g} s asked): "
                      f"max_fast_periods of the fastest listed mode")
        T = o["t_cap"]
    if not real_mode:
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
                   atol_velocity=o["ode_rtol"] * smallest * abs(s),
                   cut=FAST_FACTOR * abs(s), tangent=o["tangent"])
    # modal coordinate from the reduced state x = Nᵀ u, ẋ = Nᵀ v
    X, Xd = N.T @ sim.u, N.T @ sim.v
    den = yh @ ((2 * s * Mr + Pr) @ x)
    if den == 0:
        raise SimulationError(f"eigenvalue {s:.6g} is defective (yᴴ(2sM + P)x = 0): its modal "
                              f"coordinate is undefined")
    eta = (yh @ ((s * Mr + Pr) @ X + Mr @ Xd)) / den
    meas_delta, meas_omega, resid, eta0, se_d, se_w = fit_exponential(sim.t, eta)
    if real_mode:  # η is real: its phase is constant (0 or π), the fitted slope a residue
        meas_omega = abs(meas_omega)
    # an oscillatory mode keeps the sign of its phase slope: a response turning the other way
    # than e^{st} must not pass
    pred_omega = abs(s.imag)
    scale_w = pred_omega if pred_omega > 0 else abs(s)
    err_w = abs(meas_omega - pred_omega) / scale_w
    # the relative tolerance the run kept: a stiff model's absolute tolerances are floored at
    # the rounding noise of its forces (simulate), which the resolution must then count
    eff = max(o["ode_rtol"], sim.rtol, sim.atol_velocity / (smallest * abs(s)))
    return ModeCheck(
        **base, measured_delta=meas_delta, measured_omega=meas_omega,
        rel_error_delta=math.nan, rel_error_omega=err_w, duration=T, periods=n_per,
        efolds=abs(delta) * T if not real_mode else abs(s) * T, amplitude=a,
        fit_residual=resid, fit_amplitude=eta0, constraint_drift=sim.constraint_drift,
        velocity_drift=sim.velocity_drift, max_projection=sim.max_projection, nfev=sim.nfev,
        coordinate=names[jmax], t=sim.t, eta=eta, response=sim.u[jmax], se_delta=se_d,
        se_omega=se_w, capped=capped, unresolved=unresolved), eff
