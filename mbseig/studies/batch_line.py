"""A sweep line's equilibria and linear models with a batch axis (the points of a line at once).

:func:`batch_line` solves the equilibria of every grid point of a line together
(:func:`mbseig.statics.batch.newton_batch` on the :class:`~mbseig.model.stacked.ModelStack` of
the line's models): Newton from the first point's equilibrium on all points, then, in rounds
while any converges, every point not converged from its nearest converged neighbour,
extrapolated linearly in p from the next converged point beyond it (a continuation's secant
predictor; continuation from a converged neighbour).  The branch is then checked as the
continuation checks it, for every point at once:

- each point is reached again by Newton from its left neighbour's equilibrium (the corrector
  of a continuation step), to within ``SAME`` in the model's scales: no point of the line lies
  on another branch;
- the reduced stiffness K_r keeps its inertia (the counts of negative and of zero eigenvalues)
  along the line: no fold or branch point lies between two grid points (there the
  continuation's events, diagram and switches are needed);
- the static verdict (:func:`mbseig.statics.batch.static_verdicts`) does not become "unstable"
  (where the followed branch loses static stability the continuation may switch branches).

The samples of ``mbseig uncertainty`` (:mod:`mbseig.studies.uncertainty`) are not a line: their
points have no order between them, so no fold or branch point can lie "between" two of them, and a
statically unstable sample is a result (its verdict), not a place where a followed branch may
switch.  With ``samples=True`` the last two checks are left out; the first (every point reached
again from its neighbour's equilibrium, within ``SAME``) is kept.

Where all hold, the line's equilibrium records, static verdicts and linear models (null-space
basis by stacked SVD, reduced M, P, Q by stacked products) are formed for all points at once.
Otherwise :func:`batch_line` returns None with the reason, and the line is followed by the
continuation (:func:`mbseig.statics.continuation.follow`) point by point: the same equilibria
(the corrector is the same Newton), with its events.
"""

from __future__ import annotations

import numpy as np

from ..linear import DeclaredRigid, Displayed, LinearModel
from ..model.stacked import ModelStack, stackable
from ..statics.batch import (
    _size,
    newton_batch,
    null_bases,
    residual,
    singular,
    static_verdicts,
)
from ..statics.family import CTOL
from ..statics.result import Equilibrium

__all__ = ["batch_line", "SAME", "ROUNDS"]

#: two equilibria of one model reached by Newton from two starts are the same point when they
#: differ by at most this in the model's scales (each is within ≈ CTOL² of the root after a
#: last correction below CTOL; distinct branches of a mechanism lie orders of magnitude apart)
SAME = 1e3 * CTOL
#: rounds of restarts from converged neighbours before the line is handed to the continuation
#: (each round solves every point not converged yet, together)
ROUNDS = 40
RANK_TOL = 1e-10


def _restarts(done, values, Y):
    """(points, starts): every point not converged, started from its nearest converged point
    j, extrapolated linearly in p from the converged point next to j on the same side (the
    secant predictor of a continuation step) where there is one."""
    B = done.size
    conv = np.flatnonzero(done)
    todo = np.flatnonzero(~done)
    starts = Y.copy()
    if not conv.size or not todo.size:
        return np.zeros(0, int), starts
    pos = np.searchsorted(conv, todo)
    left = conv[np.clip(pos - 1, 0, conv.size - 1)]
    right = conv[np.clip(pos, 0, conv.size - 1)]
    j = np.where(np.abs(todo - left) <= np.abs(right - todo), left, right)
    step = np.where(j < todo, -1, 1)  # the next point beyond j, away from the point
    i = j + step
    ok = (i >= 0) & (i < B)
    ok[ok] &= done[i[ok]] & (values[j[ok]] != values[i[ok]])
    starts[todo] = Y[j]
    if ok.any():
        a, b, c = todo[ok], j[ok], i[ok]
        starts[a] = Y[b] + ((values[a] - values[b]) / (values[b] - values[c]))[:, None] \
            * (Y[b] - Y[c])
    return todo, starts


def batch_line(fam, values, eq0, *, samples=False):
    """(equilibria, linear models, record) of every grid point of the line, or (None, None,
    reason) (module docstring).  ``fam``: the line's :class:`~mbseig.statics.family.Family`;
    eq0: the first point's equilibrium (solved on its own), or the start of every point;
    samples: points without an order between them (module docstring)."""
    if fam.rows.size != fam.m:
        return None, None, "redundant constraints (self-stress: examined point by point)"
    models = fam.models(values)
    why = stackable(models)
    if why is not None:
        return None, None, why
    if any(c.single_sided for c in models[0].constraints):
        return None, None, "single-sided contacts"
    stack = ModelStack(models)
    n, B = stack.n, len(models)
    y0 = fam.start(eq0.q, values[0])
    Y = np.tile(y0, (B, 1))
    kw = {"min_norm": singular(residual(stack, Y, fam.rows)[1][:1])}
    Y, its, done, last = newton_batch(stack, Y, fam.rows, fam.scales, **kw)
    values = np.asarray(values, float)
    for _ in range(ROUNDS):
        if done.all():
            break
        todo, start = _restarts(done, values, Y)
        if not todo.size:
            break
        active = np.zeros(B, bool)
        active[todo] = True
        Y2, its2, done2, last2 = newton_batch(stack, start, fam.rows, fam.scales, active=active,
                                              **kw)
        if not done2[todo].any():
            break
        ok = todo[done2[todo]]
        Y[ok], its[ok], last[ok], done[ok] = Y2[ok], its[ok] + its2[ok], last2[ok], True
    if not done.all():
        return None, None, f"{int((~done).sum())} of {B} points did not converge in the batch"
    # every point again from its left neighbour: the same point (no jump to another branch)
    if B > 1:
        start = np.vstack([Y[:1], Y[:-1]])
        active = np.ones(B, bool)
        active[0] = False
        Yc, _, okc, _ = newton_batch(stack, start, fam.rows, fam.scales, active=active,
                                              **kw)
        if not okc[1:].all() or np.any(_size(fam.scales, Yc[1:, :n] - Y[1:, :n]) > SAME):
            return None, None, "a point is not reached from its neighbour (another branch)"
    Q = Y[:, :n]
    Lf = np.zeros((B, stack.m))
    Lf[:, fam.rows] = Y[:, n:]
    Phi_q = stack.phi_q(Q)
    nb = null_bases(Phi_q, RANK_TOL)
    if nb is None:
        return None, None, "the rank of the constraint Jacobian changes along the line"
    N, rank = nb
    K, C = stack.jacobians(Q)
    Kt = K + stack.hessian(Q, Lf) if stack.m else K
    Nt = np.swapaxes(N, 1, 2)
    Kr = Nt @ Kt @ N
    statics = static_verdicts(Kr, N)
    if not samples and any(s["verdict"] == "unstable" for s in statics):
        return None, None, "the branch is statically unstable at a grid point"
    # no eigenvalue of K_r crosses zero between grid points (a fold or branch point: there det S,
    # which is det K_r times a factor of one sign on a line of constant rank, changes sign)
    counts = {(s["index"], s["zero"]) for s in statics}
    if not samples and len(counts) > 1:
        return None, None, "the reduced stiffness changes its inertia (a fold or branch point)"
    Mr = Nt @ np.broadcast_to(stack.M, (B, n, n)) @ N
    Pr = Nt @ C @ N
    G = stack.g(Q)
    force = G - np.einsum("bkn,bk->bn", Phi_q, Lf)
    fscale = np.maximum.reduce([np.max(np.abs(G), axis=1, initial=0.0),
                                np.max(np.abs(K).sum(axis=2), axis=1, initial=0.0)
                                * models[0].length_scale,
                                np.max(np.abs(G - force), axis=1, initial=0.0)])
    fscale = np.where(np.isfinite(fscale) & (fscale > 0), fscale, 1.0)
    fr = np.max(np.abs(force), axis=1, initial=0.0) / fscale
    phi = stack.phi(Q)
    eqs, lins = [], []
    scales = models[0].constraint_scales()
    for b, model in enumerate(models):
        if model.constraints is not models[0].constraints:
            scales = model.constraint_scales()
        cr = float(np.max(np.abs(phi[b]) / scales, initial=0.0)) if stack.m else 0.0
        eq = Equilibrium(
            q=Q[b].copy(), lam=Lf[b].copy(), residual=max(float(fr[b]), cr),
            force_residual=float(fr[b]), constraint_residual=cr, iterations=int(its[b]),
            rank=int(rank), n_redundant=0, tolerances={"rank_tol": RANK_TOL, "xtol": CTOL},
            method="batch", model=model, correction=float(last[b]),
            static=statics[b], path={"start": "batch", "kind": "start" if b == 0 else "grid",
                                      "segment": 0})
        eqs.append(eq)
        lins.append(LinearModel(
            M=Mr[b], P=Pr[b], Q=Kr[b], N=N[b], q0=eq.q, lam0=eq.lam,
            coordinate_names=model.coordinate_names, name=model.name,
            parameters=model.parameters, rank=int(rank), n_constraints=stack.m,
            constraint_stiffness=True, tolerances={"rank_tol": RANK_TOL},
            rigid=DeclaredRigid(model, eq.q, eq.lam, Kr[b], N[b], stack=(stack, b)),
            display=Displayed(model, eq.q)))
    return eqs, lins, {"statics": "batch", "newton_iterations": int(its.sum())}
