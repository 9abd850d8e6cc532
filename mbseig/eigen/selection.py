"""Which modes a partial search keeps (:mod:`mbseig.eigen.partial`): coverage of the region the
ranking selects from, duplicates between shifts, conjugate partners, clusters never cut in half."""

from __future__ import annotations

import numpy as np

TARGET_ANGLES = ((0.5, 0.0, 1.0), (0.25, 0.75))  # × π: shifts on |s| = ω_t, the second set


def shift_nu(points, sigma, real_part):
    """|ν| of the shift-invert operator at the points (see :func:`companion_partial`)."""
    with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
        if real_part:
            nu = np.abs(0.5 * (1 / (points - sigma) + 1 / (points - np.conj(sigma))))
        else:
            nu = np.abs(1 / (points - sigma))
    return np.where(np.isfinite(nu), nu, np.inf)  # at the shift itself: found for sure


def dedupe(values, X, rtol, floor):
    """Indices of the eigenpairs to keep when several shifts found the same one: a pair is
    dropped when its value equals kept ones (|Δ| ≤ rtol·max(|s|, floor)) and its vector lies in
    their span (an independent vector of a repeated eigenvalue is kept)."""
    keep = []
    for i in range(values.size):
        if keep:
            kv = values[keep]
            dup = np.flatnonzero(np.abs(kv - values[i]) <= rtol * max(abs(values[i]), floor))
        else:
            dup = np.zeros(0, int)
        if dup.size:
            B = np.linalg.qr(X[:, np.asarray(keep)[dup]])[0]
            v = X[:, i] / max(np.linalg.norm(X[:, i]), np.finfo(float).tiny)
            if np.linalg.norm(v - B @ (B.conj().T @ v)) <= 1e-6:
                continue
        keep.append(i)
    return np.array(keep, int)


def covered(points, runs, margin=1e-9):
    """Every point (complex) where some run would have found an eigenvalue (|ν| > ν_min)?"""
    if not runs:
        return False
    hit = np.zeros(points.size, bool)
    for sigma, nu_min, real_part in runs:
        hit |= shift_nu(points, sigma, real_part) > nu_min * (1 + margin)
    return bool(np.all(hit))


def annulus_points(lo, hi, n_angle=73, n_radius=5):
    """Sample points of {lo ≤ |s| ≤ hi, Im s ≥ 0} (boundary and interior)."""
    th = np.linspace(0.0, np.pi, n_angle)
    rad = np.linspace(max(lo, 0.0), hi, n_radius)
    pts = (rad[:, None] * np.exp(1j * th[None, :])).ravel()
    return pts if lo > 0 else np.concatenate([pts, [0.0]])


def partner_columns(s, X):
    """src[j] = i < j where pair j is exactly the conjugate of pair i (s_j = s̄_i, x_j = x̄_i, as
    the searches build the partners), else j."""
    src = np.arange(s.size)
    taken = np.zeros(s.size, bool)
    for j in range(s.size):
        if s[j].imag == 0:
            continue
        for i in np.flatnonzero((s[:j] == np.conj(s[j])) & ~taken[:j]):
            if src[i] == i and np.array_equal(X[:, j], np.conj(X[:, i])):
                src[j] = i
                taken[i] = True
                break
    return src


def with_partners(chosen, s, tol):
    """(columns, conjugated?, eigenvalues): each kept mode of the upper half-plane followed by
    its conjugate partner where |Im s| exceeds its tolerance (exact for real matrices)."""
    cols, conj = [], []
    for i in chosen:
        cols.append(i)
        conj.append(False)
        if abs(s[i].imag) > tol[i]:
            cols.append(i)
            conj.append(True)
    cols, conj = np.array(cols, int), np.array(conj, bool)
    s_out = np.where(conj, np.conj(s[cols]), s[cols]) if cols.size else np.zeros(0, complex)
    return cols, conj, s_out


# ---------------------------------------------------------------------------------------------
# the searches: shifts, coverage, selection
# ---------------------------------------------------------------------------------------------
def cluster_tol(scale):
    return 1e-8 * scale


def slots(s, X, tie):
    """Slot label per eigenvalue: members of a defective cluster (equal within ``tie``, parallel
    vectors: the two halves of a rigid-body double zero, a Jordan block) share one mode slot."""
    slot = np.arange(s.size)
    for i in range(s.size):
        for j in range(i):
            if slot[j] == j and abs(s[i] - s[j]) <= tie:
                a, b = X[:, i], X[:, j]
                cos = abs(np.vdot(a, b)) / max(np.linalg.norm(a) * np.linalg.norm(b), 1e-300)
                if cos >= 1 - 1e-6:
                    slot[i] = j
                    break
    return slot


def pick(measure, count, omega_t, band, scale):
    """Indices of the modes to keep: inside the band, or the ``count`` nearest ω_t in the
    measure, extended by every mode of the same measure as the last (a repeated eigenvalue);
    returns (indices, distance d of the last kept, extension note)."""
    if band is not None:
        keep = np.flatnonzero((measure >= band[0]) & (measure <= band[1]))
        return keep, None, ""
    key = np.abs(measure - omega_t)
    order = np.argsort(key, kind="stable")
    if order.size == 0:
        return order, 0.0, ""
    head = order[:count]
    d = float(key[head[-1]]) if head.size else 0.0
    tie = cluster_tol(max(float(measure[head[-1]]) if head.size else 0.0, scale))
    extra = order[count:][key[order[count:]] <= d + tie]
    note = ""
    if extra.size:
        note = (f"n_modes = {count} extended to {count + extra.size}: the mode at ω_n = "
                f"{float(measure[head[-1]]):.6g} rad/s is repeated (its {1 + extra.size} members "
                f"are listed together)")
    return np.concatenate([head, extra]), d + tie, note
