"""The reader entries of rolling wheels and single-sided contacts (DESIGN §8, "Steady motions,
rolling and contact"), and of the ``[motion]`` table.

- ``type = "rolling"``: ``body`` (an axisymmetric wheel body), ``axis`` (its axle, global, at the
  reference), ``radius``, ``normal`` (default [0, 0, 1]) and ``plane_point`` (default the
  origin) → a :class:`~mbseig.model.rolling.RollingWheel`; its holonomic rows (contact, gauge)
  join the constraints as a :class:`~mbseig.model.rolling.WheelRows`, which carries the wheel.
  A rolling wheel needs a steady ``[motion]``.
- ``type = "contact"``: ``point`` (a point reference), ``normal``, ``plane_point`` (default the
  origin) → a single-sided :class:`~mbseig.model.contact.PointContact`.
- ``[motion]``: :func:`read_motion` → :class:`mbseig.model.rolling.Motion`.

Every problem is a one-line :class:`~mbseig.errors.CaseError` naming the element.
"""

from __future__ import annotations

import numpy as np

from ..errors import CaseError
from .fields import Fields

__all__ = ["MOTION_KEYS", "read_motion", "read_motion_joint"]

MOTION_KEYS = ("speed", "direction", "yaw_rate")


def read_motion_joint(builder, f, kind, constraints):
    """Read one ``rolling`` or ``contact`` joint of a 3-D case into ``constraints``."""
    if kind == "rolling":
        _rolling(builder, f, constraints)
    else:
        _contact(builder, f, constraints)


def _rolling(builder, f, constraints):
    from ..model.rolling import rolling_wheel

    f.text("type")
    name = f.text("name", None)
    bname = builder.body(f, f.text("body"))
    axis = f.vec("axis", 3)
    radius = f.num("radius", positive=True)
    normal = f.vec("normal", 3, [0.0, 0.0, 1.0])
    plane = f.vec("plane_point", 3, [0.0, 0.0, 0.0])
    f.done()
    motion = builder.data.get("motion")
    if not isinstance(motion, dict) or not any(k in motion for k in ("speed", "yaw_rate")):
        raise f.error("a rolling wheel needs a steady [motion] (speed; speed = 0 for rest)")
    b = builder.bodies[bname]
    try:
        wheel = rolling_wheel(name or f.label, builder.frames[bname], origin=b["origin"],
                              com=b["com"], inertia=b["inertia"], axis=axis, radius=radius,
                              normal=normal, plane_point=plane, length=builder.length_scale)
    except ValueError as exc:
        raise f.error(str(exc)) from None
    builder.add_constraint(constraints, wheel.holonomic(), f)


def _contact(builder, f, constraints):
    from ..model.contact import point_contact

    f.text("type")
    name = f.text("name", None)
    point = builder.point_ref(f, "point")
    normal = f.vec("normal", 3)
    plane = f.vec("plane_point", 3, [0.0, 0.0, 0.0])
    f.done()
    try:
        c = point_contact(name or f.label, point, normal=normal, plane_point=plane,
                          length=builder.length_scale)
    except ValueError as exc:
        raise f.error(str(exc)) from None
    builder.add_constraint(constraints, c, f)


def read_motion(data, params, *, file=None):
    """The ``[motion]`` table of a steady motion as a :class:`~mbseig.model.rolling.Motion`:
    ``speed`` (default 0), ``direction`` (default [1, 0, 0], normal to gravity), ``yaw_rate``
    (default 0, about the gravity axis).  Gravity gives the yaw axis and must be present."""
    from ..model.rolling import Motion

    table = data.get("motion")
    if not isinstance(table, dict):
        raise CaseError("[motion] must be a table", element="motion", file=file)
    try:
        unknown = sorted(set(table) - set(MOTION_KEYS))
        if unknown:
            raise CaseError(f"unknown field {unknown[0]!r} (fields: {', '.join(MOTION_KEYS)})",
                            element="motion")
        f = Fields(dict(table), "motion", params)
        speed = f.num("speed", 0.0)
        d = f.vec("direction", 3, [1.0, 0.0, 0.0])
        yaw = f.num("yaw_rate", 0.0)
        f.done()
        if np.linalg.norm(d) == 0:
            raise CaseError("direction has zero length", element="motion")
        grav = data.get("gravity")
        if grav is None:
            raise CaseError("a steady motion needs gravity (its axis is the yaw axis)",
                            element="motion")
        g = Fields({"gravity": grav}, "gravity", params).vec("gravity", 3)
        if np.linalg.norm(g) == 0:
            raise CaseError("a steady motion needs gravity (its axis is the yaw axis)",
                            element="motion")
        up = -g / np.linalg.norm(g)
        d = d / np.linalg.norm(d)
        if abs(up @ d) > 1e-12:
            raise CaseError("direction must be normal to gravity", element="motion")
    except CaseError as exc:
        raise exc.located(file=file) from None
    return Motion(float(speed), tuple(float(x) for x in d), float(yaw), tuple(float(x) for x in up))
