"""The co-rotational 3-D beam element (:class:`mbseig.model.beam3d.Beam3DElement`) evaluated for
many elements at once: the same formulas as the single element (its module docstring and
:mod:`mbseig.model.beam_whirl`), as arrays over a leading element axis, so that a beam of nb
elements costs a fixed number of NumPy calls instead of nb times as many.

Every function takes the section axes ``z`` (nb, 24) = [r₁, a₁, b₁, c₁, r₂, a₂, b₂, c₂] of the
members (and their rates ``zd``) and returns arrays on z; :class:`Stack` holds the members'
constant data (their maps z = C q[idx] + d, padded to one width, and their local matrices) and
maps the results back to each member's coordinates.  The sums are those of the single element
in another order: equal to rounding (tests/test_beam3d_kernel.py).

The force needs only the gradients of the deformations (g = −Bᵀ U_p, formed as the action of
Bᵀ on U_p, with no B or Hessian arrays); the tangent forms Σ_k U_p,k ∇²p_k directly in blocks.
"""

from __future__ import annotations

import numpy as np

__all__ = ["Stack", "energy_derivatives", "force_z", "frame", "mass_q", "measures",
           "stiffness_z", "velocity_map", "velocity_terms_z"]

# the dot measures p₂…p₅ = s_k e·x_k: (sign, first column of x_k in z), as _DOTS in beam3d
SIGNS = np.array([-1.0, -1.0, 1.0, 1.0])
X_AT = (6, 18, 9, 21)  # b₁, b₂, c₁, c₂
_X_COLS = np.array([[s, s + 1, s + 2] for s in X_AT])
_AXIS_COLS = np.arange(24).reshape(2, 4, 3)[:, 1:]  # (node, axis, 3) columns of a, b, c
_I3 = np.eye(3)
#: the padded width of the members' coordinates (two frame nodes: 24)
WIDTH = 24


def _dot(a, b):
    """a·b along the last axis (3 or 2), broadcast; term by term, so that a member's value
    does not depend on the batch it is in (einsum's loops do)."""
    out = a[..., 0] * b[..., 0] + a[..., 1] * b[..., 1]
    return out + a[..., 2] * b[..., 2] if a.shape[-1] == 3 else out


def _mv(A, x):
    """A x for stacks (nb, i, j) · (nb, j)."""
    return np.einsum("nij,nj->ni", A, x)


def _mtv(A, x):
    """Aᵀ x for stacks."""
    return np.einsum("nji,nj->ni", A, x)


def cross(a, b):
    """a × b along the last axis, broadcast (np.cross costs ~60 µs a call)."""
    a0, a1, a2 = a[..., 0], a[..., 1], a[..., 2]
    b0, b1, b2 = b[..., 0], b[..., 1], b[..., 2]
    return np.stack([a1 * b2 - a2 * b1, a2 * b0 - a0 * b2, a0 * b1 - a1 * b0], axis=-1)


def skew(a):
    """[a]ₓ of vectors (…, 3): (…, 3, 3)."""
    S = np.zeros(a.shape[:-1] + (3, 3), dtype=a.dtype)
    S[..., 0, 1], S[..., 0, 2] = -a[..., 2], a[..., 1]
    S[..., 1, 0], S[..., 1, 2] = a[..., 2], -a[..., 0]
    S[..., 2, 0], S[..., 2, 1] = -a[..., 1], a[..., 0]
    return S


# ---------------------------------------------------------------------------------------------
# deformations and strain energy
def measures(z, l0):
    """(p, l, e, X, ex): p (nb, 6) = [u, θ, φz₁, φz₂, φy₁, φy₂], the chord length l and
    direction e, the dot vectors X (nb, 4, 3) = [b₁, b₂, c₁, c₂] and ex = e·x_k (nb, 4)."""
    d = z[:, 12:15] - z[:, 0:3]
    length = np.sqrt(_dot(d, d))
    e = d / length[:, None]
    X = z[:, _X_COLS]
    ex = _dot(X, e[:, None, :])
    p = np.empty((z.shape[0], 6))
    p[:, 0] = length - l0
    p[:, 1] = 0.5 * (_dot(z[:, 9:12], z[:, 18:21]) - _dot(z[:, 6:9], z[:, 21:24]))
    p[:, 2:] = SIGNS * ex
    return p, length, e, X, ex


def energy_derivatives(st, p, hessian=False):
    """(U_p (nb, 6), U_pp (nb, 6, 6) or None): the element's strain energy derivatives
    (:meth:`mbseig.model.beam3d.Beam3DElement` ``_energy_derivatives``) for every member."""
    phz, phy = p[:, 2:4], p[:, 4:6]
    az, ay = _mv(st.Gz, phz), _mv(st.Gy, phy)
    eps = p[:, 0] / st.l0 + 0.5 * _dot(phz, az) + 0.5 * _dot(phy, ay)
    N = st.EA * eps
    Nl = (N * st.l0)[:, None]
    Up = np.empty_like(p)
    Up[:, 0], Up[:, 1] = N, st.GJ * p[:, 1]
    Up[:, 2:4] = Nl * az + _mv(st.Kbz, phz)
    Up[:, 4:6] = Nl * ay + _mv(st.Kby, phy)
    if not hessian:
        return Up, None
    c = np.zeros_like(p)
    c[:, 0], c[:, 2:4], c[:, 4:6] = 1.0 / st.l0, az, ay
    Upp = (st.EA * st.l0)[:, None, None] * (c[:, :, None] * c[:, None, :])
    Upp[:, 1, 1] += st.GJ
    Upp[:, 2:4, 2:4] += Nl[:, :, None] * st.Gz + st.Kbz
    Upp[:, 4:6, 4:6] += Nl[:, :, None] * st.Gy + st.Kby
    return Up, Upp


def _gradients(length, e, X, ex):
    """B = ∂p/∂z (nb, 6, 24) without the twist row (row 1, filled by the caller)."""
    nb = length.shape[0]
    B = np.zeros((nb, 6, 24))
    B[:, 0, 12:15], B[:, 0, 0:3] = e, -e
    t = SIGNS[None, :, None] * (X - ex[:, :, None] * e[:, None, :]) / length[:, None, None]
    B[:, 2:, 12:15], B[:, 2:, 0:3] = t, -t
    for k, s in enumerate(X_AT):
        B[:, 2 + k, s:s + 3] = SIGNS[k] * e
    return B


def force_z(z, Up, length, e, X, ex):
    """Bᵀ U_p (nb, 24): the elastic force on z is its negative."""
    w = Up[:, 2:] * SIGNS  # U_p,k s_k
    f = Up[:, :1] * e + np.einsum("nk,nkj->nj", w, X - ex[:, :, None] * e[:, None, :])\
        / length[:, None]
    out = np.zeros_like(z)
    out[:, 12:15], out[:, 0:3] = f, -f
    for k, s in enumerate(X_AT):
        out[:, s:s + 3] = w[:, k:k + 1] * e
    h = 0.5 * Up[:, 1:2]  # twist θ = ½ (c₁·b₂ − b₁·c₂)
    out[:, 9:12] += h * z[:, 18:21]
    out[:, 18:21] += h * z[:, 9:12]
    out[:, 6:9] -= h * z[:, 21:24]
    out[:, 21:24] -= h * z[:, 6:9]
    return out


def stiffness_z(z, Up, Upp, length, e, X, ex):
    """K_z = Bᵀ U_pp B + Σ_k U_p,k ∇²p_k (nb, 24, 24), the exact tangent on z."""
    B = _gradients(length, e, X, ex)
    B[:, 1] = 0.0
    B[:, 1, 9:12], B[:, 1, 18:21] = 0.5 * z[:, 18:21], 0.5 * z[:, 9:12]
    B[:, 1, 6:9], B[:, 1, 21:24] = -0.5 * z[:, 21:24], -0.5 * z[:, 6:9]
    K = B.transpose(0, 2, 1) @ (Upp @ B)  # (matmul member by member: 8× the three-operand
    # einsum's speed, whose loops run over all five indices)
    P = _I3 - e[:, :, None] * e[:, None, :]
    il = 1.0 / length[:, None, None]
    w = Up[:, 2:] * SIGNS
    # ∂²/∂d²: U₀ P/l + Σ s_k U_k Hdd_k, Hdd = −(x eᵀ + e xᵀ + (e·x)(I − 3 e eᵀ))/l²
    xe = np.einsum("nk,nki,nj->nij", w, X, e)
    Wdd = Up[:, 0, None, None] * P * il - (xe + xe.transpose(0, 2, 1) + (w * ex).sum(1)[
        :, None, None] * (_I3 - 3.0 * (e[:, :, None] * e[:, None, :]))) * il * il
    for a, b, s in ((12, 12, 1.0), (0, 0, 1.0), (0, 12, -1.0), (12, 0, -1.0)):
        K[:, a:a + 3, b:b + 3] += s * Wdd
    Pl = P * il
    for k, c in enumerate(X_AT):  # ∂²/∂d∂x_k = s_k P/l (d = r₂ − r₁)
        blk = w[:, k, None, None] * Pl
        K[:, 12:15, c:c + 3] += blk
        K[:, c:c + 3, 12:15] += blk
        K[:, 0:3, c:c + 3] -= blk
        K[:, c:c + 3, 0:3] -= blk
    h = 0.5 * Up[:, 1, None, None] * _I3  # the twist's constant Hessian
    for a, b, s in ((9, 18, 1.0), (6, 21, -1.0)):
        K[:, a:a + 3, b:b + 3] += s * h
        K[:, b:b + 3, a:a + 3] += s * h
    return K


# ---------------------------------------------------------------------------------------------
# the co-rotated element frame, velocity map and velocity terms (mbseig.model.beam_whirl)
def frame(z, derivatives=False):
    """R_e (nb, 3, 3) (columns e₁ e₂ e₃); with ``derivatives`` also the blocks of ∂e_k/∂z:
    [(D_k, Y_k)] with ∂e_k/∂r₂ = −∂e_k/∂r₁ = D_k, ∂e_k/∂b₁ = ∂e_k/∂b₂ = Y_k (Y₁ = 0: None)."""
    d = z[:, 12:15] - z[:, 0:3]
    ln = np.sqrt(_dot(d, d))
    e1 = d / ln[:, None]
    ybar = z[:, 6:9] + z[:, 18:21]
    n = cross(e1, ybar)
    nn = np.sqrt(_dot(n, n))
    e3 = n / nn[:, None]
    e2 = cross(e3, e1)
    Re = np.stack([e1, e2, e3], axis=2)
    if not derivatives:
        return Re
    de1 = (_I3 - e1[:, :, None] * e1[:, None, :]) / ln[:, None, None]
    P3 = (_I3 - e3[:, :, None] * e3[:, None, :]) / nn[:, None, None]
    S1, S3 = skew(e1), skew(e3)
    de3_d, de3_y = -P3 @ skew(ybar) @ de1, P3 @ S1
    de2_d, de2_y = -S1 @ de3_d + S3 @ de1, -S1 @ de3_y
    return Re, [(de1, None), (de2_d, de2_y), (de3_d, de3_y)]


def velocity_map(z, Re):
    """T_z (nb, 12, 24): local velocities v = T_z ż (beam_whirl.velocity_map_z)."""
    nb = z.shape[0]
    T = np.zeros((nb, 2, 6, 2, 12))
    Rt = Re.transpose(0, 2, 1)
    T[:, 0, 0:3, 0, 0:3] = T[:, 1, 0:3, 1, 0:3] = Rt
    # ½ R_eᵀ [x]ₓ for the node's axes x: row j is ½ e_j × x
    rot = 0.5 * cross(Rt[:, None, :, None, :], z[:, _AXIS_COLS][:, :, None, :, :])
    for i in range(2):  # rot (nb, node, j, axis, 3)
        T[:, i, 3:6, i, 3:12] = rot[:, i].reshape(nb, 3, 9)
    return T.reshape(nb, 12, 24)


def velocity_terms_z(z, zd, M):
    """h_z = Ṁ ż − ½ ∂(żᵀ T_zᵀ M T_z ż)/∂z (nb, 24) for the local masses M (nb, 12, 12)
    (beam_whirl.velocity_terms_z, term by term)."""
    Re, E = frame(z, derivatives=True)
    T = velocity_map(z, Re)
    dd = zd[:, 12:15] - zd[:, 0:3]
    dy = zd[:, 6:9] + zd[:, 18:21]
    Rdot = np.stack([_mv(D, dd) + (0.0 if Y is None else _mv(Y, dy)) for D, Y in E], axis=2)
    rd = (zd[:, 0:3], zd[:, 12:15])
    Zx, Zdx = z[:, _AXIS_COLS], zd[:, _AXIS_COLS]  # (nb, node, axis, 3)
    om = 0.5 * cross(Zx, Zdx).sum(axis=2)  # ω_i = ½ Σ x × ẋ
    lam = _mv(M, _mv(T, zd))
    a = np.concatenate([_mtv(Rdot, rd[0]), _mtv(Rdot, om[:, 0]), _mtv(Rdot, rd[1]),
                        _mtv(Rdot, om[:, 1])], axis=1)
    h = _mtv(T, _mv(M, a))
    lam2 = lam.reshape(-1, 2, 2, 3)  # (nb, node, [translation, rotation], 3)
    h[:, [0, 1, 2, 12, 13, 14]] += np.einsum("nij,nkj->nki", Rdot, lam2[:, :, 0]).reshape(-1, 6)
    g_r = np.einsum("nij,nkj->nki", Re, lam2[:, :, 1])[:, :, None]
    gdot_r = np.einsum("nij,nkj->nki", Rdot, lam2[:, :, 1])[:, :, None]
    h[:, _AXIS_COLS] += 0.5 * cross(gdot_r, Zx) + cross(g_r, Zdx)
    for k, (D, Y) in enumerate(E):  # −Jᵀλ through R_e
        m_k = sum(lam[:, 6 * i + k, None] * rd[i] + lam[:, 6 * i + 3 + k, None] * om[:, i]
                  for i in range(2))
        t = _mtv(D, m_k)
        h[:, 0:3] += t
        h[:, 12:15] -= t
        if Y is not None:
            t = _mtv(Y, m_k)
            h[:, 6:9] -= t
            h[:, 18:21] -= t
    return h


def mass_q(TC, M):
    """(T C)ᵀ M (T C) (nb, m, m)."""
    return TC.transpose(0, 2, 1) @ (M @ TC)


# ---------------------------------------------------------------------------------------------
class _Gathered:
    """A stacked field of :class:`Stack` kept as its distinct arrays and each member's index
    among them, the stack (nb, …) made when read: the members of a uniform beam share a few
    element matrices (one per element length), and a chunk gathers only its own rows."""

    def __set_name__(self, owner, name):
        self.slot = "_" + name

    def __get__(self, st, owner=None):
        values, ids = st.__dict__[self.slot]
        return values[ids]


def _distinct(arrays):
    """(the distinct arrays stacked, each one's index among them), distinct by identity."""
    index, kept, ids = {}, [], np.empty(len(arrays), dtype=np.intp)
    for k, a in enumerate(arrays):
        j = index.get(id(a))
        if j is None:
            j = index[id(a)] = len(kept)
            kept.append(a)
        ids[k] = j
    return np.stack(kept), ids


class Stack:
    """The constant data of nb member elements, stacked: z = C q[idx] + d with idx (nb, m) and
    C (nb, 24, m) padded to m = max(WIDTH, the widest member) (padding: coordinate 0, zero
    columns; one read-only map broadcast to all where the members share it); ``sizes``
    the true widths; l0, EA, GJ (nb,), the bending planes' G and K_b (nb, 2, 2), the local mass
    M and gyroscopic G (nb, 12, 12) and the spins (nb,).  ``records`` are the members'
    :meth:`~mbseig.model.beam3d.Beam3DElement.kernel_record` dicts."""

    Gz, Kbz, Gy, Kby, M, G = (_Gathered() for _ in range(6))

    def __init__(self, records):
        nb = len(records)
        self.sizes = np.array([r["idx"].size for r in records])
        m = max(int(self.sizes.max()), WIDTH)  # one width: a member's sums do not depend on
        # the others (an element alone and in its batch give the same numbers)
        self.idx = np.zeros((nb, m), dtype=np.intp)
        C0 = records[0]["C"]
        shared = C0.shape == (24, m) and all(r["C"] is C0 for r in records)
        if shared:  # one map for all (a beam's section frame: beam3d._node_map): one copy
            self.C = np.broadcast_to(C0, (nb, 24, m))
            self.Ct = np.broadcast_to(np.ascontiguousarray(C0.T), (nb, m, 24))
        else:
            self.C = np.zeros((nb, 24, m))
        for k, r in enumerate(records):
            s = self.sizes[k]
            self.idx[k, :s] = r["idx"]
            if not shared:
                self.C[k, :, :s] = r["C"]
        self.d = np.stack([r["d"] for r in records])
        if not shared:
            self.Ct = np.ascontiguousarray(self.C.transpose(0, 2, 1))
        for key in ("l0", "EA", "GJ", "spin"):
            setattr(self, key, np.array([r[key] for r in records], dtype=float))
        for key in ("Gz", "Kbz", "Gy", "Kby", "M", "G"):
            self.__dict__["_" + key] = _distinct([r[key] for r in records])

    def part(self, rows):
        """The stack of the members ``rows`` (a slice): views of this one's arrays."""
        got = object.__new__(Stack)
        for key, value in vars(self).items():
            if isinstance(value, tuple):  # a gathered field: its distinct arrays and indices
                got.__dict__[key] = (value[0], value[1][rows])
            else:
                setattr(got, key, value[rows])
        return got

    def z(self, v, offset=True):
        # (matrix products member by member: the same numbers whether C is one map shared by
        # the members or a stack, and whatever the batch)
        z = (self.C @ v[self.idx][:, :, None])[:, :, 0]
        return z + self.d if offset else z

    def to_q(self, gz):
        """Cᵀ g_z per member (nb, m)."""
        return (self.Ct @ gz[:, :, None])[:, :, 0]
