"""Spatial (3-D) case files: the reader of ``dimension = 3`` cases (the 3-D case format of the
design notes; docs/spatial.md).

Points, point masses, springs and the point joints (``distance``, ``fixed``, ``slider`` /
``point_on_line`` on a point) are read as in every dimension by
:class:`~mbseig.casefile.builder.Builder`; this subclass reads the spatial rigid bodies, joints and
forces:

- ``[[bodies]]`` (name, mass, com, inertia as [Ixx, Iyy, Izz] or 3×3 about the CoM in global
  axes at the reference, optional ``points``): mbseig gives each body the natural coordinates
  [r₀; u; v; w] (:mod:`mbseig.model.spatial_body`): r₀ its first carried point, else a basic point
  at its CoM; u, v, w unit vectors along the global axes at the reference.  Further carried
  points are attached to the body (3 linear equations each).
- point references: a basic point name or ``{ body = "b", at = [x, y, z] }``;
- ``[[joints]]``: spherical, revolute, universal, cylindrical, prismatic, weld, point_on_line,
  point_on_plane (:mod:`mbseig.model.spatial_joints`), distance, fixed, angle_driver (about a
  revolute);
- ``[[forces]]``: spring / damper / spring_damper, force, torque, torsional, bushing, rotor
  (:mod:`mbseig.model.spatial_forces`).

How it plugs into the generic builder: the body coordinates are allocated before the points
(so the point loop numbers its coordinates after them), the ``bodies`` table is hidden from the
planar body loop, joints and forces go through the :meth:`_joint` / :meth:`_force` hooks, and
the body masses, weights and rigid-body conditions are added to the built model (constraints
appended, so the indices that inverse-statics commands hold stay valid).
"""

from __future__ import annotations

import re

import dataclasses

import numpy as np
import scipy.sparse as sp

from ..model.affine import Affine
from ..model.elements import LinearConstraint
from ..model.spatial_body import (
    GROUND,
    frame_gravity,
    frame_of,
    frame_point,
    inertia_problem,
    spatial_mass_matrix,
)
from ..model.spatial_forces import (
    Rotor,
)
from ..model.spatial_joints import (
    triad_constraint,
)
from ..numerics import scatter
from .batch import LazyPoints, repeated_fields
from .builder import Builder
from .fields import REQUIRED, Fields, expand, square_matrix, template, two_names
from .spatial_readers import (
    UNIT_TOL,
    SpatialElementReaders,
)

__all__ = ["UNIT_TOL", "SpatialBuilder"]


_NAMED = re.compile(r"^\w+\[\d+\] '(.+)'$")  # an element's label with its name


class SpatialBuilder(SpatialElementReaders, Builder):
    """Reader of ``dimension = 3`` cases (module docstring)."""

    adds_mass = True

    def __init__(self, *args, **kwargs):
        super().__init__(*args, **kwargs)
        self.specs: list[dict] = []  # bodies as read, before their frames are bound
        self.frames: dict[str, Affine] = {}
        self.stations: dict[str, list] = {}  # body → [(label, Affine)] where elements act on it
        self.spatial_joints: dict[str, tuple] = {}  # joint name → (kind, b1, b2, at, axis)
        self.station_origin: dict[str, np.ndarray] = {}  # beam station "BEAM.NAME" → its node
        self.inline: dict[tuple, tuple] = {}  # (element, key) → (body, map, at its station?)
        self.pending_ends: dict[str, list] = {}  # element → its ends, named in _finish
        self.aliases: dict[str, str] = {}  # [[frames]]: a name → its body or "ground" (urdf)
        self._bound = False

    # -- the build ---------------------------------------------------------------------------
    def build(self):
        for item, label, names in expand("bodies", self.data.get("bodies", []), self.params,
                                         self._bodies):
            self._read_body(Fields(item, label, names))
        if "frames" in self.data:  # names of bodies' frames (links merged by a URDF import)
            from .urdf import read_frames

            read_frames(self, self.data["frames"])
        data = self.data
        self.data = {k: v for k, v in data.items() if k != "bodies"}
        try:
            model = super().build()
        finally:
            self.data = data
        return self._finish(model)

    def _read_body(self, f):
        bname = f.text("name")
        if bname in self.bodies or bname == "ground" or "." in bname:
            raise f.error(f"body name {bname!r} is used already, is 'ground' or contains '.'")
        mass = f.num("mass", positive=True)
        com = f.vec("com", 3)
        inertia = self._inertia(f)
        pts = f.raw("points", [])
        f.done()
        if not isinstance(pts, list) or not all(isinstance(p, str) for p in pts):
            raise f.error("points must be a list of basic point names")
        problem = inertia_problem(inertia)
        if problem:
            raise f.error(problem)
        pts = [template(p, f.names, f) for p in pts]
        if len(set(pts)) != len(pts):
            raise f.error("points lists a point twice")
        origin = None
        if not pts:  # a basic point at the centre of mass
            origin = self._allocate(bname, com)
        triad = self._allocate(bname, np.eye(3).ravel())
        self.bodies[bname] = {"label": f.label, "mass": mass, "com": com, "inertia": inertia,
                              "carried": pts, "spatial": True}
        self.specs.append({"name": bname, "f": f, "origin": origin, "triad": triad})

    def _bodies(self, section, item, label, var, ivals, params):
        """Repeated bodies (a diagonal inertia, no carried points) read at once and registered
        as :meth:`_read_body` registers them; False (declined: that reader then reads them and
        reports any problem) for anything else or any doubt."""
        got = repeated_fields(item, {"name": "name", "mass": 0, "com": 3, "inertia": 3}, var,
                              ivals, params)
        if got is None:
            return False
        names, mass, com, diag = got["name"], got["mass"], got["com"], got["inertia"]
        p = np.sort(diag, axis=1)  # principal moments (inertia_problem, with a tighter margin)
        if (len(set(names)) != len(names) or not np.all(mass > 0) or not np.all(p[:, 0] > 0)
                or not np.all(p[:, 2] <= (p[:, 0] + p[:, 1]) * (1 + 1e-13))
                or any(nm in self.bodies or nm == "ground" or "." in nm for nm in names)):
            return False
        nb, axes = len(names), [f"{v}.{a}" for v in "uvw" for a in "xyz"]
        values = np.hstack([com, np.tile(np.eye(3).ravel(), (nb, 1))]).ravel().tolist()
        idx = self.assembly.block([f"{nm}.{a}" for nm in names for a in (*"xyz", *axes)], values,
                                  (["length"] * 3 + ["direction"] * 9) * nb).reshape(nb, 12)
        inertia = np.zeros((nb, 3, 3))
        inertia[:, [0, 1, 2], [0, 1, 2]] = diag
        for k, nm in enumerate(names):
            f = Fields(item, f"{label} ({var}={int(ivals[k])})", params)
            self.bodies[nm] = {"label": f.label, "mass": float(mass[k]), "com": com[k],
                               "inertia": inertia[k], "carried": [], "spatial": True}
            self.specs.append({"name": nm, "f": f, "origin": idx[k, :3], "triad": idx[k, 3:]})
        return True

    def _allocate(self, bname, values):
        """A body's basic point at its centre of mass (3 values, lengths) or its unit vectors
        u, v, w (9 values, directions)."""
        if len(values) == 3:
            return self.assembly.coordinates([f"{bname}.{a}" for a in "xyz"], values, "length")
        return self.assembly.coordinates([f"{bname}.{v}.{a}" for v in "uvw" for a in "xyz"],
                                         values, "direction")

    def bind(self):
        """Frames of the bodies once the points exist, and the length scale of the model (its
        points, centres of mass and carried points)."""
        if self._bound:
            return
        self._bound = True
        where = [p for p in self.point_pos.values()]
        for spec in self.specs:
            b = self.bodies[spec["name"]]
            if spec["origin"] is not None:
                origin, x0 = Affine.select(spec["origin"]), b["com"]
            else:
                for p in b["carried"]:
                    self.basic_point(spec["f"], p)
                origin, x0 = self.affine_of(b["carried"][0]), self.point_pos[b["carried"][0]]
            self.frames[spec["name"]] = frame_of(origin, spec["triad"])
            b["origin"] = np.asarray(x0, float)
            where += [b["com"], x0]
        where = np.array(where)
        extent = float(np.ptp(where, axis=0).max()) if len(where) > 1 else 0.0
        self.length_scale = extent if extent > 0 else 1.0

    def _finish(self, model):
        self.bind()
        constraints, blocks, g = list(model.constraints), [], model.g_const.copy()
        mass_parts = list(model.mass_parts)
        g_gravity = np.zeros(model.n) if model.gravity_force is None else model.gravity_force.copy()
        gravity = self.gravity()
        for spec in self.specs:
            name, f = spec["name"], spec["f"]
            b, frame = self.bodies[name], self.frames[name]
            com = self.local(name, b["com"])
            blocks.append(self._embed(frame, spatial_mass_matrix(b["mass"], com, b["inertia"])))
            mass_parts.append((name, *blocks[-1]))
            if gravity is not None:
                gz = frame.C.T @ frame_gravity(b["mass"], com, gravity)
                np.add.at(g, frame.idx, gz)
                np.add.at(g_gravity, frame.idx, gz)
            constraints.append(triad_constraint(f"{f.label} (rigid body)", frame, name))
            for p in b["carried"][1:]:
                diff = self.affine_of(p) - frame_point(frame, self.local(name, self.point_pos[p]))
                self.add_constraint(constraints, LinearConstraint(
                    f"{f.label} (carries {p})", diff, np.eye(3), np.zeros(3), self.length_scale,
                    role=("carries", name, p)), f)
            marks = {"com": frame_point(frame, com),
                     **{lab: aff for lab, aff in self.stations.get(name, [])}}
            b["markers"] = []
            for k, aff in enumerate(marks.values()):
                self.markers[f"{name}.{k}"] = aff
                b["markers"].append(f"{name}.{k}")
            b["points"] = (b["markers"][0], b["markers"][min(1, len(b["markers"]) - 1)])
            b["frame"] = frame
        forces = tuple(self._with_stations(x) if isinstance(x, Rotor) else x for x in model.forces)
        mass = model.mass if model.mass is not None else sp.csr_matrix((model.n, model.n))
        if blocks and model.mass is None:
            mass = scatter(model.n, model.n, blocks)
            mass.eliminate_zeros()  # as its sum with an empty matrix
        elif blocks:
            mass = mass + scatter(model.n, model.n, blocks)
        return dataclasses.replace(
            model, mass=mass.tocsr(), g_const=g, constraints=tuple(constraints), forces=forces,
            mass_parts=tuple(mass_parts), element_ends={**model.element_ends, **self._ends()},
            gravity_force=None if gravity is None else g_gravity,
            points=LazyPoints(self.point_index, self.point_pos, self.markers),
            length_scale=self.length_scale)

    def _ends(self) -> dict:
        """The ends of the elements that act at inline points ``{body, at}`` (springs, bushings),
        named once the bodies' markers exist: the body's marker of that station ("body.k"), else
        (the ground, a beam station, a second station of one element on one body) a marker of
        its own, "body.k" after the others."""
        out = {}
        for element, ends in self.pending_ends.items():
            names = []
            for end in ends:
                if isinstance(end, str):
                    names.append(end)
                    continue
                bname, aff, at_station = end
                rec = self.bodies.get(bname) or {}
                named = [m for m in rec.get("markers", ()) if self.markers[m] is aff]
                if not named and at_station:
                    named = [bname]
                if not named:
                    k = sum(1 for m in self.markers if m.rpartition(".")[0] == bname)
                    named = [f"{bname}.{k}"]
                    self.markers[named[0]] = aff
                names.append(named[0])
            out[element] = tuple(names)
        return out

    def record_ends(self, element, f, key):
        """As the generic reader, and inline point references ``{body, at}`` too (:meth:`_ends`
        names them once the bodies' markers exist)."""
        refs = f.t.get(key)
        if not isinstance(refs, list) or not any(isinstance(r, dict) for r in refs):
            return super().record_ends(element, f, key)
        ends = [self.inline.get((f.label, f"{key}[{i}]")) if isinstance(r, dict)
                else template(r, f.names, f) for i, r in enumerate(refs)]
        if all(e is not None and (not isinstance(e, str) or e in self.point_index
                                  or e in self.markers) for e in ends):
            self.pending_ends[element] = ends
        return None

    def _with_stations(self, rotor):
        if rotor.body in self.station_origin:  # a rotor on a beam station: its node's point
            own = ("station", self.markers[rotor.body])
        else:
            b = self.bodies[rotor.body]
            own = ("centre of mass",
                   frame_point(self.frames[rotor.body], self.local(rotor.body, b["com"])))
        return dataclasses.replace(rotor, stations=(own, *self.stations.get(rotor.body, [])))

    # -- beam stations (casefile.flexible3d) -------------------------------------------------
    def register_station(self, name, frame, origin, point):
        """A beam station ``"BEAM.NAME"``: a frame wherever a body name is allowed (local
        coordinates from the node's reference position ``origin``) and a point."""
        self.frames[name] = frame
        self.station_origin[name] = np.asarray(origin, float)
        self.markers[name] = point

    def body(self, f, bname):
        if bname in self.station_origin:
            return bname
        if self.aliases.get(bname) == "ground":
            raise f.error(f"{bname!r} is a frame of the ground (frames), not a body")
        return super().body(f, self.aliases.get(bname, bname))

    def _bushing(self, f, forces, g_const):
        """A bushing's ``at`` defaults to the beam station it acts on (DESIGN §8)."""
        if not f.has("at"):
            bodies = f.t.get("bodies")
            names = ([template(x, f.names, f) for x in bodies if isinstance(x, str)]
                     if isinstance(bodies, list) else [])
            at = next((self.station_origin[x] for x in names if x in self.station_origin), None)
            if at is not None:
                f.t = {**f.t, "at": [float(c) for c in at]}
        return super()._bushing(f, forces, g_const)

    # -- references --------------------------------------------------------------------------
    def frame(self, f, bname):
        """The frame map of a body, or of the ground."""
        self.bind()
        if self.aliases.get(bname, bname) == "ground":
            return GROUND
        return self.frames[self.body(f, bname)]

    def local(self, bname, x):
        """Local coordinates of the reference-global point x in a body (or the ground)."""
        bname = self.aliases.get(bname, bname)
        if bname in self.station_origin:
            return np.asarray(x, float) - self.station_origin[bname]
        return np.asarray(x, float) - (0.0 if bname == "ground" else self.bodies[bname]["origin"])

    def _station(self, bname, label, aff):
        """A point where an element acts on a body: a whirl and unbalance station, named by the
        element's own name where the case gives one ("bearing 1"), else by its place in the case
        ("forces[0]"), not by the label errors use ("forces[0] 'bearing 1'")."""
        if bname != "ground":
            named = _NAMED.match(label)
            self.stations.setdefault(bname, []).append((named[1] if named else label, aff))

    def _carrier(self, pname):
        """The body whose basic point (origin or carried point) ``pname`` is, or None."""
        return next((b for b, r in self.bodies.items() if pname in r["carried"]), None)

    def point_ref(self, f, key):
        """A basic point name or ``{body = "b", at = [x, y, z]}`` (at: global position at the
        reference); records the point as a station of its body (for whirl)."""
        return self._point_and_body(f, key)[0]

    def _point_and_body(self, f, key):
        self.bind()
        ref = f.raw(key)
        if isinstance(ref, dict):
            sub = Fields(ref, f"{f.label}.{key}", f.names)
            bname = sub.text("body")
            bname = self.aliases.get(bname, bname)
            at = sub.vec("at", 3)
            sub.done()
            aff = frame_point(self.frame(f, bname), self.local(bname, at))
            self._station(bname, f.label, aff)
            at_station = bname in self.station_origin and not np.any(self.local(bname, at))
            self.inline[(f.label, key)] = (bname, aff, at_station)
            return aff, None if bname == "ground" else bname
        if isinstance(ref, str):
            aff = super().point_ref(f, key)
            body = self._carrier(template(ref, f.names, f))
            if body is not None:
                self._station(body, f.label, aff)
            return aff, body
        raise f.error(f"{key} must be a point name or a table {{body, at}}")

    def _two_bodies(self, f):
        b1, b2 = (self.aliases.get(b, b) for b in two_names(
            f, "bodies", 'bodies must be [body1, body2]; use "ground" for the fixed frame'))
        for b in (b1, b2):
            if b != "ground":
                self.body(f, b)
        if b1 == b2:
            raise f.error("a joint needs two different bodies")
        return b1, b2

    def _unit(self, f, key, value=None):
        a = f.vec(key, 3) if value is None else value
        n = float(np.linalg.norm(a))
        if n == 0:
            raise f.error(f"{key} must not be zero")
        if abs(n - 1.0) > UNIT_TOL:
            raise f.error(f"{key} must be a unit vector, got |{key}| = {n:.12g}")
        return a / n

    def _matrix(self, f, key, size, default=None):
        """``size`` numbers (a diagonal) or a size × size matrix."""
        return square_matrix(f, key, size, default)

    def _inertia(self, f):
        return self._matrix(f, "inertia", 3, REQUIRED)
