"""The kinematic tree of a URDF robot and its rigid groups, as Pinocchio builds them
(``pin.buildModelFromUrdf``): every link on a ``fixed`` joint is merged into its parent, so a
body is a link moved by a joint (or the root) with every link fixed to it, its mass, centre of
mass and inertia the sums of theirs.

- :func:`tree`: one root, one parent per link, no loop; the joints in breadth-first order.
- :func:`kinematics`: link and joint frames at the reference (child = parent · origin(xyz,
  rpy) · motion(q); motion a rotation by q about the axis, or a translation by q along it; a
  ``planar`` or ``floating`` joint at its zero).
- :func:`groups`: the rigid groups with their merged inertias, in global axes at the reference:

      m = Σ mᵢ,  c = Σ mᵢ cᵢ / m,  I = Σ [Rᵢ Īᵢ Rᵢᵀ + mᵢ (|dᵢ|² E − dᵢ dᵢᵀ)],  dᵢ = cᵢ − c

  (parallel-axis theorem; cᵢ = link origin + R_link·xyz of ``<inertial><origin>``, Rᵢ = R_link ·
  R(rpy of the inertial origin), Īᵢ the tensor of ``<inertia>``).  Only the merged inertia of a
  body must be a rigid body's (positive definite, triangle inequality): a link's own may be
  zero, as the point masses on fixed joints that many robots carry.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from ..model.spatial_body import inertia_problem
from .urdf_read import UrdfRobot, axis_rotation, rpy_matrix

__all__ = ["Group", "tree", "kinematics", "groups"]


@dataclass(frozen=True)
class Group:
    """A rigid group of links: ``top`` (the root, or the child of a moving joint) and every link
    fixed to it (``links``, top first, depth-first in document order).  ``body`` names the
    body: the top link if it has mass, else the first link of the group with mass (None: no
    mass at all)."""

    top: str
    links: tuple
    body: str | None
    mass: float
    com: np.ndarray = field(repr=False)
    inertia: np.ndarray = field(repr=False)
    scale: float = 0.0  # Σ of the magnitudes summed into the inertia (its rounding's scale)


def tree(robot: UrdfRobot):
    """(root, joints in breadth-first order from the root, {link: [child joints]}): one root,
    one parent per link, no loop."""
    parent_joint = {}
    for j in robot.joints.values():
        if j.child in parent_joint:
            raise robot.error(f"joint {j.name!r}", f"link {j.child!r} has two parents (joints "
                              f"{parent_joint[j.child]!r} and {j.name!r}): kinematic loops are "
                              f"not supported")
        if j.child == j.parent:
            raise robot.error(f"joint {j.name!r}", "parent and child are the same link")
        parent_joint[j.child] = j.name
    roots = [n for n in robot.links if n not in parent_joint]
    if not roots:
        raise robot.error("robot", "no root link: the joints form a kinematic loop")
    children: dict[str, list] = {}
    for j in robot.joints.values():
        children.setdefault(j.parent, []).append(j)
    order, queue, seen = [], [roots[0]], {roots[0]}
    while queue:
        link = queue.pop(0)
        for j in children.get(link, []):
            order.append(j)
            seen.add(j.child)
            queue.append(j.child)
    if len(roots) > 1:
        raise robot.error(f"link {roots[1]!r}", f"the robot has several root links "
                          f"({', '.join(map(repr, roots))}): links must form one tree")
    unreached = [n for n in robot.links if n not in seen]
    if unreached:  # one root, but a cycle not reachable from it
        raise robot.error(f"joint {parent_joint[unreached[0]]!r}",
                          "it closes a kinematic loop (not supported)")
    return roots[0], order, children


def kinematics(root, order, q):
    """({link: (R, p)}, {joint: (R, p)}) at the reference (module docstring)."""
    frames = {root: (np.eye(3), np.zeros(3))}
    jframes = {}
    for j in order:
        Rp, pp = frames[j.parent]
        Rj, pj = Rp @ rpy_matrix(j.rpy), pp + Rp @ j.xyz
        jframes[j.name] = (Rj, pj)
        if j.type in ("revolute", "continuous"):
            frames[j.child] = (Rj @ axis_rotation(j.axis, q[j.name]), pj)
        elif j.type == "prismatic":
            frames[j.child] = (Rj, pj + Rj @ j.axis * q[j.name])
        else:
            frames[j.child] = (Rj, pj)
    return frames, jframes


def _members(children, top):
    """The links fixed to ``top`` (itself first), depth-first in document order."""
    out = [top]
    for j in children.get(top, []):
        if j.type == "fixed":
            out += _members(children, j.child)
    return out


def groups(robot: UrdfRobot, root, order, children, frames) -> dict:
    """{top link: :class:`Group`} of the root and of every child of a moving joint."""
    tops = [root] + [j.child for j in order if j.type != "fixed"]
    out = {}
    with np.errstate(all="ignore"):  # numbers are in range (urdf_read): sums stay finite
        for top in tops:
            links = tuple(_members(children, top))
            massive = [n for n in links if robot.links[n].mass > 0]
            m = float(sum(robot.links[n].mass for n in massive))
            com, inertia, scale = np.zeros(3), np.zeros((3, 3)), 0.0
            parts = []
            for n in massive:
                link, (R, p) = robot.links[n], frames[n]
                Ri = R @ rpy_matrix(link.rpy)
                parts.append((link.mass, p + R @ link.xyz, Ri @ link.inertia @ Ri.T))
            if len(parts) == 1:  # one link: its own centre and inertia, exactly
                _, com, inertia = parts[0]
                scale = float(np.max(np.abs(inertia)))
            elif parts:
                com = sum(mi * ci for mi, ci, _ in parts) / m
                for mi, ci, Ii in parts:
                    d = ci - com
                    inertia = inertia + Ii + mi * (float(d @ d) * np.eye(3) - np.outer(d, d))
                    r = float(np.linalg.norm(d))  # d carries the rounding of ci and com
                    scale += float(np.max(np.abs(Ii))) + 2.0 * mi * r * (
                        r + float(np.linalg.norm(ci)) + float(np.linalg.norm(com)))
            inertia = 0.5 * (inertia + inertia.T)
            out[top] = Group(top, links, massive[0] if massive else None, m, com, inertia, scale)
    return out


def group_problem(robot: UrdfRobot, g: Group):
    """A CaseError when a body's merged inertia is not a rigid body's, naming the body and the
    links merged into it; None when it is.  A principal moment within the rounding of the
    merged sum is zero (two point masses on a line have no inertia about it, whatever sign the
    rounding leaves): (10 + L)·u·scale for L links with mass, a bound on the rounding of each
    term (R Ī Rᵀ, m(|d|² E − d dᵀ) with d's own rounding, below 10 u of its part of
    Group.scale) and of the L − 1 additions."""
    problem = inertia_problem(g.inertia)
    p = np.linalg.eigvalsh(g.inertia)
    n = sum(1 for x in g.links if robot.links[x].mass > 0)
    bound = (10 + n) * np.finfo(float).eps * g.scale if n > 1 else 0.0
    if problem is None and p[0] <= bound:
        problem = (f"inertia tensor must be positive definite (principal moments "
                   f"{', '.join(f'{x:.6g}' for x in p)}, the smallest zero within the rounding "
                   f"of the merged sum, {bound:.2g})")
    if problem is None:
        return None
    massive = [n for n in g.links if robot.links[n].mass > 0]
    if len(massive) == 1:
        return robot.error(f"link {g.body!r} <inertia>", problem)
    merged = ", ".join(repr(n) for n in g.links if n != g.body)
    return robot.error(f"link {g.body!r}", f"its inertia merged with the links fixed to it "
                       f"({merged}): {problem}")
