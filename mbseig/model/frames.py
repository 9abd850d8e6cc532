"""The natural coordinates of a model grouped as a person sees them: points (a component index
per axis), unit vectors, planar absolute angles, and frames (a body or a beam node: its triad
and origin point; a lone point), with the name a user wrote for each frame.

Coordinates are named by the reader (:mod:`mbseig.model.assembly`): a point ``P.x``, a unit
vector ``B.u.x`` (``B.v``, ``B.w``: the triad of body or node B), a planar angle ``N.theta``;
their kinds (length, direction, angle, modal) are recorded.  A beam node ``BEAM.n<k>`` is named
by its station (``BEAM.NAME``, DESIGN §8) or its arc length (``BEAM at s = 0.25 m``), never by
its index (an end node without a station: by the beam's end point, ``BEAM at P``).
"""

from __future__ import annotations

import re
from collections.abc import Mapping

import numpy as np

__all__ = ["CoordinateFrames", "rotate"]

_NODE = re.compile(r"^(?P<beam>.+)\.n(?P<k>\d+)$")


class _Axes(Mapping):
    """axis ("x", "y", "z") → coordinate index of one point or unit vector, for the axes it
    has: a mapping without a dict's size (a beam model of 10⁵ DOF has 68,000 of them;
    a dict of three costs 184 bytes, this 48).  Iterated in the order x, y, z."""

    __slots__ = ("x", "y", "z")

    def __init__(self):
        self.x = self.y = self.z = -1

    def _at(self, a):
        return self.x if a == "x" else self.y if a == "y" else self.z if a == "z" else -1

    def __getitem__(self, a):
        i = self._at(a)
        if i < 0:
            raise KeyError(a)
        return i

    def __iter__(self):
        return (a for a in "xyz" if self._at(a) >= 0)

    def __len__(self):
        return (self.x >= 0) + (self.y >= 0) + (self.z >= 0)

    def __repr__(self):
        return repr(dict(self))


_XYZ = ("x", "y", "z")


def _axes(table, head):
    got = table.get(head)
    if got is None:
        got = table[head] = _Axes()
    return got


class CoordinateFrames:
    """The model's coordinates grouped: points and unit vectors (component index per axis),
    planar absolute angles, and frames (a body or node: its triad and origin; a lone point)."""

    def __init__(self, model):
        self.dim = int(getattr(model, "dimension", 3) or 3)
        self.n = model.n
        self.points, self.vectors, self.angles = {}, {}, {}
        for i, (nm, kind) in enumerate(zip(model.coordinate_names, model.coordinate_kinds,
                                             strict=True)):
            head, _, axis = nm.rpartition(".")
            if kind == "length" and axis in _XYZ:
                setattr(_axes(self.points, head), axis, i)
            elif kind == "direction" and axis in _XYZ:
                setattr(_axes(self.vectors, head), axis, i)
            elif kind == "angle":
                self.angles[head] = i
        frames = {}
        for head in self.vectors:
            frames.setdefault(head.rpartition(".")[0] or head, set()).add(("v", head))
        for head in self.points:
            frames.setdefault(head, set()).add(("p", head))
        for head in self.angles:
            frames.setdefault(head, set()).add(("a", head))
        self.frames = frames

    def indices(self, members):
        out = []
        for kind, head in members:
            src = {"p": self.points, "v": self.vectors}.get(kind)
            out.extend(src[head].values() if src is not None else [self.angles[head]])
        return np.array(sorted(out), dtype=int)

    def generators(self, members, q):
        """(G, rots, labels): the part's rigid-motion generators as columns of G (n × g), the
        rotation part of each (None for a translation; else (axis, I): I the t × 3 indices of
        the part's points and unit vectors, −1 where a component is absent: see
        :func:`rotate`), and what each is."""
        pts = [self.points[h] for k, h in sorted(members) if k == "p"]
        vecs = [self.vectors[h] for k, h in sorted(members) if k == "v"]
        angs = [self.angles[h] for k, h in sorted(members) if k == "a"]
        axes = "xyz"[: self.dim]
        cols, rots, labels = [], [], []

        def triad(t):
            return [t.get(a, -1) for a in "xyz"]

        P = np.array([triad(p) for p in pts], int).reshape(-1, 3)
        V = np.array([triad(v) for v in vecs], int).reshape(-1, 3)
        if pts:
            centre = {a: float(np.mean(q[P[P[:, k] >= 0, k]])) if (P[:, k] >= 0).any() else 0.0
                      for k, a in enumerate(axes)}
        else:
            centre = dict.fromkeys(axes, 0.0)
        for k, a in enumerate(axes):  # translations
            g = np.zeros(self.n)
            g[P[P[:, k] >= 0, k]] = 1.0
            cols.append(g), rots.append(None), labels.append(("t", a, centre))
        ix = np.vstack([P, V])
        c = np.array([centre.get(a, 0.0) for a in "xyz"])
        R = np.where(ix >= 0, q[np.maximum(ix, 0)], 0.0)
        R[: len(P)] -= np.where(P >= 0, c, 0.0)  # points about the centroid, vectors as they are
        rot_axes = "xyz" if self.dim == 3 else ("z" if self.dim == 2 else "")
        for w in rot_axes:  # rotations about the centroid
            k = "xyz".index(w)
            g = np.zeros(self.n)
            _scatter(g, ix, _cross_axis(k, R))
            g[angs] = 1.0
            cols.append(g), rots.append((k, ix))
            labels.append(("r", w, centre if pts else None))
        G = np.column_stack(cols) if cols else np.zeros((self.n, 0))
        keep = np.flatnonzero(np.abs(G).max(axis=0) > 0)
        return G[:, keep], [rots[k] for k in keep], [labels[k] for k in keep]

    def frame_label(self, model, key):
        """The name a user wrote for frame (or point) ``key``: a beam node by its station or
        arc length, anything else as it is."""
        m = _NODE.match(key)
        beams = ((model.flexible or {}).get("bodies") or {})
        rec = beams.get(m["beam"]) if m else None
        if rec is None or "nodes" not in rec:
            return key
        k = int(m["k"])
        s = self._arc_length(model, rec, k)
        if s is None:
            return f"{m['beam']} node {k + 1} of {len(rec['nodes'])}"
        name = self._station_at(rec, s)
        if name is not None:
            return f"{m['beam']}.{name}"
        pts = rec.get("points") or []
        if pts and k in (0, len(rec["nodes"]) - 1):  # an end: the point the case names
            return f"{m['beam']} at {pts[0] if k == 0 else pts[-1]}"
        return f"{m['beam']} at s = {s:.4g} m"

    def _station_at(self, rec, s):
        """The first station (in the case's order) within 1e-9 · max(1, L) of arc length s, or
        None (the stations sorted once per beam record)."""
        stations = rec.get("stations") or {}
        if not stations:
            return None
        kept = self.__dict__.setdefault("_stations", {})
        hit = kept.get(id(rec))
        if hit is None or hit[0] is not rec:
            names = list(stations)
            at = np.array([stations[nm] for nm in names], float)
            order = np.argsort(at, kind="stable")
            hit = kept[id(rec)] = (rec, at[order], order, names)
        _, at, order, names = hit
        tol = 1e-9 * max(1.0, float(rec.get("length", 1.0)))
        lo, hi = np.searchsorted(at, s - tol, "left"), np.searchsorted(at, s + tol, "right")
        near = [int(order[j]) for j in range(lo, hi) if abs(at[j] - s) <= tol]
        return names[min(near)] if near else None

    def _arc_length(self, model, rec, k):
        """Arc length of node k of a straight beam in its reference configuration: the distance
        of the node's point from the start point (end nodes: the beam's own points)."""
        nodes, pts = rec["nodes"], rec.get("points") or []
        head = nodes[k]
        q = model.q_init

        def pos(name):
            p = self.points.get(name)
            if p is None:
                return None
            return np.array([q[p[a]] if a in p else 0.0 for a in "xyz"])

        start = pos(pts[0]) if pts else None
        here = pos(head)
        if here is None and pts:
            here = pos(pts[0]) if k == 0 else pos(pts[-1]) if k == len(nodes) - 1 else None
        if start is None or here is None:
            if k == 0:
                return 0.0
            return float(rec["length"]) if k == len(nodes) - 1 and "length" in rec else None
        return float(np.linalg.norm(here - start))


def _cross_axis(k, R):
    """e_k × r for every row r of R (…, t, 3)."""
    out = np.zeros_like(R)
    i, j = (k + 1) % 3, (k + 2) % 3
    out[..., j] = R[..., i]
    out[..., i] = -R[..., j]
    return out


def _scatter(out, ix, values):
    ok = ix >= 0
    out[ix[ok]] = values[ok]


def rotate(rot, v):
    """W v: the rotation part of a generator (:meth:`CoordinateFrames.generators`) applied to
    a full vector (zero for a translation)."""
    out = np.zeros_like(v)
    if rot is None:
        return out
    k, ix = rot
    _scatter(out, ix, _cross_axis(k, np.where(ix >= 0, v[np.maximum(ix, 0)], 0.0)))
    return out
