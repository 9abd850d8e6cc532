"""Stage 2: linearization about an equilibrium and projection onto the constraint null space
(docs/design.md, "Linearization").

With N an orthonormal basis of null Φ_q(q₀) (rank-revealing SVD, relative tolerance ``rank_tol``)
and q = q₀ + N x:

    M_r ẍ + P ẋ + Q x = 0,     M_r = Nᵀ M N,   P = Nᵀ C N,   Q = Nᵀ (K + H(λ₀)) N

    C = −∂g/∂q̇,   K = −∂g/∂q,   H(λ₀) = Σ_k λ₀,k ∇²Φ_k   (stiffness of the constraint forces)

          q̇, q ──► [ g(q, q̇) ] ──► −K, −C ─┐
                                            ├─► Nᵀ(·)N ──► M_r, P, Q
          λ₀ ────► [ Σ λ ∇²Φ ] ──► H ───────┘

Neither P nor Q is assumed symmetric: follower forces make Q non-symmetric and gyroscopic terms
make P skew.

Boundaries (README, "Input rules"): the equilibrium handed in must be finite, and M, P, Q, N
come out finite; an overflow on the way (numpy's warning, an arithmetic exception) or a
non-finite matrix is a :class:`~mbseig.errors.NumericalError` naming the linearization.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
import scipy.sparse as sp

from .model.linear_case import LinearCase
from .numerics import DOUBLE_RANGE, null_space_basis, require_finite, watched
from .statics import Equilibrium, solved

__all__ = ["LinearModel", "linearize"]

SPARSE_MIN = 5000  # coordinates above which linearize keeps M, P, Q sparse by default
CAUSE = (f"the model's masses, damping, stiffnesses or constraint forces at the equilibrium "
         f"leave {DOUBLE_RANGE} (values of the case too large or too small together)")
LINEAR_CASE_CAUSE = f"a matrix of the case (a factor times a matrix) leaves {DOUBLE_RANGE}"


@dataclass(frozen=True, eq=False)
class LinearModel:
    """Reduced linear model  M ẍ + P ẋ + Q x = 0,  q = q₀ + N x.

    First-order form (when M is invertible), state z = [x; ẋ]:

        ż = A z,   A = ┌   0        I    ┐
                       └ −M⁻¹Q   −M⁻¹P  ┘
    """

    M: np.ndarray
    P: np.ndarray
    Q: np.ndarray
    N: np.ndarray
    q0: np.ndarray
    lam0: np.ndarray
    coordinate_names: tuple
    name: str = ""
    parameters: dict = field(default_factory=dict)
    rank: int = 0
    n_constraints: int = 0
    constraint_stiffness: bool = True
    tolerances: dict = field(default_factory=dict)
    constraint_jacobian: object = None  # sparse Φ_q when M, P, Q stay in full coordinates

    @property
    def dof(self) -> int:
        if self.constraint_jacobian is not None:
            return self.M.shape[0] - self.rank
        return self.M.shape[0]

    @property
    def n_redundant(self) -> int:
        return self.n_constraints - self.rank

    def state_matrix(self) -> np.ndarray:
        """A of ż = A z; raises numpy.linalg.LinAlgError when M is singular."""
        n = self.dof
        MinvQ = np.linalg.solve(self.M, self.Q)
        MinvP = np.linalg.solve(self.M, self.P)
        return np.block([[np.zeros((n, n)), np.eye(n)], [-MinvQ, -MinvP]])

    def to_statespace(self):
        """python-control StateSpace with generalized-force inputs and x, ẋ outputs.

        ż = A z + B u,  B = [0; M⁻¹],  y = z.
        """
        import control

        n = self.dof
        A = self.state_matrix()
        B = np.vstack([np.zeros((n, n)), np.linalg.inv(self.M)])
        return control.ss(A, B, np.eye(2 * n), np.zeros((2 * n, n)))


def linearize(model, eq: Equilibrium, *, rank_tol: float | None = None,
              constraint_stiffness: bool = True, sparse: bool | None = None) -> LinearModel:
    """Linear model about ``eq`` (see module docstring).

    rank_tol : relative singular-value threshold for null Φ_q (default: the one the equilibrium
        used for the redundancy count, so both stages see the same rank).
    constraint_stiffness : include H(λ₀).  ``False`` reproduces the common mistake of dropping
        the constraint-force stiffness; it exists to measure that error, never for production.
    sparse : keep M, P, Q sparse (default: when the model has more than ``SPARSE_MIN``
        coordinates).  Without constraints N is the sparse identity; with constraints no
        null-space basis is formed: M, P, Q stay in full coordinates and ``constraint_jacobian``
        holds Φ_q(q₀) for the bordered pencil of :mod:`mbseig.eigen.partial` (N is None).

    The model linearized is the one ``eq`` belongs to (:func:`mbseig.statics.solved`): with
    inverse-statics commands resolved, the actuator settings found by the equilibrium.
    Raises :class:`~mbseig.errors.NumericalError` when the equilibrium or the result is not
    finite, or the arithmetic overflowed on the way (module docstring).
    """
    require_finite("linearization", "the equilibrium is not finite", q0=eq.q, lam0=eq.lam)
    cause = LINEAR_CASE_CAUSE if isinstance(model, LinearCase) else CAUSE
    with watched("linearization", cause):
        lin = _linearize(model, eq, rank_tol, constraint_stiffness, sparse)
    require_finite("linearization", cause, M=lin.M, P=lin.P, Q=lin.Q, N=lin.N)
    return lin


def _linearize(model, eq, rank_tol, constraint_stiffness, sparse):
    model = solved(model, eq)
    if rank_tol is None:
        rank_tol = float(eq.tolerances.get("rank_tol", 1e-10))
    if isinstance(model, LinearCase):
        return LinearModel(M=model.M, P=model.P, Q=model.Q, N=np.eye(model.n), q0=np.zeros(model.n),
                           lam0=np.zeros(0), coordinate_names=model.coordinate_names, name=model.name,
                           parameters=model.parameters, tolerances={"rank_tol": rank_tol})
    q0, lam0 = eq.q, eq.lam
    K, C = model.force_jacobians(q0)
    if constraint_stiffness and model.n_constraints:
        K = K + model.constraint_hessian(q0, lam0)
    if model.n > SPARSE_MIN if sparse is None else sparse:
        G = model.phi_q(q0) if model.n_constraints else None
        N = sp.identity(model.n, format="csr") if G is None else None
        return LinearModel(
            M=model.mass_matrix(q0).tocsr(), P=C.tocsr(), Q=K.tocsr(), N=N, q0=q0, lam0=lam0,
            coordinate_names=model.coordinate_names, name=model.name, parameters=model.parameters,
            rank=eq.rank, n_constraints=model.n_constraints,
            constraint_stiffness=constraint_stiffness,
            tolerances={"rank_tol": rank_tol, "sparse": True}, constraint_jacobian=G)
    N, rank = null_space_basis(model.phi_q(q0), model.n, rank_tol)
    Md, Cd, Kd = (A.toarray() for A in (model.mass_matrix(q0), C, K))
    if model.n_constraints == 0:
        Mr, Pr, Qr = Md, Cd, Kd
    else:
        Mr, Pr, Qr = (N.T @ A @ N for A in (Md, Cd, Kd))
    return LinearModel(
        M=Mr, P=Pr, Q=Qr, N=N, q0=q0, lam0=lam0, coordinate_names=model.coordinate_names,
        name=model.name, parameters=model.parameters, rank=rank,
        n_constraints=model.n_constraints, constraint_stiffness=constraint_stiffness,
        tolerances={"rank_tol": rank_tol},
    )
