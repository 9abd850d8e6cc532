"""The reader entries of planar joints and forces (one per element type) and the inverse-statics
drivers: fields read, element classes of :mod:`mbseig.model` constructed, nothing solved; and
:class:`ScalarUpdate`, the model along a parameter that enters only force scalars (sweeps)."""

from __future__ import annotations

import dataclasses
import re

import numpy as np

from ..errors import MbseigError
from ..model.affine import Affine, combine
from ..model.driver import AngleDriver
from ..model.elements import (
    DistanceConstraint,
    FollowerForce,
    LinearConstraint,
    SpringDamper,
    TorsionalSpringDamper,
)
from .expr import evaluate
from .fields import REQUIRED, Fields, square_matrix, template


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
        return (combine([(1.0, dirs[0]), (1.0, dirs[1])], stack=True),
                (1.0 if sense_txt == "ccw" else -1.0))

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
                f"unknown force type {kind!r} (spring, damper, spring_damper, torsional, force, "
                "follower)"
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


# The scalar fields of force elements that a sweep may change without a rebuild
# (:class:`mbseig.casefile.builder.ScalarUpdate`): case field → element attribute, per type.
LEAN_FIELDS = {
    "spring": {"stiffness": "stiffness", "damping": "damping"},
    "damper": {"stiffness": "stiffness", "damping": "damping"},
    "spring_damper": {"stiffness": "stiffness", "damping": "damping"},
    "torsional": {"stiffness": "stiffness", "damping": "damping"},
    "follower": {"magnitude": "magnitude"},
}


def force_scalar(f, kind, key):
    """One scalar field of a force element read exactly as :meth:`ElementReaders._force` reads
    it (same default, same range checks and messages); ``key`` is a field of LEAN_FIELDS."""
    if kind in ("spring", "damper", "spring_damper"):
        if key == "stiffness":
            return f.num("stiffness", 0.0 if kind == "damper" else REQUIRED, nonnegative=True)
        return f.num("damping", 0.0 if kind == "spring" else REQUIRED,
                     nonnegative=not f.flag("active", False))
    if kind == "torsional":
        return f.num(key, 0.0, nonnegative=True)
    return f.num("magnitude")


# ---------------------------------------------------------------------------------------------
_NAME = re.compile(r"[A-Za-z_][A-Za-z0-9_]*")
_NOT_MODEL = {"parameters", "configurations", "title", "description", "source", "expected",
              "schema_version", "kind"}  # read, but not evaluated into the model's elements


class ScalarUpdate:
    """The model of a planar case along one parameter that enters only the scalar fields of
    force elements (LEAN_FIELDS: a spring constant, a damping value, a follower load's
    magnitude): the elements of one full build at a reference value, those fields re-read at
    each value (with the reader's own checks).  Equal, element by element, to a full build.

    :meth:`make` returns None (build the case instead) where the parameter, or a parameter
    computed from it, appears anywhere else in the case (geometry, masses, gravity, joints,
    repeated elements, the ``[report]`` table): ``reason`` then says where.

    ``axis`` may also be a tuple of parameter names, moved together (the samples of
    ``mbseig uncertainty``): ``p`` is then a tuple of their values, in that order.
    """

    def __init__(self, data, config, overrides, axis, model0):
        self._parameters(data, config, overrides, axis, model0)
        if data.get("dimension") not in (1, 2) or data.get("kind", "multibody") != "multibody" \
                or not self._known():
            self.reason = "not a planar multibody case"
            return
        names = {f.name for f in model0.forces}
        index = {f.name: k for k, f in enumerate(model0.forces)}
        for k, item in enumerate(data.get("forces") or []):
            kind = item.get("type") if isinstance(item, dict) else None
            keys = [key for key in LEAN_FIELDS.get(kind, ())
                    if isinstance(item.get(key), str) and self._uses(item[key])]
            if not keys:
                continue
            label = f"forces[{k}]" + (f" {item['name']!r}" if isinstance(item.get("name"), str)
                                      else "")
            if "repeat" in item or label not in names or len(index) != len(model0.forces):
                self.reason = f"{label} is repeated or not one element"
                return
            self.updates.append((index[label], item, label, kind, keys))
        where = self._elsewhere(data, "")
        if where is not None:
            self.reason = f"{self.label} enters {where}"
        elif self.parameters(self._at(model0.parameters), every=True) != model0.parameters:
            self.reason = "the parameters evaluate differently"  # a safeguard: never seen

    def _parameters(self, data, config, overrides, axis, model0):
        """The parameter table at the reference (the case's, the configuration's, the fixed
        overrides) and the parameters computed from the swept one (re-evaluated, in order)."""
        self.data, self.axis, self.model0, self.reason = data, axis, model0, None
        self.axes = tuple(axis) if isinstance(axis, tuple) else (axis,)
        self.label = ", ".join(self.axes)
        self.raw = dict(data.get("parameters", {}))
        chosen = dict((data.get("configurations") or {}).get(config, {})) if config else {}
        chosen.pop("description", None)
        self.raw.update(chosen)
        self.raw.update({k: v for k, v in overrides.items() if k not in self.axes})
        deps = set(self.axes)
        for key, value in self.raw.items():  # parameters computed from the swept one
            if isinstance(value, str) and deps & set(_NAME.findall(value)):
                deps.add(key)
        self.deps, self.updates = deps, []
        self.order = [key for key in self.raw if key in deps]  # re-evaluated, in table order

    def _known(self) -> bool:
        """Every swept parameter is one of the table's."""
        return all(a in self.raw for a in self.axes)

    def _at(self, values):
        """The swept parameters' value(s) in ``values`` (a dict), as :meth:`parameters` takes
        them."""
        got = tuple(values[a] for a in self.axes)
        return got if isinstance(self.axis, tuple) else got[0]

    def _point(self, p) -> dict:
        """{name: value} of the swept parameter(s) at ``p``."""
        if isinstance(self.axis, tuple):
            return {a: float(v) for a, v in zip(self.axes, p, strict=True)}
        return {self.axis: float(p)}

    def _uses(self, text):
        return bool(self.deps & set(_NAME.findall(text)))

    def _elsewhere(self, node, path):
        """The first place outside LEAN_FIELDS whose expression uses the swept parameter."""
        return self._first_use(node, path, lean=True)

    def _anywhere(self, node, path):
        """The first place under ``node`` whose expression uses the swept parameter (every
        field: for the updates that re-read no force scalar)."""
        return self._first_use(node, path, lean=False)

    def _first_use(self, node, path, lean):
        """The first place under ``node`` (at ``path``) whose expression uses the swept
        parameter; with ``lean`` the force scalars re-read at each value are left out."""
        if isinstance(node, str):
            return path if self._uses(node) else None
        if isinstance(node, dict):
            for key, value in node.items():
                sub = f"{path}.{key}" if path else key
                if (not path and key in _NOT_MODEL) or sub == "report.studies":
                    continue  # not evaluated into the model, or study definitions
                if lean and path.startswith("forces[") and path.count(".") == 0 and \
                        key in LEAN_FIELDS.get(node.get("type"), ()) and "repeat" not in node:
                    continue  # re-read at each value
                hit = self._first_use(value, sub, lean)
                if hit is not None:
                    return hit
        elif isinstance(node, list):
            for k, value in enumerate(node):
                hit = self._first_use(value, f"{path}[{k}]", lean)
                if hit is not None:
                    return hit
        return None

    def parameters(self, p, *, every=False):
        """The ``[parameters]`` values at axis = p, as the case reader evaluates them (in the
        table's order); only those computed from the swept one are evaluated again unless
        ``every`` (the others keep the reference build's values, which they equal)."""
        point = self._point(p)
        if every:
            values = {}
            for key, value in {**self.raw, **point}.items():
                values[key] = evaluate(value, values)
            return values
        values = dict(self.model0.parameters)
        for key in self.order:
            values[key] = evaluate(point[key] if key in point else self.raw[key], values)
        return values

    def make(self, p):
        """The model at axis = p, or None where a full build is needed."""
        if self.reason is not None:
            return None
        params = self.parameters(p)
        forces = list(self.model0.forces)
        for k, item, label, kind, keys in self.updates:
            f = Fields(item, label, params)
            forces[k] = dataclasses.replace(forces[k], **{
                LEAN_FIELDS[kind][key]: force_scalar(f, kind, key) for key in keys})
        return dataclasses.replace(self.model0, forces=tuple(forces), parameters=params)


class MotionUpdate(ScalarUpdate):
    """The model of a steady-motion case along one parameter that enters only its ``[motion]``
    table (the speed, a yaw rate): the model of one full build serves every value, and the
    motion is read again at each value (:func:`~mbseig.casefile.motion_readers.read_motion`,
    with its checks).  ``reason`` says where else the parameter, or a parameter computed from
    it, appears (then every value is built)."""

    def __init__(self, data, config, overrides, axis, model0):
        self._parameters(data, config, overrides, axis, model0)
        self._motion = None  # (the first value's motion and its fields read again, kept)
        if not self._known():
            self.reason = f"{self.label} is not a parameter of the case"
            return
        if not isinstance(data.get("motion"), dict):
            self.reason = "no [motion] table"
            return
        where = self._anywhere({k: v for k, v in data.items() if k != "motion"}, "")
        if where is not None:
            self.reason = f"{self.label} enters {where}"

    def make(self, p):
        """The one model (with the parameters at axis = p), or None where a build is needed."""
        if self.reason is not None:
            return None
        return dataclasses.replace(self.model0, parameters=self.parameters(p))

    def motion(self, p, *, file=None):
        """The ``[motion]`` at axis = p: :func:`~mbseig.casefile.motion_readers.read_motion` at
        the first value; at the others its scalar fields that use the swept parameter (speed,
        yaw rate) evaluated again, where direction and gravity do not use it.  A value that is
        not a finite number in range takes :func:`read_motion` itself (its error)."""
        from .fields import in_range
        from .motion_readers import read_motion

        params = self.parameters(p)
        ref = self._motion
        if ref is None:
            m = read_motion(self.data, params, file=file)
            table = self.data["motion"]
            keys = [k for k, v in table.items() if isinstance(v, str) and self._uses(v)]
            lean = set(keys) <= {"speed", "yaw_rate"} and not self._anywhere(
                self.data.get("gravity"), "gravity")
            self._motion = (m, keys if lean else None)
            return m
        m, keys = ref
        if keys is None:
            return read_motion(self.data, params, file=file)
        table = self.data["motion"]
        try:
            values = {k: evaluate(table[k], params) for k in keys}
        except MbseigError:
            return read_motion(self.data, params, file=file)
        if not all(isinstance(x, float) and in_range(x) for x in values.values()):
            return read_motion(self.data, params, file=file)
        return dataclasses.replace(m, **{k: float(x) for k, x in values.items()})


class MassUpdate(ScalarUpdate):
    """The model of a spatial case along one parameter that enters only the masses and inertias
    of (non-repeated) bodies: the elements, coordinates and constraints of one full build, the
    mass matrix and the gravity load formed again at each value from the bodies' parts, in the
    build's order (so equal to a build bit for bit: checked on the reference build itself), the
    fields re-read with the reader's own checks.

    ``reason`` says why not where the parameter, or one computed from it, appears elsewhere (a
    length, a centre of mass, a point, a joint, a force), where a body is repeated, or where the
    model holds masses or loads that are not the bodies' own (point masses, rotors, wheels,
    flexible bodies, constant forces) or named inputs and outputs (an inertial input load
    would move with a mass): then every value is built."""

    def __init__(self, data, config, overrides, axis, model0):
        self._parameters(data, config, overrides, axis, model0)
        grav = data.get("gravity")
        self.gravity = (None if grav is None else
                        Fields({"gravity": grav}, "gravity", model0.parameters).vec("gravity", 3))
        self._parts = self._plan = None  # (the reference's, kept by its first assembly)
        self.reason = self._check(data, model0)

    def _check(self, data, model0):
        from ..model.rolling import WheelRows
        from ..model.spatial_forces import Rotor

        if data.get("dimension") != 3 or data.get("kind", "multibody") != "multibody" \
                or not self._known():
            return "not a spatial multibody case"
        if "frames" in data or model0.mass_elements or model0.flexible \
                or model0.velocity_constraints or model0.commands \
                or model0.inputs or model0.outputs \
                or any(isinstance(f, Rotor) for f in model0.forces) \
                or any(isinstance(c, WheelRows) for c in model0.constraints):
            return "a model with more than rigid bodies' masses"
        bodies = data.get("bodies") or []
        where = None
        for k, item in enumerate(bodies):
            if not isinstance(item, dict):
                continue
            keys = [key for key in ("mass", "inertia") if self._anywhere(item.get(key), key)]
            name = item.get("name")
            if keys and ("repeat" in item or not isinstance(name, str)
                         or name not in model0.bodies):
                return f"bodies[{k}] is repeated or not one body"
            if keys:
                label = f"bodies[{k}] {name!r}"
                self.updates.append((name, item, label, keys))
            rest = {key: v for key, v in item.items() if key not in ("mass", "inertia")}
            where = where or self._anywhere(rest, f"bodies[{k}]")
        where = where or self._anywhere({k: v for k, v in data.items() if k != "bodies"}, "")
        if where is not None:
            return f"{self.label} enters {where}"
        if not self.updates:
            return f"{self.label} enters no body's mass or inertia"
        m0 = model0
        try:  # twice: from the parts (scatter), then by the kept parts and plan
            got = [self._assemble(m0, {}) for _ in range(2)]
        except (KeyError, ValueError, TypeError):
            return "the bodies' parts do not rebuild the model's mass"
        same = all(mass.shape == m0.mass.shape and np.array_equal(mass.indptr, m0.mass.indptr)
                   and np.array_equal(mass.indices, m0.mass.indices)
                   and np.array_equal(mass.data, m0.mass.data) and np.array_equal(g, m0.g_const)
                   and (m0.gravity_force is None or np.array_equal(gz, m0.gravity_force))
                   for mass, g, gz, _ in got)
        return None if same else "masses or loads besides the bodies' own"

    def _assemble(self, model, new):
        """(mass, g, gravity load, {body: block}) from the bodies' parts, ``new`` {body: (block,
        gravity load)} replacing some, in the build's order (SpatialBuilder._finish): the
        other bodies' blocks and loads are those of the reference (the same numbers), and the
        mass matrix is summed by the reference's plan (:func:`mbseig.numerics.csr_from_triplets`'s
        order and sums, kept: the same bits)."""
        from ..numerics import scatter

        n = model.n
        kept = self._parts
        blocks, g, own, loads = [], np.zeros(n), {}, {}
        gz_all = np.zeros(n)
        for name, rec in model.bodies.items():
            if not rec.get("spatial"):
                continue
            frame = rec["frame"]
            if name in new:
                block, gz = new[name]
            elif kept is not None:
                block, gz = kept[name]
            else:
                block, gz = self._blocks(rec, np.array([rec["mass"]]),
                                         np.asarray(rec["inertia"], float)[None])[0]
            blocks.append((frame.idx, frame.idx, block))
            own[name], loads[name] = block, gz
            if gz is not None:
                np.add.at(g, frame.idx, gz)
                np.add.at(gz_all, frame.idx, gz)
        plan = self._plan
        if plan is None:
            mass = scatter(n, n, blocks)
            mass.eliminate_zeros()
        else:
            import scipy.sparse as sp

            order, first, indices, indptr = plan
            v = np.concatenate([np.asarray(b, float).ravel() for _, _, b in blocks])
            data = np.add.reduceat(v[order], first)
            mass = sp.csr_matrix((data, indices.copy(), indptr.copy()), shape=(n, n))
            if not data.all():
                mass.eliminate_zeros()
        if kept is None:  # (the reference: its parts and the plan of its sum, kept)
            self._parts = {k: (own[k], loads[k]) for k in own}
            self._plan = _csr_plan(n, blocks)
        return mass.tocsr(), g, gz_all, own

    def _blocks(self, rec, masses, inertias):
        """[(block Cᵀ A C, gravity load Cᵀ C(ξ_G)ᵀ m g)] of one body at B masses (B,) and
        inertias (B, 3, 3): A by :func:`~mbseig.model.spatial_body.spatial_mass_matrices` (each
        equal to spatial_mass_matrix's bits), the products one value at a time as the build
        forms them."""
        from ..model.spatial_body import point_matrix, spatial_mass_matrices

        frame = rec["frame"]
        com = np.asarray(rec["com"], float) - rec["origin"]
        A = spatial_mass_matrices(masses, com, inertias)
        Ct = frame.C.T
        Pt = point_matrix(com).T if self.gravity is not None else None
        grav = None if Pt is None else np.asarray(self.gravity, float)
        return [(Ct @ A[b] @ frame.C, None if Pt is None else Ct @ (Pt @ (masses[b] * grav)))
                for b in range(masses.size)]

    def make(self, p):
        """The model at axis = p, or None where a full build is needed."""
        return self.make_many([p])[0]

    def make_many(self, values):
        """The models at axis = each value (:meth:`make`), or [None, ...] where a full build is
        needed: the fields read at each value with the reader's checks, the changed bodies'
        mass blocks for all values at once."""
        if self.reason is not None:
            return [None] * len(values)
        from ..model.spatial_body import inertia_problem

        m0 = self.model0
        params = [self.parameters(p) for p in values]
        read = {}  # body -> ([mass], [inertia]) over the values
        for name, item, label, keys in self.updates:
            rec = m0.bodies[name]
            masses, inertias = read.setdefault(name, ([], []))
            for prm in params:
                f = Fields(item, label, prm)
                masses.append(f.num("mass", positive=True) if "mass" in keys else rec["mass"])
                if "inertia" in keys:  # (an inertia not swept was checked by the build)
                    inertia = square_matrix(f, "inertia", 3, REQUIRED)
                    problem = inertia_problem(inertia)
                    if problem:
                        raise f.error(problem)
                else:
                    inertia = rec["inertia"]
                inertias.append(inertia)
        parts = {name: self._blocks(m0.bodies[name], np.array(ms, float),
                                    np.array(js, float))
                 for name, (ms, js) in read.items()}
        out = []
        for b, prm in enumerate(params):
            new = {name: parts[name][b] for name in parts}
            mass, g, gz, own = self._assemble(m0, new)
            bodies = {k: ({**v, "mass": read[k][0][b], "inertia": read[k][1][b]}
                          if k in read else v) for k, v in m0.bodies.items()}
            mparts = tuple((nm, r, c, own[nm] if nm in new else blk)
                           for nm, r, c, blk in m0.mass_parts)
            out.append(dataclasses.replace(
                m0, mass=mass, g_const=g, bodies=bodies, mass_parts=mparts,
                gravity_force=None if m0.gravity_force is None else gz, parameters=prm))
        return out


def _csr_plan(n, blocks):
    """(order, first, indices, indptr) by which :func:`mbseig.numerics.csr_from_triplets` sums
    the triplets of ``blocks`` (as :func:`~mbseig.numerics.scatter` forms them), or None where
    scatter takes another route (more than FAST_CSR triplets)."""
    from ..numerics import FAST_CSR

    r = np.concatenate([np.repeat(np.asarray(i).ravel(), np.asarray(j).size)
                        for i, j, _ in blocks]).astype(np.int64)
    c = np.concatenate([np.tile(np.asarray(j).ravel(), np.asarray(i).size)
                        for i, j, _ in blocks]).astype(np.int64)
    if not r.size or r.size > FAST_CSR:
        return None
    key = r * n + c
    order = np.argsort(key, kind="stable")
    key = key[order]
    first = np.flatnonzero(np.concatenate(([True], key[1:] != key[:-1])))
    key = key[first]
    rows = key // n
    indptr = np.zeros(n + 1, dtype=np.int32)
    np.cumsum(np.bincount(rows, minlength=n), out=indptr[1:])
    return order, first, (key - rows * n).astype(np.int32), indptr
