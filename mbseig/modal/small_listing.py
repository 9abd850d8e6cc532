"""The listing of the fused small-dense modes path (:mod:`mbseig.modal.small`): the rules and
numbers of :func:`mbseig.modal.listing.listing`, :func:`mbseig.modal.bounds.zero_pair_floor`
and :func:`mbseig.modal.bounds.numerical_rank` for a full spectrum of a real problem, without
the generality those carry (partial spectra, complex problems, backward-error warnings: the
fused path hands those to the general stage before it gets here)."""

from __future__ import annotations

import math

import numpy as np
import scipy.linalg as sla

from ..eigen import EPS
from .bounds import Bounds, frequency_scale, numerical_rank, worst
from .rules import classify, kind_of
from .listing import account, mode_shapes
from .result import Modes, Verdict

__all__ = ["rank", "floor_zero_pairs", "small_listing"]

TINY = np.finfo(float).tiny
_GEQP3 = {}  # (dtype, shape) -> (geqp3, its optimal lwork), as bounds' own cache


def rank(X, rank_tol):
    """numerical_rank(X, rank_tol): the same normalization and pivoted QR (LAPACK geqp3)."""
    if X.shape[1] == 0:
        return 0
    Xn = X / np.maximum(np.sqrt(np.add.reduce((X.conj() * X).real, axis=0)), TINY)
    if not np.isfinite(Xn).all():
        return numerical_rank(X, rank_tol)
    key = (Xn.dtype.char, Xn.shape)
    got = _GEQP3.get(key)
    if got is None:
        if len(_GEQP3) > 256:
            _GEQP3.clear()
        geqp3 = sla.get_lapack_funcs("geqp3", (Xn,))
        got = _GEQP3[key] = geqp3, int(geqp3(Xn.copy(), lwork=-1)[-2][0].real)
    qr, _, _, _, info = got[0](Xn, lwork=got[1], overwrite_a=1)
    if info != 0:
        return numerical_rank(X, rank_tol)
    d = np.abs(qr.diagonal())
    return int((d > rank_tol * d[0]).sum()) if d.size and d[0] > 0 else 0


def floor_zero_pairs(b, sol, M, P, safety):
    """zero_pair_floor(b, sol, M, P, safety) of a real unscaled solution (γ = 1)."""
    s = sol.eigenvalues
    scale = frequency_scale(sol.norms)
    cand = (np.abs(s) <= 1e-3 * scale).nonzero()[0].tolist()
    if not cand or M is None:
        return b
    nQ = float(sol.norms[2])
    eta = np.maximum(sol.backward_error, EPS)
    err, tol, tol_re, rigid = b.err.copy(), b.tol.copy(), b.tol_re.copy(), b.rigid.copy()
    reach = math.sqrt(safety)
    for k in cand:
        x = sol.vectors[:, k]
        mx = abs(np.vdot(x, M @ x))
        px = 0.0 if P is None else abs(np.vdot(x, P @ x))
        if mx == 0 or px > abs(s[k]) * mx:
            continue
        h = math.sqrt(float(eta[k]) * float(nQ) * float(np.vdot(x, x).real) / float(mx))
        if not math.isfinite(h):  # (a floor beyond the range of doubles decides nothing)
            continue
        if abs(s[k]) <= reach * h:
            err[k] = max(err[k], h)
            tol[k] = max(tol[k], safety * h)
            tol_re[k] = max(tol_re[k], safety * h)
            rigid[k] = True
    return Bounds(err, tol, tol_re, rigid, b.cluster, b.block, b.geometric)


def _representatives(V, s, rigid_idx, rank_tol):
    """listing.rigid_representatives: one rigid-body eigenvalue per independent vector."""
    order = rigid_idx[np.lexsort((-s[rigid_idx].imag, -s[rigid_idx].real))]
    chosen, basis = [], None
    for i in order.tolist():
        v = V[:, i]
        v = v / max(_norm(v), TINY)
        r = v if basis is None else v - basis @ (basis.conj().T @ v)
        nr = _norm(r)
        if nr > rank_tol:
            chosen.append(i)
            r = r / nr
            basis = r[:, None] if basis is None else np.column_stack([basis, r])
    return np.array(sorted(chosen), int)


def _norm(v):
    """np.linalg.norm of a vector (its own evaluation, without its dispatch)."""
    if v.dtype.kind == "c":
        re, im = v.real, v.imag
        return math.sqrt(re.dot(re) + im.dot(im))
    return math.sqrt(v.dot(v))


def _columns(V, sel, flip, any_flip):
    out = V[:, sel]
    if any_flip:
        out = out.astype(complex)
        out[:, flip] = np.conj(out[:, flip])
    return out


def _shapes(X, N, coordinate_names, n_dominant):
    """listing.mode_shapes (mode_shapes itself for a zero column or an empty listing)."""
    identity = (isinstance(N, np.ndarray) and N.ndim == 2 and N.shape[0] == N.shape[1]
                and np.count_nonzero(N) == N.shape[0] and bool((N.diagonal() == 1.0).all()))
    full = X if N is None or identity else N @ X
    n_full, k = full.shape
    picks = min(n_dominant, n_full)
    if k == 0 or n_full == 0 or not picks:
        return mode_shapes(X, N, coordinate_names, n_dominant)
    cols = np.arange(k)
    piv = full[np.abs(full).argmax(axis=0), cols]
    if not piv.all():
        return mode_shapes(X, N, coordinate_names, n_dominant)
    shapes = full / piv
    mag = np.abs(shapes)
    rows = np.array(mag.T, order="C")
    top = np.empty((picks, k), dtype=np.intp)
    for t in range(picks):
        top[t] = rows.argmax(axis=1)
        rows[cols, top[t]] = -np.inf
    if n_full > 4 * n_dominant:  # a tie at the cut: the large-model rule names them
        for c in (rows.max(axis=1) == mag[top[-1], cols]).nonzero()[0].tolist():
            m = mag[:, c]
            cand = np.argpartition(-m, n_dominant)[:n_dominant]
            top[:, c] = cand[np.lexsort((cand, -m[cand]))]
    names = list(coordinate_names) if coordinate_names is not None else \
        [f"q{i + 1}" for i in range(n_full)]
    dominant = [[(names[i], m) for i, m in zip(t, tm, strict=True) if m >= 0.05]
                for t, tm in zip(top.T.tolist(), mag[top, cols].T.tolist(), strict=True)]
    return shapes, dominant


def small_listing(sol, b, *, N, coordinate_names, n_dominant, tolerances_used):
    """listing(sol, b, ...) of a full real spectrum none of whose pairs is above eta_warn."""
    s_all = sol.eigenvalues
    tol_all, rigid = b.tol, b.rigid
    free = ~rigid
    near_real = free & (np.abs(s_all.imag) <= tol_all)
    listed = free & ((s_all.imag > 0) | near_real)
    rigid_idx = rigid.nonzero()[0]
    rep = _representatives(sol.vectors, s_all, rigid_idx, tolerances_used["rigid_rank_tol"]) \
        if rigid_idx.size else np.zeros(0, int)
    listed[rep] = True
    g_rigid = int(b.geometric[rigid].max(initial=0)) if b.geometric is not None else 0
    accounting = account(sol, rigid, near_real, listed, rep, g_rigid)
    sel = listed.nonzero()[0]
    s = s_all[sel]
    is_rigid, real_listed = rigid[sel], near_real[sel]
    # as listing() has it: 1 for a simple s, the rigid share below
    mult = np.where(is_rigid, 0, 1)
    if rep.size:
        share = np.full(rep.size, accounting["rigid_eigenvalues"] // rep.size)
        share[: accounting["rigid_eigenvalues"] % rep.size] += 1
        mult[is_rigid] = share
    flip = s.imag < 0
    any_flip = bool(flip.any())
    if any_flip:
        s = np.where(flip, np.conj(s), s)
    s = np.where(real_listed, s.real + 0j, s)
    delta, omega = 0.0 - s.real, s.imag
    wn = np.abs(s)
    order = np.lexsort((omega, delta, wn))
    s, delta, omega, wn, is_rigid, mult, flip = (
        a[order] for a in (s, delta, omega, wn, is_rigid, mult, flip))
    sel = sel[order]
    X = _columns(sol.vectors, sel, flip, any_flip)
    Y = sol.left_vectors
    Y = X if Y is sol.vectors else (None if Y is None else _columns(Y, sel, flip, any_flip))
    tol, tol_s = tol_all[sel], b.tol_re[sel]
    stability_ = classify(delta, tol_s, is_rigid)
    kind = [kind_of(st, d, w, t, r) for st, d, w, t, r in zip(
        stability_, delta.tolist(), omega.tolist(), tol.tolist(), is_rigid.tolist(), strict=True)]
    pos = (wn > 0) & ~is_rigid
    zeta = np.where(pos, delta / np.where(wn > 0, wn, 1.0), 0.0)
    shapes, dominant = _shapes(X, N, coordinate_names, n_dominant)
    return Modes(
        eigenvalues=s, delta=delta, omega_n=wn, omega_d=omega, freq_hz=omega / (2 * np.pi),
        zeta=zeta, stability=stability_, kind=kind, backward_error=sol.backward_error[sel],
        condition=sol.condition[sel], error_estimate=b.err[sel], tolerance=tol_s,
        vectors=X, shapes=shapes, dominant=dominant, verdict=Verdict(worst(stability_), ""),
        solver=sol.solver, solver_reason=sol.reason, n_infinite=sol.n_infinite,
        all_eigenvalues=s_all, tolerances={**tolerances_used, **sol.details}, left_vectors=Y,
        multiplicity=mult, accounting=accounting, coverage="", partial=False,
        complex_problem=False, flags=[[] for _ in range(s.size)])
