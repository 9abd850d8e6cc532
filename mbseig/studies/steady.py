"""Linearization about a steady motion with rolling wheels (non-holonomic constraints).

Equations of motion (q natural coordinates, n; Ω the wheels' axial rates, n_w; λ, μ the
multipliers of the holonomic rows Φ and of the velocity rows ψ = A(q) q̇ + B Ω):

    M q̈ = f(q, q̇, Ω) − Φ_qᵀ λ − A(q)ᵀ μ,       f = g(q, q̇) + Σ_wheels G(q, q̇, Ω)
    J Ω̇ = −Bᵀ μ                                  (J = diag I_a: the spins' own equations)
    Φ(q) = 0,   A(q) q̇ + B Ω = 0

(M includes each wheel's :meth:`~rolling.RollingWheel.mass_correction`: the frames do not spin).

Reference (``[motion]``: speed v along d, optional yaw rate r about the gravity axis e_z): a
relative equilibrium.  Its velocity field at t = 0 is affine, q̇ = ξ(q) = L q + l
(:func:`generator`): every basic point P moves at v d + r e_z × P (the point at the origin moves
at v d; the system turns about the vertical through c = (v/r) e_z × d), every unit vector at
r e_z × e.  The motion is q(t) = 𝓡(t) q̄ with 𝓡 the rotation (or translation) of every triple;
every element is invariant under it (gravity along e_z, the ground plane normal to it, joints
between bodies; a ground joint or ground bushing is not, and the motion is refused when
Φ_q ξ ≠ 0), and M = A ⊗ I₃ commutes with 𝓡, so in the moving coordinates q̄ (p = dq̄/dt):

    q̇ = 𝓡 (p + ξ(q̄)),   q̈ = 𝓡 (ṗ + 2 L p + L ξ(q̄))

and the equations in q̄ are autonomous.  The reference is q̄ = q₀, p = 0; its spins solve
A ξ + B Ω₀ = 0, its multipliers are first fitted by least squares at the given positions (so a
configuration that is already steady is kept exactly), then (q₀, Ω₀, λ₀, μ₀) solve, by Newton on
the whole set (minimum-norm steps: cyclic coordinates leave the system singular but consistent),

    f(q₀, ξ, Ω₀) − M L ξ − Φ_qᵀλ₀ − Aᵀμ₀ = 0,   −Bᵀμ₀ = 0,   Φ(q₀) = 0,   A(q₀) ξ + B Ω₀ = 0.

For straight running L = 0 and l = v·(d on every point).

Linearization in the moving coordinates, δq = q̄ − q₀, δp = p, δΩ, δλ, δμ:

    δq̇ = δp
    M δṗ = F_q δq + F_p δp + F_Ω δΩ − Φ_qᵀ δλ − Aᵀ δμ
    J δΩ̇ = −Bᵀ δμ
    Φ_q δq = 0
    A δp + Ã δq + B δΩ = 0                                                       (*)

    F_q = −K − K_gyro + (−C − C_gyro) L − M L L − Σλ₀∇²Φ − ∂(Aᵀμ₀)/∂q   (centrifugal: −M L L)
    F_p = −C − C_gyro − 2 M L                                             (Coriolis: −2 M L)
    F_Ω = ∂G/∂Ω,   Ã = ∂(A(q) ξ)/∂q|_ξ fixed + A L

(K, C = −∂f/∂q, −∂f/∂q̇ at q̇ = ξ; the gyroscopic terms of the spins are evaluated at ξ and Ω₀).
In a turn, a rigid translation of the whole system in the ground plane (another steady turn
about a shifted centre) appears in the turning frame as the pair s = ±i r, not as s = 0.

Ã is the term a naive linearization drops: it is the change of the slip velocity when the
configuration changes at the reference velocities (a leaned, steered or yawed wheel moving
forward slips sideways unless the lateral velocities change).

Reduction (exact).  (1) N (n × d, orthonormal) spans null Φ_q(q₀); in the moving coordinates Φ_q is
constant along the reference, so δq = N x describes every δq with Φ_q δq = 0, and δp = N y.
(2) The velocity rows (*) become W [y; δΩ] = −Ã N x, W = [A N, B] (full row rank); their general
solution is [y; δΩ] = T z − S x with T (d + n_w) × k an orthonormal basis of null W and
S = W⁺ Ã N; z ∈ ℝᵏ are the independent velocities.  (3) The admissible virtual velocities are
exactly [N T_y; T_Ω] (T_y, T_Ω the rows of T for y and δΩ), so multiplying the momentum equations
by their transposes removes Φ_qᵀδλ (Φ_q N = 0) and Aᵀδμ, Bᵀδμ ((W T)ᵀ δμ = 0) without
approximation.  With M̄ = diag(NᵀMN, J), F_x = [Nᵀ F_q N; 0], F_w = [[Nᵀ F_p N, Nᵀ F_Ω], [0, 0]]
and E_y = [I_d 0]:

          state X = [x; z]   (d positions on the holonomic manifold, k independent velocities)

    ┌ I_d        0     ┐ ┌ẋ┐   ┌ −E_y S                 E_y T   ┐ ┌x┐
    └ −TᵀM̄S    TᵀM̄T ┘ └ż┘ = └ TᵀF_x − TᵀF_w S      TᵀF_w T  ┘ └z┘

since w = [y; δΩ] = T z − S x gives ẇ = T ż − S ẋ and Tᵀ M̄ ẇ = Tᵀ (F_x x + F_w w).  Each step
is an identity of the linearized equations (no neglected term), so the eigenvalues of this
pencil are those of the full descriptor system (:func:`full_descriptor`, index 3, tested).  The
state has d + k entries: positions and velocities are no longer of equal size.  The naive
variant drops ∂(A(q) ξ)/∂q|_ξ fixed (``naive=True``; the frame term A L stays).
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
import scipy.linalg as sla

from ..errors import EquilibriumError
from ..model.rolling import Motion


class SteadyMotionError(EquilibriumError):
    """The steady motion does not exist or is not found (one line, element ``motion``)."""

    def __init__(self, message, *, file=None, element="motion"):
        super().__init__(message, file=file, element=element)

__all__ = [
    "Motion",
    "SteadyLinearization",
    "SteadyMotionError",
    "SteadyState",
    "full_descriptor",
    "generator",
    "linearize_steady",
    "steady_state",
    "translation",
]


@dataclass(frozen=True, eq=False)
class SteadyState:
    """The reference motion: q₀ (t = 0), q̇₀, spins Ω₀, multipliers λ₀ (model rows, then two rows
    per wheel: contact, gauge) and μ₀ (two per wheel), the Newton record, and per wheel its
    normal force (N, > 0 pushing) and whether it is active."""

    #: the reference motion this belongs to (mbseig.studies.reference): a steady motion
    kind = "steady"

    q: np.ndarray
    qd: np.ndarray
    spin: np.ndarray
    lam: np.ndarray
    mu: np.ndarray
    residual: float
    iterations: int
    contacts: tuple = ()
    motion: Motion = None


@dataclass(frozen=True, eq=False)
class SteadyLinearization:
    """E Ẋ = A X, X = [x; z] (module docstring); q = q₀(t) + N x, [q̇ − q̇₀; Ω − Ω₀] =
    [N 0; 0 I](T z − S x)."""

    #: the reference motion this belongs to (mbseig.studies.reference): descriptor E, A
    kind = "steady"

    E: np.ndarray
    A: np.ndarray
    N: np.ndarray
    T: np.ndarray
    S: np.ndarray
    dof: int
    n_velocities: int
    naive: bool
    state: SteadyState
    tolerances: dict = field(default_factory=dict)


def translation(model, direction):
    """q̇ of a unit translation along ``direction``: every basic point coordinate (``P.x``)
    moves, unit vectors (``B.u.x``) do not."""
    d = np.asarray(direction, float)
    d = d / np.linalg.norm(d)
    t = np.zeros(model.n)
    for k, name in enumerate(model.coordinate_names):
        parts = name.split(".")
        if len(parts) == 2 and parts[1] in "xyz":
            t[k] = d["xyz".index(parts[1])]
    return t


def generator(model, motion: Motion):
    """(L, l): the reference velocity field q̇ = ξ(q) = L q + l of ``motion`` at t = 0.  The
    point at the global origin moves at v along d; with a yaw rate r the system turns about
    the vertical through c = (v/r) e_z × d:  ξ_P = r e_z × (P − c) for every basic point,
    ξ_e = r e_z × e for every unit vector (r = 0: ξ_P = v d, ξ_e = 0)."""
    d = np.asarray(motion.direction, float)
    d = d / np.linalg.norm(d)
    ez = np.asarray(motion.up, float)
    ez = ez / np.linalg.norm(ez)
    if abs(d @ ez) > 1e-12:
        raise SteadyMotionError("direction must be normal to the gravity axis")
    r = float(motion.yaw_rate)
    Sz = np.array([[0.0, -ez[2], ez[1]], [ez[2], 0.0, -ez[0]], [-ez[1], ez[0], 0.0]])
    L = np.zeros((model.n, model.n))
    lv = motion.speed * translation(model, d)
    names = model.coordinate_names
    k = 0
    while k < model.n:
        parts = names[k].split(".")
        triple = (k + 2 < model.n and parts[-1] == "x" and names[k + 1].endswith(".y")
                  and names[k + 2].endswith(".z"))
        if triple and (len(parts) == 2 or (len(parts) == 3 and parts[1] in "uvw")):
            L[k:k + 3, k:k + 3] = r * Sz
            k += 3
        else:
            k += 1
    return L, lv


class SteadyAssembly:
    """Dense blocks of the equations at (q, q̇, Ω, λ, μ) for a model with rolling wheels (their
    holonomic rows are among the model's constraints: :class:`~mbseig.model.rolling.WheelRows`)."""

    def __init__(self, model, wheels=None):
        from ..model.rolling import WheelRows, wheels_of

        self.model = model
        self.wheels = tuple(wheels_of(model) if wheels is None else wheels)
        n = model.n
        M = model.mass_matrix(model.q_init).toarray()
        for w in self.wheels:
            M[np.ix_(w.idx, w.idx)] += w.mass_correction()
        self.M = M
        self.J = np.diag([w.axial_inertia for w in self.wheels])
        self.B = np.zeros((2 * len(self.wheels), len(self.wheels)))
        for k, w in enumerate(self.wheels):
            self.B[2 * k:2 * k + 2, k] = w.spin_column
        self.n, self.m_h = n, model.n_constraints
        rows, k = {}, 0
        for c in model.constraints:
            if isinstance(c, WheelRows):
                rows[id(c.wheel)] = k
            k += c.n_eq
        self.contact_row = [rows[id(w)] for w in self.wheels]

    def phi(self, q):
        return self.model.phi(q)

    def phi_q(self, q):
        return np.asarray(self.model.phi_q(q, dense=True))

    def hessian(self, q, lam):
        return np.asarray(self.model.constraint_hessian(q, lam, dense=True))

    def velocity(self, q, qd):
        """(A(q), Ã = ∂(A q̇)/∂q)."""
        A = np.zeros((2 * len(self.wheels), self.n))
        At = np.zeros_like(A)
        for k, w in enumerate(self.wheels):
            A[2 * k:2 * k + 2, w.idx] = w.velocity_jacobian(q)
            At[2 * k:2 * k + 2, w.idx] = w.velocity_jacobian_q(q, qd)
        return A, At

    def forces(self, q, qd, spin, mu):
        """(f, F_q (without the multiplier terms), F_p, F_Ω, ∂(Aᵀμ)/∂q)."""
        f = np.array(self.model.generalized_force(q, qd), float)
        K, C = self.model.force_jacobians(q, qd, dense=True)
        Fq, Fp = -np.array(K, float), -np.array(C, float)
        FO = np.zeros((self.n, len(self.wheels)))
        Hmu = np.zeros((self.n, self.n))
        for k, w in enumerate(self.wheels):
            g, dq, dqd, dO = w.gyroscopic(q, qd, spin[k])
            ix = np.ix_(w.idx, w.idx)
            f[w.idx] += g
            Fq[ix] += dq
            Fp[ix] += dqd
            FO[w.idx, k] += dO
            Hmu[ix] += w.multiplier_stiffness(mu[2 * k:2 * k + 2])
        return f, Fq, Fp, FO, Hmu


def steady_state(model, motion: Motion, *, wheels=None, q0=None, tol=1e-12, max_iter=25):
    """The steady motion ``motion`` of ``model`` on its rolling wheels (module docstring).

    In the frame moving with the reference, q̇ = p + ξ(q) (:func:`generator`) and
    q̈ = ṗ + 2 L p + L ξ(q); at the reference p = 0.  Raises ValueError when Newton does not
    reach ``tol`` or the constraints do not allow the motion."""
    asm = SteadyAssembly(model, wheels)
    q = np.array(model.q_init if q0 is None else q0, float)
    L, ell = generator(model, motion)
    nw, n, mh = len(asm.wheels), asm.n, asm.m_h
    qd = L @ q + ell
    if np.linalg.norm(asm.phi_q(q) @ qd) > 1e-9 * max(1.0, np.abs(qd).max(initial=0.0)):
        raise SteadyMotionError("the constraints do not let the system move this way (a "
                         "ground joint, or a ground plane that does not contain the motion)")
    A, _ = asm.velocity(q, qd)
    spin = np.linalg.lstsq(asm.B, -(A @ qd), rcond=None)[0] if nw else np.zeros(0)
    # multipliers of the given configuration first (least squares), so that a configuration
    # that is already steady is kept exactly: Newton then corrects what remains
    f = asm.forces(q, qd, spin, np.zeros(2 * nw))[0]
    G = np.block([[asm.phi_q(q).T, A.T], [np.zeros((nw, mh)), asm.B.T]])
    lm = np.linalg.lstsq(G, np.concatenate([f - asm.M @ (L @ qd), np.zeros(nw)]), rcond=None)[0]
    lam, mu = lm[:mh], lm[mh:]
    sizes = np.cumsum([0, n, nw, mh, 2 * nw])
    fscale = max(1.0, float(np.abs(model.g_const).max(initial=0.0)))
    for it in range(max_iter + 1):
        qd = L @ q + ell
        Pq = asm.phi_q(q)
        A, At = asm.velocity(q, qd)
        f, Fq, Fp, FO, Hmu = asm.forces(q, qd, spin, mu)
        F = np.concatenate([(f - asm.M @ (L @ qd) - Pq.T @ lam - A.T @ mu) / fscale,
                            -asm.B.T @ mu / fscale, asm.phi(q), A @ qd + asm.B @ spin])
        res = float(np.abs(F).max(initial=0.0))
        if res <= tol:
            break
        if it == max_iter:
            raise SteadyMotionError(f"Newton stopped at residual {res:.3g} after "
                             f"{max_iter} iterations")
        Jm = np.zeros((sizes[-1], sizes[-1]))
        Jm[:n, :n] = (Fq + Fp @ L - asm.M @ L @ L - asm.hessian(q, lam) - Hmu) / fscale
        Jm[:n, n:n + nw] = FO / fscale
        Jm[:n, sizes[2]:sizes[3]] = -Pq.T / fscale
        Jm[:n, sizes[3]:] = -A.T / fscale
        Jm[n:n + nw, sizes[3]:] = -asm.B.T / fscale
        Jm[sizes[2]:sizes[3], :n] = Pq
        Jm[sizes[3]:, :n] = At + A @ L
        Jm[sizes[3]:, n:n + nw] = asm.B
        step = np.linalg.lstsq(Jm, -F, rcond=None)[0]
        q, spin = q + step[:n], spin + step[n:n + nw]
        lam, mu = lam + step[sizes[2]:sizes[3]], mu + step[sizes[3]:]
    contacts = tuple({"name": w.name, "force": float(-lam[r] / w.length),
                      "active": bool(-lam[r] >= 0)}
                     for w, r in zip(asm.wheels, asm.contact_row, strict=True))
    return SteadyState(q, L @ q + ell, spin, lam, mu, res, it, contacts, motion)


def _moving_frame_terms(model, asm, state, naive):
    """F_q, F_p, F_Ω, A, Ã of the linearized equations in the moving frame (p = q̇ − ξ(q)):
    F_q = ∂f/∂q + ∂f/∂q̇ L − M L L − Σλ∇²Φ − ∂(Aᵀμ)/∂q,  F_p = ∂f/∂q̇ − 2 M L,
    Ã = ∂(A q̇₀)/∂q + A L  (the first term dropped when ``naive``)."""
    q, qd, spin, lam, mu = state.q, state.qd, state.spin, state.lam, state.mu
    L, _ = generator(model, state.motion)
    A, At = asm.velocity(q, qd)
    if naive:
        At = np.zeros_like(At)
    _, Fq, Fp, FO, Hmu = asm.forces(q, qd, spin, mu)
    Fq = Fq + Fp @ L - asm.M @ L @ L - asm.hessian(q, lam) - Hmu
    return Fq, Fp - 2.0 * asm.M @ L, FO, A, At + A @ L


def _null(X, n, rank_tol):
    if X.shape[0] == 0:
        return np.eye(n)
    return sla.null_space(X, rcond=rank_tol)


def linearize_steady(model, state: SteadyState, *, wheels=None, naive=False, rank_tol=1e-10):
    """The first-order descriptor system E Ẋ = A X about ``state`` (module docstring).
    ``naive=True`` drops Ã (the velocity rows' derivative w.r.t. the positions)."""
    asm = SteadyAssembly(model, wheels)
    q = state.q
    nw = len(asm.wheels)
    N = _null(asm.phi_q(q), asm.n, rank_tol)
    d = N.shape[1]
    Fq, Fp, FO, A, At = _moving_frame_terms(model, asm, state, naive)
    W = np.hstack([A @ N, asm.B])
    T = _null(W, d + nw, rank_tol)
    S = np.linalg.lstsq(W, At @ N, rcond=None)[0] if W.shape[0] else np.zeros((d + nw, d))
    k = T.shape[1]
    Mbar = sla.block_diag(N.T @ asm.M @ N, asm.J)
    Fx = np.vstack([N.T @ Fq @ N, np.zeros((nw, d))])
    Fw = np.zeros((d + nw, d + nw))
    Fw[:d, :d] = N.T @ Fp @ N
    Fw[:d, d:] = N.T @ FO
    Ey = np.hstack([np.eye(d), np.zeros((d, nw))])
    E = np.block([[np.eye(d), np.zeros((d, k))], [-T.T @ Mbar @ S, T.T @ Mbar @ T]])
    Amat = np.block([[-Ey @ S, Ey @ T], [T.T @ Fx - T.T @ Fw @ S, T.T @ Fw @ T]])
    return SteadyLinearization(E, Amat, N, T, S, d, k, naive, state, {"rank_tol": rank_tol})


def full_descriptor(model, state: SteadyState, *, wheels=None, naive=False):
    """(E, A) of the unreduced linearized equations on [δq; δp; δΩ; δλ; δμ] (index 3; many
    infinite eigenvalues): the independent check of the reduction."""
    asm = SteadyAssembly(model, wheels)
    q = state.q
    n, nw, mh = asm.n, len(asm.wheels), asm.m_h
    Pq = asm.phi_q(q)
    Fq, Fp, FO, A, At = _moving_frame_terms(model, asm, state, naive)
    mv = 2 * nw
    def Z(r, c):
        return np.zeros((r, c))

    E = sla.block_diag(np.eye(n), asm.M, asm.J, Z(mh, mh), Z(mv, mv))
    Am = np.block([
        [Z(n, n), np.eye(n), Z(n, nw), Z(n, mh), Z(n, mv)],
        [Fq, Fp, FO, -Pq.T, -A.T],
        [Z(nw, n), Z(nw, n), Z(nw, nw), Z(nw, mh), -asm.B.T],
        [Pq, Z(mh, n), Z(mh, nw), Z(mh, mh), Z(mh, mv)],
        [At, A, asm.B, Z(mv, mh), Z(mv, mv)]])
    return E, Am
