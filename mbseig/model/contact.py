"""Single-sided point contacts (DESIGN §8, ``[[joints]] type = "contact"``).

A contact is the row Φ = n·(P(q) − p₀)/ℓ = 0 of a point P on the plane through p₀ with unit
normal n (linear in q: an mbseig :class:`~mbseig.model.spatial_joints.QuadraticConstraint`)
while it is ACTIVE.  The generalized constraint force is −Φ_qᵀλ, so the normal force on the
point is N = −λ/ℓ: the contact is active while N ≥ 0 (it pushes).  The active set is found by
:func:`mbseig.statics.contacts.solve_with_contacts`; a released contact is a free point.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .spatial_joints import QuadraticConstraint, Rows

__all__ = ["PointContact", "point_contact"]


@dataclass(frozen=True, eq=False)
class PointContact(QuadraticConstraint):
    """One single-sided contact row (module docstring); ``length`` is ℓ."""

    length: float = 1.0
    single_sided = True

    def force(self, lam) -> float:
        """Normal force N (> 0 pushing) carried by the row's multiplier."""
        return float(-np.asarray(lam, float).reshape(-1)[0] / self.length)

    def gap(self, q) -> float:
        """n·(P − p₀): the point's height above the plane (negative: inside)."""
        return float(self.phi(q)[0] * self.length)

    def reaction(self, q, lam) -> dict:
        return {"key": "normal_force", "label": "normal force", "value": self.force(lam),
                "unit": "N"}


def point_contact(name, point, *, normal, plane_point, length=1.0) -> PointContact:
    """A contact of the point map ``point`` (an :class:`~mbseig.model.affine.Affine` of 3
    rows) on the plane through ``plane_point`` with ``normal``.  ValueError with a one-line
    reason for a normal of zero length."""
    n = np.asarray(normal, float)
    if not np.isfinite(n).all() or np.linalg.norm(n) == 0:
        raise ValueError("normal has zero length: a contact needs the direction it pushes along")
    n = n / np.linalg.norm(n)
    p0 = np.asarray(plane_point, float)
    rows = Rows(point).linear(n / length, -(n @ p0) / length)
    return PointContact(name, rows.build(), length, None, float(length))
