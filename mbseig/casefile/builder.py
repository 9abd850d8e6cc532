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
from ..model.driver import check_command
from ..model.elements import (
    DistanceConstraint,
    LinearConstraint,
    body_direction,
    body_mass_matrix,
    body_point,
)
from ..model.system import Model
from ..numerics import scatter
from .batch import Batcher, LazyPoints
from .element_readers import ElementReaders
from .fields import Fields, expand, template, uses_time
from .report_table import parse_report


def _flexible():
    """The beams and FE-body reader (model.beams, model.fe_body), imported at first use: most
    cases have neither, and `mbseig modes` starts faster without them."""
    from . import flexible

    return flexible


__all__ = ["Builder"]

_AXES = "xyz"


class Builder(ElementReaders):
    #: a subclass that adds its own mass blocks to the model (SpatialBuilder) takes
    #: ``mass = None`` where the model has no other mass, instead of an empty sparse matrix
    adds_mass = False

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
        self.mass_reference = None  # the q at which the beams' masses M_ref were evaluated
        self.mass_parts: list = []  # (name, idx, block) of every body and mass (modal energy)
        self._affine: dict[str, Affine] = {}  # point maps, made once a build (affine_of)
        self._dirs: dict[tuple, Affine] = {}  # body directions, made once a build (body_dir)
        motion = data.get("motion")
        self.periodic = isinstance(motion, dict) and "period" in motion
        self.driven_points: list = []  # (label, coordinate indices, position) of moving pivots

    def bushings(self, item, label, var, ivals, params, forces) -> bool:
        """Repeated bushings read all at once: none in a planar case (False: declined, the
        member-by-member reader reads the entry and reports what is wrong with it)."""
        return False

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
            if fixed and self.periodic and uses_time(item.get("position")):
                # a pivot moved with time (DESIGN §8 "Periodic motions"): free coordinates
                # held on its path by a rheonomic constraint, whose multiplier drives it
                idx = self.assembly.coordinates([f"{pname}.{_AXES[a]}" for a in range(self.dim)],
                                                pos, "length")
                self.driven_points.append((label, idx, pos))
            elif fixed:
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
            raise CaseError("the model has no free coordinates (every point is fixed)",
                            element="points")
        self.n = len(self.q_init)
        q0 = np.array(self.q_init)
        self.q0 = q0
        positions = np.array([p for p in self.point_pos.values()])
        extent = float(np.ptp(positions, axis=0).max()) if len(positions) > 1 else 0.0
        self.length_scale = extent if extent > 0 else 1.0

        mass_blocks, g_const = [], np.zeros(self.n)
        gravity = self.gravity()
        constraints, forces = [], []
        for plabel, idx, pos in self.driven_points:
            constraints.append(LinearConstraint(plabel, Affine.select(idx), np.eye(self.dim), pos,
                                                self.length_scale))
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
            if (not isinstance(pts, list) or len(pts) != 2
                    or not all(isinstance(p, str) for p in pts)):
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
                          lambda m=m, inertia=inertia, com=com, L=L:
                              body_mass_matrix(m, inertia, tuple(com), L))
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
        # masses, bodies, beams
        self.gravity_force = g_const.copy() if gravity is not None else None

        for item, label, names in expand("joints", self.data.get("joints", []), self.params):
            before = len(constraints)
            self._joint(Fields(item, label, names), constraints)
            self._remember(item, "joint", constraints, before, label)

        for item, label, names in expand("forces", self.data.get("forces", []), self.params, batch):
            before = len(forces)
            self._force(Fields(item, label, names), forces, g_const)
            self._remember(item, "force", forces, before, label)

        # the blocks' structural zeros neither summed nor stored (a 3-D beam's mass in natural
        # coordinates: 84 % of its entries), nor a sum that cancels to zero
        mass = scatter(self.n, self.n, mass_blocks, nonzero=True) if mass_blocks else None
        if mass is not None:
            mass.eliminate_zeros()
        rows, vals = batch.mass_coo()
        if rows.size:
            extra = sp.csr_matrix((vals, (rows, rows)), shape=(self.n, self.n))
            if mass is None:  # (as its sum with an empty matrix: no explicit zeros)
                extra.eliminate_zeros()
            mass = extra if mass is None else mass + extra
        if mass is None and not self.adds_mass:
            mass = sp.csr_matrix((self.n, self.n))
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
            mass_reference=self.mass_reference if mass_elements else None,
            inputs=inputs, outputs=outputs, gravity_force=self.gravity_force,
            mass_parts=tuple(self.mass_parts), coordinate_kinds=tuple(self.assembly.kinds),
            element_ends=dict(self.assembly.element_ends),
        )

    def _remember(self, item, kind, elements, before, label):
        name = item.get("name")
        if isinstance(name, str) and len(elements) == before + 1:
            self.named[name] = (kind, before, label)

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
            aff = self._affine[pname] = Affine.select(self.point_index[pname],
                                                      self.point_pos[pname])
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
