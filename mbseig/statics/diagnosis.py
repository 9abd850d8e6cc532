"""What a failed static solve says (docs/design.md, "Equilibrium"): which of the failure classes
was shown, naming the constraints or the coordinates that moved most, and from where."""

from __future__ import annotations

import numpy as np

from ..model.assembly import UNITS
from .failures import NoStaticEquilibrium, NotConverged
from .newton import Settings, Stall


# ---------------------------------------------------------------------------------------------
def _dominant(vec, names, scales, count=3):
    rel = np.abs(vec) / scales.ell
    top = np.argsort(-rel, kind="stable")[:count]
    mx = rel[top[0]] if top.size else 0.0
    return [names[i] for i in top if rel[i] >= 0.2 * mx and rel[i] > 0]


def diagnose(model, q0, first: Stall, second, s: Settings):
    """The true failure message from the failed attempts (docs/design.md, "Equilibrium")."""
    names = model.coordinate_names
    last = first
    if last.free_dir is not None and last.free > np.sqrt(s.tol):
        along = ", ".join(_dominant(last.free_dir, names, s.scales))
        force = float(np.linalg.norm(last.free_dir))
        return NoStaticEquilibrium(
            f"no static equilibrium: free motion along {along} (no restoring force; an "
            f"unbalanced generalized force of {force:.4g} acts along it at the last iterate, "
            f"after {last.iterations} Newton iterations)", element="equilibrium")
    q = last.q if last.q is not None else q0
    moved = s.scales.largest(q - q0, names)
    kind = dict(zip(names, model.coordinate_kinds, strict=True))
    moved_txt = ", ".join(f"{nm} ({dq:+.3g}{_unit(kind[nm])})" for nm, dq in moved) or "none"
    hint = ("hint: start nearer the expected equilibrium (positions of the case, or q_init)")
    if second is not None:
        t = getattr(second, "load_factor", None)
        if t is not None and t > 0:
            hint += (f"; the load continuation from the unloaded state stopped at {t:.4g} of the "
                     f"loads (a limit point: beyond it the equilibrium is on another branch, or "
                     f"none exists)")
        else:
            hint += f"; the load continuation from the unloaded state failed too ({second.reason})"
    return NotConverged(
        f"did not converge from the given positions ({first.reason}; Newton correction "
        f"{first.correction:.3g} of the model's size): the coordinates that moved most: "
        f"{moved_txt}; {hint}", element="equilibrium")


def _unit(kind) -> str:
    """The unit printed after a coordinate change of this kind (none for dimensionless ones)."""
    unit = UNITS[kind]
    return "" if unit == "1" else f" {unit}"
