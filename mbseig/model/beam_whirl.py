"""The whirl stations of a spinning beam: what :mod:`mbseig.model.spatial_whirl` reads of a
beam with ``spin`` (its node frames, axis, speed and station points), like a rigid rotor; and
the kinematics of a 3-D beam element's co-rotated frame (its velocity map and the closed-form
velocity terms of its configuration-dependent mass, :class:`mbseig.model.beam3d.Beam3DElement`)."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .affine import Affine
from .spatial_body import vector_matrix


@dataclass(frozen=True, eq=False)
class SpinningShaft:
    """The whirl stations of a spinning beam (``spin``), read like a rigid ``rotor`` by
    :mod:`mbseig.model.spatial_whirl`: ``frame`` stacks the first node's frame [r; u; v; w] and
    the triads of the other nodes (a mode which only twists or tilts the nodes counts as body
    motion: ``motion_idx``, their coordinates), ``axis`` the beam axis in the first node's
    frame, ``speed`` Ω, ``stations``
    (label, Affine) of every node's point.  Not an element: it adds nothing to the equations."""

    name: str
    frame: Affine
    axis: np.ndarray
    speed: float
    stations: tuple = ()
    body: str = ""
    affine_field = "frame"

    def __post_init__(self):
        import scipy.sparse as sp

        from .affine import combine

        smap = combine([(1.0, aff) for _, aff in self.stations], stack=True)
        object.__setattr__(self, "station_map", (smap.idx, sp.csr_matrix(smap.C)))
        object.__setattr__(self, "motion_idx", self.frame.idx)

    def axis_map(self) -> Affine:
        V = vector_matrix(self.axis)
        return Affine(self.frame.idx, V @ self.frame.C[:12], V @ self.frame.d[:12])


# ---------------------------------------------------------------------------------------------
# kinematics of the co-rotated element frame (mbseig.model.beam3d.Beam3DElement's mass)
#
# z = [r₁, a₁, b₁, c₁, r₂, a₂, b₂, c₂] (node points and section axes).  The element frame
# R_e = [e₁ e₂ e₃]: e₁ = d/|d| (d = r₂ − r₁), e₃ = n/|n| with n = e₁ × (b₁ + b₂), e₂ = e₃ × e₁.
# Local velocities  v = T_z ż = [R_eᵀ ṙ₁, R_eᵀ ω₁, R_eᵀ ṙ₂, R_eᵀ ω₂],  ω_i = ½ Σ_x x × ẋ over the
# node's three axes.  With the kinetic energy ½ żᵀ T_zᵀ M T_z ż, Lagrange's velocity terms are
#
#     h_z = Ṁ ż − ½ ∂(żᵀ M(z) ż)/∂z = T_zᵀ M (Ṫ_z ż) + (Ṫ_zᵀ − J_zᵀ) M v,
#
# J_z = ∂(T_z w)/∂z at w = ż.  Every piece is closed-form: ∂e_k/∂z (E_k, 3 × 24) and the
# bilinear ω_i.


def _cross(a, b):
    """a × b of two 3-vectors (np.cross costs ~10 µs a call)."""
    return np.array([a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2],
                     a[0] * b[1] - a[1] * b[0]])


def _skew(a):
    return np.array([[0.0, -a[2], a[1]], [a[2], 0.0, -a[0]], [-a[1], a[0], 0.0]], dtype=a.dtype)


def element_frame(z, derivatives: bool = False):
    """R_e (3×3, columns e₁ e₂ e₃) of the section axes z (24,); with ``derivatives`` also
    (E₁, E₂, E₃) = ∂e_k/∂z, each 3 × 24."""
    d = z[12:15] - z[0:3]
    ln = np.sqrt(d @ d)
    e1 = d / ln
    ybar = z[6:9] + z[18:21]
    n = _cross(e1, ybar)
    nn = np.sqrt(n @ n)
    e3 = n / nn
    e2 = _cross(e3, e1)
    Re = np.column_stack([e1, e2, e3])
    if not derivatives:
        return Re
    I3 = np.eye(3)
    de1 = (I3 - np.outer(e1, e1)) / ln
    P3 = (I3 - np.outer(e3, e3)) / nn
    de3_d, de3_y = -P3 @ _skew(ybar) @ de1, P3 @ _skew(e1)
    de2_d, de2_y = -_skew(e1) @ de3_d + _skew(e3) @ de1, -_skew(e1) @ de3_y
    E = []
    for dd, dy in ((de1, None), (de2_d, de2_y), (de3_d, de3_y)):
        Ek = np.zeros((3, 24))
        Ek[:, 0:3], Ek[:, 12:15] = -dd, dd
        if dy is not None:
            Ek[:, 6:9] = Ek[:, 18:21] = dy
        E.append(Ek)
    return Re, E


def velocity_map_z(z, Re=None):
    """T_z (12 × 24): local velocities v = T_z ż in the element frame R_e."""
    Re = element_frame(z) if Re is None else Re
    T = np.zeros((12, 24))
    for i in range(2):
        o = 12 * i
        T[6 * i:6 * i + 3, o:o + 3] = Re.T
        for k in range(3):
            s = o + 3 + 3 * k
            T[6 * i + 3:6 * i + 6, s:s + 3] = 0.5 * Re.T @ _skew(z[s:s + 3])
    return T


def velocity_terms_z(z, zd, M):
    """h_z = Ṁ ż − ½ ∂(żᵀ T_zᵀ M T_z ż)/∂z (24,) for the local mass M (12×12) (block comment)."""
    Re, E = element_frame(z, derivatives=True)
    T = velocity_map_z(z, Re)
    Rdot = np.column_stack([Ek @ zd for Ek in E])
    rd = [zd[0:3], zd[12:15]]
    om = [0.5 * sum(_cross(z[s:s + 3], zd[s:s + 3]) for s in (o + 3, o + 6, o + 9))
          for o in (0, 12)]
    lam = M @ (T @ zd)
    a = np.concatenate([Rdot.T @ rd[0], Rdot.T @ om[0], Rdot.T @ rd[1], Rdot.T @ om[1]])
    h = T.T @ (M @ a)
    for i, o in enumerate((0, 12)):
        lt, lr = lam[6 * i:6 * i + 3], lam[6 * i + 3:6 * i + 6]
        h[o:o + 3] += Rdot @ lt
        g_r, gdot_r = Re @ lr, Rdot @ lr
        for s in (o + 3, o + 6, o + 9):  # (Ṫᵀλ − Jᵀλ) on the node's axes
            h[s:s + 3] += 0.5 * _cross(gdot_r, z[s:s + 3]) + _cross(g_r, zd[s:s + 3])
    for k in range(3):  # −Jᵀλ through R_e
        m_k = sum(lam[6 * i + k] * rd[i] + lam[6 * i + 3 + k] * om[i] for i in range(2))
        h -= E[k].T @ m_k
    return h
