"""The element contract: what every constraint, force and configuration-dependent mass provides.

The assembled model (:class:`~mbseig.model.system.Model`) knows elements only through these
classes; adding a joint or a force is one subclass here (or in :mod:`~mbseig.model.elements`)
plus one reader entry in :mod:`mbseig.casefile.builder`.  All arrays are local: an element acts
on the coordinates ``q[idx]`` and returns vectors and matrices on those (docs/design.md,
"Elements").

Constraint (m_e rows of Φ(q) = 0)::

    phi(q)          Φ_e(q)                      (m_e,)
    jac(q)          ∂Φ_e/∂q[idx]                (m_e, |idx|)
    hess(q, λ)      Σ_k λ_k ∇²Φ_e,k             (|idx|, |idx|)   stiffness of the constraint force
    gamma(q, q̇)     −(Φ_q q̇)_q q̇                (m_e,)           so that Φ_q q̈ = γ
    scale()         typical magnitude of Φ_e, to judge residuals
    reaction(q, λ)  what the multipliers carry, in the user's terms (key, label, value, unit)

Force (generalized force g_e(q, q̇) on q[idx])::

    force(q, q̇)       g_e                                       (|idx|,)
    jacobians(q, q̇)   (K_e, C_e) = (−∂g_e/∂q, −∂g_e/∂q̇)         (|idx|, |idx|) each

A batch of identical elements (:class:`BatchForce`, e.g.
:class:`~mbseig.model.batched.SpringDamperSet`) offers ``add_force(g, q, q̇)`` and
``jacobian_coo(q, q̇)`` on the full vectors instead, and ``nonfinite_member(q, q̇)`` (which member
of the batch has a force or stiffness that is not finite); the model uses those when present.  A
configuration-dependent mass (:class:`ConfigurationMass`: a co-rotational beam) provides
``mass(q)`` on idx.

Velocity constraint (m_e non-holonomic rows A(q) q̇ = 0, :class:`VelocityConstraint`: a wheel
rolling without slip)::

    rows(q)           A_e(q)                                 (m_e, |idx|)
    rows_q(q, q̇)      ∂(A_e(q) q̇)/∂q at the velocities q̇     (m_e, |idx|)

``rows_q`` is what a linearization about a moving reference must keep (it vanishes at rest).
The assembled model holds them apart from the holonomic constraints
(``Model.velocity_constraints``); the static path has none to satisfy.

A new element is one subclass here (or in the element modules) plus one reader entry
(:mod:`mbseig.casefile.element_readers`, :mod:`mbseig.casefile.spatial_readers`) that builds
it through :class:`mbseig.model.assembly.Assembly`.
"""

from __future__ import annotations

import numpy as np

__all__ = ["Constraint", "Force", "VelocityConstraint", "ConfigurationMass", "BatchForce"]


class _Element:
    """An element acting on the coordinates of one affine map (``affine_field`` names the field
    that holds it): ``idx`` are those coordinates."""

    name: str
    affine_field: str = ""
    #: how a drawing shows the element (mbseig.plots.mechanism, mbseig.plots.spatial): "spring"
    #: (a spring-damper between two named points), "torsional" (a torsional spring at a joint),
    #: "load" (a follower force), "rod" (a rigid distance), "guide" (a point on a line),
    #: "rotor" (a spinning rotor on a body), or "" (no glyph of its own)
    glyph = ""

    @property
    def idx(self) -> np.ndarray | None:
        """The coordinates the element acts on (those of its affine map; None for an element
        on no single map)."""
        return getattr(self, self.affine_field).idx if self.affine_field else None


class Constraint(_Element):
    """Base class of constraints (module docstring); subclasses are frozen dataclasses with at
    least ``name`` and the methods below."""

    n_eq: int = 1
    #: a single-sided constraint (a contact) pushes only: the statics release it where its
    #: multiplier would pull (mbseig.statics.contacts)
    single_sided: bool = False
    #: what the constraint is part of, e.g. ("triad", body) for a frame's own unit-vector
    #: conditions (internal to the body: the reaction table summarizes them)
    role = ()
    #: None, or (offset of a body's frame in the element's coordinates, local coordinates of the
    #: joint point, body name) where the reaction is a force and moment on that body
    wrench = None

    def phi(self, q):
        raise NotImplementedError

    def jac(self, q):
        raise NotImplementedError

    def hess(self, q, lam):
        raise NotImplementedError

    def gamma(self, q, qd):
        raise NotImplementedError

    def scale(self) -> float:
        return 1.0

    def reaction(self, q, lam) -> dict:
        """What the multipliers carry, for reports: ``{"key", "label", "value", "unit"}`` with
        ``key`` a field name (``axial_force``, ``force``, ``torque``, ...), ``value`` a number or
        a list.  The default is the multipliers themselves."""
        return {"key": "multiplier", "label": "multiplier", "value": [float(x) for x in lam],
                "unit": ""}


class Force(_Element):
    """Base class of force elements (module docstring)."""

    #: a load the statics may scale (load continuation, inverse statics): its ``magnitude`` a
    #: number (a follower force)
    scalable_load = False
    #: None, or ``velocity_terms(q, q̇)``: the element's velocity-dependent inertia terms in
    #: closed form (the 3-D beams), which the time-domain check uses instead of differences
    velocity_terms = None
    #: a structural element whose axial and shear modes lie orders of magnitude above the
    #: modes a check follows (a beam): the time-domain check integrates its model as stiff
    stiff_structure = False

    def batch_group(self, q, qd=None):
        """The batch that evaluates this element together with others of its kind at (q, q̇)
        (the 3-D beams: :mod:`mbseig.model.beam3d_batch`), or None: evaluated alone."""
        return None

    def force(self, q, qd):
        raise NotImplementedError

    def jacobians(self, q, qd):
        raise NotImplementedError


class VelocityConstraint(_Element):
    """Base class of velocity-level (non-holonomic) constraints (module docstring)."""

    n_eq: int = 1

    def rows(self, q):
        raise NotImplementedError

    def rows_q(self, q, qd):
        raise NotImplementedError


class ConfigurationMass(_Element):
    """An element whose mass matrix depends on the configuration: ``mass(q)`` on ``idx``."""

    def mass(self, q):
        raise NotImplementedError


class BatchForce:
    """A batch of identical force elements acting on the full vectors (module docstring)."""

    name: str

    def add_force(self, g, q, qd):
        raise NotImplementedError

    def jacobian_coo(self, q, qd):
        raise NotImplementedError

    def nonfinite_member(self, q, qd):
        """The label of the first member whose force or stiffness is not finite at (q, q̇),
        or None (the model's input check names the member, not the whole batch)."""
        raise NotImplementedError
