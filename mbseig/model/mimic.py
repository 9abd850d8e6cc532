"""The mimic coupling of two joints (URDF ``<mimic>``); its reader entry is
:func:`mbseig.casefile.urdf.read_mimic`.

    Φ(q) = c_F(q) − r c_L(q) − o = 0

c is a joint's coordinate measured from the reference configuration: the angle θ of a revolute
(or cylindrical) joint, right-handed about its axis, b2 relative to b1
(:func:`mbseig.model.spatial_joints.axis_angle`), or the slide s of a prismatic joint,

    s = (P₂ − P₁)·a₁,

P₁, P₂ the joint point ``at`` carried by b1 and b2 and a₁ the axis carried by b1: one bilinear
row of the body frames, zero at the reference and exactly the displacement along the axis while
the joint holds.  r is the multiplier, o the offset (θ or s units; 0 when the reference
satisfies the coupling, as the URDF expansion ensures).  With z = [z_F; z_L] the stacked frames
of the two joints and (c, ∇c, ∇²c) each coordinate with its derivatives on its own frames::

    Φ_q = [∇c_F, −r ∇c_L] W,   Σ λ∇²Φ = λ Wᵀ diag(∇²c_F, −r ∇²c_L) W,   γ = −żᵀ diag(...) ż

exactly (W the constant matrix of the stacked frame maps).  The multiplier λ is the coupling
effort: −λ is the torque (or force) the coupling applies to the follower joint in the sense of
its coordinate.

Case format (3-D), after the two joints it couples::

    [[joints]]
    type = "mimic"
    name = "finger2_mimic"
    joint = "finger2"      # the follower: a revolute, cylindrical or prismatic joint
    leader = "finger1"     # the leader: the same kinds
    multiplier = 1.0       # r (default 1)
    offset = 0.0           # o (default 0), from the reference
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from .affine import combine
from .base import Constraint
from .spatial_body import point_matrix, vector_matrix
from .spatial_joints import QuadraticMap, Rows, angle_rows, axis_angle, selectors

__all__ = ["JointCoordinate", "MimicConstraint", "joint_coordinate"]


@dataclass(frozen=True, eq=False)
class JointCoordinate:
    """A joint's coordinate from the reference: ``kind`` "angle" (two rows x, y; θ = atan2(y, x))
    or "slide" (one row: s)."""

    kind: str
    rows: QuadraticMap

    def evaluate(self, z):
        """(c, ∇c, ∇²c) with respect to this coordinate's own frames z."""
        if self.kind == "angle":
            theta, g, H = axis_angle(self.rows, z)
            return float(theta), g, H
        s = float(self.rows.values(z)[0])
        return s, self.rows.grad(z)[0], self.rows.weighted(np.ones(1))


def joint_coordinate(kind: str, frames, locals_, axis) -> JointCoordinate:
    """The coordinate of a joint of type ``kind`` between two frames (``locals_``: the joint
    point in each body's local coordinates; ``axis``: unit, global at the reference)."""
    if kind in ("revolute", "cylindrical"):
        return JointCoordinate("angle", angle_rows(frames, axis))
    if kind != "prismatic":
        raise ValueError(f"no joint coordinate for a {kind} joint")
    z = combine([(1.0, frames[0]), (1.0, frames[1])], stack=True)
    S1, S2 = selectors()
    D = point_matrix(locals_[1]) @ S2 - point_matrix(locals_[0]) @ S1  # P₂ − P₁
    return JointCoordinate("slide", Rows(z).dot(D, vector_matrix(axis) @ S1).build())


@dataclass(frozen=True, eq=False)
class MimicConstraint(Constraint):
    """Φ = c_F − r c_L − o (module docstring).

    follower, leader : the coordinates c_F, c_L of the two joints; multiplier r, offset o;
    units : "N m" (a revolute or cylindrical follower) or "N" (prismatic), of its effort −λ.
    """

    name: str
    follower: JointCoordinate
    leader: JointCoordinate
    multiplier: float = 1.0
    offset: float = 0.0
    units: str = "N m"
    aff: object = field(init=False, repr=False)  # z = [z_F; z_L], the two joints' frames
    affine_field = "aff"

    def __post_init__(self):
        aff = combine([(1.0, self.follower.rows.aff), (1.0, self.leader.rows.aff)], stack=True)
        object.__setattr__(self, "aff", aff)

    def _parts(self, q):
        aff = self.aff
        z = aff(q)
        nf = self.follower.rows.aff.C.shape[0]
        cf, gf, Hf = self.follower.evaluate(z[:nf])
        cl, gl, Hl = self.leader.evaluate(z[nf:])
        r = self.multiplier
        g = np.concatenate([gf, -r * gl])
        H = np.zeros((z.size, z.size))
        H[:nf, :nf], H[nf:, nf:] = Hf, -r * Hl
        return aff, cf - r * cl - self.offset, g, H

    def phi(self, q):
        _, value, _, _ = self._parts(q)
        if self.follower.kind == "angle" and self.leader.kind == "angle" and self.multiplier == 1:
            value = (value + math.pi) % (2 * math.pi) - math.pi  # both angles wrap alike
        return np.array([value])

    def jac(self, q):
        aff, _, g, _ = self._parts(q)
        return (g @ aff.C)[None, :]

    def hess(self, q, lam):
        aff, _, _, H = self._parts(q)
        return lam[0] * (aff.C.T @ H @ aff.C)

    def gamma(self, q, qd):
        aff, _, _, H = self._parts(q)
        zd = aff.rate(qd)
        return np.array([-(zd @ H @ zd)])

    def scale(self):
        return 1.0

    def reaction(self, q, lam):
        """The effort −λ the coupling applies to the follower joint."""
        key = "torque" if self.units == "N m" else "force"
        return {"key": key, "label": key, "value": -float(lam[0]), "unit": self.units}
