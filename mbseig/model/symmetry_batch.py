"""Rigid-body directions by construction of B models of one structure at once: the search of
:mod:`mbseig.model.symmetry` with a leading batch axis.

The parts, their generators and the three tests are those of
:func:`~mbseig.model.symmetry.rigid_directions`, each numpy call on all B models: generators
from the stacked coordinates, each element's terms from the stacked element kernels
(:class:`~mbseig.model.stacked.ModelStack`: K and g of a force, J and H(λ) of a constraint),
and every null space of a test by a stacked SVD with the same row scaling and the same ``TOL``.

Where the tests keep different numbers of directions at different models (a symmetry that holds
at some points of a line and not at others), the models of the minority are left (None) and
take :func:`~mbseig.model.symmetry.rigid_directions` on their own.  Names are formed per model
(a rotation's line passes through each model's own centroid).
"""

from __future__ import annotations

import numpy as np

from .frames import CoordinateFrames, _cross_axis
from .symmetry import TOL, RigidDirections, _describe, _parts

__all__ = ["rigid_directions_batch"]


def _null(R, scale, Bm):
    """Stacked :func:`mbseig.model.symmetry._null`: (basis (B, g, k), residual (B,), kept)
    with ``kept`` False where a model keeps another number of directions than the most."""
    nb, g, kb = Bm.shape
    if kb == 0 or R.shape[1] == 0:
        return Bm, np.zeros(nb), np.ones(nb, bool)
    S = (R @ Bm) / np.maximum(scale, np.finfo(float).tiny)[:, :, None]
    full = S.shape[1] < S.shape[2]
    _, sv, Vh = np.linalg.svd(S, full_matrices=full)
    pad = kb - sv.shape[1]
    if pad > 0:
        sv = np.concatenate([sv, np.zeros((nb, pad))], axis=1)
    keep = sv <= TOL
    count = keep.sum(axis=1)
    major = np.bincount(count).argmax()
    kept = count == major
    # the kept singular values are the smallest: the last ``major`` columns of V
    V = np.swapaxes(Vh, 1, 2)[:, :, kb - major:] if major else np.zeros((nb, kb, 0))
    res = np.where(keep, sv, 0.0).max(axis=1, initial=0.0)
    return Bm @ V, res, kept


class _Generators:
    """Stacked :meth:`CoordinateFrames.generators` of one part: G (B, n, g), the rotation part
    of each column (axis, index triples), the labels per model (centroids per model)."""

    def __init__(self, frames, members, Q):
        pts = [frames.points[h] for k, h in sorted(members) if k == "p"]
        vecs = [frames.vectors[h] for k, h in sorted(members) if k == "v"]
        angs = [frames.angles[h] for k, h in sorted(members) if k == "a"]
        dim, n = frames.dim, frames.n
        axes = "xyz"[:dim]
        B = Q.shape[0]

        def triad(t):
            return [t.get(a, -1) for a in "xyz"]

        P = np.array([triad(p) for p in pts], int).reshape(-1, 3)
        V = np.array([triad(v) for v in vecs], int).reshape(-1, 3)
        centre = np.zeros((B, 3))
        if pts:
            for k in range(dim):
                sel = P[P[:, k] >= 0, k]
                if sel.size:
                    centre[:, k] = Q[:, sel].mean(axis=1)
        cols, rots, kinds = [], [], []
        for k, a in enumerate(axes):
            g = np.zeros((B, n))
            g[:, P[P[:, k] >= 0, k]] = 1.0
            cols.append(g), rots.append(None), kinds.append(("t", a, bool(pts)))
        ix = np.vstack([P, V])
        R = np.where(ix >= 0, Q[:, np.maximum(ix, 0)], 0.0)          # (B, t, 3)
        R[:, :len(P)] -= np.where(P >= 0, centre[:, None, :], 0.0)
        rot_axes = "xyz" if dim == 3 else ("z" if dim == 2 else "")
        for w in rot_axes:
            k = "xyz".index(w)
            g = np.zeros((B, n))
            _scatter(g, ix, _cross_axis(k, R))
            g[:, angs] = 1.0
            cols.append(g), rots.append((k, ix)), kinds.append(("r", w, bool(pts)))
        G = np.stack(cols, axis=2) if cols else np.zeros((B, n, 0))
        keep = np.flatnonzero(np.abs(G).max(axis=(0, 1)) > 0)
        self.G = G[:, :, keep]
        self.rots = [rots[k] for k in keep]
        self.kinds = [kinds[k] for k in keep]
        self.centre = centre
        self.axes = axes

    def labels(self, b):
        """The labels of :meth:`CoordinateFrames.generators` at model b."""
        c = {a: float(self.centre[b, k]) for k, a in enumerate(self.axes)}
        return [(kind, axis, c if (kind == "t" or has_points) else None)
                for kind, axis, has_points in self.kinds]

    def turn(self, v):
        """W v of each generator (:func:`mbseig.model.frames.rotate`): (B, n, g), zero for a
        translation."""
        out = np.zeros((*v.shape, len(self.rots)))
        for j, rot in enumerate(self.rots):
            if rot is not None:
                k, ix = rot
                _scatter(out[:, :, j], ix,
                         _cross_axis(k, np.where(ix >= 0, v[:, np.maximum(ix, 0)], 0.0)))
        return out


def _scatter(out, ix, values):
    ok = ix >= 0
    out[:, ix[ok]] = values[:, ok]


def _elements(stack, Q, L):
    """Each element's own terms on all models: (idx, K or H (B, m, m), load (B, m), J or
    None), as :class:`mbseig.model.symmetry._Elements` forms them one model at a time."""
    items = []
    for idx, ker in stack.forces:
        Z = Q[:, idx]
        K, _ = ker.jacobians(Z, Q)
        items.append((idx, np.broadcast_to(K, (Q.shape[0], *K.shape[1:])),
                      ker.force(Z, Q), None))
    for idx, a, b, ker in stack.constraints:
        Z = Q[:, idx]
        lam = L[:, a:b]
        J = np.broadcast_to(ker.jac(Z, Q), (Q.shape[0], b - a, idx.size))
        H = ker.hess(Z, Q, lam)
        items.append((idx, H, -np.einsum("bkm,bk->bm", J, lam), J))
    return items


def _element_pass(item, gen, Bm):
    idx, K, load, J = item
    G = gen.G
    Gi = G[:, idx, :]
    absG = np.abs(Gi).max(axis=2)                                   # (B, m)
    blind = K @ Gi
    full = np.zeros(G.shape[:2])
    full[:, idx] = load
    turn = gen.turn(full)[:, idx, :]                                # (B, m, g)
    nK = np.sqrt(np.einsum("bij,bij->b", K, K))
    scale = np.broadcast_to((nK * absG.max(axis=1, initial=0.0)
                             + np.abs(load).max(axis=1, initial=0.0))[:, None],
                            (G.shape[0], idx.size))
    rows_b, rows_m, sc = [blind], [blind + turn], [scale]
    if J is not None:
        first = J @ Gi
        rows_b.append(first), rows_m.append(first)
        sc.append(np.einsum("bkm,bm->bk", np.abs(J), absG))
    scale = np.concatenate(sc, axis=1)
    nb, rb, kb = _null(np.concatenate(rows_b, axis=1), scale, Bm)
    if nb.shape[2] == Bm.shape[2]:  # every direction kept: the moving test cannot keep more
        return nb, rb, kb
    nm, rm, km = _null(np.concatenate(rows_m, axis=1), scale, Bm)
    if nb.shape[2] >= nm.shape[2]:
        return nb, rb, kb
    return nm, rm, km


def _part(gen, members, frames, elements, Phi_q, Qr, N, ok):
    B = gen.G.shape[0]
    G = gen.G
    g = G.shape[2]
    if g == 0:
        return None, np.zeros(B)
    G = G / np.linalg.norm(G, axis=1, keepdims=True)
    gen.G = G
    Bm = np.broadcast_to(np.eye(g), (B, g, g))
    worst = np.zeros(B)
    absG = np.abs(G).max(axis=2)
    if Phi_q is not None and Phi_q.shape[1]:
        Bm, r, kept = _null(Phi_q @ G, np.einsum("bkn,bn->bk", np.abs(Phi_q), absG), Bm)
        worst = np.maximum(worst, r)
        ok &= kept
    Gr = np.swapaxes(N, 1, 2) @ G
    nQ = np.sqrt(np.einsum("bij,bij->b", Qr, Qr))
    Bm, r, kept = _null(Qr @ Gr, np.broadcast_to(
        (nQ * np.abs(Gr).max(axis=(1, 2)))[:, None], Qr.shape[:2]), Bm)
    worst = np.maximum(worst, r)
    ok &= kept
    if Bm.shape[2] == 0:
        return None, worst
    mask = np.zeros(frames.n, bool)
    mask[frames.indices(members)] = True
    touching = [it for it in elements if mask[it[0]].any()]
    for _ in range(3):
        before = Bm.shape[2]
        for item in touching:
            Bm, r, kept = _element_pass(item, gen, Bm)
            worst = np.maximum(worst, r)
            ok &= kept
            if Bm.shape[2] == 0:
                return None, worst
        if Bm.shape[2] == before:
            break
    return Bm, worst


def rigid_directions_batch(models, Q0, LAM0, Qr, N, stack=None):
    """Per model its :class:`~mbseig.model.symmetry.RigidDirections` at (q₀, λ₀) with the
    reduced stiffness Qr and basis N (stacked: (B, n), (B, m), (B, d, d), (B, n, d)), or None
    where that model must take :func:`~mbseig.model.symmetry.rigid_directions` on its own
    (module docstring).  ``stack``: the models' :class:`~mbseig.model.stacked.ModelStack`."""
    from .stacked import ModelStack

    m0 = models[0]
    B, n = Q0.shape
    if not getattr(m0, "coordinate_kinds", ()):
        return [RigidDirections.none(n) for _ in range(B)]
    stack = ModelStack(models) if stack is None else stack
    frames = CoordinateFrames(m0)
    Phi_q = stack.phi_q(Q0) if m0.n_constraints else None
    elements = _elements(stack, Q0, LAM0)
    ok = np.ones(B, bool)
    found = []  # (part, directions (B, n, k), coefficients (B, g, k), generators, residual)
    for part, members in _parts(m0, frames):
        gen = _Generators(frames, members, Q0)
        Bm, worst = _part(gen, members, frames, elements, Phi_q, Qr, N, ok)
        if Bm is not None and Bm.shape[2]:
            found.append((part, gen.G @ Bm, Bm, gen, worst))
    # the found directions of each model, orthonormalized in order (a direction within the span
    # of those before it left out), for all models at once
    cols, kept, basis = [], [], np.zeros((B, n, 0))
    for part, D, coef, gen, r in found:
        for j in range(D.shape[2]):
            col = D[:, :, j]
            v = col - np.einsum("bnk,bk->bn", basis, np.einsum("bnk,bn->bk", basis, col))
            nv = np.linalg.norm(v, axis=1)
            keep = nv > 1e-8 * np.linalg.norm(col, axis=1)
            v = np.where(keep[:, None], v / np.where(keep, nv, 1.0)[:, None], 0.0)
            basis = np.concatenate([basis, v[:, :, None]], axis=2)
            cols.append((part, coef[:, :, j], gen, r))
            kept.append(keep)
    kept = np.array(kept, bool).reshape(len(cols), B)
    words = {}  # (part, coefficients, centre) -> the direction in words, once
    out = []
    for b in range(B):
        if not ok[b]:
            out.append(None)
            continue
        use = np.flatnonzero(kept[:, b])
        names, worst = [], 0.0
        for j in use.tolist():
            part, coef, gen, r = cols[j]
            key = (part, coef[b].tobytes(), gen.centre[b].tobytes())
            name = words.get(key)
            if name is None:
                name = words[key] = f"{part}: {_describe(coef[b], gen.labels(b))}"
            names.append(name)
            worst = max(worst, float(r[b]))
        out.append(RigidDirections(tuple(names), basis[b][:, use], worst))
    return out
