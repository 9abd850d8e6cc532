"""Forward dynamics driven by the model's named inputs (``[[inputs]]``), for time-domain checks
of transfer functions (``mbseig frf``; docs/design.md "Inputs and outputs").

    M q̈ + Φ_qᵀ λ = g(q, q̇) + Σ_i b_i(q) u_i(t)

:class:`ForcedDynamics` is :class:`~mbseig.check.dynamics.ForwardDynamics` with the inputs'
generalized forces added (``Model.generalized_force(q, q̇, u)``); ``inputs`` maps input names
to constants or to functions of time.
"""

from __future__ import annotations

from ..errors import CaseError
from .dynamics import ForwardDynamics

__all__ = ["ForcedDynamics"]


class ForcedDynamics(ForwardDynamics):
    """Forward dynamics with named inputs u_i(t) (module docstring)."""

    def __init__(self, model, q0, inputs, **kwargs):
        known = {i.name for i in (getattr(model, "inputs", ()) or ())}
        unknown = sorted(set(inputs) - known)
        if unknown:
            raise CaseError(f"unknown input {unknown[0]!r} "
                            f"(known: {', '.join(sorted(known)) or 'none'})",
                            element="time-domain check")
        self.inputs = dict(inputs)
        self.t = 0.0
        super().__init__(model, q0, **kwargs)

    def values(self, t):
        return {nm: (u(t) if callable(u) else float(u)) for nm, u in self.inputs.items()}

    def rhs(self, t, y):
        self.t = t
        return super().rhs(t, y)

    def force(self, q, qd):
        return self.model.generalized_force(q, qd, self.values(self.t))
