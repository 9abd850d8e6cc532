"""Coefficient tables over a parameter (DESIGN §8, 3-D flexible bodies and flexible rotors).

A bushing's ``stiffness`` or ``damping`` may be ``{parameter = "Omega", at = [w1, ..., wN],
values = [v1, ..., vN]}``: each v is ``size`` numbers (a diagonal) or a size × size matrix
(cross-coupled terms allowed), ``at`` strictly increasing.  The matrix at the parameter's
current value is the linear interpolation between the two bracketing entries (entrywise; ROSS
interpolates its bearing coefficients the same way); a value outside [w1, wN] is refused in one
line naming the element, never extrapolated.
"""

from __future__ import annotations

import numpy as np

from .fields import Fields

__all__ = ["interpolated_matrix", "table_matrices"]


def table_matrices(f: Fields, key: str, size: int):
    """(parameter name, at (N,), values (N, size, size)) of the table ``key`` of ``f``."""
    sub = Fields(f.raw(key), f"{f.label}.{key}", f.names)
    pname = sub.text("parameter")
    at = sub.raw("at")
    values = sub.raw("values")
    sub.done()
    if not isinstance(at, list) or len(at) < 1:
        raise sub.error("at must be a non-empty list of parameter values")
    at = Fields({"at": at}, sub.label, f.names).vec("at", len(at))
    if np.any(np.diff(at) <= 0):
        raise sub.error("at must be strictly increasing")
    if not isinstance(values, list) or len(values) != at.size:
        raise sub.error(f"values must list one entry per value of at ({at.size})")
    mats = []
    for k, v in enumerate(values):
        vf = Fields({"v": v}, f"{sub.label}.values[{k}]", f.names)
        if isinstance(v, list) and len(v) == size and all(isinstance(r, list) for r in v):
            mats.append(np.array([Fields({"r": r}, f"{vf.label}[{i}]", f.names).vec("r", size)
                                  for i, r in enumerate(v)]))
        elif isinstance(v, list) and len(v) == size:
            mats.append(np.diag(vf.vec("v", size)))
        else:
            raise vf.error(f"each value must be {size} numbers or a {size}x{size} matrix")
    return pname, at, np.array(mats)


def interpolated_matrix(builder, f: Fields, key: str, size: int) -> np.ndarray:
    """The size × size matrix of the table ``key`` at the current value of its parameter."""
    pname, at, mats = table_matrices(f, key, size)
    if pname not in builder.params:
        raise f.error(f"{key}: unknown parameter {pname!r} (declare it in [parameters])")
    x = float(builder.params[pname])
    if not (at[0] <= x <= at[-1]):
        raise f.error(f"{key}: {pname} = {x:g} is outside the table [{at[0]:g}, {at[-1]:g}]")
    if at.size == 1:
        return mats[0].copy()
    k = int(np.clip(np.searchsorted(at, x, side="right") - 1, 0, at.size - 2))
    t = (x - at[k]) / (at[k + 1] - at[k])
    return (1.0 - t) * mats[k] + t * mats[k + 1]
