"""Driving constraint: a prescribed relative angle between two planar directions (docs/design.md,
"Equilibrium").

    Φ(q) = wrap(θ(q) − θ*),   θ = s · atan2(a × b, a · b),   s = +1 (ccw) or −1 (cw)

a and b are the directions of two bodies (or a fixed ground direction and a body), exactly as in
:class:`~mbseig.model.elements.TorsionalSpringDamper`, so a driver and a torsional spring on the
same pair measure the same angle.  Its multiplier λ is the driving effort: the generalized force
−Φ_qᵀλ = −λ ∇θ is a torque −λ·s on body b (and +λ·s on body a), so the torque the actuator must
apply to hold the angle, in the sense of θ, is −λ.

    Φ_q = ∇θᵀ W,   Σ λ ∇²Φ = λ Wᵀ H_θ W,   γ = −q̇ᵀ Wᵀ H_θ W q̇

with W the constant matrix of the stacked direction maps [a; b] and ∇θ, H_θ the gradient and
Hessian of θ with respect to [a; b].
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ..errors import CaseError
from .affine import Affine
from .base import Constraint
from .elements import DistanceConstraint, SpringDamper, relative_angle, relative_angle_only

__all__ = ["AngleDriver", "check_command"]


def check_command(driver, targets, forces, constraints):
    """(springs, locks): the targets ``("force" | "joint", index, label)`` of an inverse-statics
    driver, checked: at most one planar spring (its free length is set) and distance joints (their
    length is set)."""
    springs = [t for t in targets if t[0] == "force"]
    locks = [t for t in targets if t[0] == "joint"]
    if len(springs) > 1:
        raise CaseError("an angle_driver can set the free length of one spring only",
                        element=driver.name)
    for _, k, label in springs:
        if not isinstance(forces[k], SpringDamper) or forces[k].diff.dim == 1:
            raise CaseError(f"sets {label}: only a planar spring or spring_damper can be set",
                            element=driver.name)
    for _, k, label in locks:
        if not isinstance(constraints[k], DistanceConstraint):
            raise CaseError(f"sets {label}: only a distance joint can be set", element=driver.name)
    return springs, locks


@dataclass(frozen=True, eq=False)
class AngleDriver(Constraint):
    """Φ = wrap(θ(q) − θ*) on the stacked directions ``dirs`` = [a; b] (4 rows)."""

    name: str
    dirs: Affine
    angle_target: float
    sense: float = 1.0
    affine_field = "dirs"  # idx = dirs.idx

    def angle(self, q) -> float:
        return relative_angle_only(self.dirs, q, self.sense, self.name)

    def _derivatives(self, q):
        _, g, H = relative_angle(self.dirs, q, self.sense, self.name)
        return g, H

    def phi(self, q):
        d = self.angle(q) - self.angle_target
        return np.array([(d + math.pi) % (2 * math.pi) - math.pi])

    def jac(self, q):
        g, _ = self._derivatives(q)
        return (g @ self.dirs.C)[None, :]

    def hess(self, q, lam):
        _, H = self._derivatives(q)
        W = self.dirs.C
        return lam[0] * (W.T @ H @ W)

    def gamma(self, q, qd):
        _, H = self._derivatives(q)
        wd = self.dirs.rate(qd)
        return np.array([-(wd @ H @ wd)])

    def scale(self):
        """Typical magnitude of Φ (an angle): 1 rad."""
        return 1.0

    def reaction(self, q, lam):
        """The torque −λ that holds the angle, in the sense of θ."""
        return {"key": "torque", "label": "torque", "value": -float(lam[0]), "unit": "N m"}
