"""Multibody case tables → :class:`~mbseig.model.Model` (points, masses, bodies, joints, forces).

One reader entry per element type: :meth:`Builder._joint` and :meth:`Builder._force` read the
fields and construct the element classes of :mod:`mbseig.model`; nothing is solved here.
Inverse-statics drivers (``angle_driver`` with ``sets``) are left on the model as pending
``commands`` for :func:`mbseig.equilibrium` to resolve.  Every problem raises
:class:`~mbseig.errors.CaseError` naming the element (``joints[2] 'rod'``).
"""

from __future__ import annotations

import numpy as np
import scipy.sparse as sp

from ..errors import CaseError
from ..model.affine import Affine, combine
from ..model.assembly import Assembly
from ..model.driver import AngleDriver, check_command
from ..model.elements import (
    DistanceConstraint,
    FollowerForce,
    LinearConstraint,
    SpringDamper,
    TorsionalSpringDamper,
    body_direction,
    body_mass_matrix,
    body_point,
)
from ..model.system import Model
from ..numerics import scatter
from .batch import Batcher, LazyPoints
from .fields import REQUIRED, Fields, expand, template
from .report_table import parse_report


def _flexible():
    """The beams and FE-body reader (model.beams, model.fe_body), imported at first use: most
    cases have neither, and `mbseig modes` starts faster without them."""
    from . import flexible

    return flexible


__all__ = ["Builder"]

_AXES = "xyz"


class Builder:
    def __init__(self, data, name, source, params, description, expected, *, files=None,
                 mesh=None):
        self.data, self.name, self.source, self.params = data, name, source, params
        self.description, self.expected = description, expected
        self.files = files  # reads matrix files (FE bodies) once: mbseig.casefile.CaseSpec
        self.mesh = mesh  # beam name or index → element count (mbseig.studies.refine)
        dim = data.get("dimension")
        if type(dim) is not int or dim not in (1, 2, 3):
            raise CaseError(f"dimension must be 1, 2 or 3, got {dim!r}", element="case")
        self.dim = dim
        self.point_index: dict[str, np.ndarray] = {}  # name → coordinate indices (−1: fixed)
        self.point_pos: dict[str, np.ndarray] = {}
        self.assembly = Assembly()  # coordinates with their kinds, element ends
        self.bodies: dict[str, dict] = {}
        self.markers: dict[str, Affine] = {}
        self.named: dict[str, tuple] = {}  # element name → ("joint" | "force", index, label)
        self.drivers: list = []  # (AngleDriver, [names it sets], fields) for inverse statics
        self.element_body: dict[str, str] = {}  # attach / follower element label → body
        self.point_forces: dict[str, tuple] = {}  # name of a constant `force` → (point, vector)
        self.mass_parts: list = []  # (name, idx, block) of every body and mass (modal energy)
        self._affine: dict[str, Affine] = {}  # point maps, made once a build (affine_of)
        self._dirs: dict[tuple, Affine] = {}  # body directions, made once a build (body_dir)

    @property
    def coord_names(self) -> list:
        return self.assembly.names

    @property
    def q_init(self) -> list:
        return self.assembly.values

    # -- points ------------------------------------------------------------------------
    def build(self):
        batch = Batcher(self)  # vectorized expansion of repeated points, masses and springs
        for item, label, names in expand("points", self.data.get("points", []), self.params, batch):
            f = Fields(item, label, names)
            pname = f.text("name")
            if pname in self.point_index:
                raise f.error(f"duplicate point name {pname!r}")
            if "." in pname:
                raise f.error(f"point name {pname!r} must not contain '.'")
            pos = f.vec("position", self.dim)
            fixed = f.flag("fixed", False)
            f.done()
            if fixed:
                idx = np.full(self.dim, -1, dtype=np.intp)
            else:
                idx = self.assembly.coordinates([f"{pname}.{_AXES[a]}" for a in range(self.dim)],
                                                pos, "length")
            self.point_index[pname] = idx
            self.point_pos[pname] = pos
        flex = any(k in self.data for k in ("beams", "fe_bodies", "refinement"))
        if flex:
            _flexible().allocate(self, self.mesh)  # beam nodes, FE-body coordinates
        else:
            self.beam_specs, self.fe_specs = [], []
        if not self.q_init:
            raise CaseError("the model has no free coordinates (every point is fixed)", element="points")
        self.n = len(self.q_init)
        q0 = np.array(self.q_init)
        self.q0 = q0
        positions = np.array([p for p in self.point_pos.values()])
        extent = float(np.ptp(positions, axis=0).max()) if len(positions) > 1 else 0.0
        self.length_scale = extent if extent > 0 else 1.0

        mass_blocks, g_const = [], np.zeros(self.n)
        gravity = self.gravity()
        constraints, forces = [], []
        batch.bind(g_const, forces, gravity)

        for item, label, names in expand("masses", self.data.get("masses", []), self.params, batch):
            f = Fields(item, label, names)
            f.raw("name", None)
            point = self.basic_point(f, f.text("point"))
            m = f.num("mass", positive=True)
            f.done()
            idx = self.point_index[point]
            free = idx[idx >= 0]
            mass_blocks.append((free, free, m * np.eye(free.size)))
            mname = item.get("name")
            self.mass_parts.append((mname if isinstance(mname, str) else f"mass at {point}",
                                    *mass_blocks[-1]))
            if gravity is not None:
                g_const[free] += m * gravity[idx >= 0]

        for item, label, names in expand("bodies", self.data.get("bodies", []), self.params):
            f = Fields(item, label, names)
            if self.dim != 2:
                raise f.error("planar rigid bodies need dimension = 2")
            bname = f.text("name")
            if bname in self.bodies or bname in self.point_index or "." in bname:
                raise f.error(f"body name {bname!r} is used already or contains '.'")
            pts = f.raw("points")
            if not isinstance(pts, list) or len(pts) != 2 or not all(isinstance(p, str) for p in pts):
                raise f.error("points must be a list of two basic point names")
            pi, pj = (self.basic_point(f, template(p, names, f)) for p in pts)
            if pi == pj:
                raise f.error("a body needs two different basic points")
            init_len = float(np.linalg.norm(self.point_pos[pj] - self.point_pos[pi]))
            L = f.num("length", init_len, positive=True)
            # mass = 0 (with inertia = 0) is a massless rod: it carries joints, springs and
            # follower loads while point masses on its basic points carry the inertia
            m = f.num("mass", nonnegative=True)
            inertia = f.num("inertia", nonnegative=True)
            com = f.vec("com", 2, [L / 2, 0.0])
            marker_table = f.raw("markers", {})
            f.done()
            if not isinstance(marker_table, dict):
                raise f.error("markers must be a table name = [x, y]")
            ri, rj = self.affine_of(pi), self.affine_of(pj)
            qb = combine([(1.0, ri), (1.0, rj)], stack=True)
            Mb = f.formed("the body's mass matrix",
                          lambda: body_mass_matrix(m, inertia, tuple(com), L))
            mass_blocks.append(self._embed(qb, Mb))
            self.mass_parts.append((bname, *mass_blocks[-1]))
            if gravity is not None:
                G = body_point(ri, rj, com, L)
                np.add.at(g_const, G.idx, G.C.T @ (m * gravity))
            self.bodies[bname] = {"points": (pi, pj), "length": L, "mass": m, "label": label}
            for mname, local in marker_table.items():
                loc = Fields({"local": local}, f"{label}.markers.{mname}", names).vec("local", 2)
                self.markers[f"{bname}.{mname}"] = body_point(ri, rj, loc, L)
            rod = DistanceConstraint(f"{label} (rigid length)", rj - ri, L)
            self.add_constraint(constraints, rod, f)

        mass_elements = []  # configuration-dependent masses (co-rotational beams)
        flexible_record = {} if not flex else _flexible().assemble(
            self, forces, constraints, mass_blocks, mass_elements, g_const, gravity)
        self.gravity_force = g_const.copy() if gravity is not None else None  # masses, bodies, beams

        for item, label, names in expand("joints", self.data.get("joints", []), self.params):
            before = len(constraints)
            self._joint(Fields(item, label, names), constraints)
            self._remember(item, "joint", constraints, before, label)

        for item, label, names in expand("forces", self.data.get("forces", []), self.params, batch):
            before = len(forces)
            self._force(Fields(item, label, names), forces, g_const)
            self._remember(item, "force", forces, before, label)

        mass = sp.csr_matrix((self.n, self.n))
        if mass_blocks:
            mass = scatter(self.n, self.n, mass_blocks)
        rows, vals = batch.mass_coo()
        if rows.size:
            mass = mass + sp.csr_matrix((vals, (rows, rows)), shape=(self.n, self.n))
        points = LazyPoints(self.point_index, self.point_pos, self.markers)
        report = {}
        if "report" in self.data:
            report = parse_report(self.data["report"], self)

        inputs, outputs = (), ()
        if "inputs" in self.data or "outputs" in self.data:
            from .signals import read_signals  # only cases with signals need the reader

            inputs, outputs = read_signals(self, forces, constraints)
        commands = tuple((d, self._driver_targets(names, f)) for d, names, f in self.drivers)
        for driver, targets in commands:  # checked now; resolved by mbseig.equilibrium
            check_command(driver, targets, forces, constraints)
        return Model(
            name=self.name, source=self.source, parameters=dict(self.params), dimension=self.dim,
            coordinate_names=tuple(self.coord_names), q_init=q0, mass=mass, g_const=g_const,
            forces=tuple(forces), constraints=tuple(constraints), points=points,
            bodies=self.bodies, length_scale=self.length_scale, description=self.description,
            expected=self.expected, report=report, commands=commands,
            mass_elements=tuple(mass_elements), flexible=flexible_record,
            inputs=inputs, outputs=outputs, gravity_force=self.gravity_force,
            mass_parts=tuple(self.mass_parts), coordinate_kinds=tuple(self.assembly.kinds),
            element_ends=dict(self.assembly.element_ends),
        )

    def _remember(self, item, kind, elements, before, label):
        name = item.get("name")
        if isinstance(name, str) and len(elements) == before + 1:
            self.named[name] = (kind, before, label)

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

    def gravity(self):
        g = self.data.get("gravity")
        if g is None:
            return None
        f = Fields({"gravity": g}, "gravity", self.params)
        return f.vec("gravity", self.dim)

    def _embed(self, aff, local):
        """A block on the components of ``aff`` mapped to its free coordinates: Cᵀ B C."""
        return (aff.idx, aff.idx, aff.C.T @ local @ aff.C)

    # -- references ----------------------------------------------------------------------
    def basic_point(self, f, pname):
        if pname not in self.point_index:
            raise f.error(f"unknown point {pname!r}")
        return pname

    def affine_of(self, pname):
        """The point's map (one object per point and build: elements share it read-only)."""
        aff = self._affine.get(pname)
        if aff is None:
            aff = self._affine[pname] = Affine.select(self.point_index[pname], self.point_pos[pname])
        return aff

    def point_ref(self, f, key):
        """A basic point name, a body marker 'body.marker', or {body = ..., local = [x, y]}."""
        ref = f.raw(key)
        if isinstance(ref, str):
            ref = template(ref, f.names, f)
            if ref in self.point_index:
                return self.affine_of(ref)
            if ref in self.markers:
                return self.markers[ref]
            raise f.error(f"unknown point {ref!r} in {key}")
        if isinstance(ref, dict):
            sub = Fields(ref, f"{f.label}.{key}", f.names)
            body = self.body(sub, sub.text("body"))
            local = sub.vec("local", 2)
            sub.done()
            return self.body_point(body, local)
        raise f.error(f"{key} must be a point name or a table {{body, local}}")

    def body(self, f, bname):
        if bname not in self.bodies:
            raise f.error(f"unknown body {bname!r}")
        return bname

    def body_point(self, bname, local):
        b = self.bodies[bname]
        pi, pj = b["points"]
        return body_point(self.affine_of(pi), self.affine_of(pj), local, b["length"])

    def body_dir(self, bname, local=(1.0, 0.0)):
        key = (bname, float(local[0]), float(local[1]))
        aff = self._dirs.get(key)
        if aff is None:
            b = self.bodies[bname]
            pi, pj = b["points"]
            aff = self._dirs[key] = body_direction(self.affine_of(pi), self.affine_of(pj), local,
                                                   b["length"])
        return aff

    def record_ends(self, element, f, key):
        """Record the named points (basic points or body markers) the two-point references
        ``key`` of ``element`` name, in the order of its difference map; an inline reference
        ({body, local}) names no point and records nothing."""
        refs = f.t.get(key)
        names = [template(r, f.names, f) if isinstance(r, str) else None for r in refs]
        if all(n in self.point_index or n in self.markers for n in names):
            self.assembly.ends(element, *names)

    def record_bodies(self, element, f):
        """Record the two bodies (None for the ground) ``element`` acts between."""
        names = [template(str(n), f.names, f) for n in f.t.get("bodies")]
        self.assembly.ends(element, "bodies", *(None if n == "ground" else n for n in names))

    def two_points(self, f):
        pts = f.raw("points")
        if not isinstance(pts, list) or len(pts) != 2:
            raise f.error("points must be a list of two point references")
        f.t = {**f.t, "points[0]": pts[0], "points[1]": pts[1]}
        a, b = self.point_ref(f, "points[0]"), self.point_ref(f, "points[1]")
        f.used |= {"points[0]", "points[1]"}
        return a, b

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
            G = _normal_basis(direction / norm)
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
                local = _local_coordinates(self, body, p(self.q0), f)
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


def _normal_basis(u):
    """Rows spanning the orthogonal complement of the unit vector u."""
    _, _, vt = np.linalg.svd(u[None, :])
    return vt[1:]


def _local_coordinates(builder, body, r, f):
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
