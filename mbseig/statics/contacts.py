"""The active set of single-sided contacts at a static equilibrium (DESIGN §8).

A single-sided constraint (``Constraint.single_sided``: :class:`~mbseig.model.contact.PointContact`)
pushes only.  :func:`solve_with_contacts` starts with every contact active and

    solves the equilibrium of the model with the active ones; releases the contact that pulls
    most (normal force N < −tol·max|N|) and says so; re-activates a released contact whose point
    would enter its plane (gap < −tol·ℓ) and says so; repeats until every active contact pushes
    and no released one penetrates.

The result is the equilibrium of the model with its active contacts (``eq.model``: every stage
after it works on that model, so a released contact is a free point), with ``contacts`` =
({"name", "force", "active"}, ...) in the case's order and the messages among its ``notes``.
An active set that comes back (a load beyond lift-off with nothing else to hold the body) is
refused in one line.

:func:`held_active` turns every contact into a bilateral row (the set held), which is what
:func:`contact_forces` and a lift-off search (:func:`mbseig.studies.steady_sweep.lift_off`)
evaluate: N(p) of the bilateral model is smooth through the lift-off value.
"""

from __future__ import annotations

import dataclasses

import numpy as np

from ..errors import EquilibriumError
from ..model.spatial_joints import QuadraticConstraint

__all__ = ["RELEASE_TOL", "contact_forces", "held_active", "solve_with_contacts"]

RELEASE_TOL = 1e-9  # a force below −RELEASE_TOL·max|N| pulls; a gap below −RELEASE_TOL·ℓ penetrates


def _offsets(constraints):
    out, k = {}, 0
    for c in constraints:
        out[id(c)] = k
        k += c.n_eq
    return out


@dataclasses.dataclass(frozen=True, eq=False)
class _HeldContact(QuadraticConstraint):
    """A contact row held active (bilateral); ``force`` as the contact's."""

    length: float = 1.0

    def force(self, lam) -> float:
        return float(-np.asarray(lam, float).reshape(-1)[0] / self.length)


def held_active(model):
    """``model`` with every single-sided row made bilateral (same name, rows and scale)."""
    cons = tuple(_HeldContact(c.name, c.rows, c.residual_scale, c.wrench, c.length)
                 if c.single_sided else c for c in model.constraints)
    return dataclasses.replace(model, constraints=cons)


def contact_forces(model, lam) -> dict:
    """{contact name: normal force} of the single-sided rows of ``model`` (or of its
    :func:`held_active` copy, same order) from the multipliers ``lam``."""
    out, k = {}, 0
    for c in model.constraints:
        if c.single_sided or isinstance(c, _HeldContact):
            out[c.name] = c.force(lam[k:k + 1])
        k += c.n_eq
    return out


def solve_with_contacts(model, solve, *, tol=RELEASE_TOL):
    """The equilibrium with the active set of the model's contacts (module docstring);
    ``solve(model) -> Equilibrium`` solves one active set."""
    contacts = [c for c in model.constraints if c.single_sided]
    others = [c for c in model.constraints if not c.single_sided]
    active, messages, seen = list(contacts), [], set()
    while True:
        key = frozenset(id(c) for c in active)
        if key in seen:
            raise EquilibriumError(
                "no active set of the contacts holds: " + "; ".join(messages[-2:])
                + " (a load beyond lift-off with nothing else to hold the body)",
                element="contacts")
        seen.add(key)
        m = dataclasses.replace(model, constraints=tuple(
            c for c in model.constraints if any(c is o for o in others)
            or any(c is a for a in active)))
        eq = solve(m)
        off = _offsets(m.constraints)
        forces = {id(c): c.force(eq.lam[off[id(c)]]) for c in active}
        scale = max([abs(v) for v in forces.values()] + [1e-300])
        pulling = [c for c in active if forces[id(c)] < -tol * scale]
        penetrating = [c for c in contacts if not any(c is a for a in active)
                       and c.gap(eq.q) < -tol * c.length]
        if not pulling and not penetrating:
            rows = tuple({"name": c.name, "force": forces.get(id(c), 0.0),
                          "active": any(c is a for a in active)} for c in contacts)
            return dataclasses.replace(eq, contacts=rows,
                                       notes=tuple(eq.notes) + tuple(messages))
        if pulling:
            worst = min(pulling, key=lambda c: forces[id(c)])
            active = [c for c in active if c is not worst]
            messages.append(f"contact {worst.name!r} released: it would pull "
                            f"({forces[id(worst)]:.6g} N)")
        else:
            back = penetrating[0]
            active.append(back)
            messages.append(f"contact {back.name!r} re-activated: its point would enter the "
                            f"plane ({back.gap(eq.q):.3g} m)")
