"""The family p ↦ model(p) of a continuation (:mod:`~mbseig.statics.continuation`): the branch
equations R(y, p) = 0 with y = (q, λ on the followed constraint rows), their Newton matrix and
∂R/∂p, evaluated through one cache per model."""

from __future__ import annotations

import numpy as np
import scipy.linalg as sla

from ..model.cache import KeptValues
from ..numerics import constraint_rank, saddle
from .linalg import (
    DENSE_LIMIT,
    StepScales,
    multipliers,
)

CORRECTOR_ITER = 8  # Newton iterations of a continuation corrector


FD_REL = 1e-7  # forward-difference step of ∂R/∂p, relative to p_scale


CTOL = 1e-11  # corrector converged: correction below CTOL in the model's scales (and p_scale)


class Family:
    """p ↦ model(p) with the residual, Newton matrix and ∂R/∂p of the branch equations."""

    def __init__(self, make, p_scale, model0, q0, *, rank_tol=1e-10):
        self.make = make
        self.p_scale = float(p_scale) if p_scale else 1.0
        self._cache: dict = {}
        self.scales = StepScales(model0)
        self.n = model0.n
        Phi_q = model0.phi_q(q0)
        self.m = Phi_q.shape[0]
        self.rows = np.arange(self.m)
        if self.m and model0.n + self.m <= DENSE_LIMIT:
            rank = constraint_rank(Phi_q, rank_tol)[0]
            if rank < self.m:
                _, _, piv = sla.qr(Phi_q.toarray().T, pivoting=True, mode="economic")
                self.rows = np.sort(piv[:rank])
        self.N = self.n + self.rows.size
        # a small model's R and J from dense evaluations (mbseig.numerics.DENSE_ASSEMBLY)
        self.dense = bool(getattr(model0, "dense_assembly", False))
        self.evaluations = 0
        self._memo_store: dict = {}
        self._evals = KeptValues(self.EVALS)  # g, Φ and Φ_q by q (the comment above _kept())
        self._pinned: dict = {}  # those at the grid points, for the records (pin())

    def model(self, p):
        key = float(p)
        m = self._cache.get(key)
        if m is None:
            m = self.make(key)
            self.evaluations += 1
            if len(self._cache) > 256:
                self._cache.pop(next(iter(self._cache)))
            self._cache[key] = m
        return m

    def models(self, values):
        """model(p) of every value; ``make.many(values)``, where the maker has it, forms the
        models not cached yet together."""
        keys = [float(p) for p in values]
        todo = [p for p in dict.fromkeys(keys) if p not in self._cache]
        many = getattr(self.make, "many", None)
        got = many(todo) if (many is not None and len(todo) > 1) else None
        if got is not None:
            for p, m in zip(todo, got, strict=True):
                if m is not None:
                    self._cache[p] = m
                    self.evaluations += 1
            fresh = {p: m for p, m in zip(todo, got, strict=True) if m is not None}
        else:
            fresh = {}
        out = [fresh[p] if p in fresh else self.model(p) for p in keys]
        while len(self._cache) > 256:
            self._cache.pop(next(iter(self._cache)))
        return out

    def lam_full(self, y):
        lam = np.zeros(self.m)
        lam[self.rows] = y[self.n:]
        return lam

    def start(self, q, p):
        """y = (q, least-squares λ_S) at an equilibrium q of model(p)."""
        model = self.model(p)
        Phi_q = model.phi_q(q)[self.rows] if self.m else model.phi_q(q)
        lam = multipliers(Phi_q, model.generalized_force(q), 1e-10, check=False)[0]
        return np.concatenate([q, lam])

    def _memo(self, what, y, p, compute):
        key = (what, float(p), y.tobytes())
        hit = self._memo_store.get(key)
        if hit is None:
            hit = compute()
            if len(self._memo_store) > 16:
                self._memo_store.pop(next(iter(self._memo_store)))
            self._memo_store[key] = hit
        return hit

    # ---- the model's evaluations at q, kept for the last few q -------------------------------
    # g(q) belongs to one model (one p); Φ(q) and Φ_q(q) to its constraint elements, which the
    # models of a lean family share (only force scalars change with p), so the model at the
    # previous grid value (the difference ∂R/∂p) reuses them.  Kept values are the arrays the
    # model returned, never changed in place, each with its owner (the model, or the tuple of
    # constraint elements), whose ids are in the key: kept alive, no other object takes them.
    EVALS = 12

    @staticmethod
    def _key(what, owner, q):
        return (what, id(owner) if what == "g" else tuple(map(id, owner)), q.tobytes())

    def _kept(self, what, owner, q, compute):
        return self._evals.get(self._key(what, owner, q), lambda: (owner, compute()))[1]

    def _g(self, model, q):
        return self._kept("g", model, q, lambda: model.generalized_force(q))

    def _phi(self, model, q):
        return self._kept("phi", model.constraints, q, lambda: model.phi(q))

    def _phi_q(self, model, q):
        return self._kept("phi_q", model.constraints, q, lambda: model.phi_q(q, dense=self.dense))

    def pin(self, p, y):
        """Keep the evaluations made at the grid point (p, y) for :meth:`known` (a small model's:
        dense, a few hundred numbers a point; the sweep records the grid points after the
        whole line is followed)."""
        if not self.dense:
            return
        model, q = self.model(p), y[:self.n]
        for what, owner in (("g", model), ("phi", model.constraints),
                            ("phi_q", model.constraints)):
            key = self._key(what, owner, q)
            hit = self._evals.peek(key)
            if hit is not None:
                self._pinned[(float(p),) + key] = hit

    def known(self, p, q) -> dict:
        """The evaluations of model(p) at q the family made, by name ("g", "phi", "phi_q"; Φ_q
        as model.phi_q(q, dense=model.dense_assembly) gives it): a
        :class:`~mbseig.statics.cache.Memo` of the model starts from them instead of evaluating
        them again."""
        model = self.model(p)
        out = {}
        for what, owner in (("g", model), ("phi", model.constraints),
                            ("phi_q", model.constraints)):
            key = self._key(what, owner, q)
            hit = self._evals.peek(key) or self._pinned.get((float(p),) + key)
            if hit is not None:
                out[what] = hit[1]
        if bool(getattr(model, "dense_assembly", False)) != self.dense:
            out.pop("phi_q", None)
        return out

    def R(self, y, p):
        return self._memo("R", y, p, lambda: self._R(y, p))

    def J(self, y, p):
        return self._memo("J", y, p, lambda: self._J(y, p))

    def Rp(self, y, p):
        return self._memo("Rp", y, p, lambda: self._Rp(y, p))

    def _R(self, y, p):
        model = self.model(p)
        q, lam = y[:self.n], y[self.n:]
        with np.errstate(all="ignore"):
            g = self._g(model, q)
            if not self.m:
                return g
            Phi_q = self._phi_q(model, q)[self.rows]
            return np.concatenate([g - Phi_q.T @ lam, -self._phi(model, q)[self.rows]])

    def _J(self, y, p):
        model = self.model(p)
        q = y[:self.n]
        with np.errstate(all="ignore"):
            K, _ = model.force_jacobians(q, dense=self.dense)
            if not self.m:
                return K if self.dense else K.tocsr()
            Phi_q = self._phi_q(model, q)[self.rows]
            H = model.constraint_hessian(q, self.lam_full(y), dense=self.dense)
            return saddle(K + H, Phi_q)

    def _Rp(self, y, p):
        h = FD_REL * self.p_scale
        return (self.R(y, p + h) - self.R(y, p)) / h

    def Rp_back(self, y, p, p_prev):
        """∂R/∂p by the difference to the previous point's parameter, whose model is built
        already: (R(y, p) − R(y, p_prev)) / (p − p_prev), accurate to O(p − p_prev).  Used for
        the tangent at a grid point reached directly (the predictor of the next one and the
        sense of p); an exact tangent replaces it wherever the sense of p or the sign of det J
        changes (folds, branch points)."""
        return (self.R(y, p) - self.R(y, p_prev)) / (p - p_prev)

    def weights(self):
        """W of z = (q, λ, p): 1/ℓ² on q, 0 on λ, 1/p_scale² on p."""
        w = np.zeros(self.N + 1)
        w[:self.n] = 1.0 / self.scales.ell**2
        w[-1] = 1.0 / self.p_scale**2
        return w

