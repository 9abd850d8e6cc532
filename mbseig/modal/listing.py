"""The listing of classified modes: conjugate pairs once, sorted by ω_n then δ, kinds, rigid-body
representatives, mode shapes in full coordinates with the dominant coordinates named, and the
accounting of every eigenvalue (listed, infinite, outside a band)."""

from __future__ import annotations

import math
import warnings

import numpy as np

from ..errors import SolverError
from .bounds import worst
from .rules import classify, kind_of
from .result import Modes, Verdict
from .scope import verdict as scoped_verdict


def coordinate_text(coordinate_names, N, vector, limit=4):
    """Coordinates carrying a null vector: 'x2' or 'x1, x2 (combination 0.707 x1 − 0.707 x2)'."""
    v = np.asarray(vector)
    full = v if N is None else np.asarray(N @ v)
    n = full.size
    names = (list(coordinate_names) if coordinate_names is not None
             else [f"x{k + 1}" for k in range(n)])
    mag = np.abs(full)
    if not mag.size or mag.max() == 0:
        return "?"
    j = int(np.argmax(mag))
    full = full * (np.conj(full[j]) / mag[j]) / np.linalg.norm(full)  # real where it can be
    idx = [i for i in np.argsort(-mag, kind="stable")[:limit] if mag[i] >= 1e-3 * mag.max()]
    if len(idx) == 1:
        return names[idx[0]]
    terms = " ".join(f"{'−' if full[i].real < 0 else '+'} {abs(full[i]):.3g} {names[i]}"
                     for i in idx)
    return f"{', '.join(names[i] for i in idx)} (combination {terms.lstrip('+ ')})"


def band_of(md: Modes, band) -> Modes:
    """The modes of a full listing with ω_lo ≤ ω_n ≤ ω_hi: a partial listing (its verdict
    covers those modes only), every eigenvalue of the band found by the dense solve."""
    import dataclasses

    lo, hi = (float(b) for b in band)
    if not (0 <= lo <= hi):
        raise SolverError(f"band must be (ω_lo, ω_hi) with 0 ≤ ω_lo ≤ ω_hi, got {band!r}")
    keep = np.flatnonzero((md.omega_n >= lo) & (md.omega_n <= hi))
    def cut(a):
        return None if a is None else (a[..., keep] if np.ndim(a) > 1 else a[keep])

    def pick(seq):
        return [seq[k] for k in keep]

    coverage = (f"{keep.size} modes of {md.vectors.shape[0]} DOF; every eigenvalue with "
                f"{lo:.6g} ≤ |s| ≤ {hi:.6g} rad/s found (dense solve of the whole spectrum); "
                f"modes outside were not listed")
    stab = pick(md.stability)
    rigid_body = pick(md.rigid_body) if md.rigid_body else None
    verdict = scoped_verdict(stab, rigid_body, f"of the modes computed ({coverage})")
    acc = {**md.accounting, "listed_modes": int(keep.size), "band": [lo, hi]}
    return dataclasses.replace(
        md, eigenvalues=cut(md.eigenvalues), delta=cut(md.delta), omega_n=cut(md.omega_n),
        omega_d=cut(md.omega_d), freq_hz=cut(md.freq_hz), zeta=cut(md.zeta), stability=stab,
        kind=pick(md.kind), backward_error=cut(md.backward_error), condition=cut(md.condition),
        error_estimate=cut(md.error_estimate), tolerance=cut(md.tolerance),
        vectors=md.vectors[:, keep], shapes=md.shapes[:, keep], dominant=pick(md.dominant),
        verdict=verdict, left_vectors=None if md.left_vectors is None else md.left_vectors[:, keep],
        multiplicity=None if md.multiplicity is None else md.multiplicity[keep],
        accounting=acc, coverage=coverage, partial=True,
        flags=pick(md.flags) if md.flags else md.flags, rigid_body=rigid_body)


# ---------------------------------------------------------------------------------------------
# listing
# ---------------------------------------------------------------------------------------------
def rigid_representatives(sol, rigid_idx, rank_tol):
    """One rigid-body eigenvalue per independent vector, the largest Re s first (greedy)."""
    order = rigid_idx[np.lexsort((-sol.eigenvalues[rigid_idx].imag,
                                  -sol.eigenvalues[rigid_idx].real))]
    chosen, basis = [], None
    for i in order:
        v = sol.vectors[:, i]
        v = v / max(np.linalg.norm(v), np.finfo(float).tiny)
        r = v if basis is None else v - basis @ (basis.conj().T @ v)
        if np.linalg.norm(r) > rank_tol:
            chosen.append(i)
            r = r / np.linalg.norm(r)
            basis = r[:, None] if basis is None else np.column_stack([basis, r])
    return np.array(sorted(chosen), int)


def listing(sol, b, *, N, coordinate_names, n_dominant, eta_warn, tolerances_used):
    s_all = sol.eigenvalues
    err_all, tol_all, tol_re_all, rigid = b.err, b.tol, b.tol_re, b.rigid
    real_problem = not sol.complex_problem
    near_real = (~rigid) & (np.abs(s_all.imag) <= tol_all)
    if real_problem:
        listed = (~rigid) & ((s_all.imag > 0) | near_real)
    else:
        listed = ~rigid
    rigid_idx = np.flatnonzero(rigid)
    rep = rigid_representatives(sol, rigid_idx, tolerances_used["rigid_rank_tol"]) \
        if rigid_idx.size else np.zeros(0, int)
    listed[rep] = True
    g_rigid = int(np.max(b.geometric[rigid], initial=0)) if b.geometric is not None else 0
    accounting = account(sol, rigid, near_real, listed, rep, g_rigid)
    sel = np.flatnonzero(listed)
    s = s_all[sel].copy()
    is_rigid, real_listed = rigid[sel], near_real[sel]
    # the algebraic multiplicity each listed eigenvalue stands for: 1 for a simple s (its
    # conjugate, implied for a real problem, is not counted), the rigid share below
    mult = np.where(is_rigid, 0, 1)
    if rep.size:  # the rigid-body eigenvalues, shared out over the listed rigid modes
        share = np.full(rep.size, accounting["rigid_eigenvalues"] // rep.size)
        share[: accounting["rigid_eigenvalues"] % rep.size] += 1
        mult[is_rigid] = share
    flip = real_problem & (s.imag < 0)  # a rigid or near-real member below the axis
    if np.any(flip):
        s = np.where(flip, np.conj(s), s)
    if real_problem:  # a near-real pair: two real eigenvalues within tolerance, listed with ω = 0
        s = np.where(real_listed, s.real + 0j, s)
    delta, omega = 0.0 - s.real, s.imag  # 0.0 − x: no negative zeros in reports
    wn = np.abs(s)
    order = np.lexsort((omega, delta, wn))
    s, delta, omega, wn, is_rigid, mult, flip = (
        a[order] for a in (s, delta, omega, wn, is_rigid, mult, flip))
    sel = sel[order]
    eta, kappa = sol.backward_error[sel], sol.condition[sel]
    err, tol, tol_s = err_all[sel], tol_all[sel], tol_re_all[sel]
    X = _columns(sol.vectors, sel, flip)  # the vectors gathered once, in the listed order
    Y = sol.left_vectors
    Y = X if Y is sol.vectors else (None if Y is None else _columns(Y, sel, flip))
    stability_ = classify(delta, tol_s, is_rigid)
    kind = [kind_of(st, d, w, t, r) for st, d, w, t, r in zip(
        stability_, delta.tolist(), omega.tolist(), tol.tolist(), is_rigid.tolist(), strict=True)]
    with np.errstate(divide="ignore", invalid="ignore"):
        zeta = np.where((wn > 0) & ~is_rigid, delta / np.where(wn > 0, wn, 1.0), 0.0)
    shapes, dominant = mode_shapes(X, N, coordinate_names, n_dominant)
    flags = [[] for _ in range(s.size)]
    bad = np.flatnonzero(eta > eta_warn)
    if bad.size:
        eta_c = sol.componentwise(sel[bad])[0]
        bad = bad[eta_c > eta_warn]
    for k in bad:
        flags[k].append(f"η = {eta[k]:.1e} above {eta_warn:g}")
    if bad.size:
        names_ = ", ".join(f"{z.real:.6g}{z.imag:+.6g}j (η={e:.1e})"
                           for z, e in zip(s[bad][:8], eta[bad][:8], strict=True))
        warnings.warn(f"{bad.size} eigenvalues miss the backward-error target {eta_warn:g} "
                      f"({sol.solver}): {names_}", RuntimeWarning, stacklevel=3)
    coverage = coverage_text(sol, len(s)) if sol.partial else ""
    verdict = Verdict(worst(stability_),
                      f"of the modes computed ({coverage})" if sol.partial else "")
    numeric_details = {k: v for k, v in sol.details.items()}
    return Modes(
        eigenvalues=s, delta=delta, omega_n=wn, omega_d=omega, freq_hz=omega / (2 * np.pi),
        zeta=zeta, stability=stability_, kind=kind, backward_error=eta, condition=kappa,
        error_estimate=err, tolerance=tol_s, vectors=X, shapes=shapes, dominant=dominant,
        verdict=verdict, solver=sol.solver, solver_reason=sol.reason, n_infinite=sol.n_infinite,
        all_eigenvalues=s_all, tolerances={**tolerances_used, **numeric_details},
        left_vectors=Y, multiplicity=mult, accounting=accounting, coverage=coverage,
        partial=sol.partial, complex_problem=sol.complex_problem, flags=flags)


def _columns(V, sel, flip):
    """V[:, sel], conjugated where ``flip`` (a member below the real axis listed above it)."""
    out = V[:, sel]
    if np.any(flip):
        out = out.astype(complex)
        out[:, flip] = np.conj(out[:, flip])
    return out


def account(sol, rigid, near_real, listed, rep, g_rigid=0):
    """Every eigenvalue accounted for, or SolverError (a dense listing; module docstring).
    ``g_rigid``: independent eigenvectors of s = 0 from T(0)'s nullity (may exceed the computed
    vectors' rank for a derogatory zero)."""
    s = sol.eigenvalues
    n_rigid = int(np.sum(rigid))
    out = {"eigenvalues": 2 * sol.n_dof if not sol.partial else None,
           "finite": int(s.size), "infinite": int(sol.n_infinite),
           "rigid_eigenvalues": n_rigid, "rigid_modes": int(rep.size), "complete": True}
    g = max(rep.size, g_rigid)
    if n_rigid > 2 * g:
        raise SolverError(
            f"s = 0 has {n_rigid} eigenvalues but only {g} independent rigid-body vectors: "
            f"a zero eigenvalue of higher order than a free motion (secular growth t^k, or a "
            f"degenerate model); no listing can account for it")
    if not sol.complex_problem:
        upper = (~rigid) & (~near_real) & (s.imag > 0)
        lower = (~rigid) & (~near_real) & (s.imag < 0)
        if int(upper.sum()) != int(lower.sum()):
            raise SolverError(f"{int(upper.sum())} eigenvalues above the real axis but "
                              f"{int(lower.sum())} below: the listing of a real problem would "
                              f"not account for every eigenvalue")
    if not sol.partial and s.size + sol.n_infinite != 2 * sol.n_dof:
        out["complete"] = False
        raise SolverError(f"{sol.solver}: {s.size} finite + {sol.n_infinite} infinite eigenvalues "
                          f"for {sol.n_dof} DOF (expected {2 * sol.n_dof}): the listing is "
                          f"incomplete, no verdict")
    out["listed_modes"] = int(np.sum(listed))
    return out


def coverage_text(sol, n_listed):
    c = sol.coverage or {}
    lo, hi = c.get("omega_n", (math.nan, math.nan))
    what = c.get("measure", "|s|")
    text = f"{n_listed} modes of {c.get('dof', sol.n_dof)} DOF; "
    if c.get("verified", True):
        text += f"every eigenvalue with {lo:.6g} ≤ {what} ≤ {hi:.6g} rad/s found"
    else:
        text += f"the range {lo:.6g} ≤ {what} ≤ {hi:.6g} rad/s could not be verified complete"
    if c.get("note"):
        text += f"; {c['note']}"
    return text + "; modes outside were not computed"


def _identity(N):
    """Whether the dense basis N is exactly the identity (a model without constraints)."""
    return (isinstance(N, np.ndarray) and N.ndim == 2 and N.shape[0] == N.shape[1]
            and np.count_nonzero(N) == N.shape[0] and bool(np.all(N.diagonal() == 1.0)))


#: entries of the full-coordinate shapes normalized and searched at once (a block of modes):
#: the temporaries of a block (|x|, its transpose) stay a few MB on a model of 10⁵ coordinates
SHAPE_BLOCK = 1 << 18


def mode_shapes(X, N, coordinate_names, n_dominant):
    """Shapes in full coordinates (largest component 1) and the dominant coordinates of each
    mode, over a block of modes at once (the per-mode arithmetic of one column at a time; the
    shapes divided in place, block by block, so that a large model holds one copy of them)."""
    full = X if N is None or _identity(N) else N @ X
    n_full, k = full.shape
    names = (list(coordinate_names) if coordinate_names is not None
             else [f"q{k + 1}" for k in range(n_full)])
    if k == 0 or n_full == 0:
        return np.zeros_like(full), [[] for _ in range(k)]
    shapes = full.copy() if full is X else full
    picks = min(n_dominant, n_full)
    step = max(1, SHAPE_BLOCK // n_full)
    dominant = []
    for c0 in range(0, k, step):
        tops, mags = _normalized(shapes[:, c0:c0 + step], n_dominant, picks)
        dominant += [[(names[i], m) for i, m in zip(t, tm, strict=True) if m >= 0.05]
                     for t, tm in zip(tops, mags, strict=True)]
    return shapes, dominant


def _normalized(block, n_dominant, picks):
    """Divides each column of ``block`` (a view of the shapes) by its largest entry in place
    (a zero column stays as it is); returns each column's ``picks`` largest |entries| as
    (indices, sizes), in the order of a stable sort by −|x| (equal ones by index)."""
    n_full, k = block.shape
    cols = np.arange(k)
    j = np.argmax(np.abs(block), axis=0)
    piv = block[j, cols]
    nz = piv != 0
    if np.all(nz):
        block /= piv
    else:
        block[:, nz] /= piv[nz]
    mag = np.abs(block)
    # one argmax per rank over the block's modes, the found entry then masked
    rows = np.array(mag.T, order="C")
    top = np.empty((picks, k), dtype=np.intp)
    for t in range(picks):
        top[t] = np.argmax(rows, axis=1)
        rows[cols, top[t]] = -np.inf
    if n_full > 4 * n_dominant and picks:
        # an entry equal to the last one picked but left out (a tie at the cut): the selection
        # of the listing's large-model rule decides which of them is named, as it always did
        last = mag[top[-1], cols]
        for c in np.flatnonzero(np.max(rows, axis=1) == last):
            m = mag[:, c]
            cand = np.argpartition(-m, n_dominant)[:n_dominant]
            top[:, c] = cand[np.lexsort((cand, -m[cand]))]
    return top.T.tolist(), np.take_along_axis(mag, top, 0).T.tolist()
