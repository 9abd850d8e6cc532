"""The 3-D reader's entries for what a URDF import writes (:mod:`mbseig.casefile.urdf`): the
top-level ``[[frames]]`` (names of merged links) and ``[[joints]] type = "mimic"``."""

from __future__ import annotations

from ..errors import CaseError
from ..model.mimic import MimicConstraint, joint_coordinate
from .fields import Fields

__all__ = ["read_frames", "read_mimic"]


def read_frames(builder, items):
    """Reader of the top-level ``[[frames]]`` of a 3-D case (:class:`~mbseig.casefile.spatial.
    SpatialBuilder`, after its bodies): each ``{name, body}`` names a body's frame, usable
    wherever a body name is; ``body`` may be ``"ground"`` (a link of a fixed base).  A URDF
    import lists every link merged into a body here, so cases keep naming it."""
    if not isinstance(items, list):
        raise CaseError("frames must be an array of tables {name, body}", element="frames")
    for k, item in enumerate(items):
        f = Fields(item, f"frames[{k}]", builder.params)
        name, body = f.text("name"), f.text("body")
        f.done()
        f.label = f"frames[{k}] {name!r}"
        if name in builder.bodies or name in builder.aliases or name == "ground" or "." in name:
            raise f.error("the name is a body's or another frame's already, is 'ground' or "
                          "contains '.'")
        if body != "ground" and body not in builder.bodies:
            raise f.error(f"unknown body {body!r}")
        builder.aliases[name] = body


def read_mimic(builder, f, constraints):
    """Reader entry for ``type = "mimic"`` in the 3-D reader
    (:class:`mbseig.casefile.spatial.SpatialBuilder`; the case format is in
    :mod:`mbseig.model.mimic`): both joints are declared before it."""
    f.text("type")
    f.text("name", None)
    coords = []
    for key in ("joint", "leader"):
        jname = f.text(key)
        j = builder.spatial_joints.get(jname)
        if j is None or j[0] not in ("revolute", "cylindrical", "prismatic"):
            raise f.error(f"{key} {jname!r} is not a revolute, cylindrical or prismatic joint "
                          f"declared before")
        kind, b1, b2, at, axis = j[:5]
        frames = (builder.frame(f, b1), builder.frame(f, b2))
        locals_ = (builder.local(b1, at), builder.local(b2, at))
        coords.append(joint_coordinate(kind, frames, locals_, axis))
    if f.raw("joint") == f.raw("leader"):
        raise f.error("a joint cannot follow itself")
    r = f.num("multiplier", 1.0)
    o = f.num("offset", 0.0)
    f.done()
    units = "N m" if coords[0].kind == "angle" else "N"
    c = MimicConstraint(f.label, coords[0], coords[1], r, o, units)
    builder.add_constraint(constraints, c, f)
