"""The reader entries of planar joints and forces (one per element type) and the inverse-statics
drivers: fields read, element classes of :mod:`mbseig.model` constructed, nothing solved."""

from __future__ import annotations

import numpy as np

from ..model.affine import Affine, combine
from ..model.driver import AngleDriver
from ..model.elements import (
    DistanceConstraint,
    FollowerForce,
    LinearConstraint,
    SpringDamper,
    TorsionalSpringDamper,
)
from .fields import REQUIRED, template


class ElementReaders:
    """Builder's methods of this module (a mixin: they use its state)."""

    def _driver_targets(self, names, f):
        """Elements named by a driver's ``sets``; names of disabled elements are skipped."""
        declared = self.declared_names()
        targets = []
        for nm in names:
            if nm in self.named:
                targets.append(self.named[nm])
            elif nm not in declared:
                raise f.error(f"sets unknown element {nm!r} (a named spring or distance joint)")
        return targets

    def declared_names(self):
        """Names of the case's joints and forces as written (enabled or not; strings only)."""
        return {item.get("name") for sec in ("joints", "forces")
                for item in (self.data.get(sec) if isinstance(self.data.get(sec), list) else [])
                if isinstance(item, dict) and isinstance(item.get("name"), str)}

    def add_constraint(self, constraints, c, f):
        if c.idx.size == 0:
            if np.any(np.abs(c.phi(self.q0)) > 1e-12 * c.scale()):
                raise f.error("constraint between fixed points cannot be satisfied")
            return
        constraints.append(c)

    # -- joints --------------------------------------------------------------------------
    def _joint(self, f, constraints):
        kind = f.text("type")
        f.text("name", None)  # names are for references (sets, report) and messages
        if kind == "distance":
            a, b = self.two_points(f)
            diff = b - a
            L = f.num("length", float(np.linalg.norm(diff(self.q0))), positive=True)
            f.done()
            self.add_constraint(constraints, DistanceConstraint(f.label, diff, L), f)
            self.record_ends(f.label, f, "points")
        elif kind == "fixed":
            p = self.point_ref(f, "point")
            target = f.vec("position", self.dim, p(self.q0))
            f.done()
            c = LinearConstraint(f.label, p, np.eye(self.dim), target, self.length_scale)
            self.add_constraint(constraints, c, f)
        elif kind in ("slider", "point_on_line"):
            if self.dim == 1:
                raise f.error("a slider needs dimension 2 or 3")
            p = self.point_ref(f, "point")
            origin = f.vec("origin", self.dim, p(self.q0))
            direction = f.vec("direction", self.dim)
            f.done()
            norm = np.linalg.norm(direction)
            if norm == 0:
                raise f.error("direction must not be zero")
            # rows: an orthonormal basis of the directions normal to the line
            G = normal_basis(direction / norm)
            c = LinearConstraint(f.label, p, G, G @ origin, self.length_scale)
            self.add_constraint(constraints, c, f)
        elif kind == "attach":
            if self.dim != 2:
                raise f.error("attach needs dimension = 2 (planar bodies)")
            p = self.point_ref(f, "point")
            body = self.body(f, f.text("body"))
            b = self.bodies[body]
            local = f.vec("local", 2, None)
            f.done()
            if local is None:
                local = local_coordinates(self, body, p(self.q0), f)
            diff = p - self.body_point(body, local)
            c = LinearConstraint(f.label, diff, np.eye(2), np.zeros(2), self.length_scale)
            self.element_body[f.label] = body
            self.add_constraint(constraints, c, f)
        elif kind == "angle_driver":
            self._angle_driver(f, constraints)
        else:
            raise f.error(
                f"unknown joint type {kind!r} (distance, fixed, slider, attach, angle_driver)")

    def _angle_driver(self, f, constraints):
        """Prescribed relative angle (driving constraint); with ``sets`` an inverse-statics
        command (see :mod:`mbseig.inverse_statics`), otherwise a permanent constraint."""
        if self.dim != 2:
            raise f.error("angle_driver needs dimension = 2")
        stacked, sense = self.angle_pair(f)
        angle = f.num("angle")
        sets = f.raw("sets", [])
        f.done()
        if isinstance(sets, str):
            sets = [sets]
        if not isinstance(sets, list) or not all(isinstance(x, str) for x in sets):
            raise f.error("sets must be an element name or a list of names")
        if stacked.idx.size == 0:
            raise f.error("angle_driver between two fixed directions")
        driver = AngleDriver(f.label, stacked, angle, sense)
        if sets:
            self.drivers.append((driver, sets, f))
        else:
            constraints.append(driver)

    def angle_pair(self, f):
        """Stacked directions [a; b] of ``bodies = [b1 or "ground", b2]`` and the sense (±1)."""
        bodies = f.raw("bodies")
        if not isinstance(bodies, list) or len(bodies) != 2:
            raise f.error("bodies must be [body1, body2]; use \"ground\" for the fixed frame")
        dirs = []
        for bname in bodies:
            bname = template(str(bname), f.names, f)
            if bname == "ground":
                dirs.append(Affine.constant(f.vec("ground_direction", 2, [1.0, 0.0])))
            else:
                dirs.append(self.body_dir(self.body(f, bname)))
        sense_txt = f.text("sense", "ccw")
        if sense_txt not in ("ccw", "cw"):
            raise f.error("sense must be 'ccw' or 'cw'")
        return combine([(1.0, dirs[0]), (1.0, dirs[1])], stack=True), (1.0 if sense_txt == "ccw" else -1.0)

    # -- forces --------------------------------------------------------------------------
    def _force(self, f, forces, g_const):
        kind = f.text("type")
        f.text("name", None)
        if kind in ("spring", "damper", "spring_damper"):
            a, b = self.two_points(f)
            diff = b - a
            d0 = diff(self.q0)
            init = float(d0[0]) if self.dim == 1 else float(np.linalg.norm(d0))
            k = f.num("stiffness", 0.0 if kind == "damper" else REQUIRED, nonnegative=True)
            # active = true: a controlled actuator whose force loop may inject energy, so its
            # damping may be negative (stability studies); passive elements must dissipate
            active = f.flag("active", False)
            c = f.num("damping", 0.0 if kind == "spring" else REQUIRED, nonnegative=not active)
            l0 = f.num("free_length", init)
            f.done()
            if self.dim > 1 and l0 < 0:
                raise f.error("free_length must not be negative")
            if diff.idx.size:
                forces.append(SpringDamper(f.label, diff, k, l0, c))
                self.record_ends(f.label, f, "points")
        elif kind == "torsional":
            if self.dim != 2:
                raise f.error("torsional springs need dimension = 2")
            stacked, sense = self.angle_pair(f)
            k = f.num("stiffness", 0.0, nonnegative=True)
            c = f.num("damping", 0.0, nonnegative=True)
            probe = TorsionalSpringDamper(f.label, stacked, k, c, 0.0, sense)
            a0 = f.num("angle0", probe.angle(self.q0) if stacked.idx.size else 0.0)
            f.done()
            if stacked.idx.size:
                forces.append(TorsionalSpringDamper(f.label, stacked, k, c, a0, sense))
                self.record_bodies(f.label, f)
        elif kind == "force":
            p = self.point_ref(f, "point")
            vec = f.vec("vector", self.dim)
            f.done()
            np.add.at(g_const, p.idx, p.C.T @ vec)
            if isinstance(f.t.get("name"), str):
                self.point_forces[f.t["name"]] = (p, vec, f.label)
        elif kind == "follower":
            if self.dim != 2:
                raise f.error("follower forces need dimension = 2")
            body = self.body(f, f.text("body"))
            at = f.vec("at", 2)
            direction = f.vec("direction", 2)
            mag = f.num("magnitude")
            f.done()
            nd = np.linalg.norm(direction)
            if nd == 0:
                raise f.error("direction must not be zero")
            p = self.body_point(body, at)
            u = self.body_dir(body, direction / nd)
            self.element_body[f.label] = body
            forces.append(FollowerForce(f.label, combine([(1.0, p), (1.0, u)], stack=True), mag))
        else:
            raise f.error(
                f"unknown force type {kind!r} (spring, damper, spring_damper, torsional, force, follower)"
            )


def normal_basis(u):
    """Rows spanning the orthogonal complement of the unit vector u."""
    _, _, vt = np.linalg.svd(u[None, :])
    return vt[1:]


def local_coordinates(builder, body, r, f):
    b = builder.bodies[body]
    pi, pj = b["points"]
    ri, rj = builder.point_pos[pi], builder.point_pos[pj]
    L = np.linalg.norm(rj - ri)
    if L == 0:
        raise f.error(f"give local: the basic points of body {body!r} coincide in the case, so "
                      "the point's local coordinates are undefined")
    e = (rj - ri) / L
    n = np.array([-e[1], e[0]])
    return np.array([(r - ri) @ e, (r - ri) @ n]) * (b["length"] / L)
