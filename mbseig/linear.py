"""Stage 2: linearization about an equilibrium and projection onto the constraint null space
(docs/design.md, "Linearization").

With N an orthonormal basis of null Φ_q(q₀) (rank-revealing SVD, relative tolerance ``rank_tol``)
and q = q₀ + N x:

    M_r ẍ + P ẋ + Q x = 0,     M_r = Nᵀ M N,   P = Nᵀ C N,   Q = Nᵀ (K + H(λ₀)) N

    C = −∂g/∂q̇,   K = −∂g/∂q,   H(λ₀) = Σ_k λ₀,k ∇²Φ_k   (stiffness of the constraint forces)

          q̇, q ──► [ g(q, q̇) ] ──► −K, −C ─┐
                                            ├─► Nᵀ(·)N ──► M_r, P, Q
          λ₀ ────► [ Σ λ ∇²Φ ] ──► H ───────┘

Null-space basis (docs/design.md, "Null-space basis"): among the orthonormal bases of
null Φ_q, N is the one closest (Frobenius) to the coordinate directions E of d independent
coordinates, N = Π E (Eᵀ Π E)^(−1/2) with Π the orthogonal projector onto null Φ_q, i.e. the
polar factor of the projected directions.  It depends on the null space alone (not on how the
SVD happened to return it), so the same input gives the same N and N(p) is continuous in a
parameter p while the selection of independent coordinates holds (pass ``reference`` to hold it
across a sweep).  The selection is made by column-pivoted QR of a basis of the null space.

Inputs and outputs (:mod:`mbseig.model.signals`): M ẍ + P ẋ + Q x = B u with B = Nᵀ [b_1 … b_k]
(b_i = ∂g/∂u_i at q₀), and y = C [x; ẋ] + D u with the outputs' Jacobians through N.  A joint's
reaction depends on δλ, which the linearized dynamics fix exactly:

    Φ_qᵀ δλ = b u − K_t N x − C_d N ẋ − M N ẍ,   ẍ = M_r⁻¹ (B u − Q x − P ẋ)

(K_t = K + H(λ₀), C_d = −∂g/∂q̇; the right side lies in range Φ_qᵀ), solved with the left inverse
(Φ_q Φ_qᵀ)⁻¹ Φ_q; with redundant constraints δλ is not unique and such an output is refused.

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

from .arguments import check
from .errors import CaseError
from .model.linear_case import LinearCase
from .model.signals import input_forces, output_rows
from .numerics import (
    DOUBLE_RANGE,
    closest_basis,
    element_name,
    null_space_basis,
    require_finite,
    watched,
)
from .statics import Equilibrium, solved

__all__ = ["LinearModel", "linearize", "continuous_null_basis"]

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

    #: the reference motion this belongs to (mbseig.studies.reference): quadratic M, P, Q with its
    #: basis N
    kind = "rest"

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
    #: the constraints' rank N already takes out (a local basis, mbseig.model.tangent): the
    #: rows left in ``constraint_jacobian`` are in N's columns and have rank − eliminated
    eliminated: int = 0
    B: np.ndarray = None  # dof × n_u: M ẍ + P ẋ + Q x = B u (None: not formed, sparse path)
    C: np.ndarray = None  # n_y × 2 dof: y = C [x; ẋ] + D u
    D: np.ndarray = None  # n_y × n_u
    input_names: tuple = ()
    output_names: tuple = ()
    output_units: tuple = ()
    input_units: tuple = ()
    angle_names: tuple = ()  # named angles of the case (mode shapes in angles)
    angle_rows: np.ndarray = None  # n_a × n: δθ = angle_rows δq
    independent: tuple = ()  # coordinates whose directions fix the null-space basis
    #: the rigid-body directions by construction (DESIGN §6), computed at the first call:
    #: a :class:`~mbseig.model.symmetry.RigidDirections` in full coordinates (None: not known)
    rigid: object = None
    #: the displayed coordinates of mode shapes (:class:`~mbseig.model.naming.DisplayMap`, built
    #: at the first call): what dominant coordinates are named by
    display: object = None

    @property
    def dof(self) -> int:
        if self.constraint_jacobian is not None:
            return self.M.shape[0] - (self.rank - self.eliminated)
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

    def state_space(self):
        """(A, B, C, D) of ż = A z + B u, y = C z + D u, z = [x; ẋ] (the named inputs and
        outputs; without any: generalized-force inputs M⁻¹ and y = z)."""
        n = self.dof
        A = self.state_matrix()
        if self.B is None or (not self.input_names and not self.output_names):
            return (A, np.vstack([np.zeros((n, n)), np.linalg.inv(self.M)]), np.eye(2 * n),
                    np.zeros((2 * n, n)))
        Bss = np.vstack([np.zeros((n, self.B.shape[1])), np.linalg.solve(self.M, self.B)])
        return A, Bss, self.C, self.D

    def to_statespace(self):
        """python-control StateSpace ż = A z + B u, y = C z + D u, z = [x; ẋ].

        With named inputs and outputs (``[[inputs]]``, ``[[outputs]]``) its input and output
        labels are their names; without, the inputs are the generalized forces (B = [0; M⁻¹])
        and the outputs the state (the earlier interface, kept).
        """
        import control  # lazily: python-control costs ~0.3 s at import

        if self.B is None:
            raise CaseError("no input or output matrices: the model was kept sparse (large "
                            "model); linearize(..., sparse=False)", element="to_statespace")
        A, B, C, D = self.state_space()
        n = self.dof
        states = [f"x{k + 1}" for k in range(n)] + [f"xdot{k + 1}" for k in range(n)]
        if self.input_names or self.output_names:
            return control.ss(A, B, C, D, inputs=list(self.input_names),
                              outputs=list(self.output_names), states=states)
        return control.ss(A, B, C, D)


def linearize(model, eq: Equilibrium, *, rank_tol: float | None = None,
              constraint_stiffness: bool = True, sparse: bool | None = None,
              reference=None, signals: bool = True, basis=None) -> LinearModel:
    """Linear model about ``eq`` (see module docstring).

    rank_tol : relative singular-value threshold for null Φ_q (default: the one the equilibrium
        used for the redundancy count, so both stages see the same rank).
    constraint_stiffness : include H(λ₀).  ``False`` reproduces the common mistake of dropping
        the constraint-force stiffness; it exists to measure that error, never for production.
    reference : coordinate names fixing the null-space basis (module docstring; default: the
        independent coordinates chosen at this point, recorded as ``independent``).
    sparse : keep M, P, Q sparse (default: when the model has more than ``SPARSE_MIN``
        coordinates).  Without constraints N is the sparse identity; with constraints no
        null-space basis is formed: M, P, Q stay in full coordinates and ``constraint_jacobian``
        holds Φ_q(q₀) for the bordered pencil of :mod:`mbseig.eigen.partial` (N is None).
    signals : form B, C, D and the named angles (False: M, P, Q and N only, B, C, D left None —
        for the points of a sweep, which use the modes alone).
    basis : (N, rank, independent, cosine) as :func:`continuous_null_basis` gives it for this
        equilibrium's Φ_q(q₀), ``rank_tol`` and no ``reference`` (a sweep line that shares another
        line's equilibria: the same q₀ and constraints), instead of computing it again.

    The model linearized is the one ``eq`` belongs to (:func:`mbseig.statics.solved`): with
    inverse-statics commands resolved, the actuator settings found by the equilibrium.
    Raises :class:`~mbseig.errors.NumericalError` when the equilibrium or the result is not
    finite, or the arithmetic overflowed on the way (module docstring).
    """
    check("linearize", locals())
    require_finite("linearization", "the equilibrium is not finite", q0=eq.q, lam0=eq.lam)
    cause = LINEAR_CASE_CAUSE if isinstance(model, LinearCase) else CAUSE
    with watched("linearization", cause):
        lin = _linearize(model, eq, rank_tol, constraint_stiffness, sparse, reference, signals,
                         basis)
    require_finite("linearization", cause, M=lin.M, P=lin.P, Q=lin.Q, N=lin.N)
    return lin


def _linearize(model, eq, rank_tol, constraint_stiffness, sparse, reference=None, signals=True,
               basis=None):
    model = solved(model, eq)
    if rank_tol is None:
        rank_tol = float(eq.tolerances.get("rank_tol", 1e-10))
    if isinstance(model, LinearCase):
        return LinearModel(M=model.M, P=model.P, Q=model.Q, N=np.eye(model.n),
                           q0=np.zeros(model.n), lam0=np.zeros(0),
                           coordinate_names=model.coordinate_names, name=model.name,
                           parameters=model.parameters, tolerances={"rank_tol": rank_tol},
                           B=np.zeros((model.n, 0)), C=np.zeros((0, 2 * model.n)),
                           D=np.zeros((0, 0)), independent=tuple(model.coordinate_names))
    q0, lam0 = eq.q, eq.lam
    use_sparse = model.n > SPARSE_MIN if sparse is None else sparse
    local = None
    if not use_sparse and basis is None and reference is None and model.n_constraints:
        local = _local(model, q0, rank_tol)
    # sparse Jacobians where N is (the sparse path, and a dense model's sparse local basis,
    # projected sparse before it is made dense); a dense model's own otherwise (no CSR round trip)
    sparse_jacobians = use_sparse or (local is not None and not local.small)
    K, C = model.force_jacobians(q0, dense=not sparse_jacobians)
    if constraint_stiffness and model.n_constraints:
        K = K + model.constraint_hessian(q0, lam0, dense=not sparse_jacobians)
    if use_sparse:
        G = model.phi_q(q0) if model.n_constraints else None
        N = sp.identity(model.n, format="csr") if G is None else None
        M = model.mass_matrix(q0).tocsr()
        tol = {"rank_tol": rank_tol, "sparse": True}
        eliminated = 0
        if G is not None and (local := _local(model, q0, rank_tol)) is not None:
            # the triads by their tangent space, small joint components by their own null
            # space (mbseig.model.tangent): the FE matrices plus what stays bordered
            N, G, eliminated = local.N, local.kept, local.rank
            M, C, K = (_project(N, A) for A in (M, C.tocsr(), K.tocsr()))
            tol.update(local.record)
        return LinearModel(
            M=M, P=C.tocsr(), Q=K.tocsr(), N=N, q0=q0, lam0=lam0,
            coordinate_names=model.coordinate_names, name=model.name, parameters=model.parameters,
            rank=eq.rank, n_constraints=model.n_constraints,
            constraint_stiffness=constraint_stiffness, tolerances=tol, constraint_jacobian=G,
            eliminated=eliminated, display=Displayed(model, q0))
    given = basis is not None and reference is None
    # Φ_q dense where the null basis is found from it; else only the signals read it (and make
    # it dense when they need its multipliers): a 10³-DOF beam model's is 18 MB dense
    G = model.phi_q(q0, dense=local is None and not given)
    Z = None
    if given:
        N, rank, independent, sigma = basis
    elif local is not None:
        N, rank, independent, sigma, Z = _dense_local(local, rank_tol, model.coordinate_names)
    else:
        N, rank, independent, sigma = continuous_null_basis(G, model.n, rank_tol,
                                                            model.coordinate_names, reference)
    if sparse_jacobians:  # Nᵀ A N = Zᵀ (N_localᵀ A N_local) Z, the inner product sparse
        Md, Cd, Kd = model.mass_matrix(q0).tocsr(), C.tocsr(), K.tocsr()
        Mr, Pr, Qr = (_project(local.N, A).toarray() for A in (Md, Cd, Kd))
        if Z is not None:
            Mr, Pr, Qr = (Z.T @ A @ Z for A in (Mr, Pr, Qr))
    elif model.n_constraints == 0:
        Md, Cd, Kd = model.mass_matrix(q0).toarray(), C, K
        Mr, Pr, Qr = Md, Cd, Kd
    else:
        Md, Cd, Kd = model.mass_matrix(q0).toarray(), C, K
        Mr, Pr, Qr = (N.T @ A @ N for A in (Md, Cd, Kd))
    io = _signals(model, q0, N, G, rank, Md, Cd, Kd, Mr, Pr, Qr) if signals else {}
    tol = {"rank_tol": rank_tol}
    if sigma is not None:
        tol["basis_min_cosine"] = sigma  # σ_min(Eᵀ Π E)^(1/2): how well E fixes N
    if local is not None:
        tol.update(local.record)
    rigid = DeclaredRigid(model, q0, lam0, Qr, N) if constraint_stiffness else None
    display = Displayed(model, q0)
    return LinearModel(
        M=Mr, P=Pr, Q=Qr, N=N, q0=q0, lam0=lam0, coordinate_names=model.coordinate_names,
        name=model.name, parameters=model.parameters, rank=rank,
        n_constraints=model.n_constraints, constraint_stiffness=constraint_stiffness,
        tolerances=tol, independent=independent, rigid=rigid, display=display, **io,
    )


def _local(model, q0, rank_tol):
    """The local basis of a model with frames (:func:`mbseig.model.tangent.local_basis`), or
    None for a model without triads (its constraints stay in the bordered pencil)."""
    from .model.tangent import local_basis, triad_coordinates

    if triad_coordinates(model)[0].shape[0] == 0:
        return None
    return local_basis(model, q0, rank_tol)


def _dense_local(local, rank_tol, names):
    """(N, rank, independent, cosine, Z) of a dense model from its local basis: the rows a
    large component left are eliminated in the local basis's columns by
    :func:`continuous_null_basis` (an SVD of those rows alone), N = N_local Z (Z None when no
    rows were left); ``independent`` names the coordinates whose unit columns N keeps."""
    N = local.dense()
    rank, sigma, Z = local.rank, None, None
    if local.kept is not None:
        Z, r, _, sigma = continuous_null_basis(local.kept.toarray(), N.shape[1], rank_tol)
        N, rank = N @ Z, rank + r
        unit = np.flatnonzero((np.abs(N) == 1.0).sum(axis=0) == 1)
        rows = np.argmax(np.abs(N[:, unit]), axis=0) if unit.size else np.zeros(0, int)
    else:  # the same columns found among the sparse basis's entries (a unit entry is the
        # column's largest: its columns are unit vectors)
        S = sp.csc_matrix(local.N)
        ones = np.abs(S.data) == 1.0
        col = np.repeat(np.arange(S.shape[1]), np.diff(S.indptr))
        unit = np.flatnonzero(np.bincount(col[ones], minlength=S.shape[1]) == 1)
        rows = S.indices[ones][np.isin(col[ones], unit)]
    return N, rank, tuple(names[i] for i in np.sort(rows)), sigma, Z


def _project(N, A):
    """Nᵀ A N (CSR); exactly symmetric where A is (the sums of Nᵀ A N in two orders differ by
    rounding only)."""
    R = (N.T @ A @ N).tocsr()
    if (A != A.T).nnz == 0:
        R = ((R + R.T) * 0.5).tocsr()
    R.eliminate_zeros()
    return R


class Displayed:
    """The model's :func:`~mbseig.model.naming.display_map` at q₀, built at the first call."""

    def __init__(self, model, q0):
        self._args, self._value = (model, q0), None

    def __call__(self):
        if self._value is None:
            from .model.naming import display_map

            self._value = display_map(*self._args)
            self._args = None
        return self._value


class DeclaredRigid:
    """The rigid-body directions by construction of a model at its reference
    (:func:`mbseig.model.symmetry.rigid_directions`), found at the first call and kept: the
    modes stage asks only when a mode is rigid-body."""

    def __init__(self, model, q0, lam0, Q, N, *, stack=None):
        self._args, self._value = (model, q0, lam0, Q, N), None
        self.stack = stack  # (the ModelStack of a batched line that holds the model, its row)

    def __call__(self):
        if self._value is None:
            from .model.symmetry import rigid_directions

            self._value = rigid_directions(*self._args)
            self._args = self.stack = None
        return self._value

    @property
    def pending(self):
        """True until the directions are found."""
        return self._value is None


def declare_many(rigids):
    """Find the directions of many pending :class:`DeclaredRigid` at once where their models
    have one structure (:func:`mbseig.model.symmetry_batch.rigid_directions_batch`: the same
    tests on all of them); any other stays pending and is found on its own when asked."""
    from .model.stacked import stackable
    from .model.symmetry_batch import rigid_directions_batch

    todo = [r for r in rigids if isinstance(r, DeclaredRigid) and r.pending]
    if len(todo) < 2:
        return
    args = [r._args for r in todo]
    models = [a[0] for a in args]
    dense = all(isinstance(a[3], np.ndarray) and isinstance(a[4], np.ndarray) for a in args)
    if not dense or len({(a[3].shape, a[4].shape) for a in args}) != 1:
        return
    stack = None  # the stack of a batched line (its models stacked already), where all hold it
    if all(r.stack is not None and r.stack[0] is todo[0].stack[0] for r in todo):
        stack = todo[0].stack[0]
        rows = [r.stack[1] for r in todo]
        stack = stack if rows == list(range(stack.B)) else stack.take(rows)
    elif stackable(models) is not None:
        return
    got = rigid_directions_batch(models, np.stack([np.asarray(a[1], float) for a in args]),
                                 np.stack([np.asarray(a[2], float) for a in args]),
                                 np.stack([a[3] for a in args]), np.stack([a[4] for a in args]),
                                 stack=stack)
    for r, value in zip(todo, got, strict=True):
        r.stack = None
        if value is not None:
            r._value, r._args = value, None


def continuous_null_basis(Phi_q, n, rank_tol, names=None, reference=None):
    """(N, rank, independent names, cosine) of the module docstring's "Null-space basis".

    reference : coordinate names (or indices) whose directions E fix N; default: the d
        coordinates chosen by column-pivoted QR of a basis of the null space.  ``cosine`` is the
        smallest singular value of Zᵀ E (the cosine of the largest angle between span E and the
        null space); None without constraints.
    """
    Z, rank = null_space_basis(Phi_q, n, rank_tol)
    names = list(names) if names is not None else [f"q{k + 1}" for k in range(n)]
    d = Z.shape[1]
    if Phi_q.shape[0] == 0 or d == 0:
        return Z, rank, tuple(names) if d == n else (), None
    sel = None
    if reference is not None:
        sel = []
        for r in reference:
            if isinstance(r, str) and r in names:
                sel.append(names.index(r))
            elif isinstance(r, (int, np.integer)) and not isinstance(r, bool) \
                    and 0 <= int(r) < len(names):
                sel.append(int(r))
            else:
                raise CaseError(f"unknown coordinate {r!r} in the reference of the null-space "
                                f"basis", element="linearization")
        sel = np.array(sel, dtype=np.intp)
        if sel.size != d:
            raise CaseError(f"reference names {sel.size} coordinates for a null space of "
                            f"dimension {d}", element="linearization")
    N, sel, cosine = closest_basis(Z, sel)  # the polar factor of Π E (Zᵀ E = U Σ Vᵀ)
    if reference is not None and cosine <= 1e-8:
        raise CaseError("the reference coordinates do not fix the null space (repeated, or a "
                        "direction the constraints forbid): N would be arbitrary",
                        element="linearization")
    # N is the polar factor of Π E: independent of the SVD's choice of Z (up to rounding)
    return N, rank, tuple(names[i] for i in sel), cosine


def _signals(model, q0, N, G, rank, Md, Cd, Kd, Mr, Pr, Qr):
    """B, C, D, names and the named angles (module docstring, "Inputs and outputs")."""
    inputs, outputs = getattr(model, "inputs", ()) or (), getattr(model, "outputs", ()) or ()
    d = N.shape[1]
    b = input_forces(model, q0)
    B = N.T @ b
    in_names = tuple(i.name for i in inputs)
    C = np.zeros((len(outputs), 2 * d))
    D = np.zeros((len(outputs), len(inputs)))
    lam_maps = None
    for j, out in enumerate(outputs):
        Jq, Jv, Jl, Du = output_rows(model, out, q0)
        C[j, :d], C[j, d:] = Jq @ N, Jv @ N
        for nm, v in Du.items():
            D[j, in_names.index(nm)] += v
        if Jl is not None:
            if lam_maps is None:
                lam_maps = _multiplier_maps(model, G, rank, N, b, Md, Cd, Kd, Mr, Pr, Qr, out)
            Lx, Lv, Lu = lam_maps
            C[j, :d] += Jl @ Lx
            C[j, d:] += Jl @ Lv
            D[j] += Jl @ Lu
    names, rows = _named_angles(model, q0, outputs)
    return {"B": B, "C": C, "D": D, "input_names": in_names,
            "output_names": tuple(o.name for o in outputs),
            "output_units": tuple(o.unit for o in outputs),
            "input_units": tuple(i.unit(model) for i in inputs),
            "angle_names": names, "angle_rows": rows}


def _multiplier_maps(model, G, rank, N, b, Md, Cd, Kd, Mr, Pr, Qr, out):
    """(L_x, L_v, L_u) with δλ = L_x x + L_v ẋ + L_u u (module docstring)."""
    G = G.toarray() if sp.issparse(G) else np.asarray(G)
    if rank < G.shape[0]:
        raise CaseError(f"{G.shape[0] - rank} redundant constraints: the multipliers, and so "
                        f"the reaction output {out.name!r}, are not unique", element=out.label)
    try:
        MN = Md @ N
        Xq = np.linalg.solve(Mr, Qr)
        Xp = np.linalg.solve(Mr, Pr)
        Xu = np.linalg.solve(Mr, N.T @ b)
        left = np.linalg.solve(G @ G.T, G)  # (Φ_q Φ_qᵀ)⁻¹ Φ_q
    except np.linalg.LinAlgError:
        raise CaseError(f"the reduced mass matrix is singular: the reaction output {out.name!r} "
                        f"has no linearization (accelerations undetermined)",
                        element=out.label) from None
    Lx = left @ (-Kd @ N + MN @ Xq)
    Lv = left @ (-Cd @ N + MN @ Xp)
    Lu = left @ (b - MN @ Xu)
    return Lx, Lv, Lu


def _named_angles(model, q0, outputs):
    """Names and full-coordinate rows of the case's named angles: report angles, torsional
    elements and angle outputs (first name wins)."""
    from .model.elements import TorsionalSpringDamper

    names, rows = [], []

    def add(name, idx, grad):
        if name in names:
            return
        r = np.zeros(model.n)
        np.add.at(r, idx, grad)
        names.append(name)
        rows.append(r)

    for a in (getattr(model, "report", None) or {}).get("angles", ()):
        drv = a.get("driver")
        if drv is not None and drv.idx.size:
            add(a["name"], drv.idx, drv.jac(q0)[0])
    for f in model.forces:
        if isinstance(f, TorsionalSpringDamper):
            W, g = f.torque_parts(q0, np.zeros(model.n))[:2]
            add(element_name(f.name), f.idx, g @ W)
    for o in outputs:
        if o.kind == "angle" and o.quantity == "angle":
            Jq = output_rows(model, o, q0)[0]
            add(o.name, np.arange(model.n), Jq)
    return tuple(names), (np.array(rows) if rows else np.zeros((0, model.n)))
