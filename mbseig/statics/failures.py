"""What the statics can say when it finds no equilibrium, and what it warns about when it does
(docs/design.md, "Equilibrium").

Each failure is an :class:`~mbseig.errors.EquilibriumError` (one line, exit code 2 on the
command line), and each says only what was shown:

- :class:`ConstraintsUnsatisfiable`: the position solve of Φ(q) = 0 *alone* (no forces) stops
  at a least-squares minimum with Φ ≠ 0: no nearby position satisfies the constraints.  The
  message names the constraint with the largest relative residual.
- :class:`NoStaticEquilibrium`: the model moves without restoring force along a direction in
  which its loads push it (a null direction of the reduced tangent stiffness with a load along
  it).  The message names the coordinates of that direction.
- :class:`NotConverged`: neither of the above was shown; Newton from the given positions (and
  the load continuation from the unloaded state) did not converge.  The message names the
  coordinates that moved most and gives a hint.
- :class:`UndeterminedSelfStress`: redundant constraints carry a self-stress that statics cannot
  determine, and the stiffness (so the verdict) depends on it.

:class:`StaticInstabilityWarning` is issued when the equilibrium found is statically unstable.
"""

from __future__ import annotations

from ..errors import EquilibriumError, ReportedWarning

__all__ = ["ConstraintsUnsatisfiable", "NoStaticEquilibrium", "NotConverged",
           "UndeterminedSelfStress", "StaticInstabilityWarning"]


class ConstraintsUnsatisfiable(EquilibriumError):
    """A position solve of Φ = 0 alone stops at a least-squares minimum with Φ ≠ 0."""


class NoStaticEquilibrium(EquilibriumError):
    """Free motion: a direction without restoring force along which the loads push."""


class NotConverged(EquilibriumError):
    """Newton (and the load continuation) did not converge from the given positions."""


class UndeterminedSelfStress(EquilibriumError):
    """Redundant constraints with a self-stress that changes the stiffness."""


class StaticInstabilityWarning(ReportedWarning, RuntimeWarning):
    """The equilibrium found is statically unstable (a divergence)."""
