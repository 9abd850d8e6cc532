"""The assembled nonlinear model.

    M q̈ + Φ_qᵀ(q) λ = g(q, q̇),        Φ(q) = 0

M is constant in natural coordinates (point masses and planar bodies on their basic points), so it
is assembled once.  g, its Jacobians, Φ, Φ_q, Σ λ_k ∇²Φ_k and γ are assembled on demand from the
element kernels of :mod:`mbseig.model.elements` as sparse matrices.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from functools import cached_property

import numpy as np
import scipy.sparse as sp

from ..numerics import DENSE_ASSEMBLY, FAST_CSR, coo_sum, scatter
from .base import BatchForce
from .batched import kernel_groups
from .cache import KeptValues

__all__ = ["Model"]


@dataclass(frozen=True, eq=False)
class Model:
    """A constrained multibody model in natural coordinates.

    Attributes
    ----------
    coordinate_names : names of the n coordinates, e.g. ``("B.x", "B.y", ...)``.
    q_init : initial guess of the coordinates (from the case's point positions).
    mass : constant n×n mass matrix (CSR).
    g_const : constant generalized forces (gravity, constant point forces).
    forces, constraints : element objects (see :mod:`mbseig.model.elements`).
    points : named affine maps of every basic point and body marker, for reports and drawings.
    bodies : body name → (basic point i, basic point j).
    report : the case's ``[report]`` table as parsed by :mod:`mbseig.casefile.report_table`
        (joint angles with their ranges of motion, pins, actuator), empty when absent.
    commands : inverse-statics commands not yet resolved, ``(AngleDriver, targets)`` per driver
        with targets ``("force" | "joint", index, label)`` (the elements it sets); loading leaves
        them pending and :func:`mbseig.equilibrium` resolves them (:mod:`mbseig.statics.inverse`).
    drivers : one record per resolved driver (target angle, effort, the free length or locked
        length it set), on the model that :func:`mbseig.equilibrium` returns as ``eq.model``.
    mass_elements : (element, M_ref) pairs for masses that depend on the configuration
        (co-rotational beams, ``element.mass(q)`` on ``element.idx``); ``mass`` holds them as
        M_ref (at the builder's initial positions) and :meth:`mass_matrix` re-evaluates them.
    inputs, outputs : named :class:`~mbseig.model.signals.Input` / ``Output`` of the case's
        ``[[inputs]]`` and ``[[outputs]]`` (:mod:`mbseig.model.signals`).
    gravity_force : the part of ``g_const`` that is gravity (masses, bodies, beams), or None.
    mass_parts : (name, rows, cols, block) per body and point mass: ``mass`` is their sum plus any
        batched or flexible masses (modal energy per body, :mod:`mbseig.studies.design`).
    flexible : ``{"bodies": {name: record}, "refinement": {...}}`` for beams and FE bodies
        (theory, slenderness, elements, warnings), see :mod:`mbseig.casefile.flexible`.
    coordinate_kinds : the kind of each coordinate (length, direction, angle, modal) and
    element_ends : the named points each element acts between, both recorded by the reader
        (:mod:`mbseig.model.assembly`).
    """

    name: str
    source: str
    parameters: dict
    dimension: int
    coordinate_names: tuple
    q_init: np.ndarray
    mass: sp.csr_matrix
    g_const: np.ndarray
    forces: tuple
    constraints: tuple
    points: dict = field(default_factory=dict)
    bodies: dict = field(default_factory=dict)
    length_scale: float = 1.0
    description: str = ""
    expected: dict = field(default_factory=dict)
    report: dict = field(default_factory=dict)  # parsed [report] table
    drivers: tuple = ()  # inverse-statics records (mbseig.statics.inverse)
    commands: tuple = ()  # pending inverse-statics commands (resolved by mbseig.equilibrium)
    mass_elements: tuple = ()
    flexible: dict = field(default_factory=dict)
    inputs: tuple = ()
    outputs: tuple = ()
    gravity_force: np.ndarray = None
    mass_parts: tuple = ()
    coordinate_kinds: tuple = ()  # per coordinate: length, direction, angle, modal (assembly)
    velocity_constraints: tuple = ()  # non-holonomic rows A(q) q̇ = 0 (model.base)
    element_ends: dict = field(default_factory=dict)  # element → the points it acts between
    # the last dense evaluations (K and C, Φ_q, H(λ)) of a small model, keyed by q (and λ):
    # a sweep point's corrector, force scale, static stability and linearization ask for the
    # same matrices at one q; read-only arrays, so that a caller cannot change a kept one
    _dense_kept: KeptValues = field(default_factory=lambda: KeptValues(8, readonly=True),
                                    init=False, repr=False, compare=False)

    # ---- sizes ---------------------------------------------------------------------------
    @property
    def n(self) -> int:
        return len(self.coordinate_names)

    @cached_property
    def n_constraints(self) -> int:
        return sum(c.n_eq for c in self.constraints)

    def constraint_row_names(self) -> list[str]:
        return [c.name for c in self.constraints for _ in range(c.n_eq)]

    def _row_offsets(self):
        return self._layout[0]

    @cached_property
    def _layout(self):
        """What the dense assembly of a small model repeats at every evaluation, made once per
        model (the elements are fixed), each entry at its first use: [0] the constraint row
        offsets, then the flat keys (row · n_cols + column, row-major as each block) of [1]
        every single force's K and C blocks, [2] Φ_q's and [3] H's blocks in element order.
        The dense sums are then one bincount of the blocks' values on these keys, as
        :func:`mbseig.numerics.scatter` forms them (the same sums in the same order)."""
        return _Layout(self)

    def _sparse(self, which, n_rows, blocks):
        """The sparse sum of the blocks, as :func:`mbseig.numerics.scatter` forms it (the same
        triplets in the same order), on the indices of ``self._layout.pairs(which)``."""
        rows, cols = self._layout.pairs(which)
        vals = [np.asarray(v, dtype=float).ravel() for _, _, v in blocks]
        if sum(v.size for v in vals) != rows.size or not rows.size:
            return scatter(n_rows, self.n, blocks)
        v = np.concatenate(vals)
        if v.size > FAST_CSR:  # (coo_sum's own path for so many, without copying the indices)
            return sp.coo_matrix((v, (rows, cols)), shape=(n_rows, self.n)).tocsr()
        return coo_sum(n_rows, self.n, [(rows, cols, v)])

    @cached_property
    def _groups(self):
        """(constraint groups, single forces, their groups): the elements of one kind that
        one kernel evaluates at once (:func:`mbseig.model.batched.kernel_groups`), made once."""
        singles = [f for f in self.forces if not isinstance(f, BatchForce)]
        return kernel_groups(self.constraints), singles, kernel_groups(singles)

    def _each(self, which, method, *args):
        """[element.method(*args)] of the constraints (``which`` 0) or the single forces (1),
        in element order, the grouped ones evaluated by their group."""
        elements = self.constraints if which == 0 else self._groups[1]
        groups = self._groups[2 * which]
        if not groups:
            return [getattr(e, method)(*args) for e in elements]
        out = [None] * len(elements)
        for pos, group in groups:
            for k, v in zip(pos.tolist(), getattr(group, method)(*args)):
                out[k] = v
        return [getattr(e, method)(*args) if v is None else v for e, v in zip(elements, out)]

    def mass_matrix(self, q=None) -> sp.csr_matrix:
        """M(q): ``mass`` with the configuration-dependent element masses evaluated at q."""
        if q is None or not self.mass_elements:
            return self.mass
        blocks = [(e.idx, e.idx, e.mass(q) - M_ref) for e, M_ref in self.mass_elements]
        return (self.mass + scatter(self.n, self.n, blocks)).tocsr()

    def _kept(self, key, compute):
        """compute() once per key among the last few dense evaluations (read-only arrays,
        :class:`~mbseig.model.cache.KeptValues`); a model above the dense-assembly size keeps
        nothing (a dense K of a model examined up to the dense limit of 4000 unknowns would
        hold 128 MB)."""
        if not self.dense_assembly:
            return compute()
        return self._dense_kept.get(key, compute)

    # ---- forces --------------------------------------------------------------------------
    def generalized_force(self, q, qd=None, u=None) -> np.ndarray:
        """g(q, q̇), plus Σ b_i(q) u_i of the named inputs when ``u`` ({name: value}) is given
        (:mod:`mbseig.model.signals`)."""
        qd = np.zeros(self.n) if qd is None else qd
        g = self.g_const.copy()
        if u:
            known = {i.name: i for i in self.inputs}
            for nm, value in u.items():
                g += value * known[nm].generalized_force(self, q)
        single = iter(self._each(1, "force", q, qd))
        for f in self.forces:
            if isinstance(f, BatchForce):  # a batch of identical elements (model/batched.py)
                f.add_force(g, q, qd)
            else:
                np.add.at(g, f.idx, next(single))
        return g

    def force_jacobians(self, q, qd=None, *, dense=False):
        """(K, C) = (−∂g/∂q, −∂g/∂q̇) as CSR matrices (dense arrays when ``dense``)."""
        if dense and qd is None:
            return self._kept(("K", q.tobytes()), lambda: self._force_jacobians(q, None, True))
        return self._force_jacobians(q, qd, dense)

    def _force_jacobians(self, q, qd, dense):
        qd = np.zeros(self.n) if qd is None else qd
        kb, cb, kt, ct = [], [], [], []
        single = iter(self._each(1, "jacobians", q, qd))
        for f in self.forces:
            if isinstance(f, BatchForce):  # batches give COO triplets
                Kt, Ct = f.jacobian_coo(q, qd)
                kt.append(Kt)
                ct.append(Ct)
                continue
            K, C = next(single)
            kb.append((f.idx, f.idx, K))
            cb.append((f.idx, f.idx, C))
        if dense:
            K, C = (_summed(self.n, self.n, self._layout[1], b) for b in (kb, cb))
        else:
            K, C = (self._sparse(1, self.n, b) for b in (kb, cb))
        if kt:
            K = K + coo_sum(self.n, self.n, kt, dense=dense)
            C = C + coo_sum(self.n, self.n, ct, dense=dense)
        return K, C

    # ---- constraints ---------------------------------------------------------------------
    def phi(self, q) -> np.ndarray:
        if not self.constraints:
            return np.zeros(0)
        return np.concatenate(self._each(0, "phi", q))

    def phi_q(self, q, *, dense=False) -> sp.csr_matrix:
        """Φ_q(q) (CSR; a dense array when ``dense``)."""
        if dense:
            return self._kept(("phi_q", q.tobytes()), lambda: self._phi_q(q, True))
        return self._phi_q(q, False)

    def _phi_q(self, q, dense):
        off = self._row_offsets()
        if dense:
            jacs = self._each(0, "jac", q)
            return _summed(self.n_constraints, self.n, self._layout[2],
                           [(None, None, J) for J in jacs],
                           lambda: [(np.arange(off[k], off[k + 1]), c.idx, jacs[k])
                                    for k, c in enumerate(self.constraints)])
        jacs = self._each(0, "jac", q)
        blocks = [(np.arange(off[k], off[k + 1]), c.idx, jacs[k]) for k, c in enumerate(self.constraints)]
        return self._sparse(2, self.n_constraints, blocks)

    def constraint_hessian(self, q, lam, *, dense=False) -> sp.csr_matrix:
        """H(λ) = Σ_k λ_k ∇²Φ_k(q), the stiffness of the constraint forces (CSR; a dense array
        when ``dense``)."""
        if dense:
            lam = np.asarray(lam, dtype=float)
            return self._kept(("H", q.tobytes(), lam.tobytes()),
                              lambda: self._constraint_hessian(q, lam, True))
        return self._constraint_hessian(q, lam, False)

    def _constraint_hessian(self, q, lam, dense):
        off = self._row_offsets()
        hs = [None] * len(self.constraints)
        for pos, group in self._groups[0]:  # the members' multipliers, one row each
            rows = off[pos][:, None] + np.arange(group.B.shape[1])
            for k, H in zip(pos.tolist(), group.hess(lam[rows])):
                hs[k] = H
        blocks = [(c.idx, c.idx, c.hess(q, lam[off[k]:off[k + 1]]) if hs[k] is None else hs[k])
                  for k, c in enumerate(self.constraints)]
        if dense:
            return _summed(self.n, self.n, self._layout[3], blocks)
        return self._sparse(3, self.n, blocks)

    @property
    def dense_assembly(self) -> bool:
        """Whether the statics assemble this model's Jacobians densely (a small model:
        :data:`mbseig.numerics.DENSE_ASSEMBLY`)."""
        return self.n + self.n_constraints <= DENSE_ASSEMBLY

    def gamma(self, q, qd) -> np.ndarray:
        """γ = −(Φ_q q̇)_q q̇, so that Φ_q q̈ = γ on the constraint manifold."""
        if not self.constraints:
            return np.zeros(0)
        return np.concatenate(self._each(0, "gamma", q, qd))

    # ---- input safety (README, "Input rules") -------------------------------------------------
    def nonfinite_element(self, q):
        """(element name, what) of the first element whose force, stiffness, constraint or
        constraint derivatives are not finite at q, or None: the check before the equilibrium,
        so that an overflow is named by its element instead of surfacing inside a solver."""
        qd = np.zeros(self.n)
        if self.mass.nnz and not np.all(np.isfinite(self.mass.data)):
            return "mass matrix", "the assembled mass matrix"
        if not np.all(np.isfinite(self.g_const)):
            k = int(np.argmax(~np.isfinite(self.g_const)))
            return f"coordinate {self.coordinate_names[k]}", "the sum of gravity and point forces"
        # evaluated under errstate "ignore": an overflow is judged by the results below
        with np.errstate(all="ignore"):
            for f in self.forces:
                if isinstance(f, BatchForce):  # a batch: name the member
                    member = f.nonfinite_member(q, qd)
                    if member is not None:
                        return member, "the force or its stiffness"
                elif not _finite(lambda: (f.force(q, qd), *f.jacobians(q, qd))):
                    return f.name, "the force or its stiffness"
            for e, _ in self.mass_elements:
                if not _finite(lambda: (e.mass(q),)):
                    return e.name, "the mass matrix"
            for c in self.constraints:
                if not _finite(lambda: (c.phi(q), c.jac(q), c.hess(q, np.ones(c.n_eq)))):
                    return c.name, "the constraint or its derivatives"
        return None

    def constraint_scales(self) -> np.ndarray:
        if not self.constraints:
            return np.zeros(0)
        return np.concatenate([np.full(c.n_eq, c.scale()) for c in self.constraints])


class _Layout:
    """Model._layout: its entries made at their first use (a model's statics may need Φ_q and
    never the force blocks' keys)."""

    def __init__(self, model):
        self.model, self.kept = model, {}

    def __getitem__(self, which):
        if which not in self.kept:
            self.kept[which] = (np.cumsum([0] + [c.n_eq for c in self.model.constraints])
                                if which == 0 else _block_keys(self._blocks(which), self.model.n))
        return self.kept[which]

    def pairs(self, which):
        """(rows, columns) of entry ``which``'s triplets, as scatter forms them from the blocks
        (the sparse sums; int32 where scipy takes them so)."""
        if ("pairs", which) not in self.kept:
            m = self.model
            kind = np.int32 if max(m.n, m.n_constraints) < 2**31 - 1 else np.int64
            self.kept[("pairs", which)] = _block_pairs(self._blocks(which), kind)
        return self.kept[("pairs", which)]

    def _blocks(self, which):
        m = self.model
        if which == 1:
            blocks = [(f.idx, f.idx) for f in m.forces if not isinstance(f, BatchForce)]
        elif which == 2:
            off = self[0]
            blocks = [(np.arange(off[k], off[k + 1]), c.idx) for k, c in enumerate(m.constraints)]
        else:
            blocks = [(c.idx, c.idx) for c in m.constraints]
        return blocks


def _runs(blocks):
    """(R, C) stacked row and column indices of the runs of blocks of one shape, in order."""
    run = []
    for r, c in blocks:
        r, c = np.asarray(r).ravel(), np.asarray(c).ravel()
        if run and (r.size != run[0][0].size or c.size != run[0][1].size):
            yield np.array([x for x, _ in run]), np.array([y for _, y in run])
            run = []
        run.append((r, c))
    if run:
        yield np.array([x for x, _ in run]), np.array([y for _, y in run])


def _block_keys(blocks, n_cols):
    """The flat keys row · n_cols + column of the blocks (row-major each, in block order)."""
    parts = [(R[:, :, None] * n_cols + C[:, None, :]).ravel() for R, C in _runs(blocks)]
    if not parts:
        return np.zeros(0, np.intp)
    return (parts[0] if len(parts) == 1 else np.concatenate(parts)).astype(np.intp, copy=False)


def _block_pairs(blocks, kind):
    """(rows, columns) of the blocks' entries, row-major each, in block order."""
    rows, cols = [], []
    for R, C in _runs(blocks):
        shape = (R.shape[0], R.shape[1], C.shape[1])
        rows.append(np.broadcast_to(R[:, :, None], shape).astype(kind).ravel())
        cols.append(np.broadcast_to(C[:, None, :], shape).astype(kind).ravel())
    if not rows:
        return np.zeros(0, kind), np.zeros(0, kind)
    return tuple(x[0] if len(x) == 1 else np.concatenate(x) for x in (rows, cols))


def _summed(n_rows, n_cols, keys, blocks, full=None):
    """The dense sum of the blocks' values on the model's precomputed keys (one bincount, as
    :func:`mbseig.numerics.scatter` sums them); scatter itself (of ``full()``, the blocks with
    their indices, when given) where the values do not match the keys."""
    vals = [np.asarray(v, dtype=float).ravel() for _, _, v in blocks]
    total = sum(v.size for v in vals)
    if total != keys.size:
        return scatter(n_rows, n_cols, full() if full is not None else blocks, dense=True)
    if not total:
        return np.zeros((n_rows, n_cols))
    return np.bincount(keys, weights=np.concatenate(vals),
                       minlength=n_rows * n_cols).reshape(n_rows, n_cols)


def _finite(evaluate) -> bool:
    """Whether every array ``evaluate()`` returns is finite (a Python-float overflow is not)."""
    try:
        arrays = evaluate()
    except (OverflowError, ZeroDivisionError, FloatingPointError):
        return False
    return all(np.all(np.isfinite(a)) for a in arrays)
