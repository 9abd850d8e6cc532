"""Vectorized expansion of repeated case elements (``repeat = {i = [first, last]}``).

Repeated points, point masses and spring/damper elements are expanded for all values of the
index at once: each expression is parsed once and evaluated on a numpy array of index values
(the whitelist of :mod:`mbseig.casefile.expr`, walked by the same code with numpy functions), each
name template is formatted once per member, and springs become one
:class:`~mbseig.model.batched.SpringDamperSet`.

Anything unusual (an unknown field, a value outside the number rule, a name that clashes, a point
that is a body marker, an ``enabled`` or ``name`` field, ...) makes the batch decline, and the
element is expanded one member at a time by :mod:`mbseig.casefile.builder`, which then reports
the precise error. The batch path therefore changes speed, never results or messages.
"""

from __future__ import annotations

import ast
import re
from collections.abc import Mapping

import numpy as np

from ..errors import ExpressionError
from ..model.affine import Affine
from ..model.batched import SpringDamperSet
from .expr import Dialect, parse, walk
from .fields import in_range

__all__ = ["Batcher", "vector_evaluate", "vector_template", "repeated_fields", "LazyPoints"]

_TEMPLATE = re.compile(r"\{([^{}]*)\}")
_FUNCS = {
    "sqrt": np.sqrt, "sin": np.sin, "cos": np.cos, "tan": np.tan, "asin": np.arcsin,
    "acos": np.arccos, "atan": np.arctan, "atan2": np.arctan2, "exp": np.exp, "log": np.log,
    "abs": np.abs, "deg": np.radians,
    "min": lambda *a: np.minimum.reduce(np.broadcast_arrays(*a)),
    "max": lambda *a: np.maximum.reduce(np.broadcast_arrays(*a)),
}
_BIN = {ast.Add: np.add, ast.Sub: np.subtract, ast.Mult: np.multiply, ast.Div: np.divide,
        ast.Pow: np.power, ast.Mod: np.mod}


class _Decline(Exception):
    """The batch path does not handle this element; expand it member by member."""


_VECTOR = Dialect(_FUNCS, _BIN, lambda message: _Decline())


def vector_evaluate(value, names, var, ivals):
    """Values of a number or expression for every index value (array), or raise _Decline."""
    if isinstance(value, bool):
        raise _Decline
    if isinstance(value, (int, float)):
        out = np.full(ivals.size, float(value))
    elif isinstance(value, str):
        try:
            tree = parse(value)
            with np.errstate(all="ignore"):
                out = np.broadcast_to(np.asarray(walk(tree, {**names, var: ivals}, value, _VECTOR),
                                                 float), ivals.shape).copy()
        except (ExpressionError, ArithmeticError, ValueError, TypeError):
            raise _Decline from None
    else:
        raise _Decline
    if not (np.all(np.isfinite(out)) and in_range(out)):
        raise _Decline  # the member-by-member path names the member and the rule
    return out


def vector_template(text, names, var, ivals):
    """``"m{i + 1}"`` for every index value: a list of strings (integers only), or _Decline."""
    if not isinstance(text, str):
        raise _Decline
    parts = _TEMPLATE.split(text)
    if len(parts) == 1:
        return [text] * ivals.size
    cols = []
    for k, part in enumerate(parts):
        if k % 2 == 0:
            cols.append([part] * ivals.size if part else None)
            continue
        v = vector_evaluate(part, names, var, ivals)
        if not np.all(v == np.round(v)) or np.any(np.abs(v) > 1e15):
            raise _Decline
        cols.append(list(map(str, v.astype(np.int64).tolist())))
    if len(parts) == 3:  # one placeholder: "prefix{expr}suffix"
        pre, suf = parts[0], parts[2]
        return [pre + s + suf for s in cols[1]]
    cols = [c for c in cols if c is not None]
    return ["".join(t) for t in zip(*cols, strict=True)] if len(cols) > 1 else cols[0]


def repeated_fields(item, kinds, var, ivals, params, optional=()):
    """The fields of a repeated element for every index value at once, or None (the element is
    then read member by member, which reports any problem).  ``kinds`` maps each allowed key to
    ``"name"`` (a name template), ``"names"`` (a list of templates), 0 (a number), a size
    (a list of that many numbers) or None (left to the caller); keys in ``optional`` may be absent,
    any other key declines."""
    if "enabled" in item or set(item) - {*kinds, "repeat"} or ivals.size == 0:
        return None
    out = {}
    try:
        for key, kind in kinds.items():
            if key not in item:
                if key in optional:
                    continue
                return None
            value = item[key]
            if kind is None:  # read by the caller (a type)
                continue
            if kind == "name":
                out[key] = vector_template(value, params, var, ivals)
            elif kind == "names":
                if not isinstance(value, list):
                    return None
                out[key] = [vector_template(v, params, var, ivals) for v in value]
            elif kind == 0:
                out[key] = vector_evaluate(value, params, var, ivals)
            elif isinstance(value, list) and len(value) == kind:
                out[key] = np.column_stack([vector_evaluate(v, params, var, ivals)
                                            for v in value])
            else:
                return None
    except _Decline:
        return None
    return out


class LazyPoints(Mapping):
    """name → :class:`Affine` of every basic point and marker, built on first access."""

    def __init__(self, index, positions, markers):
        self._index, self._pos, self._markers, self._cache = index, positions, dict(markers), {}

    def __getitem__(self, name):
        if name in self._markers:
            return self._markers[name]
        a = self._cache.get(name)
        if a is None:
            if name not in self._index:
                raise KeyError(name)
            a = self._cache[name] = Affine.select(self._index[name], self._pos[name])
        return a

    def __iter__(self):
        yield from self._index
        yield from (m for m in self._markers if m not in self._index)

    def __len__(self):
        return len(self._index) + sum(1 for m in self._markers if m not in self._index)


class Batcher:
    """Callbacks for :func:`mbseig.casefile.fields.expand`: ``batch(section, item, label, var,
    ivals, params) -> bool`` (True when the whole repeated element was added)."""

    def __init__(self, builder):
        self.b = builder
        self.mass_rows: list[np.ndarray] = []
        self.mass_vals: list[np.ndarray] = []
        self.g_const = None
        self.gravity = None
        self.forces = None
        self._rows: dict[str, int] = {}  # point name → row of the index/position tables
        self._idx_chunks, self._pos_chunks, self._n_rows, self._tables = [], [], 0, None

    def bind(self, g_const, forces, gravity):
        self.g_const, self.forces, self.gravity = g_const, forces, gravity

    def __call__(self, section, item, label, var, ivals, params):
        handler = {"points": self._points, "masses": self._masses,
                   "forces": self._forces}.get(section)
        if (handler is None or ivals.size == 0 or "enabled" in item
                or "name" in item and section != "points"):
            return False
        try:
            handler(item, label, var, ivals, params)
        except _Decline:
            return False
        return True

    def mass_coo(self):
        if not self.mass_rows:
            return np.zeros(0, np.intp), np.zeros(0)
        return np.concatenate(self.mass_rows), np.concatenate(self.mass_vals)

    # -- sections --------------------------------------------------------------------------
    def _points(self, item, label, var, ivals, params):
        b = self.b
        if set(item) - {"name", "position", "fixed", "repeat"}:
            raise _Decline
        names = vector_template(item.get("name"), params, var, ivals)
        pos_t = item.get("position")
        fixed = item.get("fixed", False)
        if not isinstance(pos_t, list) or len(pos_t) != b.dim or not isinstance(fixed, bool):
            raise _Decline
        pos = np.column_stack([vector_evaluate(v, params, var, ivals) for v in pos_t])
        if len(set(names)) != len(names) or any("." in nm or nm in b.point_index for nm in names):
            raise _Decline
        nb, dim = pos.shape
        if fixed:
            idx = np.full((nb, dim), -1, dtype=np.intp)
        else:
            axes = "xyz"[:dim]
            idx = b.assembly.coordinates([f"{nm}.{ax}" for nm in names for ax in axes],
                                         pos.ravel().tolist(), "length").reshape(nb, dim)
        b.point_index.update(zip(names, idx, strict=True))
        b.point_pos.update(zip(names, pos, strict=True))
        self._register(names, idx, pos)

    def _register(self, names, idx, pos):
        start = self._n_rows
        self._rows.update(zip(names, range(start, start + len(names)), strict=True))
        self._idx_chunks.append(np.asarray(idx, np.intp).reshape(len(names), -1))
        self._pos_chunks.append(np.asarray(pos, float).reshape(len(names), -1))
        self._n_rows += len(names)
        self._tables = None

    def _point_rows(self, refs, params, var, ivals):
        """(idx, pos) arrays (nb, dim) of templated basic-point names."""
        b = self.b
        names = vector_template(refs, params, var, ivals)
        missing = [nm for nm in set(names) if nm not in self._rows]
        if missing:  # points added one at a time by the builder
            if any(nm not in b.point_index for nm in missing):
                raise _Decline
            self._register(missing, [b.point_index[nm] for nm in missing],
                           [b.point_pos[nm] for nm in missing])
        if self._tables is None:
            self._tables = (np.concatenate(self._idx_chunks), np.concatenate(self._pos_chunks))
        rows = np.fromiter(map(self._rows.__getitem__, names), dtype=np.intp, count=len(names))
        return self._tables[0][rows], self._tables[1][rows]

    def _masses(self, item, label, var, ivals, params):
        if set(item) - {"point", "mass", "repeat"}:
            raise _Decline
        idx, _ = self._point_rows(item.get("point"), params, var, ivals)
        m = vector_evaluate(item.get("mass"), params, var, ivals)
        if not np.all(m > 0):
            raise _Decline
        mm = np.broadcast_to(m[:, None], idx.shape)
        ok = idx >= 0
        self.mass_rows.append(idx[ok])
        self.mass_vals.append(mm[ok])
        if self.gravity is not None:
            np.add.at(self.g_const, idx[ok], (mm * self.gravity[None, :])[ok])

    def _forces(self, item, label, var, ivals, params):
        kind = item.get("type")
        if kind == "bushing":  # spatial bushings (spatial_readers); a planar builder declines
            if not self.b.bushings(item, label, var, ivals, params, self.forces):
                raise _Decline
            return
        if kind not in ("spring", "damper", "spring_damper"):
            raise _Decline
        if set(item) - {"type", "points", "stiffness", "damping", "free_length", "repeat"}:
            raise _Decline
        pts = item.get("points")
        if not isinstance(pts, list) or len(pts) != 2:
            raise _Decline
        ia, pa = self._point_rows(pts[0], params, var, ivals)
        ib, pb = self._point_rows(pts[1], params, var, ivals)

        def num(key, default):
            if key not in item:
                if default is None:
                    raise _Decline
                return np.full(ivals.size, default)
            v = vector_evaluate(item[key], params, var, ivals)
            if not np.all(v >= 0):
                raise _Decline
            return v

        k = num("stiffness", 0.0 if kind == "damper" else None)
        c = num("damping", 0.0 if kind == "spring" else None)
        d0 = pb - pa
        init = d0[:, 0] if self.b.dim == 1 else np.linalg.norm(d0, axis=1)
        if "free_length" in item:
            l0 = vector_evaluate(item["free_length"], params, var, ivals)
        else:
            l0 = init
        if self.b.dim > 1 and np.any(l0 < 0):
            raise _Decline
        live = np.any(ia >= 0, axis=1) | np.any(ib >= 0, axis=1)
        sel = np.flatnonzero(live)
        labels = _Labels(label, var, ivals[sel].astype(np.int64))
        self.forces.append(SpringDamperSet(label, ia[sel], ib[sel], pa[sel], pb[sel], k[sel],
                                           np.asarray(l0, float)[sel], c[sel], labels))


class _Labels:
    """Element labels ``forces[1] (i=7)`` of a batch, formatted on demand."""

    def __init__(self, label, var, ivals):
        self.label, self.var, self.ivals = label, var, ivals

    def __len__(self):
        return self.ivals.size

    def __getitem__(self, k):
        return f"{self.label} ({self.var}={int(self.ivals[k])})"
