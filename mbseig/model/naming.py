"""Mode shapes in the user's terms: the displacements a person reads, named by what the case
wrote (DESIGN §6: a body and its direction, a beam station, a point, a joint), never by an
internal unit vector or node index.

A displacement δq of the natural coordinates maps linearly to

    point P (basic point, a body's origin, a beam node):  "P x", "P y", "P z"   (δr, m)
    triad of body or node B:                               "B θx", "B θy", "B θz"
                                                            δθ = ½ (u × δu + v × δv + w × δw)
    planar absolute angle of a beam node N:                "N θ"               (rad)
    any other coordinate (a 1-D mass, a modal coordinate):  its own name

(δθ is the small rotation of the triad: for δe = δθ × e on each unit vector e of an orthonormal
triad, ½ Σ e × (δθ × e) = δθ).  A point and a triad of one frame share its name.

Dominant coordinates (:func:`dominant`) compare these rows with rotations weighted by the
model's length scale (a rotation of 1 rad moves a point at that distance by as much as a
translation of that length), and name the largest.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
import scipy.sparse as sp

from .frames import CoordinateFrames

__all__ = ["DisplayMap", "display_map", "dominant"]

MIN_SHARE = 0.05  # a dominant coordinate moves at least 5 % of the largest (as the listing)
DOMINANT_BLOCK = 1 << 18  # displayed entries of a block of modes ranked at once (2 MB)


@dataclass(frozen=True, eq=False)
class DisplayMap:
    """``names`` of the displayed rows (a sequence), ``T`` (rows × n, CSR) from δq to them,
    ``weight`` per row (the length scale on rotations, 1 elsewhere) for comparing their
    sizes."""

    names: Sequence
    T: sp.csr_matrix
    weight: np.ndarray

    def apply(self, full):
        """The displayed displacements of full-coordinate vectors (columns)."""
        return self.T @ full


def display_map(model, q) -> DisplayMap:
    """The :class:`DisplayMap` of ``model`` at the configuration ``q`` (module docstring)."""
    n = model.n
    kinds = getattr(model, "coordinate_kinds", ()) or ()
    if len(kinds) != n:  # no structure (a linear case): the coordinates themselves
        names = tuple(model.coordinate_names)
        return DisplayMap(names, sp.identity(n, format="csr"), np.ones(n))
    fr = CoordinateFrames(model)
    names, weight = [], []  # per row: (frame key, suffix) or a name; its weight
    one_row, one_col = [], []  # rows of one coordinate (a point's axis, an angle, the rest)
    triad_row, triad_idx = [], []  # a triad's first row (θx; θy, θz follow), its u, v, w x y z
    scale = float(getattr(model, "length_scale", 1.0) or 1.0)
    labels = _Labels(fr, model)  # (a row's name is (frame key, suffix) until read: _Names)
    for key in fr.frames:
        members = fr.frames[key]
        for kind, head in sorted(members):
            if kind == "p":
                for a, i in sorted(fr.points[head].items()):
                    one_row.append(len(names))
                    one_col.append(i)
                    names.append((key, _AXIS[a]))
                    weight.append(1.0)
            elif kind == "a":
                one_row.append(len(names))
                one_col.append(fr.angles[head])
                names.append((key, " θ"))
                weight.append(scale)
        triad = {head.rpartition(".")[2]: fr.vectors[head] for kind, head in members if kind == "v"}
        if set(triad) == {"u", "v", "w"} and all(len(t) == 3 for t in triad.values()):
            triad_row.append(len(names))
            triad_idx.extend(triad[e][a] for e in "uvw" for a in "xyz")
            names.extend((key, sfx) for sfx in _ROTATION)
            weight.extend((scale, scale, scale))
    used = np.zeros(n, bool)
    used[np.asarray(one_col, np.intp)] = True
    used[np.asarray(triad_idx, np.intp)] = True
    for i in np.flatnonzero(~used):  # the rest under their own names
        one_row.append(len(names))
        one_col.append(int(i))
        names.append(str(model.coordinate_names[i]))
        weight.append(1.0)
    rows, cols, vals = _triad_rows(np.asarray(triad_row, np.intp),
                                   np.asarray(triad_idx, np.intp).reshape(-1, 3, 3), q)
    T = sp.csr_matrix((np.concatenate([np.ones(len(one_row)), vals]),
                       (np.concatenate([np.asarray(one_row, np.intp), rows]),
                        np.concatenate([np.asarray(one_col, np.intp), cols]))),
                      shape=(len(names), n))
    return DisplayMap(labels.names(names), T, np.asarray(weight))


_AXIS = {"x": " x", "y": " y", "z": " z"}  # (one string per suffix, shared by the rows)
_ROTATION = (" θx", " θy", " θz")


def _triad_rows(first, idx, q):
    """(rows, cols, values) of the rotation rows of every triad at once: δθ = ½ Σ e × δe over
    e = u, v, w, whose component a is ½ Σ (e_b δe_c − e_c δe_b) ((a, b, c) cyclic).  ``first``:
    each triad's θx row; ``idx`` (k × 3 × 3): the coordinates of its u, v, w by x, y, z."""
    if not first.size:
        return np.zeros(0, np.intp), np.zeros(0, np.intp), np.zeros(0)
    rows, cols, vals = [], [], []
    for a, (b, c) in enumerate(((1, 2), (2, 0), (0, 1))):
        ib, ic = idx[:, :, b], idx[:, :, c]  # (k, 3): per vector
        rows.append(np.repeat(first + a, 6))
        cols.append(np.stack([ic, ib], axis=2).reshape(-1))
        vals.append(np.stack([0.5 * q[ib], -0.5 * q[ic]], axis=2).reshape(-1))
    return np.concatenate(rows), np.concatenate(cols), np.concatenate(vals)


class _Labels:
    """The frames' labels (:meth:`CoordinateFrames.frame_label`), each made when a name that
    uses it is first read: a listing reads the few rows its modes move most, and a beam model
    has thousands of nodes."""

    def __init__(self, fr, model):
        self._fr, self._model, self._known = fr, model, {}

    def label(self, key):
        got = self._known.get(key)
        if got is None:
            got = self._known[key] = self._fr.frame_label(self._model, key)
        return got

    def names(self, parts):
        return _Names(self, tuple(parts))


class _Names(Sequence):
    """The display map's row names: (frame key, suffix) parts named on first read."""

    def __init__(self, labels, parts):
        self._labels, self._parts = labels, parts

    def __len__(self):
        return len(self._parts)

    def __getitem__(self, i):
        if isinstance(i, slice):
            return tuple(self[k] for k in range(*i.indices(len(self))))
        part = self._parts[i]
        if isinstance(part, str):
            return part
        return self._labels.label(part[0]) + part[1]

    def __eq__(self, other):
        return isinstance(other, Sequence) and tuple(self) == tuple(other)

    __hash__ = None


def dominant(display: DisplayMap, full, count=3):
    """Per column of ``full`` (full-coordinate mode shapes): the ``count`` displayed rows that
    move most, as [(name, size relative to the largest)], those of at least ``MIN_SHARE``."""
    out = []
    step = max(1, DOMINANT_BLOCK // max(display.T.shape[0], 1))
    for c0 in range(0, full.shape[1], step):  # (a block of modes at a time: a model of 10⁵
        D = np.abs(display.apply(full[:, c0:c0 + step]))  # coordinates holds no copy of all)
        D *= display.weight[:, None]
        for col in D.T:
            top = float(col.max(initial=0.0))
            if top == 0.0 or not np.isfinite(top):
                out.append([])
                continue
            order = np.argsort(-col, kind="stable")[:count]
            out.append([(display.names[i], float(col[i] / top)) for i in order
                        if col[i] >= MIN_SHARE * top])
    return out
