"""Steady motions of one model at many motions at once: the pipeline of
:func:`mbseig.studies.steady_modes.analyze_steady` with a leading batch axis.

A sweep of a steady motion over its speed (or yaw rate) changes the ``[motion]`` table alone:
the model is built once (:class:`~mbseig.casefile.element_readers.MotionUpdate` says whether
the swept parameter enters anything else) and B motions are analysed together, each numpy call
working on all of them:

- the steady state by Newton on all points (:func:`mbseig.studies.steady.steady_state`'s
  equations, start, tolerance and iteration limit; minimum-norm steps by stacked
  pseudo-inverses where it solves by least squares), each point stopping when it converges;
- the linearization in the moving frame (:func:`~mbseig.studies.steady.linearize_steady`: null
  spaces by stacked SVD with its rank rule, the wheels' velocity rows, spins and multiplier
  terms by batched kernels of :class:`~mbseig.model.rolling.RollingWheel`'s formulas);
- the declared cyclic directions (:func:`~mbseig.studies.steady_modes.cyclic_directions`): the
  candidates of each point, the whole usable set checked for invariance and deflated exactly
  (:func:`mbseig.eigen.deflate_subspace`'s construction);
- the eigenvalues of the deflated pencil s E₂ − A₂ by
  :func:`mbseig.eigen.batch.solve_descriptor_batch` (stacked ``eig`` of E₂⁻¹A₂ where E₂ is well
  conditioned, with the QZ path's η and κ);
- the mode rows and verdict by :func:`~mbseig.studies.steady_modes.mode_rows` and its
  classification.

Identical inputs give identical outputs, so quantities of the positions alone (null spaces,
pseudo-inverses of the velocity rows) are computed once per distinct q: along a straight run the
positions do not change with the speed.

A point the batch does not cover is named with its reason and analysed on its own by
:func:`~mbseig.studies.steady_modes.analyze_steady` (which also gives the exact error where
there is one): a steady state that does not converge or that the constraints forbid, a null
space whose rank differs from the batch's, a candidate set whose union is not invariant (the
subset search is the one-point path's), a pencil the batched solver does not cover (E₂
ill-conditioned, a pair whose vectors fail their backward-error check), anything not finite.
"""

from __future__ import annotations

from types import SimpleNamespace

import numpy as np

from ..eigen.batch import solve_descriptor_batch
from ..model.stacked import STACK_MAX
from .steady import SteadyAssembly, generator, translation
from .steady_rows import INVARIANT_TOL, PLANE, Cyclic, mode_rows, verdict_of

__all__ = ["SteadyStack"]

TOL, MAX_ITER, RANK_TOL = 1e-12, 25, 1e-10  # steady_state's and linearize_steady's defaults
KEEP = 64  # distinct positions whose position-only quantities are kept
_EPS = np.finfo(float).eps


def _skew(v):
    """(…, 3, 3) cross-product matrices of the rows of ``v`` (…, 3)."""
    S = np.zeros(v.shape[:-1] + (3, 3))
    S[..., 0, 1], S[..., 0, 2] = -v[..., 2], v[..., 1]
    S[..., 1, 0], S[..., 1, 2] = v[..., 2], -v[..., 0]
    S[..., 2, 0], S[..., 2, 1] = -v[..., 1], v[..., 0]
    return S


def _norm(X):
    """Frobenius norms of a stack (B, …)."""
    X = X.reshape(X.shape[0], -1)
    return np.sqrt(np.einsum("bi,bi->b", X, X.conj()).real)


def _pinv(X):
    """Stacked pseudo-inverses with ``numpy.linalg.lstsq``'s cut-off (eps·max(m, n)·σ_max): the
    minimum-norm least-squares solutions the one-point path takes."""
    if X.shape[1] == 0 or X.shape[2] == 0:
        return np.zeros((X.shape[0], X.shape[2], X.shape[1]))
    return np.linalg.pinv(X, rtol=_EPS * max(X.shape[1:]))


def _null(X, rcond):
    """Stacked ``scipy.linalg.null_space(X, rcond)`` (B, n, n − r) and the nullity of each; the
    basis is None where the nullities differ."""
    B, m, n = X.shape
    if m == 0:
        return np.broadcast_to(np.eye(n), (B, n, n)), np.full(B, n)
    _, s, vh = np.linalg.svd(X, full_matrices=True)
    num = (s > s.max(axis=1, initial=0.0)[:, None] * rcond).sum(axis=1)
    if (num != num[0]).any():
        return None, n - num
    return np.swapaxes(vh[:, num[0]:, :], 1, 2), n - num


class _Wheel:
    """One rolling wheel's velocity rows, spin moment and multiplier terms on a batch
    (:class:`~mbseig.model.rolling.RollingWheel`'s formulas, z = C q[idx] + d of its frame)."""

    def __init__(self, w):
        from ..model.spatial_body import vector_matrix

        C, self.d, self.idx = w.frame.C, w.frame.d, w.frame.idx
        self.C, self.Ia = C, float(w.axial_inertia)
        self.XT = [X.T for X, _ in w._xy]
        self.YT = [Y.T for _, Y in w._xy]
        self.XC = [X @ C for X, _ in w._xy]
        self.YC = [Y @ C for _, Y in w._xy]
        self.H = np.stack([C.T @ Y.T @ X @ C for X, Y in w._xy])
        self.VaC = vector_matrix(w.axis) @ C
        self.Ck = np.stack([C[3 * k:3 * k + 3] for k in range(1, 4)])  # (3, 3, m)
        self.C9t = self.Ck.reshape(9, -1).T                              # (m, 9)

    def frame(self, Q, QD):
        q, qd = Q[:, self.idx], QD[:, self.idx]
        return q @ self.C.T + self.d, qd @ self.C.T, qd

    def velocity(self, Z, ZD):
        """A (B, 2, m) and Ã = ∂(A q̇)/∂q (B, 2, m)."""
        A = np.stack([(Z @ XT) @ YC for XT, YC in zip(self.XT, self.YC, strict=True)], axis=1)
        At = np.stack([(ZD @ YT) @ XC for YT, XC in zip(self.YT, self.XC, strict=True)], axis=1)
        return A, At

    def gyroscopic(self, Z, QDw, spin):
        """(g, ∂g/∂q, ∂g/∂q̇, ∂g/∂Ω) of T = −I_a Ω ȧ on the frame (:meth:`RollingWheel.
        gyroscopic` and :func:`~mbseig.model.spatial_forces.moment_force`, batched): on each
        unit vector e_k of the frame g = ½ T × e_k, ∂g/∂e_k = ½ skew(T), ∂g/∂T = −½ skew(e_k)."""
        B = Z.shape[0]
        ad = QDw @ self.VaC.T                                # ȧ (B, 3)
        T = -self.Ia * spin[:, None] * ad
        E = Z[:, 3:].reshape(B, 3, 3)                        # e_k (B, 3, 3)
        g = (0.5 * np.cross(T[:, None, :], E)).reshape(B, 9) @ self.C9t.T
        ST = 0.5 * _skew(T)
        dq = self.C9t @ (ST[:, None] @ self.Ck[None]).reshape(B, 9, -1)
        dqd = (0.5 * self.Ia * spin)[:, None, None] * (self.C9t @ (_skew(E) @ self.VaC)
                                                       .reshape(B, 9, -1))
        dO = (0.5 * self.Ia * np.cross(E, ad[:, None, :])).reshape(B, 9) @ self.C9t.T
        return g, dq, dqd, dO

    def multiplier_stiffness(self, MU):
        return np.einsum("br,rij->bij", MU, self.H)


def _empty_like(t, B):
    """Arrays for the terms of B points (filled as they converge)."""
    out = {}
    for key, val in t.items():
        if key == "blocks":
            out[key] = [tuple(np.empty((B, *x.shape[1:])) for x in blk) for blk in val]
        elif val is None:
            out[key] = None
        else:
            out[key] = np.empty((B, *val.shape[1:]), val.dtype)
    return out


def _put(kept, t, rows, sel):
    """kept[rows] = t[sel], key by key."""
    for key, val in t.items():
        if key == "blocks":
            for dst, src in zip(kept[key], val, strict=True):
                for d_, s_ in zip(dst, src, strict=True):
                    d_[rows] = s_[sel]
        elif val is not None:
            kept[key][rows] = val[sel]


def _mv(A, x):
    """Stacked matrix-vector products (B, r, c) · (B, c) → (B, r)."""
    return (A @ x[:, :, None])[:, :, 0]


class SteadyStack:
    """The steady-motion equations of one model at B motions (module docstring).  ``reason``
    is None where the batch applies to the model, else why not."""

    def __init__(self, model):
        from ..model.stacked import ModelStack

        self.model, self.reason = model, None
        if model.mass_elements or model.commands:
            self.reason = ("a configuration-dependent mass" if model.mass_elements
                           else "inverse-statics commands pending")
            return
        if model.n + model.n_constraints > STACK_MAX:
            self.reason = f"{model.n + model.n_constraints} unknowns (above {STACK_MAX})"
            return
        self.asm = asm = SteadyAssembly(model)
        if not asm.wheels:
            self.reason = "no rolling wheels"
            return
        self.stack = ModelStack([model])
        self.wheels = [_Wheel(w) for w in asm.wheels]
        self.n, self.nw, self.mh = model.n, len(asm.wheels), model.n_constraints
        self.M, self.J, self.Bw = asm.M, asm.J, asm.B
        self.pinvB = np.linalg.pinv(asm.B, rtol=_EPS * max(asm.B.shape))
        self.fscale = max(1.0, float(np.abs(model.g_const).max(initial=0.0)))
        self.rows = np.asarray(asm.contact_row, int)
        self.lengths = np.array([w.length for w in asm.wheels])
        self._fields, self._memo = {}, {}

    # ---- quantities of the positions alone -------------------------------------------------
    def _once(self, name, Q, fn):
        """fn(rows) over the distinct rows of Q not computed before, spread back to every row:
        identical positions give identical results (null spaces, pseudo-inverses, Φ_q), so
        each is computed once per distinct q and kept (the last KEEP of them)."""
        if (Q == Q[:1]).all():  # one position for all (a straight run, a batch of one)
            first, inv = np.zeros(1, int), np.zeros(Q.shape[0], int)
        else:
            _, first, inv = np.unique(Q, axis=0, return_index=True, return_inverse=True)
            inv = inv.ravel()
        keys_u = [Q[i].tobytes() for i in first]
        memo = self._memo.setdefault(name, {})
        missing = [j for j, k in enumerate(keys_u) if k not in memo]
        if missing:
            got = fn(first[missing])
            parts = got if isinstance(got, tuple) else (got,)
            if parts[0] is None:  # (nullities that differ: none kept; each row's nullity)
                held = dict(zip(missing, parts[1], strict=True))
                nul = np.array([held[j] if j in held else memo[k][1].shape[-1]
                                for j, k in enumerate(keys_u)])
                return None, nul[inv]
            for jj, j in enumerate(missing):
                memo[keys_u[j]] = tuple(p[jj] for p in parts)
            while len(memo) > KEEP:
                memo.pop(next(iter(memo)))
        rows = [memo[k] for k in keys_u]
        if len(rows) == 1:  # one position: a read-only view of its results for every row
            out = tuple(np.broadcast_to(x, (Q.shape[0], *np.shape(x))) for x in rows[0])
        else:
            out = tuple(np.stack([r[i] for r in rows])[inv] for i in range(len(rows[0])))
        return out if len(out) > 1 else out[0]

    # ---- equations -------------------------------------------------------------------------
    def _field(self, motion):
        """(unit-yaw generator, translation along d, lateral translation) of the motion
        (:func:`generator`, :func:`translation`), kept per direction and axis."""
        key = (tuple(motion.direction), tuple(motion.up))
        hit = self._fields.get(key)
        if hit is None:
            import dataclasses

            unit = generator(self.model, dataclasses.replace(motion, yaw_rate=1.0, speed=0.0))[0]
            d = np.asarray(motion.direction, float)
            d = d / np.linalg.norm(d)
            up = np.asarray(motion.up, float)
            up = up / np.linalg.norm(up)
            hit = self._fields[key] = (unit, translation(self.model, d),
                                       translation(self.model, np.cross(up, d)))
        return hit

    def terms(self, Q, QD, SPIN):
        """Φ_q, A, Ã = ∂(A q̇)/∂q, f, F_q, F_p, F_Ω at (q, q̇, Ω) (:class:`SteadyAssembly`'s
        ``phi_q``, ``velocity`` and ``forces`` without the multiplier term), batched."""
        B, n, nw = Q.shape[0], self.n, self.nw
        model = self.model
        if model.forces:  # each model's own elements, one point at a time (the same numbers)
            f = np.stack([np.array(model.generalized_force(q, qd), float)
                          for q, qd in zip(Q, QD, strict=True)])
            KC = [model.force_jacobians(q, qd, dense=True) for q, qd in zip(Q, QD, strict=True)]
            Fq = -np.stack([np.asarray(k, float) for k, _ in KC])
            Fp = -np.stack([np.asarray(c, float) for _, c in KC])
        else:
            f = np.broadcast_to(model.g_const, (B, n)).astype(float)
            Fq = Fp = None  # (the wheels' blocks alone)
        FO = np.zeros((B, n, nw))
        A, At = self.velocity(Q, QD)
        blocks = []
        for k, w in enumerate(self.wheels):
            Z, _, QDw = w.frame(Q, QD)
            g, dq, dqd, dO = w.gyroscopic(Z, QDw, SPIN[:, k])
            f[:, w.idx] += g
            blocks.append((dq, dqd))
            FO[:, w.idx, k] += dO
        Pq = self._once("Pq", Q, lambda rows: self.stack.phi_q(Q[rows]))
        return {"Pq": Pq, "A": A, "At": At, "f": f, "Fq": Fq, "Fp": Fp, "FO": FO,
                "blocks": blocks}

    def dense(self, t, rows):
        """(F_q, F_p) (len(rows), n, n) of the terms ``t`` at ``rows``: the model's forces and
        the wheels' blocks."""
        B, n = len(rows), self.n
        Fq = np.zeros((B, n, n)) if t["Fq"] is None else t["Fq"][rows]  # (copies: fancy index)
        Fp = np.zeros((B, n, n)) if t["Fp"] is None else t["Fp"][rows]
        for w, (dq, dqd) in zip(self.wheels, t["blocks"], strict=True):
            ix = np.ix_(w.idx, w.idx)
            Fq[:, ix[0], ix[1]] += dq[rows]
            Fp[:, ix[0], ix[1]] += dqd[rows]
        return Fq, Fp

    def velocity(self, Q, QD):
        """A (B, 2 n_w, n) and Ã = ∂(A q̇)/∂q of the wheels' velocity rows."""
        B, n, nw = Q.shape[0], self.n, self.nw
        A = np.zeros((B, 2 * nw, n))
        At = np.zeros_like(A)
        for k, w in enumerate(self.wheels):
            Z, ZD, _ = w.frame(Q, QD)
            A[:, 2 * k:2 * k + 2, w.idx], At[:, 2 * k:2 * k + 2, w.idx] = w.velocity(Z, ZD)
        return A, At

    def multiplier_stiffness(self, MU):
        """∂(Aᵀμ)/∂q (B, n, n)."""
        H = np.zeros((MU.shape[0], self.n, self.n))
        for k, w in enumerate(self.wheels):
            ix = np.ix_(w.idx, w.idx)
            H[:, ix[0], ix[1]] += w.multiplier_stiffness(MU[:, 2 * k:2 * k + 2])
        return H

    # ---- the pipeline ----------------------------------------------------------------------
    def analyse(self, motions, *, naive=False, full=False):
        """Per motion a :class:`SimpleNamespace` (eigenvalues, modes, verdict, n_rigid,
        contacts) or the reason (a string) the batch does not cover it.  ``naive``: the
        linearization without Ã (:func:`~mbseig.studies.steady.linearize_steady`'s flag);
        ``full``: each namespace also holds the steady state (q, qd, spin, lam, mu, residual,
        iterations), the linearization (E, A, N, T, S, dof, k), the declared directions
        (``cyclic``) and the pencil's solution (``solution``: s, vectors, left vectors, η, κ,
        norms, E₂, A₂) for :func:`~mbseig.studies.steady_modes.analyze_steady`."""
        from ..errors import MbseigError

        out = [None] * len(motions)
        fields = []
        for b, mo in enumerate(motions):
            try:
                fields.append(self._field(mo))
            except MbseigError as exc:  # (a direction along gravity: the one-point path says)
                fields.append(None)
                out[b] = str(exc)
        idx = [b for b, f in enumerate(fields) if f is not None]
        if not idx:
            return out
        mot = [motions[b] for b in idx]
        fld = [fields[b] for b in idx]
        r = np.array([float(m.yaw_rate) for m in mot])
        v = np.array([float(m.speed) for m in mot])
        turning = r != 0
        if turning.any() and not turning.all():  # one kind of motion per batch
            for j in np.flatnonzero(turning):
                out[idx[j]] = "turning and straight points in one batch"
            keep = np.flatnonzero(~turning)
            idx, fld, r, v = [idx[j] for j in keep], [fld[j] for j in keep], r[keep], v[keep]
        unit = np.stack([f[0] for f in fld])
        L = r[:, None, None] * unit if r.any() else None  # straight running: L = 0 exactly
        ell = v[:, None] * np.stack([f[1] for f in fld])
        res = self._solve(L, ell, unit, r, v, fld, naive=bool(naive), full=bool(full))
        for b, item in zip(idx, res, strict=True):
            out[b] = item
        return out

    def _state(self, L, ell):
        """The steady states (steady_state, batched): (Q, SPIN, LAM, MU, terms at them, the
        reason per point where the batch gives none, the last residual and the iterations of
        each converged point)."""
        n, nw, mh = self.n, self.nw, self.mh
        Bn = ell.shape[0]
        why = [""] * Bn
        Lx = (lambda Lm, x: _mv(Lm, x)) if L is not None else (lambda Lm, x: 0.0 * x)
        Q = np.tile(np.asarray(self.model.q_init, float), (Bn, 1))
        QD = Lx(L, Q) + ell
        A, _ = self.velocity(Q, QD)
        Pq = self._once("Pq", Q, lambda rows: self.stack.phi_q(Q[rows]))
        bad = np.linalg.norm(_mv(Pq, QD), axis=1) > 1e-9 * np.maximum(
            1.0, np.abs(QD).max(axis=1, initial=0.0))
        SPIN = -(_mv(A, QD) @ self.pinvB.T)
        t = self.terms(Q, QD, SPIN)  # (the spins enter the wheels' moments)
        G = np.zeros((Bn, n + nw, mh + 2 * nw))
        G[:, :n, :mh] = np.swapaxes(Pq, 1, 2)
        G[:, :n, mh:] = np.swapaxes(A, 1, 2)
        G[:, n:, mh:] = self.Bw.T
        Gp = self._once("G+", Q, lambda first: _pinv(G[first]))
        MLqd = (Lx(L, QD) @ self.M.T) if L is not None else np.zeros((Bn, n))
        rhs = np.concatenate([t["f"] - MLqd, np.zeros((Bn, nw))], axis=1)
        lm = _mv(Gp, rhs)
        LAM, MU = lm[:, :mh], lm[:, mh:]
        sizes = np.cumsum([0, n, nw, mh, 2 * nw])
        kept = None
        resid, its = np.zeros(Bn), np.zeros(Bn, int)
        todo = ~bad
        for b in np.flatnonzero(bad):
            why[b] = "the constraints do not let the system move this way"
        a = np.flatnonzero(todo)
        for it in range(MAX_ITER + 1):
            if not a.size:
                break
            if it:
                q = Q[a]
                qd = (Lx(L[a], q) if L is not None else 0.0) + ell[a]
                t = self.terms(q, qd, SPIN[a])
            else:
                q, qd = Q[a], QD[a]
            Pq, A, f = t["Pq"], t["A"], t["f"]
            Ml = (Lx(L[a], qd) @ self.M.T) if L is not None else 0.0
            F = np.concatenate([
                (f - Ml - _mv(np.swapaxes(Pq, 1, 2), LAM[a])
                 - _mv(np.swapaxes(A, 1, 2), MU[a])) / self.fscale,
                -(MU[a] @ self.Bw) / self.fscale,
                self._once("Phi", q, lambda rows, q=q: self.stack.phi(q[rows])),
                _mv(A, qd) + SPIN[a] @ self.Bw.T], axis=1)
            res = np.abs(F).max(axis=1, initial=0.0)
            conv = res <= TOL
            resid[a[conv]], its[a[conv]] = res[conv], it
            if it == 0 and conv.all() and a.size == Bn:
                kept = t  # every point steady as started: its terms are those at the start
            else:
                if kept is None:
                    kept = _empty_like(t, Bn)
                _put(kept, t, a[conv], conv)
            todo[a[conv]] = False
            if it == MAX_ITER or conv.all():
                break
            k = ~conv
            a, q = a[k], q[k]
            l_ = L[a] if L is not None else None
            Jm = np.zeros((a.size, sizes[-1], sizes[-1]))
            Fq_k, Fp_k = self.dense(t, np.flatnonzero(k))
            J11 = Fq_k - self.stack.hessian(q, LAM[a]) - self.multiplier_stiffness(MU[a])
            if l_ is not None:
                J11 = J11 + Fp_k @ l_ - self.M @ (l_ @ l_)
            Jm[:, :n, :n] = J11 / self.fscale
            Jm[:, :n, n:n + nw] = t["FO"][k] / self.fscale
            Jm[:, :n, sizes[2]:sizes[3]] = -np.swapaxes(Pq[k], 1, 2) / self.fscale
            Jm[:, :n, sizes[3]:] = -np.swapaxes(A[k], 1, 2) / self.fscale
            Jm[:, n:n + nw, sizes[3]:] = -self.Bw.T / self.fscale
            Jm[:, sizes[2]:sizes[3], :n] = Pq[k]
            Jm[:, sizes[3]:, :n] = t["At"][k] + (A[k] @ l_ if l_ is not None else 0.0)
            Jm[:, sizes[3]:, n:n + nw] = self.Bw
            step = -_mv(_pinv(Jm), F[k])
            Q[a] += step[:, :n]
            SPIN[a] += step[:, n:n + nw]
            LAM[a] += step[:, sizes[2]:sizes[3]]
            MU[a] += step[:, sizes[3]:]
        for b in np.flatnonzero(todo):
            why[b] = "the steady state did not converge in the batch"
        if kept is None:
            kept = _empty_like(t, Bn)
        return Q, SPIN, LAM, MU, kept, why, resid, its

    def _solve(self, L, ell, unit, r, v, fields, *, naive, full):
        n, nw = self.n, self.nw
        Bn = ell.shape[0]
        out = [None] * Bn
        Q, SPIN, LAM, MU, t, why, resid, its = self._state(L, ell)
        live = np.array([not w for w in why])
        for b in np.flatnonzero(~live):
            out[b] = why[b]
        # ---- linearization (linearize_steady), the points whose state converged -----------
        while live.any():
            a = np.flatnonzero(live)
            N, nul = self._once("N", Q[a],
                                lambda first, a=a: _null(t["Pq"][a][first], RANK_TOL))
            if N is not None:
                break
            major = np.bincount(nul).argmax()
            for b in a[nul != major]:
                out[b] = "the rank of Φ_q differs from the batch's"
            live[a[nul != major]] = False
        if not live.any():
            return out
        q, lam, mu, spin = Q[a], LAM[a], MU[a], SPIN[a]
        l_ = L[a] if L is not None else None
        qd = (_mv(l_, q) if l_ is not None else 0.0) + ell[a]
        Ba, d = a.size, N.shape[2]
        Nt = np.swapaxes(N, 1, 2)
        A, At = t["A"][a], t["At"][a]
        if naive:  # (the velocity rows' position derivative dropped; A L stays)
            At = np.zeros_like(At)
        if l_ is None and t["Fq"] is None:  # the wheels' blocks and the rows' curvature alone:
            NqN = -self.stack.projected_hessian(q, lam, N)  # projected element by element
            NpN = np.zeros_like(NqN)
            for k_, (w, (dq, dqd)) in enumerate(zip(self.wheels, t["blocks"], strict=True)):
                Ni = N[:, w.idx, :]
                Nit = np.swapaxes(Ni, 1, 2)
                NqN += Nit @ (dq[a] - w.multiplier_stiffness(mu[:, 2 * k_:2 * k_ + 2])) @ Ni
                NpN += Nit @ dqd[a] @ Ni
        else:
            Fq, Fp = self.dense(t, a)
            Fq = Fq - self.stack.hessian(q, lam) - self.multiplier_stiffness(mu)
            if l_ is not None:
                Fq = Fq + Fp @ l_ - self.M @ (l_ @ l_)
                Fp = Fp - 2.0 * (self.M @ l_)
                At = At + A @ l_
            NqN, NpN = Nt @ Fq @ N, Nt @ Fp @ N
        W = np.concatenate([A @ N, np.broadcast_to(self.Bw, (Ba, 2 * nw, nw))], axis=2)
        T, _ = self._once("T", q, lambda first: _null(W[first], RANK_TOL))
        if T is None:  # (a velocity-row rank that differs along the batch: each on its own)
            for b in a:
                out[b] = "the rank of the velocity rows differs along the batch"
            return out
        Wp = self._once("W+", q, lambda first: _pinv(W[first]))
        k = T.shape[2]
        S = Wp @ (At @ N)
        Mbar = np.zeros((Ba, d + nw, d + nw))
        Mbar[:, :d, :d] = Nt @ self.M @ N
        Mbar[:, d:, d:] = self.J
        Fx = np.zeros((Ba, d + nw, d))
        Fx[:, :d] = NqN
        Fw = np.zeros((Ba, d + nw, d + nw))
        Fw[:, :d, :d] = NpN
        Fw[:, :d, d:] = Nt @ t["FO"][a]
        Tt = np.swapaxes(T, 1, 2)
        E = np.zeros((Ba, d + k, d + k))
        E[:, :d, :d] = np.eye(d)
        E[:, d:, :d] = -Tt @ Mbar @ S
        E[:, d:, d:] = Tt @ Mbar @ T
        Am = np.zeros_like(E)
        Am[:, :d, :d] = -S[:, :d]
        Am[:, :d, d:] = T[:, :d]
        Am[:, d:, :d] = Tt @ Fx - Tt @ Fw @ S
        Am[:, d:, d:] = Tt @ Fw @ T
        # ---- the declared directions (cyclic_directions) ---------------------------------
        turn = bool(r[0] != 0)
        bad = np.zeros(Ba, bool)
        fa = [fields[b] for b in a]
        t_along = np.stack([f[1] for f in fa])
        t_side = np.stack([f[2] for f in fa])
        unit_a = unit[a]
        zero_w = np.zeros((Ba, nw))

        def Lt(x):
            return _mv(l_, x) if l_ is not None else np.zeros_like(x)

        h = _mv(unit_a, q)
        cands = [(PLANE + " (along the motion)" if turn else "position along the motion",
                  t_along, -Lt(t_along), zero_w),
                 (PLANE + " (lateral)" if turn else "lateral position", t_side, -Lt(t_side),
                  zero_w),
                 ("heading" if not turn else "heading (phase along the turn)", h,
                  _mv(unit_a, qd) - Lt(h), zero_w)]
        if not turn:
            speed = v[a]
            moving = speed != 0
            if not moving.all():
                for j in np.flatnonzero(~moving):
                    out[a[j]] = "points at rest and moving in one batch"
                bad |= ~moving
            with np.errstate(divide="ignore", invalid="ignore"):
                cands.append(("speed along the motion", np.zeros((Ba, n)),
                              ell[a] / speed[:, None], spin / speed[:, None]))
        vecs, misses = [], []
        ones = np.ones(Ba)
        for _, dq, dp, dw in cands:
            x = _mv(Nt, dq)
            Ntdp = _mv(Nt, dp)
            ws = np.concatenate([Ntdp, dw], axis=1) + _mv(S, x)
            z = _mv(Tt, ws)
            ref = np.maximum.reduce([np.linalg.norm(dq, axis=1), np.linalg.norm(dp, axis=1),
                                     ones])
            miss = np.maximum.reduce([np.linalg.norm(_mv(N, x) - dq, axis=1),
                                      np.linalg.norm(_mv(N, Ntdp) - dp, axis=1),
                                      np.linalg.norm(_mv(T, z) - ws, axis=1)])
            misses.append(miss / ref)
            vecs.append(np.concatenate([x, z], axis=1))
        misses = np.stack(misses, axis=1)          # (Ba, c)
        usable = misses <= INVARIANT_TOL
        Y = np.stack(vecs, axis=2)                 # (Ba, d + k, c)
        nA = np.maximum(_norm(Am), 1e-300)
        first = np.flatnonzero(~bad)
        if not first.size:
            return out
        pattern = usable[first[0]]
        other = ~bad & ~(usable == pattern).all(axis=1)
        for j in np.flatnonzero(other):  # another usable set: the one-point path's search
            out[a[j]] = "another set of usable rigid-body candidates"
        bad |= other
        keep = np.flatnonzero(pattern)
        names = [cands[c][0] for c in keep]
        dropped_idx = [c for c in range(len(cands)) if c not in keep]
        kc = keep.size
        g = np.flatnonzero(~bad)
        if kc:
            Yk = Y[g][:, :, keep]
            sv = np.linalg.svd(Yk, compute_uv=False)
            independent = (sv > 1e-9 * np.abs(Yk).max(axis=(1, 2))[:, None]).sum(axis=1) == kc
            Qb = np.linalg.qr(Yk)[0]
            EQ, AQ = E[g] @ Qb, Am[g] @ Qb
            Jb = _pinv(EQ) @ AQ
            fail = ~independent | ~(_norm(AQ - EQ @ Jb) / nA[g] <= INVARIANT_TOL)
            for j in g[fail]:
                out[a[j]] = "the usable rigid-body candidates are not invariant together"
            g, basis = g[~fail], Qb[~fail]
            if not g.size:
                return out
            Eg, Ag = E[g], Am[g]
            ES, AS = Eg @ basis, Ag @ basis
            Jd = _pinv(ES) @ AS
            resd = _norm(AS - ES @ Jd) / nA[g]
            Sp = np.linalg.qr(basis, mode="complete")[0][:, :, kc:]
            Q2t = np.swapaxes(np.linalg.qr(ES, mode="complete")[0][:, :, kc:], 1, 2)
            E2, A2 = Q2t @ Eg @ Sp, Q2t @ Ag @ Sp
            rr = r[a][g]
            poly = (np.linalg.matrix_power(Jd, kc) if not turn
                    else Jd @ (Jd @ Jd + (rr * rr)[:, None, None] * np.eye(kc)))
            jn = np.maximum(_norm(Jd), np.abs(rr))
            pn = _norm(poly)
            with np.errstate(divide="ignore", invalid="ignore"):
                resid = np.maximum(resd, np.where(pn > 0, pn / jn ** (kc if not turn else 3),
                                                  0.0))
        else:
            E2, A2 = E[g], Am[g]
            basis = np.zeros((g.size, d + k, 0))
            resid = np.zeros(g.size)
            Jd = np.zeros((g.size, 0, 0))
        # ---- eigenvalues of the deflated pencil, the rows and verdicts --------------------
        sol = solve_descriptor_batch(E2, A2)
        forces = -lam[:, self.rows] / self.lengths  # (Ba, nw): each wheel's normal force
        for jj, j in enumerate(g):
            if sol["reason"][jj]:
                out[a[j]] = sol["reason"][jj]
                continue
            dropped = tuple((cands[c][0], float(misses[j, c])) for c in dropped_idx)
            cyc = Cyclic(tuple(names), basis[jj], Jd[jj], float(resid[jj]), dropped,
                         float(r[a[j]]))
            one = SimpleNamespace(eigenvalues=sol["s"][jj], backward_error=sol["eta"][jj],
                                  condition=sol["kappa"][jj])
            rows = mode_rows(one, declared=cyc, formed_in=n)
            contacts = tuple({"name": w.name, "force": float(c), "active": bool(c >= 0)}
                             for w, c in zip(self.asm.wheels, forces[j], strict=True))
            out[a[j]] = SimpleNamespace(eigenvalues=sol["s"][jj], modes=tuple(rows),
                                        verdict=verdict_of(rows), n_rigid=len(names),
                                        contacts=contacts, cyclic=cyc)
            if full:
                out[a[j]].__dict__.update(
                    q=q[j].copy(), qd=qd[j].copy(), spin=spin[j].copy(), lam=lam[j].copy(),
                    mu=mu[j].copy(), residual=float(resid[a[j]]),
                    iterations=int(its[a[j]]), E=E[j].copy(), A=Am[j].copy(),
                    N=np.array(N[j]), T=np.array(T[j]), S=S[j].copy(), dof=d, k=k,
                    solution={key: sol[key][jj] for key in
                              ("s", "eta", "kappa", "vectors", "left", "norms", "cond")},
                    E2=E2[jj].copy(), A2=A2[jj].copy())
        return out
