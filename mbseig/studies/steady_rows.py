"""The mode rows of a steady motion and its declared rigid-body directions (DESIGN §8, §6):
what the one-point analysis (:mod:`mbseig.studies.steady_modes`) and a sweep's batch
(:mod:`mbseig.studies.steady_batch`) both list.  The rules are stated in
:mod:`mbseig.studies.steady_modes`' docstring."""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ..modal.rules import kind_of, stability

__all__ = ["SAFETY", "INVARIANT_TOL", "PLANE", "Cyclic", "mode_rows", "verdict_of"]

SAFETY = 10.0  # τ = SAFETY·κ max(η, nε)·max(|s|, 1): mbseig's safety factor on the error bound
#: a declared direction set is invariant when ‖A S − E S J‖ ≤ INVARIANT_TOL ‖A‖ (rounding level of
#: forming the pencil, whose entries carry a few ε of their magnitude; 1e-11 leaves 10³ of margin)
INVARIANT_TOL = 1e-11


def mode_rows(sol, *, safety=SAFETY, declared=None, formed_in=1) -> list:
    """Mode records as the quadratic paths list them: δ = −Re s, a pair once (Im s > 0), sorted
    by ω_n then δ, with η, κ and the tolerance τ (:mod:`mbseig.studies.steady_modes`:
    ``formed_in`` is n, the number of coordinates the pencil was formed from); first the
    ``declared`` rigid-body modes (:class:`Cyclic`), each named in ``rigid_body``."""
    rows = [] if declared is None else declared.rows()
    floor = max(int(formed_in), 1) * np.finfo(float).eps
    for s, eta, kap in zip(sol.eigenvalues, sol.backward_error, sol.condition, strict=True):
        tol = safety * kap * max(eta, floor) * max(abs(s), 1.0)
        if s.imag < -tol:
            continue  # the conjugate of a listed pair
        wd = float(s.imag) if s.imag > tol else 0.0
        delta = -float(s.real)
        wn = float(abs(s))
        stab = stability(delta, tol)  # |δ| <= |s| <= τ for a rigid-body mode: critical
        kind = kind_of(stab, delta, wd, tol, rigid=wn <= tol)
        rows.append({"rigid_body": None, "eigenvalue": [float(s.real), wd], "delta": delta,
                     "omega_n": wn,
                     "omega_d": wd, "freq_hz": wd / (2 * math.pi),
                     "freq_n_hz": wn / (2 * math.pi),
                     "zeta": delta / wn if wn > 0 and kind != "rigid-body" else 0.0,
                     "stability": stab, "kind": kind, "backward_error": float(eta),
                     "condition": float(kap), "tolerance": float(tol)})
    rows.sort(key=lambda r: (r["omega_n"], r["delta"]))
    for k, r in enumerate(rows):
        r["index"] = k + 1
    return rows


def verdict_of(rows):
    """The verdict of the rows (:func:`mbseig.modal.scope.verdict`: the declared rigid-body
    modes left out)."""
    from ..modal.scope import verdict

    return verdict([r["stability"] for r in rows], [r.get("rigid_body") for r in rows],
                   zero=all(r["omega_n"] == 0 for r in rows if r.get("rigid_body")))


@dataclass(frozen=True, eq=False)
class Cyclic:
    """The declared rigid-body directions of a steady motion
    (:mod:`mbseig.studies.steady_modes`): their names, the orthonormal basis S of their span in
    the state X, J (A S = E S J), the invariance residual, and the candidates dropped (name:
    residual)."""

    names: tuple
    basis: np.ndarray
    J: np.ndarray
    residual: float
    dropped: tuple = ()
    yaw_rate: float = 0.0

    def rows(self) -> list:
        """One row per declared eigenvalue (a pair once): 0 for each direction of straight
        running and for a turn's heading, ±i r for a turn's two positions in the ground plane
        (checked on J: J is nilpotent, or J (J² + r² I) = 0, in :func:`cyclic_directions`)."""
        plane = [n for n in self.names if n.startswith(PLANE)]
        rows = []
        for name in self.names:
            if name in plane and self.yaw_rate:
                if name != plane[0]:
                    continue
                name, wd = " and ".join(plane), abs(self.yaw_rate)
            else:
                wd = 0.0
            rows.append({"rigid_body": name, "eigenvalue": [0.0, wd], "delta": 0.0,
                         "omega_n": wd, "omega_d": wd, "freq_hz": wd / (2 * math.pi),
                         "freq_n_hz": wd / (2 * math.pi), "zeta": 0.0, "stability": "critical",
                         "kind": "rigid-body", "backward_error": 0.0, "condition": 1.0,
                         "tolerance": float(self.residual)})
        return sorted(rows, key=lambda r: r["omega_n"])


PLANE = "position in the ground plane"
