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
    rows, cols, vals, names, weight = [], [], [], [], []
    used = np.zeros(n, bool)
    scale = float(getattr(model, "length_scale", 1.0) or 1.0)

    def row(name, idx, coef, w):
        r = len(names)
        names.append(name)
        weight.append(w)
        rows.extend([r] * len(idx))
        cols.extend(idx)
        vals.extend(coef)

    labels = _Labels(fr, model)  # (a row's name is (frame key, suffix) until read: _Names)
    for key in fr.frames:
        members = fr.frames[key]
        for kind, head in sorted(members):
            if kind == "p":
                for a, i in sorted(fr.points[head].items()):
                    row((key, f" {a}"), [i], [1.0], 1.0)
                    used[i] = True
            elif kind == "a":
                i = fr.angles[head]
                row((key, " θ"), [i], [1.0], scale)
                used[i] = True
        triad = {head.rpartition(".")[2]: fr.vectors[head] for kind, head in members if kind == "v"}
        if set(triad) == {"u", "v", "w"} and all(len(t) == 3 for t in triad.values()):
            # δθ = ½ Σ e × δe: component a of e × δe is e_b δe_c − e_c δe_b
            for a, b, c in (("x", "y", "z"), ("y", "z", "x"), ("z", "x", "y")):
                idx, coef = [], []
                for t in triad.values():
                    idx += [t[c], t[b]]
                    coef += [0.5 * q[t[b]], -0.5 * q[t[c]]]
                row((key, f" θ{a}"), idx, coef, scale)
            for t in triad.values():
                used[list(t.values())] = True
    for i in np.flatnonzero(~used):  # the rest under their own names
        row(str(model.coordinate_names[i]), [int(i)], [1.0], 1.0)
    T = sp.csr_matrix((vals, (rows, cols)), shape=(len(names), n))
    return DisplayMap(labels.names(names), T, np.asarray(weight))


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
    D = np.abs(display.apply(full)) * display.weight[:, None]
    out = []
    for col in D.T:
        top = float(col.max(initial=0.0))
        if top == 0.0 or not np.isfinite(top):
            out.append([])
            continue
        order = np.argsort(-col, kind="stable")[:count]
        out.append([(display.names[i], float(col[i] / top)) for i in order
                    if col[i] >= MIN_SHARE * top])
    return out
