"""The search strategies of the partial paths, one per family of paths (registered in
:mod:`mbseig.eigen.partial`): Lanczos on the undamped problem (eigh, proportional), Arnoldi on
the companion pencil with shifts where the ranking looks (companion), SLEPc TOAR (slepc)."""

from __future__ import annotations

import numpy as np

from ..errors import SolverError
from .measures import (
    expand_pairs,
)
from .selection import (
    TARGET_ANGLES,
    annulus_points,
    cluster_tol,
    covered,
    dedupe,
    pick,
    slots,
    with_partners,
)
from .shift_invert import (
    companion_partial,
    undamped_partial,
)

EPS = np.finfo(float).eps
UPPER_TOL = 1e-9  # Im s ≥ −UPPER_TOL·|s|: an eigenvalue of the upper half-plane (or real)
#: a shift's Lanczos run covers the w-interval strictly inside its farthest returned Ritz value
#: (every eigenvalue it did not return lies at least that far): the interval's end must lie
#: inside by this fraction of that distance r, so that a copy of a multiple eigenvalue at the
#: very edge is never taken as covered, and by the edge Ritz value's own error where that is
#: larger (shift-invert: about ε ν_max absolute in ν = 1/(w − σ), i.e. ε r/r_min relative in
#: the distance, r_min the nearest one's; 1e3 of it is kept).  It was a fixed 1e-3, which a
#: clustered spectrum (the lowest modes of a shaft on many supports) failed, doubling k.
COVER_MARGIN = 1e-6


def symmetric_search(run, want, omega_t, band, max_modes):
    """Undamped modes (ω², v) for the symmetric paths, ranked by ω_n = √|ω²|."""
    Mb, Qb = run.Mb, run.Qb
    scale = run.w_scale
    if band is not None:
        mid = 0.5 * (band[0] ** 2 + band[1] ** 2)
        sigmas = [mid, -mid] if band[0] > 0 else [0.0]
    else:
        sigmas = [omega_t**2, -omega_t**2] if omega_t > 0 else [0.0]
    k = want + 2
    while True:
        k = min(k, run.limit)
        if k < 1 or (want > run.limit):
            raise SolverError(f"{want} modes asked of a problem with {run.dof} degrees of "
                              f"freedom: use the dense path")
        ws, Vs, covered = [], [], []
        for sg in sigmas:
            w, V, used = undamped_partial(Mb, Qb, k, sg, scale**2, run.ncv, run.maxiter,
                                           run.tol, run.purify)
            ws.append(w)
            Vs.append(V)
            dist = np.abs(w - used)
            r = float(np.max(dist))
            r_min = float(np.min(dist))
            margin = max(COVER_MARGIN, 1e3 * EPS * r / r_min) if r_min > 0 else 1.0
            covered.append((used, r * (1 - min(margin, 1.0))))
        w, V = np.concatenate(ws), np.column_stack(Vs)
        if len(sigmas) > 1:
            keep = dedupe(w, V, 1e-10, scale * scale)
            w, V = w[keep], V[:, keep]
        omega = np.sqrt(np.abs(w))
        idx, d, note = pick(omega, want, omega_t, band, scale)
        lo, hi = (band if band is not None else (max(omega_t - d, 0.0), omega_t + d))
        # the selection is right when both w-intervals [lo², hi²] and [−hi², −lo²] are covered
        need = [(lo * lo, hi * hi), (-hi * hi, -lo * lo)]
        ok = all(any(c - r <= a and b <= c + r for c, r in covered) for a, b in need)
        if ok or k >= run.limit:
            break
        if k >= max_modes:
            raise SolverError(f"the requested modes need more than max_modes = {max_modes} "
                              f"eigenpairs per shift")
        k = min(2 * k, max_modes)
    order = idx[np.argsort(w[idx], kind="stable")]
    return {"w": w[order], "V": V[:, order], "k": k, "shifts": [c for c, _ in covered],
            "coverage": {"measure": "undamped ω_n", "omega_n": (lo, hi), "note": note,
                         "verified": ok}}


def companion_search(run, want, omega_t, band, max_modes):
    """Eigenvalues of the general (companion) path ranked by |s|."""
    Mb, Pb, Qb = run.Mb, run.Pb, run.Qb
    scale = run.w_scale
    def on_circle(angles):
        out = []
        for a in angles:
            z = omega_t * np.exp(1j * np.pi * a)
            out.append(complex(z.real, z.imag) if abs(z.imag) > 1e-12 * omega_t else float(z.real))
        return out

    circle = band is None and omega_t > 0
    sigmas = on_circle(TARGET_ANGLES[0]) if circle else [0.0]
    extra = list(TARGET_ANGLES[1:]) if circle else []
    k = 2 * want + 1
    runs = {}
    while True:
        if k > run.limit:
            raise SolverError(f"{want} modes asked of a problem with {run.dof} degrees of "
                              f"freedom: use the dense path")
        for sg in sigmas:
            if (sg, k) not in runs:
                runs[(sg, k)] = companion_partial(Mb, Pb, Qb, k, sg, scale, run.ncv,
                                                   run.maxiter, run.tol, run.purify)
        parts = [runs[(sg, k)] for sg in sigmas]
        discs = [p[3] for p in parts]
        if len(parts) == 1:  # one shift (the lowest modes): no copies
            s, X1, X2 = parts[0][:3]
        else:
            s = np.concatenate([p[0] for p in parts])
            X1 = np.concatenate([p[1] for p in parts], axis=1)
            X2 = np.concatenate([p[2] for p in parts], axis=1)
        if len(sigmas) > 1:
            keep = dedupe(s, X1, 1e-9, scale)
            s, X1, X2 = s[keep], X1[:, keep], X2[:, keep]
        tol = UPPER_TOL * np.maximum(np.abs(s), 1e-300)
        upper = np.flatnonzero(s.imag >= -tol)
        slot = slots(s[upper], X1[:, upper], cluster_tol(scale))
        first = np.flatnonzero(slot == np.arange(slot.size))  # one candidate per slot
        idx, d, note = pick(np.abs(s[upper[first]]), want, omega_t, band, scale)
        idx = np.flatnonzero(np.isin(slot, first[idx]))  # every member of the slots picked
        lo, hi = (band if band is not None else (max(omega_t - d, 0.0), omega_t + d))
        ok = covered(annulus_points(lo, hi), discs)
        if ok:
            break
        if extra:  # more shifts on the circle before more eigenvalues per shift
            sigmas = sigmas + on_circle(extra.pop(0))
            continue
        if k >= run.limit or want >= max_modes:
            if band is not None:
                raise SolverError(f"band {band!r} holds more than max_modes = {max_modes} modes")
            break
        k = min(2 * k, run.limit)
    cols, conj, s_out = with_partners(upper[idx], s, tol)

    def gather(X):  # the kept columns, conjugated where they are the partners (one copy)
        out = np.asarray(X)[:, cols].astype(complex)
        out[:, conj] = out[:, conj].conj()
        return out

    X1o = gather(X1)
    X2o = X1o if X2 is X1 else gather(X2)
    del runs, parts, X1, X2
    return {"s": np.asarray(s_out, complex), "X1": X1o, "X2": X2o, "k": k,
            "shifts": [c if c.imag else float(c.real) for c, _, _ in discs],
            "coverage": {"measure": "|s|", "omega_n": (lo, hi), "note": note, "verified": ok}}


def slepc_search(run, want, omega_t, band):
    """The lowest modes from SLEPc (:mod:`mbseig.eigen.slepc`): TOAR with shift-and-invert at 0
    on the same bordered pencil, selected and covered as :func:`companion_search` does."""
    from .slepc import slepc_solve

    if band is not None or omega_t != 0.0:
        raise SolverError("solver 'partial-slepc' computes the lowest modes (n_modes, target 0); "
                          "for a band or a target use partial-companion")
    Mb, Pb, Qb = run.Mb, run.Pb, run.Qb
    scale = run.w_scale
    nev = 2 * want + 1
    while True:
        if nev > run.limit:
            raise SolverError(f"{want} modes asked of a problem with {run.dof} degrees of "
                              f"freedom: use the dense path")
        s_all, X_up, info = slepc_solve(Mb, Pb, Qb, nev, 0.0, ncv=run.ncv, upper_tol=UPPER_TOL)
        upper = info.pop("columns")  # X_up holds the vectors of the upper half-plane only
        if not (np.all(np.isfinite(s_all)) and np.all(np.isfinite(X_up))):
            raise SolverError("partial-slepc returned non-finite eigenpairs (is T(0) = Q "
                              "singular? a rigid-body mode: use partial-companion)")
        # SLEPc guarantees the nev nearest to the target; pairs it converged beyond them are
        # not, so the disc |s| ≤ reach that is known complete ends at the nev-th
        reach = (float(np.sort(np.abs(s_all))[min(nev, s_all.size) - 1]) if s_all.size
                 else 0.0)
        disc = (0.0 + 0.0j, 1.0 / reach if reach > 0 else np.inf, False)
        tol = UPPER_TOL * np.maximum(np.abs(s_all), 1e-300)
        slot = slots(s_all[upper], X_up, cluster_tol(scale))
        first = np.flatnonzero(slot == np.arange(slot.size))
        idx, d, note = pick(np.abs(s_all[upper[first]]), want, 0.0, None, scale)
        idx = np.flatnonzero(np.isin(slot, first[idx]))
        lo, hi = 0.0, d
        ok = first.size > want and covered(annulus_points(lo, hi), [disc])
        if ok or nev >= run.limit:
            break
        nev = min(2 * nev, run.limit)
    cols, conj, s_out = with_partners(upper[idx], s_all, tol)
    # the measured columns only (row-major, for the measures' blocks of rows), each partner
    # marked: the checks run once per conjugate pair and expand to every pair at the end
    X = expand_pairs(np.asarray(X_up, complex), np.searchsorted(upper, cols[~conj]),
                     np.zeros(int(np.sum(~conj)), bool))
    del X_up
    return {"s": s_out, "X": X, "partner": conj, "k": nev, "shifts": [0.0],
            "coverage": {"measure": "|s|", "omega_n": (lo, hi), "note": note, "verified": ok},
            "slepc": info}
