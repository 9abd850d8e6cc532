"""The assembled nonlinear model.

    M q̈ + Φ_qᵀ(q) λ = g(q, q̇),        Φ(q) = 0

M is constant in natural coordinates (point masses and planar bodies on their basic points), so it
is assembled once.  g, its Jacobians, Φ, Φ_q, Σ λ_k ∇²Φ_k and γ are assembled on demand from the
element kernels of :mod:`mbseig.model.elements` as sparse matrices.
"""

from __future__ import annotations

from contextlib import contextmanager
from dataclasses import dataclass, field
from functools import cached_property
from itertools import groupby

import numpy as np
import scipy.sparse as sp

from ..numerics import DENSE_ASSEMBLY, FAST_CSR, coo_sum, nonzero_sum, scatter
from .base import BatchForce, Force
from .batched import kernel_groups
from .cache import KeptValues

__all__ = ["Model"]


@dataclass(frozen=True, eq=False)
class Model:
    """A constrained multibody model in natural coordinates.

    Attributes
    ----------
    coordinate_names : names of the n coordinates, e.g. ``("B.x", "B.y", ...)``; q_init : their
        initial guess (from the case's point positions); mass : constant n×n mass matrix (CSR).
    g_const : constant generalized forces (gravity, constant point forces); gravity_force : the
        part of it that is gravity (masses, bodies, beams), or None.
    forces, constraints : element objects (see :mod:`mbseig.model.elements`).
    points : named affine maps of every basic point and body marker, for reports and drawings;
        bodies : body name → (basic point i, basic point j).
    report : the case's ``[report]`` table (:mod:`mbseig.casefile.report_table`: joint angles with
        their ranges of motion, pins, actuator), empty when absent.
    commands : pending inverse-statics commands, ``(AngleDriver, targets)`` per driver, targets
        ``("force" | "joint", index, label)``, resolved by :func:`mbseig.equilibrium`
        (:mod:`mbseig.statics.inverse`); drivers : one record per resolved driver (target angle,
        effort, the free or locked length it set) on the model it returns as ``eq.model``.
    mass_elements : (element, M_ref) pairs for masses that depend on the configuration
        (co-rotational beams, ``element.mass(q)`` on ``element.idx``); ``mass`` holds them as
        M_ref (at the builder's initial positions) and :meth:`mass_matrix` re-evaluates them;
        mass_reference : those positions (the q at which every M_ref was evaluated), or None.
    inputs, outputs : named :class:`~mbseig.model.signals.Input` / ``Output`` of the case's
        ``[[inputs]]`` and ``[[outputs]]``.  mass_parts : (name, rows, cols, block) per body and
        point mass: ``mass`` is their sum plus any batched or flexible masses.
    flexible : ``{"bodies": {name: record}, "refinement": {...}}`` for beams and FE bodies
        (theory, slenderness, elements, warnings), see :mod:`mbseig.casefile.flexible`.
    coordinate_kinds, element_ends : the kind of each coordinate (length, direction, angle,
        modal) and the named points each element acts between (:mod:`mbseig.model.assembly`).
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
    mass_reference: np.ndarray = None  # the q of every M_ref (mass_matrix there: ``mass``)
    flexible: dict = field(default_factory=dict)
    inputs: tuple = ()
    outputs: tuple = ()
    gravity_force: np.ndarray = None
    mass_parts: tuple = ()
    coordinate_kinds: tuple = ()  # per coordinate: length, direction, angle, modal (assembly)
    velocity_constraints: tuple = ()  # non-holonomic rows A(q) q̇ = 0 (model.base)
    element_ends: dict = field(default_factory=dict)  # element → the points it acts between
    # the last dense evaluations (K and C, Φ_q, H(λ)) of a small model, keyed by q (and λ): a
    # sweep point's steps ask for the same matrices at one q; read-only (callers cannot change them)
    _dense_kept: KeptValues = field(default_factory=lambda: KeptValues(8, readonly=True),
                                    init=False, repr=False, compare=False)

    @property
    def n(self) -> int:
        return len(self.coordinate_names)

    @cached_property
    def n_constraints(self) -> int:
        return sum(c.n_eq for c in self.constraints)

    def constraint_row_names(self) -> list[str]:
        return [c.name for c in self.constraints for _ in range(c.n_eq)]

    @cached_property
    def _layout(self):
        """What every assembly repeats, made once per model at first use: [0] the constraint
        row offsets, the flat keys of [1] the single forces' K and C, [2] Φ_q's, [3] H's blocks
        (dense sums: one bincount, scatter's sums in its order); ``pairs``, ``mass_plan``."""
        return _Layout(self)

    def _sparse(self, which, n_rows, blocks):
        """The sparse sum of the blocks as :func:`mbseig.numerics.scatter` forms it (the same
        triplets, order and sums: ``self._layout.pairs``).  Past FAST_CSR triplets, the forces'
        K and C (``which`` 1) and the constraint Hessian H (3) are summed from their nonzero
        entries (:func:`nonzero_sum`: the same terms, no stored zeros; a list of blocks is emptied
        as it is read), and Φ_q keeps its pattern (the time-domain check refills it)."""
        size = sum(np.size(v) for _, _, v in blocks)
        if which in (1, 3) and size > FAST_CSR:
            return nonzero_sum(n_rows, self.n, blocks)
        rows, cols = self._layout.pairs(which)
        vals = [np.asarray(v, dtype=float).ravel() for _, _, v in blocks]
        if size != rows.size or not rows.size:
            return scatter(n_rows, self.n, blocks)
        v = np.concatenate(vals)
        if v.size <= FAST_CSR:
            return self._layout.pairs(which, n_rows).csr(v)
        # (coo_sum's own path for so many, without copying the indices)
        return sp.coo_matrix((v, (rows, cols)), shape=(n_rows, self.n)).tocsr()

    @cached_property
    def _groups(self):
        """(constraint groups, single forces, their groups): :func:`~.batched.kernel_groups`."""
        singles = [f for f in self.forces if not isinstance(f, BatchForce)]
        return kernel_groups(self.constraints), singles, kernel_groups(singles)

    def _prime(self, elements, kind, q, qd=None):
        """Evaluate ``kind`` of the batched elements (3-D beams) among ``elements`` at (q, q̇),
        one batch per group, before the model asks them one by one."""
        groups = {}
        for e in elements:
            g = e.batch_group(q, qd) if isinstance(e, Force) else None
            if g is not None:
                groups.setdefault(id(g), (g, []))[1].append(e)
        for g, members in groups.values():
            g.prime(kind, members, q, qd)

    def _each(self, which, method, *args):
        """[element.method(*args)] of the constraints (``which`` 0) or single forces (1)."""
        elements = self.constraints if which == 0 else self._groups[1]
        if which == 1 and method in ("force", "jacobians") and self._batched_forces:
            self._prime(elements, method, *args)
        groups = self._groups[2 * which]
        if not groups:
            return [getattr(e, method)(*args) for e in elements]
        out = [None] * len(elements)
        for pos, group in groups:
            for k, v in zip(pos.tolist(), getattr(group, method)(*args), strict=True):
                out[k] = v
        return [getattr(e, method)(*args) if v is None else v
                for e, v in zip(elements, out, strict=True)]

    @cached_property
    def _batched_forces(self) -> bool:
        """Whether some single force is evaluated in batches (:meth:`_prime`)."""
        return any(isinstance(f, Force) and type(f).batch_group is not Force.batch_group
                   for f in self.forces)

    def mass_matrix(self, q=None, *, fixed=False) -> sp.csr_matrix:
        """M(q): ``mass`` with the configuration-dependent element masses evaluated at q, the
        sums of ``mass + scatter(blocks)`` (no stored zeros; ``fixed``: one pattern at all q)."""
        if q is None or not self.mass_elements:
            return self.mass
        if not fixed and self.mass_reference is not None \
                and np.array_equal(q, self.mass_reference):
            # at the positions where every M_ref was evaluated, M(q) is ``mass`` by definition
            # (mass + Σ (M_e(q) − M_ref), each term zero), with no element evaluated
            M = self.mass.copy()
            M.eliminate_zeros()  # (the sum stores none)
            return M
        if self._batched_forces:
            self._prime([e for e, _ in self.mass_elements], "mass", q)
        blocks = [(e.idx, e.idx, e.mass(q) - M_ref) for e, M_ref in self.mass_elements]
        if not fixed and not any(np.any(v) for _, _, v in blocks):
            # every configuration mass its reference (q at the build's positions: the rest of a
            # beam model): mass + 0, exactly, without scattering the zeros (the sum stores none)
            M = self.mass.copy()
            M.eliminate_zeros()
            return M
        vals = [np.asarray(v, dtype=float).ravel() for _, _, v in blocks]
        S, pos, U = self._layout.mass_plan()
        if S is None or sum(v.size for v in vals) != S.order.size:
            return (self.mass + scatter(self.n, self.n, blocks)).tocsr()
        data = np.zeros(U.keys.size)
        data[pos[0]] = self.mass.data
        data[pos[1]] += S.values(np.concatenate(vals))  # mass + (the blocks' sum), as scipy adds
        M = U.csr(data, summed=True)
        if not fixed:
            M.eliminate_zeros()  # (the sparse sum stores none)
        return M

    def _kept(self, key, compute):
        """compute() once per key among the last few dense evaluations (read-only arrays,
        :class:`~mbseig.model.cache.KeptValues`); none above the dense-assembly size (128 MB
        for a dense K at its limit of 4000 unknowns)."""
        if not self.dense_assembly:
            return compute()
        return self._dense_kept.get(key, compute)

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
        scope = self.__dict__.get("_kept_sparse")
        if scope is None or qd is not None or dense:
            return self._force_jacobians(q, qd, dense)
        key = q.tobytes()
        if scope.get("key") != key:  # (one q at a time: the memory of one K and C)
            scope.clear()
            KC = self._force_jacobians(q, None, False)
            for A in KC:
                A.data.setflags(write=False)  # shared by every caller in the scope
            scope.update(key=key, KC=KC)
        return scope["KC"]

    @contextmanager
    def keeping_jacobians(self):
        """Within: the sparse (K, C) at q̇ = 0 of the last q asked is kept (read-only) and served
        again at that q, so that the input check, the static solve and the linearization of one
        point assemble them once (they ask at q₀: a beam model's equilibrium is its build
        positions); on leaving, it is let go.  Nested scopes share the outermost one."""
        if "_kept_sparse" in self.__dict__:
            yield
            return
        self.__dict__["_kept_sparse"] = {}
        try:
            yield
        finally:
            self.__dict__.pop("_kept_sparse", None)

    def _force_jacobians(self, q, qd, dense):
        qd = np.zeros(self.n) if qd is None else qd
        kb, cb, kt, ct = [], [], [], []
        single = iter(self._each(1, "jacobians", q, qd))
        for f in self.forces:
            if isinstance(f, BatchForce):  # batches give COO triplets
                for t, x in zip((kt, ct), f.jacobian_coo(q, qd), strict=True):
                    t.append(x)
                continue
            for b, x in zip((kb, cb), next(single), strict=True):
                b.append((f.idx, f.idx, x))
        del single  # (its list held every block: kb and cb are now their only holders)
        if dense:
            K, C = (_summed(self.n, self.n, self._layout[1], b) for b in (kb, cb))
        else:
            K = self._sparse(1, self.n, kb)
            # no damping anywhere (every block exactly zero: beams at rest, springs without
            # dampers): an empty C rather than its pattern of stored zeros
            C = (self._sparse(1, self.n, cb) if any(np.any(x) for _, _, x in cb)
                 else sp.csr_matrix((self.n, self.n)))
        if kt:
            K = K + coo_sum(self.n, self.n, kt, dense=dense)
            C = C + coo_sum(self.n, self.n, ct, dense=dense)
        return K, C

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
        off, jacs = self._layout[0], self._each(0, "jac", q)

        def blocks():
            return [(np.arange(off[k], off[k + 1]), c.idx, jacs[k])
                    for k, c in enumerate(self.constraints)]

        if dense:
            return _summed(self.n_constraints, self.n, self._layout[2],
                           [(None, None, J) for J in jacs], blocks)
        return self._sparse(2, self.n_constraints, blocks())

    def constraint_hessian(self, q, lam, *, dense=False) -> sp.csr_matrix:
        """H(λ) = Σ_k λ_k ∇²Φ_k(q), the stiffness of the constraint forces (CSR; a dense array
        when ``dense``)."""
        if dense:
            lam = np.asarray(lam, dtype=float)
            return self._kept(("H", q.tobytes(), lam.tobytes()),
                              lambda: self._constraint_hessian(q, lam, True))
        return self._constraint_hessian(q, lam, False)

    def _constraint_hessian(self, q, lam, dense):
        blocks = self._hessian_blocks(q, lam)
        if dense:
            return _summed(self.n, self.n, self._layout[3], blocks)
        return self._sparse(3, self.n, blocks)

    def _hessian_blocks(self, q, lam):
        """(idx, idx, λ_k ∇²Φ_k) of every constraint (its group's where it has one)."""
        off = self._layout[0]
        hs = [None] * len(self.constraints)
        for pos, group in self._groups[0]:  # the members' multipliers, one row each
            rows = off[pos][:, None] + np.arange(group.B.shape[1])
            for k, H in zip(pos.tolist(), group.hess(lam[rows]), strict=True):
                hs[k] = H
        return [(c.idx, c.idx, c.hess(q, lam[off[k]:off[k + 1]]) if hs[k] is None else hs[k])
                for k, c in enumerate(self.constraints)]

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
            if _finite(lambda: self._assembled(q, qd)):
                # every term is finite: no element to name, without evaluating each one
                # alone (and without summing them)
                return None
            for f in self.forces:
                if isinstance(f, BatchForce):  # a batch: name the member
                    member = f.nonfinite_member(q, qd)
                    if member is not None:
                        return member, "the force or its stiffness"
                elif not _finite(lambda f=f: (f.force(q, qd), *f.jacobians(q, qd))):
                    return f.name, "the force or its stiffness"
            for e, _ in self.mass_elements:
                if not _finite(lambda e=e: (e.mass(q),)):
                    return e.name, "the mass matrix"
            for c in self.constraints:
                if not _finite(lambda c=c: (c.phi(q), c.jac(q), c.hess(q, np.ones(c.n_eq)))):
                    return c.name, "the constraint or its derivatives"
        return None

    def _assembled(self, q, qd):
        """What :meth:`nonfinite_element` checks element by element, evaluated as the model
        evaluates it (batches, groups) but not summed: the force g and every element's K, C,
        Φ, Φ_q and H(1) blocks, and M(q) summed.  Within
        :meth:`keeping_jacobians` (q̇ = 0), K and C are their sums instead, which the solve then
        reuses: a sum is finite only where every term is (IEEE arithmetic carries an inf or a
        NaN through every addition), and a sparse sum drops no stored term."""
        # a generator: each kind's terms are checked and let go before the next kind is
        # evaluated (a 10⁵-DOF beam model's K and C blocks alone are 160 MB)
        yield self.generalized_force(q, qd)
        if "_kept_sparse" in self.__dict__ and not np.any(qd):
            yield from (A.data for A in self.force_jacobians(q))
        else:
            for KC in self._each(1, "jacobians", q, qd):
                yield from KC
            for f in self.forces:
                if isinstance(f, BatchForce):
                    yield from (t[2] for t in f.jacobian_coo(q, qd))
        if self.mass_elements:  # M(q) = mass + Σ (M_e(q) − M_ref), summed as the solve sums it
            yield self.mass_matrix(q).data  # (at the mass reference: ``mass``, unevaluated)
        if self.constraints:
            yield self.phi(q)
            yield from self._each(0, "jac", q)
            yield from (H for _, _, H in self._hessian_blocks(q, np.ones(self.n_constraints)))

    def constraint_scales(self) -> np.ndarray:
        if not self.constraints:
            return np.zeros(0)
        return np.concatenate([np.full(c.n_eq, c.scale()) for c in self.constraints])


class _Layout:
    """Model._layout, each entry made at its first use."""

    def __init__(self, model):
        self.model, self.kept = model, {}

    def __getitem__(self, which):
        if which not in self.kept:
            self.kept[which] = (np.cumsum([0] + [c.n_eq for c in self.model.constraints])
                                if which == 0 else _block_keys(self._blocks(which), self.model.n))
        return self.kept[which]

    def pairs(self, which, n_rows=None):
        """(rows, columns) of entry ``which``'s triplets, as scatter forms them from the blocks
        (the sparse sums; int32 where scipy takes them so); their :class:`_Sum` if n_rows.
        Kept up to FAST_CSR triplets; more are made at each use (a 10⁴-DOF beam model's K:
        8 MB of indices that every later stage would carry, for 7 ms of work per assembly)."""
        m, key = self.model, ("pairs" if n_rows is None else "sum", which)
        got = self.kept.get(key)
        if got is None:
            kind = np.int32 if max(m.n, m.n_constraints) < 2**31 - 1 else np.int64
            got = (_block_pairs(self._blocks(which), kind) if n_rows is None
                   else _Sum(n_rows, m.n, *self.pairs(which)))
            if n_rows is not None or got[0].size <= FAST_CSR:
                self.kept[key] = got
        return got

    def mass_plan(self):
        """(S, positions of ``mass``'s and of S's entries in U, U): the _Sum S of the mass
        elements' blocks, U of the union with ``mass``'s pattern (Nones: past FAST_CSR)."""
        if "mass" not in self.kept:
            m, n, M = self.model, self.model.n, self.model.mass
            r, c = _block_pairs([(e.idx, e.idx) for e, _ in m.mass_elements], np.int64)
            self.kept["mass"] = (None,) * 3
            if M.has_canonical_format and r.size <= FAST_CSR:
                S, keys = (_Sum(n, n, r, c),
                           np.repeat(np.arange(n), np.diff(M.indptr)) * n + M.indices)
                U = _Sum(n, n, *np.divmod(np.union1d(keys, S.keys), n))
                self.kept["mass"] = (S, [np.searchsorted(U.keys, k) for k in (keys, S.keys)], U)
        return self.kept["mass"]

    def _blocks(self, which):
        m, off = self.model, self[0]
        if which == 1:
            return [(f.idx, f.idx) for f in m.forces if not isinstance(f, BatchForce)]
        if which == 2:
            return [(np.arange(off[k], off[k + 1]), c.idx) for k, c in enumerate(m.constraints)]
        return [(c.idx, c.idx) for c in m.constraints]


class _Sum:
    """CSR sums of values on fixed triplets (rows, cols): the order and segments of
    :func:`mbseig.numerics.csr_from_triplets` (stable sort of the keys, ``reduceat``) made once."""

    def __init__(self, n_rows, n_cols, r, c):
        r, c = np.asarray(r, dtype=np.int64), np.asarray(c, dtype=np.int64)
        self.order = np.argsort(r * n_cols + c, kind="stable")
        key = (r * n_cols + c)[self.order]
        self.first = np.flatnonzero(np.concatenate(([True], key[1:] != key[:-1])))
        self.keys, self.shape = key[self.first], (n_rows, n_cols)
        rows = self.keys // n_cols
        self.indices = (self.keys - rows * n_cols).astype(np.int32)
        self.indptr = np.cumsum(np.bincount(rows + 1, minlength=n_rows + 1)).astype(np.int32)

    def values(self, v):
        return np.add.reduceat(np.asarray(v, dtype=float)[self.order], self.first)

    def csr(self, v, summed=False):  # of the triplets' values v (of the sums' if ``summed``)
        v = v if summed else self.values(v)
        return sp.csr_matrix((v, self.indices.copy(), self.indptr.copy()), shape=self.shape)


def _runs(blocks):
    """(R, C) stacked row and column indices of the runs of blocks of one shape, in order."""
    blocks = [(np.asarray(r).ravel(), np.asarray(c).ravel()) for r, c in blocks]
    for _, run in groupby(blocks, key=lambda b: (b[0].size, b[1].size)):
        yield tuple(np.array(x) for x in zip(*run, strict=True))


def _block_keys(blocks, n_cols):
    """The flat keys row · n_cols + column of the blocks (row-major each, in block order)."""
    rows, cols = _block_pairs(blocks, np.intp)
    return rows * n_cols + cols


def _block_pairs(blocks, kind):
    """(rows, columns) of the blocks' entries, row-major each, in block order."""
    rows, cols = [np.zeros(0, kind)], [np.zeros(0, kind)]
    for R, C in _runs(blocks):
        shape = (R.shape[0], R.shape[1], C.shape[1])
        rows.append(np.broadcast_to(R[:, :, None], shape).astype(kind).ravel())
        cols.append(np.broadcast_to(C[:, None, :], shape).astype(kind).ravel())
    return np.concatenate(rows), np.concatenate(cols)


def _summed(n_rows, n_cols, keys, blocks, full=None):
    """The dense sum of the blocks' values on the precomputed keys (one bincount, as scatter
    sums them); scatter itself (of ``full()`` when given) where the values do not match."""
    vals = [np.asarray(v, dtype=float).ravel() for _, _, v in blocks]
    if (total := sum(v.size for v in vals)) != keys.size:
        return scatter(n_rows, n_cols, full() if full is not None else blocks, dense=True)
    w = np.concatenate(vals) if total else np.zeros(0)
    return np.bincount(keys, weights=w, minlength=n_rows * n_cols).reshape(n_rows, n_cols)


_FINITE_CHUNK = 1 << 16  # entries of small arrays judged at once by _finite


def _finite(evaluate) -> bool:
    """Whether every array ``evaluate()`` returns (or yields) is finite (a Python-float
    overflow is not).  Small arrays (an element's blocks: a beam model yields thousands) are
    judged a chunk at a time, concatenated, instead of one call each."""
    try:
        chunk, size = [], 0
        for a in evaluate():
            a = np.asarray(a)
            if a.size >= _FINITE_CHUNK:
                if not np.all(np.isfinite(a)):
                    return False
                continue
            chunk.append(a.ravel())
            size += a.size
            if size >= _FINITE_CHUNK:
                if not np.all(np.isfinite(np.concatenate(chunk))):
                    return False
                chunk, size = [], 0
        return not chunk or bool(np.all(np.isfinite(np.concatenate(chunk))))
    except (OverflowError, ZeroDivisionError, FloatingPointError):
        return False
