"""Robots from URDF: a URDF file → the plain 3-D case tables (design notes §8, "Robots from
URDF" and "3-D case format").

The URDF is read with :mod:`xml.etree.ElementTree` as data (no entity, include or macro is
expanded; a file still holding xacro markup is refused with the command that expands it;
meshes, collision and visual elements, transmissions and ``<gazebo>`` blocks are ignored).
Only the ``<link>`` and ``<joint>`` children of ``<robot>`` are read, every number checked
where it is read (:mod:`.urdf_read`).  The model is the one Pinocchio builds
(``pin.buildModelFromUrdf``; :mod:`.urdf_tree`), every ``at``, ``axis``, ``com`` and
``inertia`` in global axes at the reference configuration, as the 3-D format wants:

- reference configuration: the joint values ``positions = {JOINT = value}`` (rad or m; others 0;
  a ``<mimic>`` follower takes multiplier·leader + offset).  Link frames follow by forward
  kinematics from the root at the origin: child = parent · origin(xyz, rpy) · motion(q), with
  rpy the fixed-axis roll-pitch-yaw of URDF, R = Rz(yaw) Ry(pitch) Rx(roll), and motion a
  rotation by q about ``<axis>`` (revolute, continuous) or a translation by q along it
  (prismatic);
- bodies: every link on a ``fixed`` joint is merged into its parent, so a body is the root, or a
  link a joint moves, with all the links fixed to it: its mass, centre of mass and inertia
  the sums of theirs (parallel-axis theorem; products of inertia included: I = [[ixx, ixy,
  ixz], [ixy, iyy, iyz], [ixz, iyz, izz]] rotated by R_link·R(rpy of the inertial origin)).
  A link's own inertia may be zero (a point mass on a fixed joint); only a body's merged
  inertia must be a rigid body's, else the error names the body and the links merged into it.
  The body is named after its top link, or, when that has no mass, after the first link with
  mass fixed below it (document order), which then carries the moving joint; a body with no
  mass at all that a joint moves is an error, and so is a massless floating root;
- frames: every merged link is a ``[[frames]]`` entry ``{name = LINK, body = BODY}`` (BODY is
  ``"ground"`` for the links of a fixed, massless root), so the case can name it wherever a
  body name is allowed (:func:`read_frames`);
- joints: ``revolute`` / ``continuous`` → ``revolute`` (``at`` = the joint frame's origin,
  ``axis`` its ``<axis>`` in global axes), ``prismatic`` → ``prismatic``, ``planar`` →
  ``planar`` (``normal`` = the axis: the child slides in the plane normal to it and turns about
  it, as the URDF specification says; Pinocchio 4.1 ignores the axis and always uses the joint
  frame's z), ``floating`` → nothing (the child body is free), ``fixed`` → merged; joint names
  are element names;
- ``floating = false``: the root body is welded to the ground (``ROOT_to_ground``, or the fixed
  joint that joins it to a massless root); a massless root *is* the ground; ``true``: the root
  body is free;
- ``stiffness = {default = k, JOINT = k}`` and ``damping`` (the same, or ``"urdf"``: each
  joint's ``<dynamics damping>``): a ``torsional`` force ``JOINT_spring`` on a revolute joint
  (zero torque at the reference), on a prismatic joint a ``spring`` / ``damper`` /
  ``spring_damper`` ``JOINT_spring`` between ``{body = parent, at = at}`` and ``{body = child,
  at = at + ℓ·axis}`` (free length ℓ = the distance at the reference, so zero force there; the
  prismatic joint keeps the line along the axis, so the force is k·s exactly).  ``default``
  applies to every revolute, continuous and prismatic joint, ``<mimic>`` followers included
  (``JOINT = 0`` removes one); a planar or floating joint takes none (a bushing can hold it);
  values may be numbers or expressions of the case's parameters;
- ``<mimic joint="L" multiplier="r" offset="o">`` on joint F → ``[[joints]] type = "mimic"``,
  ``name = "F_mimic"``, ``joint = "F"``, ``leader = "L"``, ``multiplier = r``: θ_F = r θ_L with
  both measured from the reference (which satisfies the URDF relation, so no offset remains);
  the element is :class:`mbseig.model.mimic.MimicConstraint`, read by :func:`read_mimic`.

Every problem raises :class:`~mbseig.errors.CaseError` naming the URDF file and the element
(``link 'fore'``, ``joint 'elbow'``) or the case's ``urdf`` table.
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np

from ..errors import CaseError
from .fields import MIN_MAGNITUDE, RANGE_RULE, in_range
from .urdf_read import (  # noqa: F401
    MOVING,
    Joint,
    Link,
    UrdfRobot,
    axis_rotation,
    read_urdf,
    rpy_matrix,
)
from .urdf_entries import read_frames, read_mimic  # noqa: F401 (the 3-D reader's entries)
from .urdf_tree import group_problem, groups, kinematics, tree

__all__ = ["UrdfRobot", "expand_urdf", "import_urdf", "read_frames", "read_mimic", "read_urdf",
           "urdf_tables"]

ONE_DOF = ("revolute", "continuous", "prismatic")  # the joints with a position and a spring
_URDF_KEYS = {"file", "positions", "stiffness", "damping", "floating"}


# ---------------------------------------------------------------------------------------------
# URDF → case tables
# ---------------------------------------------------------------------------------------------
def _joint_positions(robot, positions, where):
    """Joint values of the reference: the given ones, mimic followers from their leaders."""
    q = {}
    for name, value in positions.items():
        if name not in robot.joints:
            raise CaseError(f"unknown joint {name!r}", file=where[0], element=where[1])
        if robot.joints[name].type not in ONE_DOF:
            raise CaseError(f"joint {name!r} is {robot.joints[name].type}: it has no position "
                            f"(a revolute, continuous or prismatic joint has)", file=where[0],
                            element=where[1])
        if (isinstance(value, bool) or not isinstance(value, (int, float))
                or not math.isfinite(value)):
            raise CaseError(f"{name} must be a finite number (rad or m), got {value!r}",
                            file=where[0], element=where[1])
        q[name] = float(value)
    done: dict[str, float] = {}

    def value(name, chain=()):
        if name in done:
            return done[name]
        j = robot.joints[name]
        if j.mimic is None:
            done[name] = q.get(name, 0.0)
            return done[name]
        leader, mult, off = j.mimic
        if j.type not in ONE_DOF:
            raise robot.error(f"joint {name!r}", f"<mimic> on a {j.type} joint (a revolute, "
                              f"continuous or prismatic joint may follow another)")
        if leader not in robot.joints or robot.joints[leader].type not in ONE_DOF:
            raise robot.error(f"joint {name!r}", f"<mimic> refers to {leader!r}, which is not a "
                              f"revolute, continuous or prismatic joint of the robot")
        if leader in chain or leader == name:
            raise robot.error(f"joint {name!r}", "<mimic> joints follow each other in a cycle")
        with np.errstate(all="ignore"):
            v = mult * value(leader, (*chain, name)) + off
        if not math.isfinite(v):
            raise robot.error(f"joint {name!r}", f"<mimic> gives a position out of the double "
                              f"range ({mult!r} × {leader} + {off!r})")
        if name in q and abs(q[name] - v) > 1e-12 * max(1.0, abs(v)):
            raise CaseError(f"{name} = {q[name]!r} contradicts its <mimic> of {leader!r} "
                            f"({v!r}); leave it out", file=where[0], element=where[1])
        done[name] = v
        return v

    for name, j in robot.joints.items():
        if j.type in MOVING:
            value(name)
    return done


def _gains(robot, table, key, moving, where):
    """{joint: value} of a stiffness or damping table (numbers ≥ 0 or expressions)."""
    if table is None:
        return {}
    if table == "urdf" and key == "damping":
        return {n: robot.joints[n].damping for n in moving if robot.joints[n].damping > 0}
    if not isinstance(table, dict):
        alt = ' or "urdf"' if key == "damping" else ""
        raise CaseError(f"{key} must be a table {{default = ..., JOINT = ...}}{alt}, got "
                        f"{table!r}", file=where[0], element=where[1])
    for name, v in table.items():
        if name != "default" and name not in moving:
            kind = robot.joints[name].type if name in robot.joints else None
            why = (f"a {kind} joint: a joint spring acts on a revolute, continuous or prismatic "
                   f"joint (a bushing can hold a {kind} one)" if kind in ("planar", "floating")
                   else "not a moving joint of the robot")
            raise CaseError(f"{key}: {name!r} is {why}", file=where[0], element=where[1])
        ok = isinstance(v, str) or (isinstance(v, (int, float)) and not isinstance(v, bool)
                                    and math.isfinite(v) and v >= 0)
        if not ok:
            raise CaseError(f"{key}.{name} must be a number >= 0 or an expression, got {v!r}",
                            file=where[0], element=where[1])
    out = {}
    for name in moving:
        v = table.get(name, table.get("default"))
        if v is not None and v != 0:
            out[name] = float(v) if isinstance(v, int) else v
    return out


def urdf_tables(robot: UrdfRobot, *, positions=None, stiffness=None, damping=None,
                floating: bool = False, where=("", "urdf")) -> dict:
    """``{"bodies", "joints", "forces", "frames"}`` of the 3-D format for a robot (module
    docstring).  ``where`` = (file, element) names the case table that gave the options."""
    root, order, children = tree(robot)
    q = _joint_positions(robot, positions or {}, where)
    moving = [j.name for j in robot.joints.values() if j.type in ONE_DOF]
    k = _gains(robot, stiffness, "stiffness", moving, where)
    c = _gains(robot, damping, "damping", moving, where)
    frames, jframes = kinematics(root, order, q)
    for name in robot.links:
        if name == "ground" or "." in name:
            why = ("'ground' names the case's fixed frame" if name == "ground" else
                   "'.' separates beam stations and body markers in a case ('shaft.disk1')")
            raise robot.error(f"link {name!r}", f"the link's name cannot be a name of the case "
                              f"({why}); rename the link in the URDF")
    rigid = groups(robot, root, order, children, frames)
    body_of = {}  # link → its body, or "ground"
    bodies, joints, forces, mimics = [], [], [], []
    for top, g in rigid.items():
        if g.body is None and top == root and not floating:
            name = "ground"
        elif g.body is None:
            raise _no_mass(robot, top, order, floating)
        else:
            name = g.body
            problem = group_problem(robot, g)
            if problem:
                raise problem
            bodies.append(_body(robot, g))
        body_of.update({link: name for link in g.links})
    root_body = body_of[root]
    if root_body != "ground" and not floating:
        fixed_in = next((j for j in order if j.child == root_body), None)
        joints.append({"type": "weld", "bodies": ["ground", root_body],
                       "name": fixed_in.name if fixed_in else f"{root}_to_ground",
                       "at": _list(jframes[fixed_in.name][1]) if fixed_in else [0.0, 0.0, 0.0]})
    for j in order:
        if j.type in ("fixed", "floating"):  # merged; a free child (no joint)
            continue
        b1, b2 = body_of[j.parent], body_of[j.child]
        at = _list(jframes[j.name][1])
        axis = _unit_list(jframes[j.name][0] @ j.axis)
        if j.type == "planar":
            joints.append({"type": "planar", "name": j.name, "bodies": [b1, b2], "at": at,
                           "normal": axis})
            continue
        joints.append({"type": MOVING[j.type], "name": j.name, "bodies": [b1, b2], "at": at,
                       "axis": axis})
        if j.mimic is not None:  # after every joint: its leader may come later in the tree
            mimics.append({"type": "mimic", "name": f"{j.name}_mimic", "joint": j.name,
                           "leader": j.mimic[0], "multiplier": j.mimic[1]})
        forces += _spring(j, b1, b2, at, axis, k.get(j.name, 0), c.get(j.name, 0))
    named = {b["name"] for b in bodies}
    links = [{"name": n, "body": b} for n, b in body_of.items() if n not in named]
    joints += mimics
    for e in joints + forces:
        _in_range(robot, e)
    names = [e["name"] for e in joints + forces]
    clash = sorted({n for n in names if names.count(n) > 1})
    if clash:
        raise robot.error("robot", f"element name {clash[0]!r} of the expanded case is used "
                          f"twice (a joint of that name exists)")
    return {"bodies": bodies, "joints": joints, "forces": forces, "frames": links}


def _no_mass(robot, top, order, floating):
    """The error for a rigid group without mass: moved by a joint, or a floating root."""
    into = next((j for j in order if j.child == top), None)
    if into is None:
        free = [j.name for j in order if j.parent == top and j.type == "floating"]
        hint = (f"; its joint {free[0]!r} is floating already: leave floating out" if free
                else "")
        return robot.error(f"link {top!r}", f"the floating root link has no <inertial> mass "
                           f"and no link with mass is fixed to it{hint}")
    return robot.error(f"link {top!r}", f"it has no <inertial> mass (nor a link with mass fixed "
                       f"to it) but joint {into.name!r} moves it")


def _list(v):
    return [float(x) + 0.0 for x in v]


def _unit_list(v):
    """A unit vector's components, those below 1e-100 (the case number rule's floor) as 0: a
    turn of the direction below 1e-100 rad, far below its rounding (1.1e-16)."""
    return [float(x) + 0.0 if abs(x) >= MIN_MAGNITUDE else 0.0 for x in v]


def _in_range(robot, element):
    """Every position of a generated joint or spring in the case number rule, else refused
    naming the URDF joint (URDF values near 1e-100 or 1e100 combine to smaller or larger
    ones)."""
    for key in ("at", "points"):
        value = element.get(key)
        if value is None:
            continue
        values = [p["at"] for p in value] if key == "points" else [value]
        if not all(in_range(v) for v in values):
            name = element.get("joint", element["name"].removesuffix("_spring"))
            raise robot.error(f"joint {name!r}", f"its position at the reference, {values!r}, "
                              f"is out of range: {RANGE_RULE}")


def _body(robot, g):
    """The [[bodies]] entry of a rigid group (its merged inertia, urdf_tree); every number in
    the case's range (README, "Input rules"), else refused naming the link."""
    entry = {"name": g.body, "mass": g.mass, "com": _list(g.com),
             "inertia": [_list(row) for row in g.inertia]}
    for key in ("mass", "com", "inertia"):
        if not in_range(entry[key]):
            merged = f" merged with {', '.join(map(repr, g.links[1:]))}" if len(g.links) > 1 else ""
            raise robot.error(f"link {g.body!r}", f"its {key}{merged} at the reference, "
                              f"{entry[key]!r}, is out of range: {RANGE_RULE}")
    return entry


def _spring(j, b1, b2, at, axis, k, c):
    """The joint spring-damper (module docstring); none when k = c = 0."""
    if not k and not c:
        return []
    gains = {**({"stiffness": k} if k else {}), **({"damping": c} if c else {})}
    if j.type != "prismatic":
        return [{"type": "torsional", "name": f"{j.name}_spring", "joint": j.name, **gains}]
    ell = 1.0 + max(abs(j.limit[0]), abs(j.limit[1]))  # longer than any stroke of the joint
    tip = _list(np.array(at) + ell * np.array(axis))
    kind = "spring_damper" if k and c else ("spring" if k else "damper")
    return [{"type": kind, "name": f"{j.name}_spring",
             "points": [{"body": b1, "at": at}, {"body": b2, "at": tip}], **gains}]


# ---------------------------------------------------------------------------------------------
# Entry points
# ---------------------------------------------------------------------------------------------
def expand_urdf(case: dict, case_path) -> dict:
    """The case dict with its ``[urdf]`` table replaced by the robot's bodies, joints and
    forces (placed before the case's own entries, which may refer to link and joint names).
    A case without ``[urdf]`` is returned unchanged."""
    if "urdf" not in case:
        return case
    case_path = Path(case_path)
    file = str(case_path)
    table = case["urdf"]
    if not isinstance(table, dict):
        raise CaseError("[urdf] must be a table", file=file, element="urdf")
    unknown = sorted(set(table) - _URDF_KEYS)
    if unknown:
        raise CaseError(f"unknown field {unknown[0]!r} ({', '.join(sorted(_URDF_KEYS))})",
                        file=file, element="urdf")
    if case.get("dimension") != 3:
        raise CaseError("a case with [urdf] needs dimension = 3", file=file, element="urdf")
    fname = table.get("file")
    if not isinstance(fname, str) or not fname:
        raise CaseError("file must name the URDF file (relative to the case)", file=file,
                        element="urdf")
    floating = table.get("floating", False)
    if not isinstance(floating, bool):
        raise CaseError(f"floating must be true or false, got {floating!r}", file=file,
                        element="urdf")
    positions = table.get("positions", {})
    if not isinstance(positions, dict):
        raise CaseError("positions must be a table {JOINT = value}", file=file,
                        element="urdf.positions")
    robot = read_urdf(case_path.parent / fname, referrer=(file, "urdf.file"))
    tables = urdf_tables(robot, positions=positions, stiffness=table.get("stiffness"),
                         damping=table.get("damping"), floating=floating, where=(file, "urdf"))
    out = {key: value for key, value in case.items() if key != "urdf"}
    for key in ("bodies", "joints", "forces", "frames"):
        own = case.get(key, [])
        if not isinstance(own, list):
            raise CaseError(f"{key} must be an array of tables", file=file, element=key)
        if tables[key] or own:
            out[key] = tables[key] + list(own)
    return out


def import_urdf(urdf_path, out_toml=None, *, positions=None, stiffness=None, damping=None,
                floating: bool = False, gravity=(0.0, 0.0, -9.81),
                title: str | None = None) -> dict:
    """The plain 3-D case equivalent to a URDF (``mbseig import-urdf ROBOT.urdf --out CASE.toml``).

    Parameters
    ----------
    urdf_path : str or pathlib.Path
        The robot's URDF file.
    out_toml : str or pathlib.Path, optional
        Where to write the case (TOML); nothing is written when omitted.
    positions : dict, optional
        {joint: value} of the reference configuration (rad or m; the others 0).
    stiffness : dict, optional
        {"default": k, joint: k}: a torsional (revolute) or axial (prismatic) spring on each
        joint named or covered by the default.
    damping : dict or str, optional
        The same for dampers, or "urdf": each joint's ``<dynamics damping>``.
    floating : bool
        The root body free (False: welded to the ground).
    gravity : sequence of 3 numbers or None
        Gravity in the robot's base frame (None: no gravity).
    title : str, optional
        The case's title (default: the robot's name and the file's).

    Returns
    -------
    dict
        The case as the 3-D format's tables (:func:`mbseig.read_case` takes it as it is).

    Examples
    --------
    >>> case = import_urdf("two_link_arm.urdf", positions={"shoulder": 0.3})  # doctest: +SKIP
    >>> sorted(case)[:3]  # doctest: +SKIP
    ['bodies', 'dimension', 'forces']
    """
    from .writer import to_toml

    urdf_path = Path(urdf_path)
    robot = read_urdf(urdf_path)
    tables = urdf_tables(robot, positions=positions, stiffness=stiffness, damping=damping,
                         floating=floating, where=(str(urdf_path), "import-urdf options"))
    case = {"schema_version": 1,
            "title": title or f"{robot.name} (imported from {urdf_path.name})",
            "dimension": 3}
    if gravity is not None:
        case["gravity"] = [float(g) if not isinstance(g, str) else g for g in gravity]
    case.update({k: v for k, v in tables.items() if v})
    if out_toml is not None:
        Path(out_toml).write_text(to_toml(case), encoding="utf-8")
    return case
