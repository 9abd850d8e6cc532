"""The reader entries of spatial joints and forces (DESIGN §8, 3-D case format): spherical,
revolute, universal, cylindrical, prismatic, weld, point_on_line, point_on_plane, the angle
driver; point forces, torques, torsional springs, bushings and rotors."""

from __future__ import annotations

import numpy as np

from ..model.affine import Affine, combine
from ..model.spatial_body import (
    FRAME_SIZE,
    GROUND,
    frame_point,
    frame_vector,
    point_matrices,
)
from ..model.spatial_forces import (
    BodyMoment,
    PointFollowerForce,
    QuadraticSpringDamper,
    Rotor,
    SpatialTorsional,
    bushing_maps,
    bushing_rows,
)
from ..model.spatial_joints import (
    JOINT_ROWS,
    QuadraticConstraint,
    SpatialAngleDriver,
    angle_rows,
    joint_rows,
)
from .batch import repeated_fields
from .fields import REQUIRED, TIME, Fields, uses_time

UNIT_TOL = 1e-9  # |‖axis‖ − 1| allowed, and the tolerance of perpendicular / coincident axes
FORCE_TYPES = ("spring", "damper", "spring_damper", "force", "torque", "torsional", "bushing",
               "rotor")
JOINT_TYPES = (*JOINT_ROWS, "distance", "fixed", "slider", "angle_driver", "rolling", "contact",
               "mimic")
AXIS_KEY = {"revolute": "axis", "cylindrical": "axis", "prismatic": "axis",
             "point_on_line": "axis", "point_on_plane": "normal", "planar": "normal"}


class SpatialElementReaders:
    """SpatialBuilder's methods of this module (a mixin: they use its state)."""

    # -- joints ------------------------------------------------------------------------------
    def _joint(self, f, constraints):
        kind = f.raw("type", None)
        if not isinstance(kind, str):
            raise f.error(f"type must be a string, got {kind!r}")
        if kind in JOINT_ROWS and (kind != "point_on_line" or f.has("bodies")):
            self._spatial_joint(f, kind, constraints)
        elif kind == "angle_driver":
            self._angle_driver3(f, constraints)
        elif kind in ("distance", "fixed", "slider", "point_on_line"):
            self.bind()
            super()._joint(f, constraints)
        elif kind == "mimic":  # a coupled joint of a robot description (casefile.urdf)
            from .urdf import read_mimic

            self.bind()
            read_mimic(self, f, constraints)
        elif kind in ("rolling", "contact"):  # DESIGN §8, steady motions and contact
            from .motion_readers import read_motion_joint

            self.bind()
            read_motion_joint(self, f, kind, constraints)
        else:
            raise f.error(f"unknown joint type {kind!r} ({', '.join(JOINT_TYPES)})")

    def _spatial_joint(self, f, kind, constraints):
        f.text("type")
        name = f.text("name", None)
        b1, b2 = self._two_bodies(f)
        at = f.vec("at", 3)
        if kind == "universal":
            axes = f.raw("axes")
            if not isinstance(axes, list) or len(axes) != 2:
                raise f.error("axes must be [axis in body1, axis in body2]")
            axes = tuple(self._unit(f, f"axes[{k}]", Fields({"a": a}, f.label, f.names).vec("a", 3))
                         for k, a in enumerate(axes))
            if abs(axes[0] @ axes[1]) > UNIT_TOL:
                raise f.error(f"the axes of a universal joint must be perpendicular, got "
                              f"axes[0]·axes[1] = {axes[0] @ axes[1]:.6g}")
        elif kind in AXIS_KEY:
            axes = (self._unit(f, AXIS_KEY[kind]),)
        else:
            axes = ()
        f.done()
        frames = (self.frame(f, b1), self.frame(f, b2))
        locals_ = (self.local(b1, self._material(f, b1, b2, at)),
                   self.local(b2, self._material(f, b2, b1, at)))
        rows = joint_rows(kind, frames, locals_, axes, self.length_scale)
        on = (FRAME_SIZE, locals_[1], b2) if b2 != "ground" else (0, locals_[0], b1)
        self._coincident_axes(f, kind, b1, b2, at, axes)
        self.add_constraint(constraints, QuadraticConstraint(f.label, rows, 1.0, on), f)
        for b, fr, loc in zip((b1, b2), frames, locals_, strict=True):
            self._station(b, f.label, frame_point(fr, loc))
        if name is not None:
            self.spatial_joints[name] = (kind, b1, b2, at, axes[0] if axes else None, f.label)

    def _material(self, f, body, other, at):
        """Where the joint sits on ``body``: ``at``, except in a periodic case whose ``at``
        moves with t (DESIGN §8, "Periodic motions"), read as a pivot driven on the ground: the
        ground's point follows at(t), the body's is the material point at the reference
        position at(0) (a joint that moved along the body with its pivot would drive nothing).
        Between two bodies a moving ``at`` has no such reading and is refused, as is a moving
        axis."""
        if not (self.periodic and uses_time(f.t.get("at"))):
            for key in ("axis", "axes", "normal"):
                if self.periodic and uses_time(f.t.get(key)):
                    raise f.error(f"{key} uses t: a joint's axis cannot move with time (drive "
                                  f"a body with an angle_driver instead)")
            return at
        if "ground" not in (body, other):
            raise f.error("at uses t, but a joint between two bodies has no ground to drive "
                          "it: hold a body's point on the moving position with a fixed joint "
                          "(point, position with t) instead")
        if body == "ground":
            return at
        return Fields({"at": f.t["at"]}, f.label, {**f.names, TIME: 0.0}).vec("at", 3)

    def _coincident_axes(self, f, kind, b1, b2, at, axes):
        """Two revolute or cylindrical joints between the same bodies must share their axis."""
        if kind not in ("revolute", "cylindrical"):
            return
        for okind, o1, o2, oat, oaxis, olabel in self.spatial_joints.values():
            if okind in ("revolute", "cylindrical") and {o1, o2} == {b1, b2}:
                apart = np.linalg.norm(np.cross(oat - at, axes[0])) / self.length_scale
                if np.linalg.norm(np.cross(oaxis, axes[0])) > UNIT_TOL or apart > UNIT_TOL:
                    raise f.error(f"its axis does not coincide with that of {olabel} between "
                                  f"the same bodies (the pair would be locked)")

    def _revolute(self, f):
        """(frames, axis) of the revolute or cylindrical joint named by ``joint``."""
        jname = f.text("joint")
        j = self.spatial_joints.get(jname)
        if j is None or j[0] not in ("revolute", "cylindrical"):
            raise f.error(f"joint {jname!r} is not a revolute or cylindrical joint declared before")
        return (self.frame(f, j[1]), self.frame(f, j[2])), j[4]

    def _angle_driver3(self, f, constraints):
        """A prescribed angle about a revolute axis; with ``sets`` an inverse-statics command."""
        f.text("type")
        f.text("name", None)
        frames, axis = self._revolute(f)
        rows = angle_rows(frames, axis)
        driver = SpatialAngleDriver(f.label, rows.aff, f.num("angle"), 1.0, rows=rows)
        sets = name_list(f, f.raw("sets", []))
        f.done()
        if sets:
            self.drivers.append((driver, sets, f))
        else:
            constraints.append(driver)

    # -- forces ------------------------------------------------------------------------------
    def _force(self, f, forces, g_const):
        self.bind()
        kind = f.raw("type", None)
        if not isinstance(kind, str):
            raise f.error(f"type must be a string, got {kind!r}")
        if kind in ("spring", "damper", "spring_damper"):
            return super()._force(f, forces, g_const)
        if kind not in FORCE_TYPES:
            raise f.error(f"unknown force type {kind!r} ({', '.join(FORCE_TYPES)})")
        f.text("type")
        f.text("name", None)
        read = {"force": self._point_force, "torque": self._torque, "torsional": self._torsional,
                "bushing": self._bushing, "rotor": self._rotor}[kind]
        read(f, forces, g_const)

    def _point_force(self, f, forces, g_const):
        p, body = self._point_and_body(f, "point")
        vec = f.vec("vector", 3)
        follower = f.flag("follower", False)
        f.done()
        if not follower:
            np.add.at(g_const, p.idx, p.C.T @ vec)
            if isinstance(f.t.get("name"), str):
                self.point_forces[f.t["name"]] = (p, vec, f.label)
            return
        if body is None:
            raise f.error("a follower force needs a point on a body ({body, at} or a point the "
                          "body carries)")
        F = frame_vector(self.frames[body], vec)
        forces.append(PointFollowerForce(f.label, combine([(1.0, p), (1.0, F)], stack=True)))

    def _torque(self, f, forces, g_const):
        body = self.body(f, f.text("body"))
        vec = f.vec("vector", 3)
        follower = f.flag("follower", False)
        f.done()
        frame = self.frames[body]
        T = frame_vector(frame, vec) if follower else Affine.constant(vec)
        forces.append(BodyMoment(f.label, combine([(1.0, frame), (1.0, T)], stack=True)))

    def _torsional(self, f, forces, g_const):
        frames, axis = self._revolute(f)
        k = f.num("stiffness", 0.0, nonnegative=True)
        c = f.num("damping", 0.0, nonnegative=True)
        a0 = f.num("angle0", 0.0)
        f.done()
        rows = angle_rows(frames, axis)
        if rows.aff.idx.size:
            forces.append(SpatialTorsional(f.label, rows.aff, k, c, a0, 1.0, rows=rows))

    def _bushing(self, f, forces, g_const):
        b1, b2 = self._two_bodies(f)
        at = f.vec("at", 3)
        K = self._coefficients(f, "stiffness", REQUIRED)
        D = self._coefficients(f, "damping")
        f.done()
        if not (np.all(np.isfinite(K)) and np.all(np.isfinite(D))):
            raise f.error("stiffness and damping must be finite")
        self._add_bushing(f.label, (self.frame(f, b1), self.frame(f, b2)), (b1, b2), at, K, D,
                          forces)

    def _add_bushing(self, label, frames, bodies, at, K, D, forces):
        locals_ = (self.local(bodies[0], at), self.local(bodies[1], at))
        ends = []
        for b, fr, loc in zip(bodies, frames, locals_, strict=True):
            ends.append((b, frame_point(fr, loc), b in self.station_origin and not np.any(loc)))
            self._station(b, label, ends[-1][1])
        forces.append(QuadraticSpringDamper(label, bushing_rows(frames, locals_), K, D))
        self.pending_ends[label] = ends  # drawn between its point on b1 and on b2

    def bushings(self, item, label, var, ivals, params, forces):
        """Repeated bushings between bodies, ``at`` given, diagonal stiffness and damping: read
        for all index values at once (:func:`~mbseig.casefile.batch.repeated_fields`) and added
        as the member-by-member reader adds them; False (declined: that reader then reads them
        and reports any problem) for anything else."""
        got = repeated_fields(item, {"type": None, "bodies": "names", "at": 3, "stiffness": 6,
                                     "damping": 6}, var, ivals, params, optional=("damping",))
        if got is None or len(got["bodies"]) != 2:
            return False
        self.bind()
        pairs, known = list(zip(*got["bodies"], strict=True)), {*self.frames, "ground"}
        if any(a == b or a not in known or b not in known for a, b in pairs):
            return False  # an unknown body, the same twice: the member reader names it
        at, K, D = got["at"], got["stiffness"], got.get("damping")
        loc = [np.array([self.local(b, x) for b, x in zip(col, at, strict=True)])
               for col in got["bodies"]]
        frames = [[GROUND if b == "ground" else self.frames[b] for b in col]
                  for col in got["bodies"]]
        P = [point_matrices(x) for x in loc]
        stacks = [combine([(1.0, f0), (1.0, f1)], stack=True)
                  for f0, f1 in zip(*frames, strict=True)]
        maps = bushing_maps(stacks, loc[0], loc[1])
        for k, (b1, b2) in enumerate(pairs):
            label_k, ends = f"{label} ({var}={int(ivals[k])})", []
            for e, b in enumerate((b1, b2)):
                fr = frames[e][k]
                point = Affine(fr.idx, P[e][k] @ fr.C, P[e][k] @ fr.d)
                ends.append((b, point, b in self.station_origin and not np.any(loc[e][k])))
                self._station(b, label_k, point)
            forces.append(QuadraticSpringDamper(label_k, maps[k], np.diag(K[k]),
                                                np.zeros((6, 6)) if D is None else np.diag(D[k])))
            self.pending_ends[label_k] = ends
        return True

    def _coefficients(self, f, key, default=None):
        """A bushing's 6×6 stiffness or damping: 6 numbers, a 6×6 matrix, or a table over a
        parameter ``{parameter, at, values}`` interpolated at its value (casefile.tables)."""
        if isinstance(f.t.get(key), dict):
            from .tables import interpolated_matrix

            return interpolated_matrix(self, f, key, 6)
        return self._matrix(f, key, 6, default)

    def _rotor(self, f, forces, g_const):
        body = self.body(f, f.text("body"))
        axis = self._unit(f, "axis")
        jp = f.num("polar_inertia", positive=True)
        speed = f.num("speed")
        f.done()
        forces.append(Rotor(f.label, self.frames[body], axis, jp, speed, body=body))


def name_list(f, value):
    """An element name or a list of names (``sets``)."""
    names = [value] if isinstance(value, str) else value
    if not isinstance(names, list) or not all(isinstance(x, str) for x in names):
        raise f.error("sets must be an element name or a list of names")
    return names
