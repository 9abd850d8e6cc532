"""Reading a URDF file (xml.etree; data only, nothing executed): links with their inertials,
joints with their origins, axes, limits, dynamics and mimic tags, and the errors that name the
URDF element; frame algebra (rpy matrices, axis rotations)."""

from __future__ import annotations

import math
import xml.etree.ElementTree as ET
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from ..errors import CaseError

MOVING = {"revolute": "revolute", "continuous": "revolute", "prismatic": "prismatic"}


# ---------------------------------------------------------------------------------------------
# Reading
# ---------------------------------------------------------------------------------------------
@dataclass(frozen=True)
class Link:
    name: str
    mass: float  # 0: massless
    xyz: np.ndarray = field(repr=False)  # inertial origin in the link frame
    rpy: np.ndarray = field(repr=False)
    inertia: np.ndarray = field(repr=False)  # 3×3 in the inertial frame


@dataclass(frozen=True)
class Joint:
    name: str
    type: str  # revolute, continuous, prismatic, fixed
    parent: str
    child: str
    xyz: np.ndarray = field(repr=False)
    rpy: np.ndarray = field(repr=False)
    axis: np.ndarray = field(repr=False)  # unit, in the joint frame
    damping: float = 0.0
    mimic: tuple | None = None  # (leader, multiplier, offset)
    limit: tuple = (0.0, 0.0)  # (lower, upper) as written, 0 where absent


@dataclass(frozen=True)
class UrdfRobot:
    """The links and joints of a URDF file, as read (document order)."""

    name: str
    path: str
    links: dict
    joints: dict

    def error(self, element: str, message: str) -> CaseError:
        return CaseError(message, file=self.path, element=element)


def _floats(el, attr, n, default, where, path):
    text = el.get(attr) if el is not None else None
    if text is None:
        return np.array(default, float)
    try:
        vals = [float(x) for x in text.split()]
    except ValueError:
        vals = None
    if vals is None or len(vals) != n or not all(math.isfinite(v) for v in vals):
        raise CaseError(f"{attr}={text!r} must be {n} finite number{'s' * (n > 1)}",
                        file=path, element=where)
    return np.array(vals)


def _named(el, tag, seen, path):
    """(name, "tag 'name'") of a <link> or <joint>: named, and not twice."""
    name = el.get("name")
    if not name:
        raise CaseError(f"a <{tag}> without a name", file=path, element=tag)
    if name in seen:
        raise CaseError(f"duplicate {tag} name", file=path, element=f"{tag} {name!r}")
    return name, f"{tag} {name!r}"


def read_urdf(path, *, referrer=None) -> UrdfRobot:
    """Parse a URDF file (module docstring); structural checks are in :func:`urdf_tables`.
    ``referrer`` = (case file, element) that names the URDF, if any: a URDF that cannot be
    opened is then reported against that case element, naming both files."""
    path = Path(path)
    p = str(path)
    try:
        root = ET.parse(path).getroot()
    except OSError as exc:
        reason = exc.strerror or str(exc)
        if referrer is not None:
            raise CaseError(f"{p}: cannot read URDF file: {reason}", file=str(referrer[0]),
                            element=referrer[1]) from None
        raise CaseError(f"cannot read URDF file: {reason}", file=p) from None
    except ET.ParseError as exc:
        raise CaseError(f"malformed XML: {exc}", file=p) from None
    if root.tag != "robot":
        raise CaseError(f"the root element must be <robot>, got <{root.tag}>", file=p)
    links, joints = {}, {}
    for el in root.findall("link"):
        name, where = _named(el, "link", links, p)
        inertial = el.find("inertial")
        mass, xyz, rpy, inertia = 0.0, np.zeros(3), np.zeros(3), np.zeros((3, 3))
        if inertial is not None:
            m = inertial.find("mass")
            mass = float(_floats(m, "value", 1, [0.0], f"{where} <mass>", p)[0])
            if mass < 0:
                raise CaseError(f"<mass value> must not be negative, got {mass:g}", file=p,
                                element=where)
            origin = inertial.find("origin")
            xyz = _floats(origin, "xyz", 3, [0, 0, 0], f"{where} <inertial><origin>", p)
            rpy = _floats(origin, "rpy", 3, [0, 0, 0], f"{where} <inertial><origin>", p)
            i = inertial.find("inertia")
            if mass > 0 and i is None:
                raise CaseError("<inertial> with a mass needs <inertia>", file=p, element=where)
            c = {k: float(_floats(i, k, 1, [0.0], f"{where} <inertia>", p)[0])
                 for k in ("ixx", "ixy", "ixz", "iyy", "iyz", "izz")}
            inertia = np.array([[c["ixx"], c["ixy"], c["ixz"]], [c["ixy"], c["iyy"], c["iyz"]],
                                [c["ixz"], c["iyz"], c["izz"]]])
        links[name] = Link(name, mass, xyz, rpy, inertia)
    for el in root.findall("joint"):
        name, where = _named(el, "joint", joints, p)
        jtype = el.get("type")
        if jtype not in (*MOVING, "fixed"):
            raise CaseError(f"unsupported joint type {jtype!r} (revolute, continuous, "
                            f"prismatic, fixed)", file=p, element=where)
        ends = []
        for tag in ("parent", "child"):
            e = el.find(tag)
            if e is None or not e.get("link"):
                raise CaseError(f"needs <{tag} link=...>", file=p, element=where)
            if e.get("link") not in links:
                raise CaseError(f"<{tag}> refers to the missing link {e.get('link')!r}", file=p,
                                element=where)
            ends.append(e.get("link"))
        origin = el.find("origin")
        xyz = _floats(origin, "xyz", 3, [0, 0, 0], f"{where} <origin>", p)
        rpy = _floats(origin, "rpy", 3, [0, 0, 0], f"{where} <origin>", p)
        axis = _floats(el.find("axis"), "xyz", 3, [1, 0, 0], f"{where} <axis>", p)
        if jtype != "fixed":
            n = float(np.linalg.norm(axis))
            if n == 0:
                raise CaseError("<axis xyz> must not be zero", file=p, element=where)
            axis = axis / n
        dyn = el.find("dynamics")
        damping = float(_floats(dyn, "damping", 1, [0.0], f"{where} <dynamics>", p)[0])
        if damping < 0:
            raise CaseError(f"<dynamics damping> must not be negative, got {damping:g}",
                            file=p, element=where)
        lim = el.find("limit")
        limit = (float(_floats(lim, "lower", 1, [0.0], f"{where} <limit>", p)[0]),
                 float(_floats(lim, "upper", 1, [0.0], f"{where} <limit>", p)[0]))
        mimic = None
        mel = el.find("mimic")
        if mel is not None:
            leader = mel.get("joint")
            if not leader:
                raise CaseError("<mimic> needs joint=...", file=p, element=where)
            mimic = (leader,
                     float(_floats(mel, "multiplier", 1, [1.0], f"{where} <mimic>", p)[0]),
                     float(_floats(mel, "offset", 1, [0.0], f"{where} <mimic>", p)[0]))
        joints[name] = Joint(name, jtype, ends[0], ends[1], xyz, rpy, axis, damping, mimic, limit)
    if not links:
        raise CaseError("the robot has no <link>", file=p)
    return UrdfRobot(root.get("name", path.stem), p, links, joints)


# ---------------------------------------------------------------------------------------------
# Geometry
# ---------------------------------------------------------------------------------------------
def rpy_matrix(rpy) -> np.ndarray:
    """URDF's fixed-axis roll, pitch, yaw: R = Rz(yaw) Ry(pitch) Rx(roll)."""
    r, p, y = rpy
    cr, sr, cp, sp, cy, sy = math.cos(r), math.sin(r), math.cos(p), math.sin(p), math.cos(y), math.sin(y)
    return np.array([[cy * cp, cy * sp * sr - sy * cr, cy * sp * cr + sy * sr],
                     [sy * cp, sy * sp * sr + cy * cr, sy * sp * cr - cy * sr],
                     [-sp, cp * sr, cp * cr]])


def axis_rotation(a, angle) -> np.ndarray:
    """Rotation by ``angle`` about the unit vector a (Rodrigues)."""
    K = np.array([[0.0, -a[2], a[1]], [a[2], 0.0, -a[0]], [-a[1], a[0], 0.0]])
    return np.eye(3) + math.sin(angle) * K + (1.0 - math.cos(angle)) * (K @ K)
