"""The verdict and what it covers (DESIGN §6): the one place a verdict is made.

    verdict = worst stability over the listed modes that are not rigid-body by construction
              ("critical" when no such mode is left)

Rigid-body modes by construction are the zero eigenvalues a model has whatever its parameters:
the directions its structure declares (:mod:`mbseig.model.symmetry` at rest, the cyclic
coordinates of a steady motion), never the eigenvalues that happen to lie near 0.  A declared
direction is left out of the verdict only where the eigensolver found s = 0 along it: the
declared direction must lie in the span of the eigenvectors of the eigenvalues classified
rigid-body (|s| within their bound), to within the angle ``ANGLE_TOL``.  Any other eigenvalue
within its bound of 0 (a divergence about to start) stays in the verdict as critical, and a
declared direction the solver did not find at 0 is said in the scope and left in.

Per listed mode, ``rigid_body`` names the declared direction (None for every other mode);
``scope`` says in words which modes the verdict leaves out.
"""

from __future__ import annotations

import dataclasses

import numpy as np
import scipy.sparse as sp

from .result import STABILITY_ORDER, Verdict

__all__ = ["ANGLE_TOL", "verdict", "apply_scope", "scope_text", "reduced_directions",
           "spectrum_verdict", "spectrum_verdicts"]

#: sin of the largest angle between a declared direction and the computed zero eigenspace for
#: the direction to count as found there: the computed eigenvectors of an exact, isolated s = 0
#: are within O(ε‖T‖/gap) of it (1e-12 and less in the bundled cases), so 1e-6 is met by every
#: found direction while a direction at a distinctly other angle is not (it is then counted)
ANGLE_TOL = 1e-6


def verdict(stability, rigid_body=None, partial_scope="", *, zero=True) -> Verdict:
    """The worst of ``stability`` over the modes whose ``rigid_body`` entry is None (all when
    ``rigid_body`` is None); "critical" when none is left.  ``partial_scope``: what a partial
    spectrum covers; ``zero``: every mode left out has s = 0 (a turn's in-plane pair has not)."""
    counted = [s for k, s in enumerate(stability) if rigid_body is None or rigid_body[k] is None]
    word = max(counted, key=STABILITY_ORDER.get) if counted else "critical"
    names = [r for r in (rigid_body or []) if r is not None]
    return Verdict(word, partial_scope, scope_text(names, len(counted) == 0, zero=zero))


def scope_text(names, none_left=False, missing=(), *, zero=True) -> str:
    """'4 rigid-body modes (s = 0) by construction not counted: a; b; c; d' (or '')."""
    parts = []
    if names:
        k = len(names)
        parts.append(f"{k} rigid-body mode{'s' if k > 1 else ''}{' (s = 0)' if zero else ''} "
                     f"by construction not counted: {'; '.join(names)}")
        if none_left:
            parts.append("no other mode: critical")
    if missing:
        parts.append(f"declared but not found at s = 0 (counted): {'; '.join(missing)}")
    return "; ".join(parts)


def reduced_directions(D, N):
    """Declared directions D (full coordinates, orthonormal columns) in the reduced
    coordinates x of q = q₀ + N x (N orthonormal; None or the identity: D itself)."""
    D = np.asarray(D)
    if N is None or D.shape[1] == 0:
        return D
    if sp.issparse(N):
        N = N.toarray()
    Dr = N.T @ D
    q, _ = np.linalg.qr(Dr)
    return q


def apply_scope(md, directions, names, *, shape_fn=None):
    """``md`` (a :class:`~mbseig.modal.result.Modes`) with the declared rigid-body directions
    (``directions``: reduced coordinates, orthonormal columns; ``names``) marked and left out of
    the verdict (module docstring).  The listed rigid-body modes that are declared get the
    declared vectors; the others keep a basis of the rest of the computed zero eigenspace and,
    of the computed eigenvalues near 0, those with the largest Re s.  ``shape_fn(X)`` gives
    (shapes, dominant) of vectors X as the listing forms them."""
    k_rigid = [k for k, kd in enumerate(md.kind) if kd == "rigid-body"]
    rigid_body = [None] * len(md)
    D = np.asarray(directions) if directions is not None else np.zeros((0, 0))
    if not k_rigid or D.size == 0 or md.partial and md.vectors.shape[0] != D.shape[0]:
        missing = tuple(names) if D.size and not k_rigid else ()
        v = verdict(md.stability, rigid_body, _partial(md))
        return _replace(md, v, rigid_body, missing)
    Z, _ = np.linalg.qr(md.vectors[:, k_rigid])
    inside = np.linalg.norm(D - Z @ (Z.conj().T @ D), axis=0) <= ANGLE_TOL
    Din = D[:, inside]
    if Din.shape[1] > len(k_rigid):
        Din, inside = Din[:, :len(k_rigid)], _first(inside, len(k_rigid))
    c = Din.shape[1]
    missing = tuple(nm for nm, ok in zip(names, inside, strict=False) if not ok)
    if c == 0:
        return _replace(md, verdict(md.stability, rigid_body, _partial(md)), rigid_body, missing)
    found = [nm for nm, ok in zip(names, inside, strict=False) if ok]
    # the zero eigenspace: the declared directions (within it), then an orthonormal rest
    P, _ = np.linalg.qr(Z @ (Z.conj().T @ Din))
    rest = Z - P @ (P.conj().T @ Z)
    U, sv, _ = np.linalg.svd(rest, full_matrices=False)
    others = U[:, : len(k_rigid) - c]
    # the positions: the counted ones show the largest Re s of the eigenvalues near 0
    order = sorted(k_rigid, key=lambda k: -md.eigenvalues[k].real)
    counted_pos, declared_pos = order[: len(k_rigid) - c], sorted(order[len(k_rigid) - c:])
    X = md.vectors.astype(complex if np.iscomplexobj(md.vectors) or np.iscomplexobj(P) else float,
                          copy=True)
    for j, k in enumerate(declared_pos):
        X[:, k] = P[:, j]
        rigid_body[k] = found[j]
    for j, k in enumerate(counted_pos):
        X[:, k] = others[:, j]
    changed = sorted(k_rigid)
    shapes, dominant = md.shapes.copy(), list(md.dominant)
    if shape_fn is not None:
        sh, dom = shape_fn(X[:, changed])
        shapes = shapes.astype(sh.dtype, copy=False) if sh.dtype.kind == "c" else shapes
        for j, k in enumerate(changed):
            shapes[:, k] = sh[:, j]
            dominant[k] = dom[j]
    md = dataclasses.replace(md, vectors=X, shapes=shapes, dominant=dominant)
    return _replace(md, verdict(md.stability, rigid_body, _partial(md)), rigid_body, missing)


def _first(mask, k):
    out = np.zeros_like(mask)
    out[np.flatnonzero(mask)[:k]] = True
    return out


def _partial(md):
    return md.verdict.scope if isinstance(md.verdict, Verdict) else ""


def _replace(md, v, rigid_body, missing):
    if missing:
        v = Verdict(v.word, v.scope, "; ".join(t for t in (v.rigid_scope,
                                                            scope_text((), False, missing)) if t))
    return dataclasses.replace(md, verdict=v, rigid_body=rigid_body)


def spectrum_verdict(stabilities, rigid, vectors, rigid_directions=None, N=None,
                     rank_tol=1e-6) -> Verdict:
    """The verdict of a whole computed spectrum (every eigenvalue, not a listing: a sweep's
    point), with the rule of :func:`verdict`: the eigenvalues classified rigid-body
    (``rigid`` mask, critical) are left out when their eigenvectors span no more than the
    declared directions found among them (``rigid_directions()``: a RigidDirections in full
    coordinates, called only when an eigenvalue is rigid-body); any other zero counts.
    :func:`spectrum_verdicts` of this one spectrum."""
    codes = np.array([STABILITY_ORDER[w] for w in stabilities], int)
    return spectrum_verdicts(codes[None], np.asarray(rigid, bool)[None],
                             np.asarray(vectors)[None], [rigid_directions], [N], rank_tol)[0]


_WORDS = ("stable", "critical", "unstable")  # STABILITY_ORDER's words by their order


def spectrum_verdicts(codes, rigid, vectors, directions, N, rank_tol=1e-6) -> list:
    """:func:`spectrum_verdict` of B whole spectra at once: ``codes`` (B, k) the stabilities as
    STABILITY_ORDER's numbers, ``rigid`` (B, k), ``vectors`` (B, n, k) (or B arrays (n, k)),
    ``directions`` (B,) each the declared RigidDirections or a callable giving them (asked only
    where an eigenvalue is rigid-body; None: none declared), N (B,) each the reduced basis
    (n_full, n; None or sparse too).  The spectra with as many rigid-body eigenvalues and
    declared directions are tested together: the span Z of their rigid-body vectors (stacked
    SVD, singular values above rank_tol of the largest), each declared direction found in it
    when within ANGLE_TOL of it, the dimensions of Z beyond the directions found counted as
    critical."""
    codes = np.asarray(codes)
    rigid = np.asarray(rigid, bool)
    B = codes.shape[0]
    out = [None] * B
    worst_other = np.max(np.where(rigid, -1, codes), axis=1, initial=-1)
    nr = rigid.sum(axis=1)
    groups = {}
    got = {}
    for b in range(B):
        d = directions[b] if nr[b] else None
        g = d() if callable(d) else d
        if g is None:  # (no rigid-body eigenvalue, or none declared: every mode counts;
            word = int(np.max(codes[b], initial=-1))  # none at all: "critical", as verdict)
            out[b] = Verdict(_WORDS[word] if word >= 0 else "critical", "", "")
            continue
        got[b] = g
        Nb = N[b]
        dense = isinstance(Nb, np.ndarray)
        key = (int(nr[b]), len(g.names), np.shape(vectors[b]), g.vectors.shape,
               Nb.shape if dense else ("each", b))
        groups.setdefault(key, []).append(b)
    for (r, _, _, _, nkey), members in groups.items():
        idx = np.array(members)
        if isinstance(nkey, tuple) and nkey[:1] == ("each",):
            Dr = reduced_directions(got[members[0]].vectors, N[members[0]])[None]
        else:
            D = np.stack([got[b].vectors for b in members])
            Dr, _ = np.linalg.qr(np.swapaxes(np.stack([N[b] for b in members]), 1, 2) @ D)
        cols = np.nonzero(rigid[idx])[1].reshape(idx.size, r)
        X = np.take_along_axis(np.stack([np.asarray(vectors[b]) for b in members]),
                               cols[:, None, :], axis=2)
        X = X / np.maximum(np.linalg.norm(X, axis=1, keepdims=True), np.finfo(float).tiny)
        U, sv, _ = np.linalg.svd(X, full_matrices=False)
        keep = sv > rank_tol * np.maximum(sv.max(axis=1, initial=0.0),
                                          np.finfo(float).tiny)[:, None]
        Z = U * keep[:, None, :]  # the kept columns; the others zero (no part in Z Zᴴ)
        res = Dr - Z @ (np.swapaxes(Z.conj(), 1, 2) @ Dr)
        inside = np.linalg.norm(res, axis=1) <= ANGLE_TOL
        rank = keep.sum(axis=1)
        for j, b in enumerate(members):
            names = [nm for nm, ok in zip(got[b].names, inside[j], strict=True) if ok]
            worst = int(worst_other[b])
            if int(rank[j]) > len(names):
                worst = max(worst, STABILITY_ORDER["critical"])
            counted = worst >= 0
            out[b] = Verdict(_WORDS[worst] if counted else "critical", "",
                             scope_text(names, not counted))
    return out
