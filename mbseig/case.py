"""Case files: TOML → :class:`~mbseig.model.Model` or :class:`LinearCase`.

A case is data.  Numeric fields hold numbers or whitelisted expressions (:mod:`mbseig.expr`) over
the ``[parameters]`` table; string fields may hold ``{expr}`` templates (``"m{i+1}"``) inside a
``repeat = {i = [first, last]}`` element.  Every problem raises :class:`~mbseig.errors.CaseError`
naming the file, the element (``joints[2] 'rod'``) and what is wrong.  The format is documented in
README.md ("Case files") and by the cases in ``cases/``.
"""

from __future__ import annotations

import re
import tomllib
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
import scipy.sparse as sp

from .case_batch import Batcher, LazyPoints
from .errors import CaseError, MbseigError
from .expr import evaluate
from .model.affine import Affine, combine
from .model.elements import (
    DistanceConstraint,
    FollowerForce,
    LinearConstraint,
    SpringDamper,
    TorsionalSpringDamper,
    body_direction,
    body_mass_matrix,
    body_point,
)
from .model.system import Model

__all__ = ["load_case", "LinearCase", "SCHEMA_VERSION", "parse_param_overrides"]

SCHEMA_VERSION = 1
MAX_REPEAT = 2_000_000
_REQUIRED = object()
_AXES = "xyz"
_TOP_KEYS = {
    "schema_version", "title", "description", "source", "kind", "dimension", "gravity",
    "parameters", "points", "masses", "bodies", "joints", "forces", "matrices", "expected",
    "configurations", "report", "beams", "fe_bodies", "refinement",
}


@dataclass(frozen=True, eq=False)
class LinearCase:
    """A linear case: (M s² + P s + Q) x = 0 given directly, M, P, Q possibly parameter sums."""

    name: str
    source: str
    parameters: dict
    M: np.ndarray
    P: np.ndarray
    Q: np.ndarray
    description: str = ""
    expected: dict = field(default_factory=dict)

    @property
    def n(self) -> int:
        return self.M.shape[0]

    @property
    def coordinate_names(self):
        return tuple(f"x{k + 1}" for k in range(self.n))

    @property
    def n_constraints(self) -> int:
        """Always 0: the matrices are already in independent coordinates."""
        return 0


# ---------------------------------------------------------------------------------------------
def parse_param_overrides(items) -> dict:
    """``["n=20", "k=1e3"]`` → ``{"n": "20", "k": "1e3"}`` (values are expressions)."""
    out = {}
    for item in items or ():
        name, sep, value = item.partition("=")
        if not sep or not name.strip() or not value.strip():
            raise CaseError(f"--param expects NAME=VALUE, got {item!r}")
        out[name.strip()] = value.strip()
    return out


def load_case(path, config: str | None = None, **params):
    """Read a case file and build its model.

    ``params`` override entries of the case's ``[parameters]`` table (numbers or expressions);
    ``config`` selects a named entry of its ``[configurations]`` table (a set of parameter
    values).  Raises :class:`CaseError` naming the file and element on any problem.
    """
    path = Path(path)
    try:
        text = path.read_bytes().decode("utf-8")
    except OSError as exc:
        raise CaseError(f"cannot read case file: {exc.strerror or exc}", file=str(path)) from None
    except UnicodeDecodeError:
        raise CaseError("case file is not UTF-8 text", file=str(path)) from None
    try:
        data = tomllib.loads(text)
    except tomllib.TOMLDecodeError as exc:
        raise CaseError(f"malformed TOML: {exc}", file=str(path)) from None
    try:
        return build_case(data, name=path.stem, source=str(path), base_dir=path.parent,
                          config=config, overrides=params)
    except MbseigError as exc:
        raise exc.located(file=str(path)) from None


def build_case(data, *, name, source, base_dir=Path("."), config=None, overrides=None, mesh=None):
    """Build from parsed TOML; ``mesh`` maps a beam's name or index to its element count."""
    unknown = sorted(set(data) - _TOP_KEYS)
    if unknown:
        raise CaseError(f"unknown top-level field {unknown[0]!r}", element="case")
    version = data.get("schema_version", None)
    if version != SCHEMA_VERSION:
        raise CaseError(f"schema_version must be {SCHEMA_VERSION}, got {version!r}", element="case")
    params = _parameters(data.get("parameters", {}), data.get("configurations", {}), config,
                         dict(overrides or {}))
    kind = data.get("kind", "multibody")
    description = str(data.get("description", data.get("title", "")))
    expected = data.get("expected", {})
    if not isinstance(expected, dict):
        raise CaseError("[expected] must be a table", element="expected")
    if kind == "linear":
        return _linear_case(data, name, source, base_dir, params, description, expected)
    if kind != "multibody":
        raise CaseError(f"kind must be 'multibody' or 'linear', got {kind!r}", element="case")
    builder = _Builder(data, name, source, params, description, expected)
    builder.base_dir, builder.mesh = base_dir, mesh  # FE matrix files; beam meshes (mbseig.refine)
    return builder.build()


def _parameters(table, configurations, config, overrides):
    if not isinstance(table, dict):
        raise CaseError("[parameters] must be a table", element="parameters")
    raw = dict(table)
    if config is not None:
        if not isinstance(configurations, dict) or config not in configurations:
            known = ", ".join(sorted(configurations)) if isinstance(configurations, dict) else ""
            raise CaseError(f"unknown configuration {config!r} (known: {known or 'none'})",
                            element="configurations")
        chosen = configurations[config]
        if not isinstance(chosen, dict):
            raise CaseError("a configuration must be a table of parameter values",
                            element=f"configurations.{config}")
        for key, value in chosen.items():
            if key == "description":
                continue
            if key not in raw:
                raise CaseError(f"sets unknown parameter {key!r}", element=f"configurations.{config}")
            raw[key] = value
    for key, value in overrides.items():
        if key not in raw:
            known = ", ".join(raw) or "none"
            raise CaseError(f"unknown parameter {key!r} (known: {known})", element="--param")
        raw[key] = value
    values: dict[str, float] = {}
    for key, value in raw.items():
        if not re.fullmatch(r"[A-Za-z_][A-Za-z0-9_]*", key):
            raise CaseError(f"invalid parameter name {key!r}", element="parameters")
        try:
            values[key] = evaluate(value, values)
        except MbseigError as exc:
            raise exc.located(element=f"parameters.{key}") from None
    return values


# ---------------------------------------------------------------------------------------------
class _Fields:
    """Typed access to one element table; unknown keys are rejected by :meth:`done`."""

    def __init__(self, table, label, names):
        if not isinstance(table, dict):
            raise CaseError("each element must be a table", element=label)
        self.t, self.label, self.names, self.used = table, label, names, {"repeat", "enabled"}

    def error(self, message):
        return CaseError(message, element=self.label)

    def has(self, key):
        return key in self.t

    def raw(self, key, default=_REQUIRED):
        self.used.add(key)
        if key not in self.t:
            if default is _REQUIRED:
                raise self.error(f"missing field {key!r}")
            return default
        return self.t[key]

    def num(self, key, default=_REQUIRED, *, positive=False, nonnegative=False):
        value = self.raw(key, default)
        if value is None:
            return None
        try:
            x = evaluate(value, self.names)
        except MbseigError as exc:
            raise exc.located(element=f"{self.label}.{key}") from None
        if positive and not x > 0:
            raise self.error(f"{key} must be positive, got {x:g}")
        if nonnegative and not x >= 0:
            raise self.error(f"{key} must not be negative, got {x:g}")
        return x

    def vec(self, key, size, default=_REQUIRED):
        if key not in self.t and default is not _REQUIRED:
            self.used.add(key)
            return None if default is None else np.asarray(default, dtype=float)
        value = self.raw(key, default)
        if value is None:
            return None
        if not isinstance(value, list) or len(value) != size:
            raise self.error(f"{key} must be a list of {size} numbers, got {value!r}")
        try:
            return np.array([evaluate(v, self.names) for v in value])
        except MbseigError as exc:
            raise exc.located(element=f"{self.label}.{key}") from None

    def text(self, key, default=_REQUIRED):
        value = self.raw(key, default)
        if value is None:
            return None
        if not isinstance(value, str):
            raise self.error(f"{key} must be a string, got {value!r}")
        return _template(value, self.names, self)

    def flag(self, key, default):
        value = self.raw(key, default)
        if not isinstance(value, bool):
            raise self.error(f"{key} must be true or false, got {value!r}")
        return value

    def done(self):
        extra = sorted(set(self.t) - self.used)
        if extra:
            raise self.error(f"unknown field {extra[0]!r}")


def _template(text, names, fields):
    def sub(match):
        try:
            x = evaluate(match.group(1), names)
        except MbseigError as exc:
            raise fields.error(f"bad template {text!r}: {exc.message}") from None
        return str(int(x)) if float(x).is_integer() else repr(x)

    return re.sub(r"\{([^{}]*)\}", sub, text)


def _expand(section, items, params, batch=None):
    """Yield (label, names) for every element of a section, expanding ``repeat``."""
    if not isinstance(items, list):
        raise CaseError(f"[[{section}]] must be an array of tables", element=section)
    total = 0
    for k, item in enumerate(items):
        if not isinstance(item, dict):
            raise CaseError("each element must be a table", element=f"{section}[{k}]")
        label = f"{section}[{k}]"
        if "name" in item and isinstance(item["name"], str):
            label += f" {item['name']!r}"
        rep = item.get("repeat")
        if rep is None:
            if _enabled(item, label, params):
                yield item, label, params
            continue
        if not isinstance(rep, dict) or len(rep) != 1:
            raise CaseError("repeat must be a table {index = [first, last]}", element=label)
        (var, bounds), = rep.items()
        if var in params or not re.fullmatch(r"[A-Za-z_]\w*", var):
            raise CaseError(f"repeat index {var!r} clashes with a parameter or is not a name",
                            element=label)
        if not isinstance(bounds, list) or len(bounds) != 2:
            raise CaseError("repeat bounds must be [first, last]", element=label)
        try:
            first, last = (evaluate(b, params) for b in bounds)
        except MbseigError as exc:
            raise exc.located(element=label) from None
        if not (first.is_integer() and last.is_integer()):
            raise CaseError("repeat bounds must be integers", element=label)
        count = int(last) - int(first) + 1
        total += max(count, 0)
        if total > MAX_REPEAT:
            raise CaseError(f"more than {MAX_REPEAT} repeated elements", element=label)
        if batch is not None and batch(section, item, label, var,
                                       np.arange(int(first), int(last) + 1, dtype=float), params):
            continue  # expanded at once by mbseig.case_batch
        for i in range(int(first), int(last) + 1):
            names = {**params, var: float(i)}
            if _enabled(item, f"{label} ({var}={i})", names):
                yield item, f"{label} ({var}={i})", names


def _enabled(item, label, names):
    """``enabled = expr``: the element exists only where expr ≠ 0 (e.g. set by a configuration)."""
    if "enabled" not in item:
        return True
    value = item["enabled"]
    if isinstance(value, bool):
        return value
    try:
        return evaluate(value, names) != 0
    except MbseigError as exc:
        raise exc.located(element=f"{label}.enabled") from None


class _Builder:
    def __init__(self, data, name, source, params, description, expected):
        self.data, self.name, self.source, self.params = data, name, source, params
        self.description, self.expected = description, expected
        dim = data.get("dimension")
        if dim not in (1, 2, 3):
            raise CaseError(f"dimension must be 1, 2 or 3, got {dim!r}", element="case")
        self.dim = dim
        self.point_index: dict[str, np.ndarray] = {}  # name → coordinate indices (−1: fixed)
        self.point_pos: dict[str, np.ndarray] = {}
        self.coord_names: list[str] = []
        self.q_init: list[float] = []
        self.bodies: dict[str, dict] = {}
        self.markers: dict[str, Affine] = {}
        self.named: dict[str, tuple] = {}  # element name → ("joint" | "force", index, label)
        self.drivers: list = []  # (AngleDriver, [names it sets], fields) for inverse statics
        self.element_body: dict[str, str] = {}  # attach / follower element label → body

    # -- points ------------------------------------------------------------------------
    def build(self):
        batch = Batcher(self)  # vectorized expansion of repeated points, masses and springs
        for item, label, names in _expand("points", self.data.get("points", []), self.params, batch):
            f = _Fields(item, label, names)
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
                idx = np.arange(len(self.q_init), len(self.q_init) + self.dim, dtype=np.intp)
                self.coord_names += [f"{pname}.{_AXES[a]}" for a in range(self.dim)]
                self.q_init += list(pos)
            self.point_index[pname] = idx
            self.point_pos[pname] = pos
        from .flexible import allocate as allocate_flexible, assemble as assemble_flexible

        allocate_flexible(self, getattr(self, "mesh", None))  # beam nodes, FE-body coordinates
        if not self.q_init:
            raise CaseError("the model has no free coordinates (every point is fixed)", element="points")
        self.n = len(self.q_init)
        q0 = np.array(self.q_init)
        self.q0 = q0
        positions = np.array([p for p in self.point_pos.values()])
        extent = float(np.ptp(positions, axis=0).max()) if len(positions) > 1 else 0.0
        self.length_scale = extent if extent > 0 else 1.0

        mass_blocks, g_const = [], np.zeros(self.n)
        gravity = self._gravity()
        constraints, forces = [], []
        batch.bind(g_const, forces, gravity)

        for item, label, names in _expand("masses", self.data.get("masses", []), self.params, batch):
            f = _Fields(item, label, names)
            f.raw("name", None)
            point = self._basic_point(f, f.text("point"))
            m = f.num("mass", positive=True)
            f.done()
            idx = self.point_index[point]
            free = idx[idx >= 0]
            mass_blocks.append((free, free, m * np.eye(free.size)))
            if gravity is not None:
                g_const[free] += m * gravity[idx >= 0]

        for item, label, names in _expand("bodies", self.data.get("bodies", []), self.params):
            f = _Fields(item, label, names)
            if self.dim != 2:
                raise f.error("planar rigid bodies need dimension = 2")
            bname = f.text("name")
            if bname in self.bodies or bname in self.point_index or "." in bname:
                raise f.error(f"body name {bname!r} is used already or contains '.'")
            pts = f.raw("points")
            if not isinstance(pts, list) or len(pts) != 2 or not all(isinstance(p, str) for p in pts):
                raise f.error("points must be a list of two basic point names")
            pi, pj = (self._basic_point(f, _template(p, names, f)) for p in pts)
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
            ri, rj = self._affine_of(pi), self._affine_of(pj)
            qb = combine([(1.0, ri), (1.0, rj)], stack=True)
            Mb = body_mass_matrix(m, inertia, tuple(com), L)
            mass_blocks.append(self._embed(qb, Mb))
            if gravity is not None:
                G = body_point(ri, rj, com, L)
                np.add.at(g_const, G.idx, G.C.T @ (m * gravity))
            self.bodies[bname] = {"points": (pi, pj), "length": L, "mass": m, "label": label}
            for mname, local in marker_table.items():
                loc = _Fields({"local": local}, f"{label}.markers.{mname}", names).vec("local", 2)
                self.markers[f"{bname}.{mname}"] = body_point(ri, rj, loc, L)
            rod = DistanceConstraint(f"{label} (rigid length)", rj - ri, L)
            self._add_constraint(constraints, rod, f)

        mass_elements = []  # configuration-dependent masses (co-rotational beams)
        flexible = assemble_flexible(self, forces, constraints, mass_blocks, mass_elements,
                                     g_const, gravity)

        for item, label, names in _expand("joints", self.data.get("joints", []), self.params):
            before = len(constraints)
            self._joint(_Fields(item, label, names), constraints)
            self._remember(item, "joint", constraints, before, label)

        for item, label, names in _expand("forces", self.data.get("forces", []), self.params, batch):
            before = len(forces)
            self._force(_Fields(item, label, names), forces, g_const)
            self._remember(item, "force", forces, before, label)

        mass = sp.csr_matrix((self.n, self.n))
        if mass_blocks:
            from .model.system import _scatter
            mass = _scatter(self.n, self.n, mass_blocks)
        rows, vals = batch.mass_coo()
        if rows.size:
            mass = mass + sp.csr_matrix((vals, (rows, rows)), shape=(self.n, self.n))
        points = LazyPoints(self.point_index, self.point_pos, self.markers)
        report = {}
        if "report" in self.data:
            from .device import parse_report

            report = parse_report(self.data["report"], self)

        def make_model(forces, constraints, q_init=None, drivers=()):
            return Model(
                name=self.name, source=self.source, parameters=dict(self.params), dimension=self.dim,
                coordinate_names=tuple(self.coord_names), q_init=q0 if q_init is None else q_init,
                mass=mass, g_const=g_const, forces=tuple(forces), constraints=tuple(constraints),
                points=points, bodies=self.bodies, length_scale=self.length_scale,
                description=self.description, expected=self.expected, report=report,
                drivers=tuple(drivers), mass_elements=tuple(mass_elements), flexible=flexible,
            )

        if self.drivers:
            from .inverse_statics import resolve_drivers

            pending = [(d, self._driver_targets(names, f)) for d, names, f in self.drivers]
            forces, constraints, q_guess, records = resolve_drivers(
                make_model, forces, constraints, pending)
            return make_model(forces, constraints, q_guess, records)
        return make_model(forces, constraints)

    def _remember(self, item, kind, elements, before, label):
        name = item.get("name")
        if isinstance(name, str) and len(elements) == before + 1:
            self.named[name] = (kind, before, label)

    def _driver_targets(self, names, f):
        """Elements named by a driver's ``sets``; names of disabled elements are skipped."""
        declared = {item.get("name") for sec in ("joints", "forces")
                    for item in self.data.get(sec, []) if isinstance(item, dict)}
        targets = []
        for nm in names:
            if nm in self.named:
                targets.append(self.named[nm])
            elif nm not in declared:
                raise f.error(f"sets unknown element {nm!r} (a named spring or distance joint)")
        return targets

    def _gravity(self):
        g = self.data.get("gravity")
        if g is None:
            return None
        f = _Fields({"gravity": g}, "gravity", self.params)
        return f.vec("gravity", self.dim)

    def _embed(self, aff, local):
        """A block on the components of ``aff`` mapped to its free coordinates: Cᵀ B C."""
        return (aff.idx, aff.idx, aff.C.T @ local @ aff.C)

    # -- references ----------------------------------------------------------------------
    def _basic_point(self, f, pname):
        if pname not in self.point_index:
            raise f.error(f"unknown point {pname!r}")
        return pname

    def _affine_of(self, pname):
        return Affine.select(self.point_index[pname], self.point_pos[pname])

    def _point_ref(self, f, key):
        """A basic point name, a body marker 'body.marker', or {body = ..., local = [x, y]}."""
        ref = f.raw(key)
        if isinstance(ref, str):
            ref = _template(ref, f.names, f)
            if ref in self.point_index:
                return self._affine_of(ref)
            if ref in self.markers:
                return self.markers[ref]
            raise f.error(f"unknown point {ref!r} in {key}")
        if isinstance(ref, dict):
            sub = _Fields(ref, f"{f.label}.{key}", f.names)
            body = self._body(sub, sub.text("body"))
            local = sub.vec("local", 2)
            sub.done()
            return self._body_point(body, local)
        raise f.error(f"{key} must be a point name or a table {{body, local}}")

    def _body(self, f, bname):
        if bname not in self.bodies:
            raise f.error(f"unknown body {bname!r}")
        return bname

    def _body_point(self, bname, local):
        b = self.bodies[bname]
        pi, pj = b["points"]
        return body_point(self._affine_of(pi), self._affine_of(pj), local, b["length"])

    def _body_dir(self, bname, local=(1.0, 0.0)):
        b = self.bodies[bname]
        pi, pj = b["points"]
        return body_direction(self._affine_of(pi), self._affine_of(pj), local, b["length"])

    def _two_points(self, f):
        pts = f.raw("points")
        if not isinstance(pts, list) or len(pts) != 2:
            raise f.error("points must be a list of two point references")
        f.t = {**f.t, "_a": pts[0], "_b": pts[1]}
        a, b = self._point_ref(f, "_a"), self._point_ref(f, "_b")
        f.used |= {"_a", "_b"}
        return a, b

    def _add_constraint(self, constraints, c, f):
        if c.idx.size == 0:
            if np.any(np.abs(c.phi(self.q0)) > 1e-12 * c.scale()):
                raise f.error("constraint between fixed points cannot be satisfied")
            return
        constraints.append(c)

    # -- joints --------------------------------------------------------------------------
    def _joint(self, f, constraints):
        kind = f.text("type")
        name = f.text("name", None)
        if kind == "distance":
            a, b = self._two_points(f)
            diff = b - a
            L = f.num("length", float(np.linalg.norm(diff(self.q0))), positive=True)
            f.done()
            self._add_constraint(constraints, DistanceConstraint(f.label, diff, L), f)
        elif kind == "fixed":
            p = self._point_ref(f, "point")
            target = f.vec("position", self.dim, p(self.q0))
            f.done()
            c = LinearConstraint(f.label, p, np.eye(self.dim), target, self.length_scale)
            self._add_constraint(constraints, c, f)
        elif kind in ("slider", "point_on_line"):
            if self.dim == 1:
                raise f.error("a slider needs dimension 2 or 3")
            p = self._point_ref(f, "point")
            origin = f.vec("origin", self.dim, p(self.q0))
            direction = f.vec("direction", self.dim)
            f.done()
            norm = np.linalg.norm(direction)
            if norm == 0:
                raise f.error("direction must not be zero")
            # rows: an orthonormal basis of the directions normal to the line
            G = _normal_basis(direction / norm)
            c = LinearConstraint(f.label, p, G, G @ origin, self.length_scale)
            self._add_constraint(constraints, c, f)
        elif kind == "attach":
            if self.dim != 2:
                raise f.error("attach needs dimension = 2 (planar bodies)")
            p = self._point_ref(f, "point")
            body = self._body(f, f.text("body"))
            b = self.bodies[body]
            local = f.vec("local", 2, None)
            f.done()
            if local is None:
                local = _local_coordinates(self, body, p(self.q0))
            diff = p - self._body_point(body, local)
            c = LinearConstraint(f.label, diff, np.eye(2), np.zeros(2), self.length_scale)
            self.element_body[f.label] = body
            self._add_constraint(constraints, c, f)
        elif kind == "angle_driver":
            self._angle_driver(f, constraints)
        else:
            raise f.error(
                f"unknown joint type {kind!r} (distance, fixed, slider, attach, angle_driver)")
        del name

    def _angle_driver(self, f, constraints):
        """Prescribed relative angle (driving constraint); with ``sets`` an inverse-statics
        command (see :mod:`mbseig.inverse_statics`), otherwise a permanent constraint."""
        from .model.driver import AngleDriver

        if self.dim != 2:
            raise f.error("angle_driver needs dimension = 2")
        stacked, sense = self._angle_pair(f)
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

    def _angle_pair(self, f):
        """Stacked directions [a; b] of ``bodies = [b1 or "ground", b2]`` and the sense (±1)."""
        bodies = f.raw("bodies")
        if not isinstance(bodies, list) or len(bodies) != 2:
            raise f.error("bodies must be [body1, body2]; use \"ground\" for the fixed frame")
        dirs = []
        for bname in bodies:
            bname = _template(str(bname), f.names, f)
            if bname == "ground":
                dirs.append(Affine.constant(f.vec("ground_direction", 2, [1.0, 0.0])))
            else:
                dirs.append(self._body_dir(self._body(f, bname)))
        sense_txt = f.text("sense", "ccw")
        if sense_txt not in ("ccw", "cw"):
            raise f.error("sense must be 'ccw' or 'cw'")
        return combine([(1.0, dirs[0]), (1.0, dirs[1])], stack=True), (1.0 if sense_txt == "ccw" else -1.0)

    # -- forces --------------------------------------------------------------------------
    def _force(self, f, forces, g_const):
        kind = f.text("type")
        f.text("name", None)
        if kind in ("spring", "damper", "spring_damper"):
            a, b = self._two_points(f)
            diff = b - a
            d0 = diff(self.q0)
            init = float(d0[0]) if self.dim == 1 else float(np.linalg.norm(d0))
            k = f.num("stiffness", 0.0 if kind == "damper" else _REQUIRED, nonnegative=True)
            # active = true: a controlled actuator whose force loop may inject energy, so its
            # damping may be negative (stability studies); passive elements must dissipate
            active = f.flag("active", False)
            c = f.num("damping", 0.0 if kind == "spring" else _REQUIRED, nonnegative=not active)
            l0 = f.num("free_length", init)
            f.done()
            if self.dim > 1 and l0 < 0:
                raise f.error("free_length must not be negative")
            if diff.idx.size:
                forces.append(SpringDamper(f.label, diff, k, l0, c))
        elif kind == "torsional":
            if self.dim != 2:
                raise f.error("torsional springs need dimension = 2")
            bodies = f.raw("bodies")
            if not isinstance(bodies, list) or len(bodies) != 2:
                raise f.error("bodies must be [body1, body2]; use \"ground\" for the fixed frame")
            dirs = []
            for k_, bname in enumerate(bodies):
                bname = _template(str(bname), f.names, f)
                if bname == "ground":
                    gdir = f.vec("ground_direction", 2, [1.0, 0.0])
                    dirs.append(Affine.constant(gdir))
                else:
                    dirs.append(self._body_dir(self._body(f, bname)))
            k = f.num("stiffness", 0.0, nonnegative=True)
            c = f.num("damping", 0.0, nonnegative=True)
            sense_txt = f.text("sense", "ccw")
            if sense_txt not in ("ccw", "cw"):
                raise f.error("sense must be 'ccw' or 'cw'")
            sense = 1.0 if sense_txt == "ccw" else -1.0
            stacked = combine([(1.0, dirs[0]), (1.0, dirs[1])], stack=True)
            probe = TorsionalSpringDamper(f.label, stacked, k, c, 0.0, sense)
            a0 = f.num("angle0", probe.angle(self.q0) if stacked.idx.size else 0.0)
            f.done()
            if stacked.idx.size:
                forces.append(TorsionalSpringDamper(f.label, stacked, k, c, a0, sense))
        elif kind == "force":
            p = self._point_ref(f, "point")
            vec = f.vec("vector", self.dim)
            f.done()
            np.add.at(g_const, p.idx, p.C.T @ vec)
        elif kind == "follower":
            if self.dim != 2:
                raise f.error("follower forces need dimension = 2")
            body = self._body(f, f.text("body"))
            at = f.vec("at", 2)
            direction = f.vec("direction", 2)
            mag = f.num("magnitude")
            f.done()
            nd = np.linalg.norm(direction)
            if nd == 0:
                raise f.error("direction must not be zero")
            p = self._body_point(body, at)
            u = self._body_dir(body, direction / nd)
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


def _local_coordinates(builder, body, r):
    b = builder.bodies[body]
    pi, pj = b["points"]
    ri, rj = builder.point_pos[pi], builder.point_pos[pj]
    L = np.linalg.norm(rj - ri)
    e = (rj - ri) / L
    n = np.array([-e[1], e[0]])
    return np.array([(r - ri) @ e, (r - ri) @ n]) * (b["length"] / L)


# ---------------------------------------------------------------------------------------------
def _linear_case(data, name, source, base_dir, params, description, expected):
    mats = data.get("matrices")
    if not isinstance(mats, dict):
        raise CaseError("a linear case needs a [matrices] table with M, P (optional) and Q",
                        element="matrices")
    unknown = sorted(set(mats) - {"M", "P", "Q"})
    if unknown:
        raise CaseError(f"unknown matrix {unknown[0]!r} (M, P, Q)", element="matrices")
    out = {}
    for key in ("M", "Q", "P"):
        if key not in mats:
            if key == "P":
                continue
            raise CaseError(f"missing matrix {key}", element="matrices")
        out[key] = _matrix_value(mats[key], f"matrices.{key}", params, base_dir)
    n = out["M"].shape[0]
    out.setdefault("P", np.zeros((n, n)))
    for key, A in out.items():
        if A.shape != (n, n):
            raise CaseError(f"must be {n}×{n} like M, got {A.shape[0]}×{A.shape[1]}",
                            element=f"matrices.{key}")
    return LinearCase(name=name, source=source, parameters=dict(params), M=out["M"], P=out["P"],
                      Q=out["Q"], description=description, expected=expected)


def _matrix_value(value, label, params, base_dir):
    """A matrix, a {file = ...} reference, or a list of {factor, matrix|file} terms."""
    if isinstance(value, list) and value and all(isinstance(v, dict) for v in value):
        total = None
        for k, term in enumerate(value):
            f = _Fields(term, f"{label}[{k}]", params)
            factor = f.num("factor", 1.0)
            A = _matrix_value(f.raw("matrix"), f"{label}[{k}].matrix", params, base_dir)
            f.done()
            total = factor * A if total is None else total + factor * A
            if total.shape != A.shape:
                raise CaseError("terms have different shapes", element=label)
        return total
    if isinstance(value, dict):
        f = _Fields(value, label, params)
        fname = f.text("file")
        key = f.text("key", None)
        f.done()
        return _matrix_file(base_dir / fname, key, label)
    if isinstance(value, list) and value and all(isinstance(r, list) for r in value):
        width = len(value[0])
        if width == 0 or any(len(r) != width for r in value) or width != len(value):
            raise CaseError("a matrix must be a non-empty square list of rows", element=label)
        try:
            return np.array([[evaluate(x, params) for x in row] for row in value])
        except MbseigError as exc:
            raise exc.located(element=label) from None
    raise CaseError("expected a matrix (list of rows), {file = ...} or a list of terms",
                    element=label)


def _matrix_file(path, key, label):
    try:
        if path.suffix == ".npz":
            with np.load(path, allow_pickle=False) as z:
                if key is None or key not in z:
                    raise CaseError(f"{path.name} has no array {key!r} (has {', '.join(z)})",
                                    element=label)
                A = np.asarray(z[key], dtype=float)
        elif path.suffix == ".mtx":
            import scipy.io

            A = scipy.io.mmread(str(path))
            A = A.toarray() if sp.issparse(A) else np.asarray(A, dtype=float)
        else:
            raise CaseError(f"matrix files must be .npz or .mtx, got {path.name!r}", element=label)
    except OSError as exc:
        raise CaseError(f"cannot read {path}: {exc}", element=label) from None
    except ValueError as exc:
        raise CaseError(f"cannot read {path}: {exc}", element=label) from None
    if A.ndim != 2 or A.shape[0] != A.shape[1] or not np.all(np.isfinite(A)):
        raise CaseError(f"{path.name}: matrix must be square and finite", element=label)
    return A


