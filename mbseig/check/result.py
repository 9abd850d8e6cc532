"""The results of the time-domain check: :class:`ModeCheck` per mode (predicted and measured δ
and ω, their errors, pass or fail and why) and :class:`CheckResult` (every mode, the integrator
and the tolerances used)."""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from ..display import fmt
from ..plots import plot_check


# ---------------------------------------------------------------------------------------------
# Results
# ---------------------------------------------------------------------------------------------
def pd(m):
    """The predicted δ as read (the zero rule with its bound, :mod:`mbseig.display`)."""
    return fmt(m.predicted_delta, m.bound_delta)


def pw(m):
    """The predicted ω as read."""
    return fmt(m.predicted_omega, m.bound_omega)


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
    se_delta: float = math.nan  # standard errors of the fitted slopes
    se_omega: float = math.nan
    amplification: float = math.nan  # state errors → modal coordinate (≈ 1; ≫ 1 near a defect)
    amplitude_share_delta: float = 0.0  # |δ(a) − δ(a/10)| when re-run at a tenth (else 0)
    amplitude_share_omega: float = 0.0
    resolution_delta: float = math.nan  # u_δ: what the run resolves of δ
    resolution_omega: float = math.nan  # u_ω
    #: the error bounds of the predicted δ and ω (the mode's tolerance and error bound): a
    #: prediction within its bound of 0 reads 0 (DESIGN §6; the JSON keeps the raw value)
    bound_delta: float = math.nan
    bound_omega: float = math.nan
    tolerance_delta: float = math.nan  # the δ tolerance applied: max(delta_rtol·|δ_p|, u_δ)
    tolerance_omega: float = math.nan
    capped: bool = False  # the run was cut at max_fast_periods of the fastest mode
    unresolved: str = ""  # what the run could not resolve (empty: everything asked)
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
            "predicted_bound": {"delta": num(self.bound_delta), "omega": num(self.bound_omega)},
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
                "omega_eff": float(self.probe_omega), "omega_ref": float(self.probe_reference),
                "ratio": probe_ratio(self), "checked": probe_text(self)},
            "resolution": {"delta": num(self.resolution_delta),
                           "omega": num(self.resolution_omega)},
            "tolerance": {"delta": num(self.tolerance_delta), "omega": num(self.tolerance_omega)},
            "capped": bool(self.capped),
            "unresolved": self.unresolved or None,
        }


def probe_ratio(m) -> float | None:
    """ω_eff/ω_ref of a rigid-body mode's static probe; None where it is undefined: ω_ref = 0,
    no force or stiffness anywhere in the model to compare a restoring force with."""
    return m.probe_omega / m.probe_reference if m.probe_reference > 0 else None


def probe_text(m) -> str:
    """What a rigid-body mode's static probe checked, in words."""
    if m.probe_reference > 0:
        return f"static probe: restoring ω_eff vs ω_ref {m.probe_reference:.4g}"
    found = "0" if m.probe_omega == 0 else f"{m.probe_omega:.3g} rad/s"
    return ("static probe: no force or stiffness in the model to scale it (ω_ref = 0, no ratio); "
            f"passes only if moving along the mode restores nothing: ω_eff = {found}")


@dataclass(frozen=True, eq=False)
class CheckResult:
    """Outcome of :func:`check_modes`: one :class:`ModeCheck` per requested mode.

    ``passed`` is True when no mode failed (neither a fit nor a rigid-body probe); ``tolerances``
    records every tolerance and option used; ``reactions`` are the equilibrium constraint
    reactions (see :func:`reaction_forces`; in :meth:`to_dict` the joints and other constraints
    as ``reactions``, the bodies' normalization conditions apart as ``reactions_internal``) and
    ``actuators`` the inverse-statics driver records (effort per actuator,
    :mod:`mbseig.inverse_statics`) of the model, if it has any.
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
            "reactions": [dict(r) for r in self.reactions if r.get("kind") != "internal"],
            "reactions_internal": [
                {"element": r["element"], "body": r.get("on"), "multipliers": r["multipliers"],
                 "error": r["reaction_error"]}
                for r in self.reactions if r.get("kind") == "internal"],
            "actuators": [dict(r) for r in self.actuators],
        }

    def table(self) -> str:
        head = (f"{'#':>3} {'kind':<11} {'delta pred':>12} {'delta meas':>12} {'err':>9} "
                f"{'omega pred':>12} {'omega meas':>12} {'err':>9}  {'result':<6} {'periods':>7}")
        rows = [head, "-" * len(head)]
        for m in self.modes:
            if m.skipped:
                if math.isnan(m.probe_omega):
                    rows.append(f"{m.index:>3} {m.kind:<11} {pd(m):>12} {'':>12} "
                                f"{'':>9} {pw(m):>12} {'':>12} {'':>9}  skip    "
                                f"({m.skipped})")
                else:
                    rel = probe_ratio(m)
                    rows.append(f"{m.index:>3} {m.kind:<11} {pd(m):>12} {'':>12} "
                                f"{'':>9} {pw(m):>12} {m.probe_omega:>12.6g} "
                                f"{'n/a' if rel is None else format(rel, '.2e'):>9}  "
                                f"{'pass' if m.passed else 'FAIL':<6}  ({probe_text(m)})")
                continue
            rows.append(
                f"{m.index:>3} {m.kind:<11} {pd(m):>12} {m.measured_delta:>12.6g} "
                f"{m.rel_error_delta:>9.2e} {pw(m):>12} {m.measured_omega:>12.6g} "
                f"{m.rel_error_omega:>9.2e}  {'pass' if m.passed else 'FAIL':<6} {m.periods:>7.1f}")
        return "\n".join(rows)

    def plot(self, directory) -> list:
        """Write one PNG per simulated mode to ``directory``; returns the paths."""
        return plot_check(self, directory)
