"""Rigid-body directions by construction (DESIGN §6): the zero-stiffness motions a model has
whatever its parameters, found from its structure, never from which eigenvalues lie near 0.

A candidate is a rigid motion of one *part* of the model, applied to the part's natural
coordinates (points translate and rotate, unit vectors rotate, absolute angles of planar beams
shift, modal coordinates stay) and to nothing else:

* each body (with the basic points only it carries), each beam node and each point mass alone,
* each connected part (the frames linked by elements that act between two or more of them),
* the whole model.

In d dimensions a part's rigid motions form a space of 1 (1-D), 3 (2-D) or 6 (3-D) generators
d(a) = G a: translations and rotations about the part's centroid.  The subspace of the a that
are rigid-body directions by construction is what survives three tests, each at the rounding
level of its own terms (``TOL`` relative):

1. every constraint is satisfied to first order, Φ_q d = 0;
2. every element, *on its own*, is either blind to the motion or moves with it: for a force
   element with stiffness K_e and generalized force g_e, and a constraint with H_e = Σλ∇²Φ_e and
   force −Φ_eᵀλ,

       blind:   K_e d = 0                  (H_e d = 0)
       moving:  K_e d + W g_e = 0          (H_e d − W Φ_eᵀλ = 0)

   where W is the rotation part of the generator (d(q) = W q + t): the second is the exact
   identity of an element invariant under the motion (its load turns with it), the first that
   of an element the motion does not reach (a spherical joint, a bushing without torsional
   stiffness, a spring at a point of the axis);
3. the reduced stiffness vanishes along it, Q Nᵀd = 0 (normwise: Q is formed as NᵀKN, whose
   small entries are rounding residue of the large ones).

Tests 1 and 2 are row by row (a constraint row, an element), each against the magnitudes of its
own terms.

Test 2 is what makes the directions structural: a divergence about to start (a buckling load,
the bicycle's capsize) is a null vector of Q by a cancellation between elements that resist and
elements that drive, and no element passes test 2 on such a direction; what is left to test 3
for directions that pass test 2 are the loads' moments about the axis (gravity at a centre of
mass off the axis), which depend on geometry, not on stiffness values.  Directions found in
several parts are kept once, named by the smallest part that has them.

Models without structure (``kind = "linear"`` cases) have none: every zero eigenvalue of theirs
counts in the verdict.  Only the dense reduced path (N formed) is analysed; a model linearized on
the sparse path declares none.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import scipy.sparse as sp

from .base import BatchForce
from .frames import CoordinateFrames, rotate

__all__ = ["RigidDirections", "rigid_directions", "TOL"]

#: relative rounding level of the tests (module docstring): the residual of an exact identity
#: evaluated in floating point is a few ε times the sum of the magnitudes of its terms (elements'
#: matrices are formed in O(10) operations per entry, and a row sums at most a few dozen products),
#: so 1e-11 leaves a margin of 10³ over that and still rejects a symmetry broken by 1e-11 relative
TOL = 1e-11


@dataclass(frozen=True, eq=False)
class RigidDirections:
    """The rigid-body directions by construction of a model at a reference.

    ``vectors`` (n × k, full coordinates, orthonormal columns), ``names`` (what each is, in the
    user's terms), ``residual`` (the largest relative residual of the three tests over the
    directions kept) and ``tolerance`` (``TOL``)."""

    names: tuple
    vectors: np.ndarray
    residual: float = 0.0
    tolerance: float = TOL

    def __len__(self):
        return len(self.names)

    @classmethod
    def none(cls, n):
        return cls((), np.zeros((n, 0)))


# ---------------------------------------------------------------------------------------------
# tests
# ---------------------------------------------------------------------------------------------
def _null(R, scale, B):
    """The b in span B (orthonormal columns) with |R B b|ᵢ ≤ TOL·scaleᵢ·|b| for every row i:
    a basis of the right null space of the row-scaled R B at ``TOL``."""
    if B.shape[1] == 0 or R.shape[0] == 0:
        return B, 0.0
    S = (R @ B) / np.maximum(scale, np.finfo(float).tiny)[:, None]
    _, sv, Vh = np.linalg.svd(S, full_matrices=S.shape[0] < S.shape[1])  # Vh: all of b's space
    sv = np.concatenate([sv, np.zeros(B.shape[1] - sv.size)])
    keep = sv <= TOL
    return B @ Vh.conj().T[:, keep], float(sv[keep].max(initial=0.0))


class _Elements:
    """Each element's own terms at (q₀, λ₀): (idx, K_e or H_e, its load, first-order rows)."""

    def __init__(self, model, q, lam):
        n, zero = model.n, np.zeros(model.n)
        self.items = []
        for f in model.forces:
            if isinstance(f, BatchForce):
                (r, c, v), _ = f.jacobian_coo(q, zero)
                K = sp.coo_matrix((v, (r, c)), shape=(n, n)).tocsr()
                g = np.zeros(n)
                f.add_force(g, q, zero)
                idx = np.unique(np.concatenate([r, c, np.flatnonzero(g)])).astype(int)
                self.items.append((idx, K[idx][:, idx].toarray(), g[idx], None))
            else:
                K, _ = f.jacobians(q, zero)
                self.items.append((f.idx, np.asarray(K, float), np.asarray(f.force(q, zero)), None))
        off = 0
        for c in model.constraints:
            lam_e = lam[off:off + c.n_eq]
            off += c.n_eq
            J = np.atleast_2d(np.asarray(c.jac(q), float))
            H = np.asarray(c.hess(q, lam_e), float)
            self.items.append((c.idx, H, -(J.T @ lam_e), J))

    def touching(self, mask):
        return [it for it in self.items if mask[it[0]].any()]


def _element_pass(item, G, rots, B):
    """Restrict B to the directions element ``item`` is blind to or moves with (module doc)."""
    idx, K, load, J = item
    Gi = G[idx]
    absG = np.abs(Gi).max(axis=1)
    blind = K @ Gi
    full = np.zeros(G.shape[0])
    full[idx] = load
    turn = np.column_stack([rotate(r, full)[idx] for r in rots]) if rots else np.zeros_like(blind)
    # the element's own scale, normwise (its matrix is formed with cancellations, so an entry
    # of its product can be rounding residue of the others)
    scale = np.full(len(idx), np.linalg.norm(K) * absG.max(initial=0.0)
                    + np.abs(load).max(initial=0.0))
    rows_b, rows_m, sc = [blind], [blind + turn], [scale]
    if J is not None:
        first = J @ Gi
        rows_b.append(first), rows_m.append(first), sc.append(np.abs(J) @ absG)
    scale = np.concatenate(sc)
    nb, rb = _null(np.vstack(rows_b), scale, B)
    if nb.shape[1] == B.shape[1]:  # every direction kept: the moving test cannot keep more
        return nb, rb
    nm, rm = _null(np.vstack(rows_m), scale, B)
    return (nb, rb) if nb.shape[1] >= nm.shape[1] else (nm, rm)


def _part_directions(frames, members, q, elements, Phi_q, Qr, N):
    G, rots, labels = frames.generators(members, q)
    if G.shape[1] == 0:
        return np.zeros((frames.n, 0)), [], 0.0
    G = G / np.linalg.norm(G, axis=0)
    B = np.eye(G.shape[1])
    worst = 0.0
    absG = np.abs(G).max(axis=1)
    if Phi_q is not None and Phi_q.shape[0]:  # test 1 (all constraints at once: cheap filter)
        B, r = _null(Phi_q @ G, np.abs(Phi_q) @ absG, B)
        worst = max(worst, r)
    Gr = N.T @ G  # test 3
    B, r = _null(Qr @ Gr, np.full(Qr.shape[0], np.linalg.norm(Qr) * np.abs(Gr).max()), B)
    worst = max(worst, r)
    if B.shape[1] == 0:
        return np.zeros((frames.n, 0)), [], worst
    mask = np.zeros(frames.n, bool)
    mask[frames.indices(members)] = True
    touching = elements.touching(mask)
    for _ in range(3):  # test 2, element by element, until no element removes a direction
        before = B.shape[1]
        for item in touching:
            B, r = _element_pass(item, G, rots, B)
            worst = max(worst, r)
            if B.shape[1] == 0:
                return np.zeros((frames.n, 0)), [], worst
        if B.shape[1] == before:
            break
    return G @ B, [(B[:, k], labels) for k in range(B.shape[1])], worst


def _describe(coef, labels):
    """A direction's motion in words: a translation along a unit vector, a rotation about a
    line (through a point, along a unit vector), or for a part without points of its own (a
    triad turning about the point that carries it) a spin about an axis."""
    t, om, centre = np.zeros(3), np.zeros(3), None
    for c, (kind, axis, cen) in zip(coef, labels, strict=True):
        k = "xyz".index(axis)
        (t if kind == "t" else om)[k] += c
        if cen is not None:
            centre = np.array([cen.get(a, 0.0) for a in "xyz"])

    def fmt(v):
        v = v * np.sign(v[np.argmax(np.abs(v))])  # the largest component positive
        return "(" + ", ".join(f"{x:.4g}" if abs(x) > 1e-12 else "0" for x in v + 0.0) + ")"

    w = np.linalg.norm(om)
    if w <= 1e-9 * max(np.linalg.norm(t), 1e-300):
        return f"translation along {fmt(t / np.linalg.norm(t))}"
    if centre is None:
        return f"spin about {fmt(om / w)}"
    p = centre + np.cross(om, t) / w**2
    p = np.where(np.abs(p) <= 1e-12 * max(1.0, np.abs(p).max()), 0.0, p)
    return (f"rotation about the line through ({', '.join(f'{x:.4g}' for x in p + 0.0)}) "
            f"along {fmt(om / w)}")


def _parts(model, frames):
    """(label, members) of every part, smallest first (module docstring)."""
    out = []
    owner = {}
    for b, rec in (getattr(model, "bodies", {}) or {}).items():
        if "points" in rec and isinstance(rec["points"], tuple):  # planar: its two basic points
            members = {("p", p) for p in rec["points"] if p in frames.points}
        else:
            members = set(frames.frames.get(b, set()))
            members |= {("p", p) for p in rec.get("carried", ()) if p in frames.points}
        if members:
            out.append((b, frozenset(members)))
            for m in members:
                owner.setdefault(m, b)
    for key, members in frames.frames.items():
        if not all(m in owner for m in members):
            out.append((key, frozenset(members)))
    # connected parts: frames linked by elements that act on two or more of them
    frame_of = {}
    for key, members in frames.frames.items():
        for i in frames.indices(members):
            frame_of[int(i)] = key
    parent = {k: k for k in frames.frames}

    def find(k):
        while parent[k] != k:
            parent[k] = parent[parent[k]]
            k = parent[k]
        return k

    for e in (*model.forces, *model.constraints):
        idx = e.idx
        if idx is None:
            continue
        keys = {frame_of[int(i)] for i in np.asarray(idx).ravel() if int(i) in frame_of}
        keys = sorted(keys)
        for k in keys[1:]:
            parent[find(k)] = find(keys[0])
    groups = {}
    for k in frames.frames:
        groups.setdefault(find(k), set()).update(frames.frames[k])
    if len(groups) > 1:
        for root, members in groups.items():
            out.append((f"part with {root}", frozenset(members)))
    out.append(("the whole model", frozenset(m for ms in frames.frames.values() for m in ms)))
    return out


def rigid_directions(model, q0, lam0, Qr, N, *, label=None) -> RigidDirections:
    """The rigid-body directions by construction of ``model`` at (q₀, λ₀) with the reduced
    stiffness Qr = Nᵀ(K + H(λ₀))N (module docstring).  ``label(part)`` names a part for the
    user (default: the part's own name)."""
    n = model.n
    if N is None or not getattr(model, "coordinate_kinds", ()):
        return RigidDirections.none(n)
    frames = CoordinateFrames(model)
    Qr = np.asarray(Qr.toarray() if sp.issparse(Qr) else Qr, float)
    N = np.asarray(N.toarray() if sp.issparse(N) else N, float)
    Phi_q = model.phi_q(q0, dense=True) if model.n_constraints else None
    elements = _Elements(model, q0, np.asarray(lam0, float))
    basis = np.zeros((n, 0))
    names, worst = [], 0.0
    for part, members in _parts(model, frames):
        D, coefs, r = _part_directions(frames, members, q0, elements, Phi_q, Qr, N)
        if not coefs:
            continue
        for col, (coef, labels) in zip(D.T, coefs, strict=True):
            v = col - basis @ (basis.T @ col)
            nv = np.linalg.norm(v)
            if nv <= 1e-8 * np.linalg.norm(col):
                continue  # found in a smaller part already
            basis = np.column_stack([basis, v / nv])
            name = label(part) if label else part
            names.append(f"{name}: {_describe(coef, labels)}")
            worst = max(worst, r)
    return RigidDirections(tuple(names), basis, worst)
