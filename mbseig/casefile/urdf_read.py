"""Reading a URDF file (xml.etree; data only, nothing executed): links with their inertials,
joints with their origins, axes, limits, dynamics and mimic tags, and the errors that name the
URDF element; frame algebra (rpy matrices, axis rotations).

Every number is checked where it is read, as the case's numbers are (README, "Input rules"):
the right count, finite, and 0 or of magnitude 1e-100 to 1e100 (then the products the import
forms, m·|r|², R I Rᵀ and their sums, stay far inside the double range); refused in one line
naming the file, the link or joint, the XML element and the attribute, never rewritten.  What
URDF readers (urdfdom, so Pinocchio) require is required here: a ``<mass value>`` and all six
``<inertia>`` attributes in an ``<inertial>``; a non-zero ``<axis>`` on a moving joint (then
made a unit vector).  What they do not read is not read either: the axis of a ``fixed`` or
``floating`` joint, the limits of all but prismatic joints (whose stroke sets a spring's free
length).  A file that still holds xacro markup (``<xacro:macro>``, ``${...}``) is refused with
the command that expands it.
"""

from __future__ import annotations

import math
import re
import xml.etree.ElementTree as ET
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from ..errors import CaseError
from .fields import RANGE_RULE, in_range

MOVING = {"revolute": "revolute", "continuous": "revolute", "prismatic": "prismatic",
          "planar": "planar"}
JOINT_KINDS = ("revolute", "continuous", "prismatic", "fixed", "planar", "floating")
XACRO_NS = ("http://www.ros.org/wiki/xacro", "http://wiki.ros.org/xacro",
            "http://ros.org/wiki/xacro")
_SUBSTITUTION = re.compile(r"\$\{|\$\(")
_INERTIA = ("ixx", "ixy", "ixz", "iyy", "iyz", "izz")


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
    type: str  # one of JOINT_KINDS
    parent: str
    child: str
    xyz: np.ndarray = field(repr=False)
    rpy: np.ndarray = field(repr=False)
    axis: np.ndarray = field(repr=False)  # unit, in the joint frame (moving joints)
    damping: float = 0.0
    mimic: tuple | None = None  # (leader, multiplier, offset)
    limit: tuple = (0.0, 0.0)  # (lower, upper) of a prismatic joint as written, 0 where absent


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
    """The ``n`` numbers of attribute ``attr`` of ``el`` (``default`` where it is absent)."""
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
    if not all(in_range(v) for v in vals):
        raise CaseError(f"{attr}={text!r} is out of range: {RANGE_RULE}", file=path,
                        element=where)
    return np.array(vals)


def _number(el, attr, default, where, path):
    return float(_floats(el, attr, 1, [default], where, path)[0])


def _named(el, tag, seen, path):
    """(name, "tag 'name'") of a <link> or <joint>: named, and not twice."""
    name = el.get("name")
    if not name:
        after = f", after {tag} {list(seen)[-1]!r}" if seen else ""
        raise CaseError(f"a <{tag}> without a name (the {tag} number {len(seen) + 1} of the "
                        f"file{after})", file=path, element=tag)
    if name in seen:
        raise CaseError(f"duplicate {tag} name", file=path, element=f"{tag} {name!r}")
    return name, f"{tag} {name!r}"


def _xacro_error(path, what):
    return CaseError(f"the file still holds xacro markup ({what}): expand it first, e.g. "
                     f"`xacro {Path(path).name} > robot.urdf` (ROS's xacro, or `pip install "
                     f"xacro`), and read the expanded file", file=path)


def _xacro_markup(root):
    """What xacro markup an element tree still holds (a tag or a substitution), or None."""
    for el in root.iter():
        tag = el.tag if isinstance(el.tag, str) else ""
        ns = tag[1:].partition("}")[0] if tag.startswith("{") else ""
        if ns in XACRO_NS or tag.startswith("xacro:"):
            return f"<xacro:{tag.rpartition('}')[2]}>"
        for value in el.attrib.values():
            if _SUBSTITUTION.search(value):
                return f"the substitution {value!r}"
    return None


def _parse(path, p, referrer):
    try:
        data = path.read_bytes()
    except OSError as exc:
        reason = exc.strerror or str(exc)
        if referrer is not None:
            raise CaseError(f"{p}: cannot read URDF file: {reason}", file=str(referrer[0]),
                            element=referrer[1]) from None
        raise CaseError(f"cannot read URDF file: {reason}", file=p) from None
    try:
        root = ET.fromstring(data)
    except ET.ParseError as exc:
        if "unbound prefix" in str(exc) and b"<xacro:" in data:  # xacro: undeclared
            raise _xacro_error(p, "<xacro:...> elements") from None
        raise CaseError(f"malformed XML: {exc}", file=p) from None
    markup = _xacro_markup(root)
    if markup:
        raise _xacro_error(p, markup)
    if root.tag != "robot":
        raise CaseError(f"the root element must be <robot>, got <{root.tag}>", file=p)
    return root


def _link(el, where, p):
    inertial = el.find("inertial")
    if inertial is None:
        return 0.0, np.zeros(3), np.zeros(3), np.zeros((3, 3))
    m = inertial.find("mass")
    if m is None or m.get("value") is None:
        raise CaseError("<inertial> needs <mass value=...>", file=p, element=where)
    mass = _number(m, "value", 0.0, f"{where} <mass>", p)
    if mass < 0:
        raise CaseError(f"<mass value> must not be negative, got {mass:g}", file=p,
                        element=where)
    origin = inertial.find("origin")
    xyz = _floats(origin, "xyz", 3, [0, 0, 0], f"{where} <inertial><origin>", p)
    rpy = _floats(origin, "rpy", 3, [0, 0, 0], f"{where} <inertial><origin>", p)
    i = inertial.find("inertia")
    missing = [k for k in _INERTIA if i is None or i.get(k) is None]
    if missing:
        raise CaseError(f"<inertial> needs <inertia> with {', '.join(_INERTIA)} (missing "
                        f"{', '.join(missing)})", file=p, element=where)
    c = {k: _number(i, k, 0.0, f"{where} <inertia>", p) for k in _INERTIA}
    inertia = np.array([[c["ixx"], c["ixy"], c["ixz"]], [c["ixy"], c["iyy"], c["iyz"]],
                        [c["ixz"], c["iyz"], c["izz"]]])
    return mass, xyz, rpy, inertia


def unit(a):
    """a / |a| without overflow or underflow (a finite, not zero): scaled by its largest
    entry first."""
    a = np.asarray(a, float)
    a = a / np.max(np.abs(a))
    return a / math.hypot(*a)


def _joint(el, name, where, links, p):
    jtype = el.get("type")
    if jtype not in JOINT_KINDS:
        raise CaseError(f"unsupported joint type {jtype!r} ({', '.join(JOINT_KINDS)})", file=p,
                        element=where)
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
    axis = np.array([1.0, 0.0, 0.0])
    if jtype in MOVING:
        axis = _floats(el.find("axis"), "xyz", 3, [1, 0, 0], f"{where} <axis>", p)
        if not np.any(axis):
            raise CaseError(f"<axis xyz={el.find('axis').get('xyz')!r}> must not be zero", file=p,
                            element=where)
        axis = unit(axis)
    damping = _number(el.find("dynamics"), "damping", 0.0, f"{where} <dynamics>", p)
    if damping < 0:
        raise CaseError(f"<dynamics damping> must not be negative, got {damping:g}", file=p,
                        element=where)
    limit = (0.0, 0.0)
    if jtype == "prismatic":
        lim = el.find("limit")
        limit = (_number(lim, "lower", 0.0, f"{where} <limit>", p),
                 _number(lim, "upper", 0.0, f"{where} <limit>", p))
    mimic = None
    mel = el.find("mimic")
    if mel is not None and jtype in MOVING:
        leader = mel.get("joint")
        if not leader:
            raise CaseError("<mimic> needs joint=...", file=p, element=where)
        mimic = (leader, _number(mel, "multiplier", 1.0, f"{where} <mimic>", p),
                 _number(mel, "offset", 0.0, f"{where} <mimic>", p))
    return Joint(name, jtype, ends[0], ends[1], xyz, rpy, axis, damping, mimic, limit)


def read_urdf(path, *, referrer=None) -> UrdfRobot:
    """Parse a URDF file (module docstring); structural checks are in :func:`urdf_tables`.
    ``referrer`` = (case file, element) that names the URDF, if any: a URDF that cannot be
    opened is then reported against that case element, naming both files."""
    path = Path(path)
    p = str(path)
    root = _parse(path, p, referrer)
    links, joints = {}, {}
    for el in root.findall("link"):
        name, where = _named(el, "link", links, p)
        links[name] = Link(name, *_link(el, where, p))
    for el in root.findall("joint"):
        name, where = _named(el, "joint", joints, p)
        joints[name] = _joint(el, name, where, links, p)
    if not links:
        raise CaseError("the robot has no <link>", file=p)
    return UrdfRobot(root.get("name", path.stem), p, links, joints)


# ---------------------------------------------------------------------------------------------
# Geometry
# ---------------------------------------------------------------------------------------------
def rpy_matrix(rpy) -> np.ndarray:
    """URDF's fixed-axis roll, pitch, yaw: R = Rz(yaw) Ry(pitch) Rx(roll)."""
    r, p, y = rpy
    cr, sr, cp, sp, cy, sy = (math.cos(r), math.sin(r), math.cos(p), math.sin(p), math.cos(y),
                              math.sin(y))
    return np.array([[cy * cp, cy * sp * sr - sy * cr, cy * sp * cr + sy * sr],
                     [sy * cp, sy * sp * sr + cy * cr, sy * sp * cr - cy * sr],
                     [-sp, cp * sr, cp * cr]])


def axis_rotation(a, angle) -> np.ndarray:
    """Rotation by ``angle`` about the unit vector a (Rodrigues)."""
    K = np.array([[0.0, -a[2], a[1]], [a[2], 0.0, -a[0]], [-a[1], a[0], 0.0]])
    return np.eye(3) + math.sin(angle) * K + (1.0 - math.cos(angle)) * (K @ K)
