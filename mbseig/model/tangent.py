"""A local, exact basis of the constraints' null space: the node and body triads eliminated by
their known tangent space, the other constraints component by component (docs/beams3d.md,
"Lean flexible models").

A spatial rigid body and a 3-D beam node carry a point r and three unit vectors u, v, w with
six conditions (u·u = v·v = w·w = 1, u·v = v·w = w·u = 0).  Where they hold, the tangent space of
the conditions is known exactly: a translation δr and a small rotation θ,

    δu = θ × u,   δv = θ × v,   δw = θ × w,

so the nine triad coordinates of a frame are replaced by the three columns (eᵢ × u, eᵢ × v,
eᵢ × w)/√2 (i = x, y, z).  Those columns are orthonormal (Σ_k (eᵢ × k)·(eⱼ × k) = 2δᵢⱼ for an
orthonormal triad), so the map T (n × n_t: these columns for every triad, a unit column for every
other coordinate) is orthonormal and Φ_triad,q T = 0 exactly, with no decomposition at all.

The other rows (joints, welds, drivers, fixed points) in those columns, G = Φ_other,q T, are
sparse and couple few columns each.  They split into connected components (rows sharing a
column); each component of at most :data:`LOCAL_MAX` columns gets the orthonormal basis of its
own null space that is closest to its coordinate directions (the polar factor of mbseig.linear's
"Null-space basis", here per component), and its rank is counted with the relative threshold
``rank_tol`` · (largest singular value over the components).  A column no row touches keeps its
unit column.  N = T · blockdiag(components, identity) is orthonormal, sparse and local: for a
model of beams it is the standard finite-element basis (a translation and a rotation per node),
so Nᵀ M N and Nᵀ K N are the FE matrices plus the joints.  A component larger than
:data:`LOCAL_MAX` columns (a long closed chain) is not decomposed: its rows stay in the
bordered pencil of the partial path, in the columns of N (``kept``).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import scipy.sparse as sp
from scipy.sparse.csgraph import connected_components

from ..numerics import closest_basis

__all__ = ["LOCAL_MAX", "LocalBasis", "local_basis", "triad_coordinates"]

#: columns of a constraint component whose null space is taken by its own dense SVD; a larger
#: component stays in the bordered pencil (an SVD there would cost as one of the whole Jacobian)
LOCAL_MAX = 600
#: columns of T up to which the joints are eliminated together by one dense SVD (:func:`_small`:
#: below it finding components costs more than the SVD: 0.36 against 1.3 ms, 21 coordinates)
SMALL_DENSE = 200
_HALF = np.sqrt(0.5)


@dataclass(frozen=True, eq=False)
class LocalBasis:
    """N (n × d, orthonormal) with Φ_q N = 0 on the eliminated rows, and what is left.

    basis : N as found (CSR; a dense array for a small model, :func:`_small`), read as CSR by
    :attr:`N` and as an array by :meth:`dense`; rank : the rank eliminated (6 per triad plus
    each component's rank); kept : the remaining rows in the columns of N (CSR, None when none
    is left) and ``kept_rows`` their row indices in Φ_q; triads, components, largest : counts
    for the record (the largest component's columns)."""

    basis: object
    rank: int
    kept: object
    kept_rows: np.ndarray
    triads: int
    components: int
    largest: int

    @property
    def N(self) -> sp.csr_matrix:
        got = self.__dict__.get("_csr")
        if got is None:
            got = self.basis if sp.issparse(self.basis) else sp.csr_matrix(self.basis)
            object.__setattr__(self, "_csr", got)
        return got

    def dense(self) -> np.ndarray:
        return self.basis.toarray() if sp.issparse(self.basis) else self.basis

    @property
    def small(self) -> bool:
        """Whether N was found dense (a small model)."""
        return not sp.issparse(self.basis)

    @property
    def record(self) -> dict:
        return {"basis": "local", "triads": self.triads, "components": self.components,
                "largest_component": self.largest,
                "bordered_rows": int(self.kept_rows.size)}


def triad_coordinates(model):
    """(rows, coords): the constraint rows (k × 6) of every frame's triad conditions whose nine
    vector coordinates are free coordinates of that frame alone (k × 9: u, v, w each x, y, z),
    found from the constraints' role ("triad", …); other triads (none in mbseig's builders) are
    left with the other constraints.  Found once per model (the model's structure)."""
    kept = model.__dict__.get("_triads")
    if kept is None or kept[0] is not model.constraints:
        kept = (model.constraints, _triads(model))
        model.__dict__["_triads"] = kept
    return kept[1]


def _triads(model):
    rows, coords, seen = [], [], set()
    off = 0
    for c in model.constraints:
        n_eq = c.n_eq
        if c.role and c.role[0] == "triad" and n_eq == 6:
            idx = _selected(c.aff)
            if idx is not None and not seen.intersection(idx.tolist()):
                seen.update(idx.tolist())
                rows.append(np.arange(off, off + 6))
                coords.append(idx)
        off += n_eq
    if not rows:
        return np.zeros((0, 6), np.intp), np.zeros((0, 9), np.intp)
    return np.array(rows, np.intp), np.array(coords, np.intp)


_FRAME_TRIAD = np.eye(12)[3:]  # the triad rows of a frame map on the frame's 12 coordinates


def _selected(aff):
    """The nine coordinate indices of a frame map's triad rows (rows 3–11) where those rows
    select distinct coordinates with unit weight and no offset; None otherwise."""
    C, d = aff.C[3:], aff.d[3:]
    if C.shape[0] != 9 or np.any(d != 0):
        return None
    if C.shape[1] == 12 and np.array_equal(C, _FRAME_TRIAD):  # a frame's own coordinates
        return np.asarray(aff.idx, np.intp)[3:]
    nz = C != 0
    if not np.all(nz.sum(axis=1) == 1):
        return None
    cols = np.argmax(nz, axis=1)
    if np.any(C[np.arange(9), cols] != 1.0) or np.unique(cols).size != 9:
        return None
    if np.any(nz[:, cols].sum(axis=0) != 1) or nz.sum() != 9:
        return None
    return np.asarray(aff.idx, np.intp)[cols]


def tangent_map(n, coords, q, *, dense=False):
    """T (n × n_t, CSR; an array with ``dense``) of the module docstring: its columns in the
    order of the coordinates, each triad's three rotations at its u.x."""
    k = coords.shape[0]
    plain, col_of = _layout(n, coords)
    n_t = col_of.size
    rows = [plain]
    cols = [col_of[:plain.size]]
    vals = [np.ones(plain.size)]
    if k:
        E = q[coords].reshape(k, 3, 3) * _HALF  # [triad, vector (u v w), component]
        x, y, z = E[..., 0], E[..., 1], E[..., 2]
        zero = np.zeros_like(x)
        rc = col_of[plain.size:].reshape(k, 3)
        # θ = eᵢ: δe = eᵢ × e for each of u, v, w (e_x × e = (0, −e_z, e_y), and so on)
        for i, D in enumerate((np.stack([zero, -z, y], axis=-1),
                               np.stack([z, zero, -x], axis=-1),
                               np.stack([-y, x, zero], axis=-1))):
            rows.append(coords.ravel())
            cols.append(np.repeat(rc[:, i], 9))
            vals.append(D.reshape(-1))
    r, c, v = np.concatenate(rows), np.concatenate(cols), np.concatenate(vals)
    if dense:
        T = np.zeros((n, n_t))
        T[r, c] = v  # (one entry per pair)
        return T
    T = sp.csr_matrix((v, (r, c)), shape=(n, n_t))
    T.eliminate_zeros()
    return T


def _layout(n, coords):
    """(the coordinates outside every triad, the column of each of them and then of each
    triad's three rotations): coordinates in their order, a triad's rotations at its u.x."""
    k = coords.shape[0]
    in_triad = np.zeros(n, bool)
    in_triad[coords.ravel()] = True
    plain = np.flatnonzero(~in_triad)
    anchor = np.concatenate([plain, np.repeat(coords[:, 0], 3)])
    sub = np.concatenate([np.zeros(plain.size), np.tile([0.0, 1.0, 2.0], k)])
    order = np.lexsort((sub, anchor))
    col_of = np.empty(order.size, np.intp)
    col_of[order] = np.arange(order.size)
    return plain, col_of


def local_basis(model, q, rank_tol, *, local_max=LOCAL_MAX) -> LocalBasis:
    """The :class:`LocalBasis` of ``model`` at ``q`` (module docstring); the last one is kept on
    the model (the statics' rank and the linearization ask at the same q)."""
    q = np.asarray(q, float)
    key = (q.tobytes(), float(rank_tol), int(local_max))
    kept = model.__dict__.get("_local_basis")
    if kept is not None and kept[0] == key and kept[1] is model.constraints:
        return kept[2]
    got = _local_basis(model, q, rank_tol, local_max)
    model.__dict__["_local_basis"] = (key, model.constraints, got)
    return got


def _local_basis(model, q, rank_tol, local_max):
    n = model.n
    trows, coords = triad_coordinates(model)
    m = model.n_constraints
    keep = np.ones(m, bool)
    keep[trows.ravel()] = False
    other = np.flatnonzero(keep)
    if n - 6 * coords.shape[0] <= min(SMALL_DENSE, local_max):  # all of it one component
        return _small(model, q, rank_tol, tangent_map(n, coords, q, dense=True), other,
                      coords.shape[0])
    T = tangent_map(n, coords, q)
    n_t = T.shape[1]
    if other.size == 0:
        return LocalBasis(T, 6 * coords.shape[0], None, other, coords.shape[0], 0, 0)
    G = (model.phi_q(q)[other] @ T).tocsr()
    G.eliminate_zeros()
    pattern = abs(G).astype(bool).astype(np.int8)
    m2 = G.shape[0]
    graph = sp.bmat([[None, pattern], [pattern.T, None]], format="csr")
    n_comp, label = connected_components(graph, directed=False)
    row_lab, col_lab = label[:m2], label[m2:]
    touched = np.unique(row_lab)
    cols_of = _groups(col_lab, n_comp)
    rows_of = _groups(row_lab, n_comp)
    blocks, kept, largest = [], [], 0
    for c in touched:
        cc, rr = cols_of[c], rows_of[c]
        largest = max(largest, cc.size)
        if cc.size > local_max:
            kept.append(rr)
            continue
        blocks.append((rr, cc, np.linalg.svd(G[rr][:, cc].toarray(), full_matrices=True)))
    sigma_ref = max((b[2][1][0] for b in blocks if b[2][1].size), default=0.0)
    vals_n = []
    done = np.zeros(n_t, bool)
    rank = 6 * coords.shape[0]
    for _rr, cc, (_u, s, vt) in blocks:
        r = int(np.sum(s > rank_tol * sigma_ref)) if sigma_ref > 0 else 0
        rank += r
        done[cc] = True
        if vt.shape[0] > r:
            vals_n.append((_closest(vt[r:].T), cc))  # orthonormal null space of the component
    # assemble N2: identity for untouched (and kept) columns, the components' bases
    free = np.flatnonzero(~done)
    data, ri, ci = [np.ones(free.size)], [free], [np.arange(free.size)]
    next_col = free.size
    for Z, cc in vals_n:
        rr_, jj = np.nonzero(Z)
        data.append(Z[rr_, jj])
        ri.append(cc[rr_])
        ci.append(jj + next_col)
        next_col += Z.shape[1]
    # columns in the order of the coordinate each stands at (a component's at its first column)
    anchors = np.concatenate([free] + [np.full(Z.shape[1], cc.min()) for Z, cc in vals_n])
    sub = np.concatenate([np.zeros(free.size)] + [np.arange(Z.shape[1]) for Z, _ in vals_n])
    order = np.lexsort((sub, anchors))
    new = np.empty(next_col, np.intp)
    new[order] = np.arange(next_col)
    N2 = sp.csr_matrix((np.concatenate(data), (np.concatenate(ri), new[np.concatenate(ci)])),
                       shape=(n_t, next_col))
    N = (T @ N2).tocsr()
    kept_rows = np.concatenate(kept) if kept else np.zeros(0, np.intp)
    Gk = (G[kept_rows] @ N2).tocsr() if kept else None
    return LocalBasis(N, rank, Gk, other[kept_rows], coords.shape[0],
                      int(touched.size), largest)


def _small(model, q, rank_tol, Td, other, n_triads):
    """A small model (at most SMALL_DENSE columns of T), dense throughout: its joints in T's
    columns at once by one SVD of those rows (a few dozen columns: cheaper than finding
    components) and the polar factor closest to the coordinate directions.  The polar factor
    of the block-diagonal projector is block diagonal where the selection is, so this is the
    local basis up to the selection of the coordinates (and rounding)."""
    if other.size == 0:
        return LocalBasis(Td, 6 * n_triads, None, other, n_triads, 0, 0)
    G = model.phi_q(q, dense=True)[other] @ Td
    _, sv, vt = np.linalg.svd(G, full_matrices=True)
    r = int(np.sum(sv > rank_tol * sv[0])) if sv.size and sv[0] > 0 else 0
    Z = vt[r:].T
    N = Td @ _closest(Z) if Z.shape[1] else np.zeros((Td.shape[0], 0))
    touched = int(np.count_nonzero(np.any(G != 0, axis=0)))
    return LocalBasis(N, 6 * n_triads + r, None, np.zeros(0, np.intp), n_triads, 1, touched)


def _groups(labels, n_groups):
    """Indices of each label value (a list of arrays, one per group)."""
    order = np.argsort(labels, kind="stable")
    bounds = np.searchsorted(labels[order], np.arange(n_groups + 1))
    return [order[bounds[k]:bounds[k + 1]] for k in range(n_groups)]


def _closest(Z):
    """:func:`mbseig.numerics.closest_basis` of span Z, its rounding of exact zeros (below
    1e-15 of the largest entry) set to zero, so that N keeps the sparsity of the coordinate
    directions it holds: unit columns where the null space holds them."""
    N = closest_basis(Z)[0]
    N[np.abs(N) < 1e-15 * np.abs(N).max(initial=0.0)] = 0.0
    return N
