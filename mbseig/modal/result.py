"""The result of the modes stage: :class:`Modes` (eigenvalues, damping, classification, error
measures and shapes) and its :class:`Verdict`."""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np


class Verdict(str):
    """The verdict word ("stable", "critical" or "unstable"): it compares equal to, and is written
    to JSON as, the word; ``scope`` says what it covers ("" for the full spectrum, "of the modes
    computed (...)" for a partial one), and ``str()``/formatting give the word with its scope;
    ``rigid_scope`` which modes it leaves out (the rigid-body modes by construction,
    :mod:`mbseig.modal.scope`), and ``full_scope`` both."""

    def __new__(cls, word, scope="", rigid_scope=""):
        obj = super().__new__(cls, word)
        obj.scope = scope
        obj.rigid_scope = rigid_scope
        return obj

    def __reduce__(self):
        return (Verdict, (self.word, self.scope, self.rigid_scope))

    @property
    def full_scope(self) -> str:
        return "; ".join(t for t in (self.scope, self.rigid_scope) if t)

    @property
    def word(self) -> str:
        return str.__str__(self)

    def __str__(self):
        return f"{self.word} {self.scope}" if self.scope else self.word

    def __format__(self, spec):
        return format(str(self), spec)

STABILITY_ORDER = {"stable": 0, "critical": 1, "unstable": 2}
DENSE_MAX = 5000  # sparse input above this size needs a partial-spectrum request
BAND_DENSE_MAX = 2000  # a band of a model up to this size is listed from the dense solution


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
    # algebraic multiplicity each listed s stands for (rigid: share)
    multiplicity: np.ndarray = None
    accounting: dict = field(default_factory=dict)  # every eigenvalue accounted (module doc)
    coverage: str = ""  # partial spectrum: what was computed ("" for the full spectrum)
    partial: bool = False
    complex_problem: bool = False
    flags: list = field(default_factory=list)  # per mode: notes ("η above eta_warn", ...)
    #: per mode: the declared rigid-body direction it is (by construction, left out of the
    #: verdict: mbseig.modal.scope), or None
    rigid_body: list = None

    def __len__(self):
        return self.eigenvalues.size

    @property
    def freq_n_hz(self) -> np.ndarray:
        """Natural frequencies ω_n/2π = |s|/2π (Hz); ``freq_hz`` is the damped ω_d/2π."""
        return self.omega_n / (2 * np.pi)

    def zero_bounds(self):
        """(bound of Re s and δ, bound of Im s and |s|) per mode, for the zero rule
        (:mod:`mbseig.display`): the tolerance that decided the stability, and the error bound
        of s with the safety factor (|s| within it: rigid-body)."""
        re = np.asarray(self.tolerance, float)
        safety = float(self.tolerances.get("safety", 10.0)) if self.tolerances else 10.0
        im = np.maximum(re, safety * np.asarray(self.error_estimate, float))
        return re, im

    def shown(self):
        """The listed numbers as a person reads them (the zero rule, :mod:`mbseig.display`):
        a dict of arrays re, im, delta, omega_n, freq_n_hz, freq_hz, zeta."""
        from ..display import shown_array

        bre, bim = self.zero_bounds()
        wn = shown_array(self.omega_n, bim)
        delta = shown_array(self.delta, bre)
        with np.errstate(divide="ignore", invalid="ignore"):
            zeta = np.where(wn > 0, delta / np.where(wn > 0, wn, 1.0), 0.0) + 0.0
        return {"re": shown_array(self.eigenvalues.real, bre),
                "im": shown_array(self.eigenvalues.imag, bim), "delta": delta,
                "omega_n": wn, "freq_n_hz": wn / (2 * np.pi),
                "freq_hz": shown_array(self.omega_d, bim) / (2 * np.pi), "zeta": zeta}

    def __repr__(self):
        n = len(self)
        scope = f", {self.coverage}" if self.coverage else ""
        if n == 0:
            return f"<Modes: none listed, verdict {self.verdict}, solver {self.solver}{scope}>"
        f = self.shown()["freq_n_hz"]
        lo, hi = float(np.min(f)), float(np.max(f))
        return (f"<Modes: {n} listed, f_n {lo:.4g} … {hi:.4g} Hz, verdict {self.verdict}, "
                f"solver {self.solver}{scope}>")

    def to_dataframe(self):
        """The listed modes as a pandas DataFrame, one row a mode (index: mode number from 1):
        eigenvalue parts, δ, ω_n, ω_d, f_n, f_d, ζ, stability, kind, η, κ, tolerance, dominant
        coordinates.  pandas is optional: ImportError with the install hint when missing."""
        try:
            import pandas as pd
        except ImportError:
            raise ImportError("Modes.to_dataframe needs pandas (pip install pandas)") from None
        n = len(self)
        return pd.DataFrame({
            "re": self.eigenvalues.real, "im": self.eigenvalues.imag, "delta": self.delta,
            "omega_n": self.omega_n, "omega_d": self.omega_d, "freq_n_hz": self.freq_n_hz,
            "freq_hz": self.freq_hz, "zeta": self.zeta, "stability": list(self.stability),
            "kind": list(self.kind), "backward_error": self.backward_error,
            "condition": self.condition, "tolerance": self.tolerance,
            "dominant": [", ".join(nm for nm, _ in d) for d in self.dominant],
        }, index=pd.RangeIndex(1, n + 1, name="mode"))

    def table(self) -> str:
        """Readable fixed-width table of the listed modes."""
        head = (f"{'#':>3} {'Re s':>13} {'Im s':>13} {'delta':>11} {'omega_n':>11} "
                f"{'f_n [Hz]':>11} {'f_d [Hz]':>11} "
                f"{'zeta':>10} {'eta':>8}  {'stability':<9} {'kind':<11} dominant")
        rows = [head, "-" * len(head)]
        v = self.shown()  # the zero rule: a value within its bound of 0 reads 0
        for k in range(len(self)):
            rb = self.rigid_body[k] if self.rigid_body else None
            dom = rb if rb else ", ".join(f"{nm}" for nm, _ in self.dominant[k][:3])
            note = f"  [{'; '.join(self.flags[k])}]" if self.flags and self.flags[k] else ""
            rows.append(
                f"{k + 1:>3} {v['re'][k]:>13.6g} {v['im'][k]:>13.6g} {v['delta'][k]:>11.4g} "
                f"{v['omega_n'][k]:>11.6g} {v['freq_n_hz'][k]:>11.6g} {v['freq_hz'][k]:>11.6g} "
                f"{v['zeta'][k]:>10.3g} "
                f"{self.backward_error[k]:>8.1e}  {self.stability[k]:<9} {self.kind[k]:<11} "
                f"{dom}{note}"
            )
        if self.coverage:
            rows.append(f"partial spectrum: {self.coverage}")
        scope = getattr(self.verdict, "rigid_scope", "")
        if scope:
            rows.append(f"verdict scope: {scope}")
        rows.append("values within their error bound of 0 are printed as 0 (the JSON keeps them)")
        rows.append("f_n = omega_n/2pi = |s|/2pi (natural), f_d = omega_d/2pi (damped; 0 for a "
                    "real eigenvalue)")
        return "\n".join(rows)
