"""One cache of the model quantities a static solve asks for at one q (Φ, Φ_q, g, K, C, the
constraint Hessian), kept across the Newton steps, the force scale and the stability check."""

from __future__ import annotations

import numpy as np

from ..model.cache import KeptValues
from ..model.system import Model
from .linalg import SMALL, multipliers


class Memo:
    """The model seen through a small cache of its assembled quantities at the last few q (the
    statics asks for Φ, Φ_q, g, K and H at one q several times; assembling them is what costs
    on large models).  Every other attribute is the model's own."""

    SIZE = 6

    def __init__(self, model, *, q=None, known=None):
        self._model = model
        self._cache = KeptValues(self.SIZE)
        self._solves = KeptValues(2)  # least-squares multipliers at the last q
        # a small model's Jacobians as dense arrays (mbseig.numerics.DENSE_ASSEMBLY)
        self._dense = bool(getattr(model, "dense_assembly", False))
        # evaluations at q made elsewhere ({"g", "phi", "phi_q": value}, each as this cache
        # would compute it: :meth:`mbseig.statics.family.Family.known`)
        for what, value in (known or {}).items():
            self._cache.get((what, q.tobytes()), lambda v=value: v)

    def __getattr__(self, name):
        return getattr(self._model, name)

    @property
    def model(self):
        """The model behind the cache."""
        return self._model

    def _get(self, key, compute):
        return self._cache.get(key, compute)

    def phi(self, q):
        return self._get(("phi", q.tobytes()), lambda: self._model.phi(q))

    # (``dense``: accepted for the model's signature; the memo gives its own form, dense for a
    # small model, and callers that need a dense array convert with mbseig.numerics.dense)
    def phi_q(self, q, *, dense=None):
        return self._get(("phi_q", q.tobytes()), lambda: self._model.phi_q(q, dense=self._dense))

    def generalized_force(self, q, qd=None):
        if qd is not None:
            return self._model.generalized_force(q, qd)
        return self._get(("g", q.tobytes()), lambda: self._model.generalized_force(q))

    def force_jacobians(self, q, qd=None, *, dense=None):
        if qd is not None:
            return self._model.force_jacobians(q, qd, dense=self._dense)
        return self._get(("K", q.tobytes()),
                         lambda: self._model.force_jacobians(q, dense=self._dense))

    def least_squares(self, q, rank_tol, check):
        """:func:`~mbseig.statics.linalg.multipliers` of Φ_q(q), g(q) (λ, rank, how), computed
        once per q: the force scale, the Newton's multipliers and the record ask for it at the
        same q.  Up to ``SMALL`` unknowns one SVD gives λ and the rank, and a call without
        ``check`` returns that λ (the same λ: the rank only reads the singular values) with
        the rank m it reports unchecked.  λ is a copy."""
        m, n = self._model.n_constraints, self._model.n
        small = m + n <= SMALL
        full = bool(check) or small
        lam, rank, how = self._solves.get(
            (q.tobytes(), float(rank_tol), full),
            lambda: multipliers(self.phi_q(q), self.generalized_force(q), rank_tol, check=full,
                                rank=self._local_rank(q, rank_tol) if full and not small
                                else None))
        return lam.copy(), (rank if check else m), how

    def _local_rank(self, q, rank_tol):
        """The rank of Φ_q(q) from the local basis of a model with frames (no SVD of the whole
        Jacobian: :mod:`mbseig.model.tangent`), or None (no frames, or rows it leaves)."""
        from ..model.tangent import local_basis, triad_coordinates

        model = self._model
        if not isinstance(model, Model) or triad_coordinates(model)[0].shape[0] == 0:
            return None
        local = local_basis(model, q, rank_tol)
        return local.rank if local.kept is None else None

    def constraint_hessian(self, q, lam, *, dense=None):
        return self._get(("H", q.tobytes(), np.asarray(lam).tobytes()),
                         lambda: self._model.constraint_hessian(q, lam, dense=self._dense))
