"""Whirl of a mode of a spinning rotor (the 3-D case format, "Whirl of a mode"; docs/spatial.md).

A mode s = −δ + iω (ω ≥ 0) with full-coordinate shape x moves a station P (r_P = C q + d) along
X e^{st}, X = C x[idx].  In the plane normal to the spin axis a (unit, at the equilibrium),
with (e₁, e₂, a) right-handed and X₁ = e₁·X, X₂ = e₂·X, the orbit is the sum of a circle turning
counterclockwise about a (forward for Ω > 0) of radius r_f = |X₁ + iX₂|/2 and one turning
clockwise of radius r_b = |X₁ − iX₂|/2; its semi-axes are r_f + r_b and |r_f − r_b|, and

    κ = σ (r_f − r_b) / (r_f + r_b) ∈ [−1, 1],    σ = sign Ω (+1 for Ω = 0)

is ROSS's signed ratio of minor to major axis: κ > 0 turns with the spin, κ < 0 against it,
|κ| = 1 is a circle and κ = 0 a straight line.  The stations are the rotor body's centre of mass
and every point where a joint, bushing or spring acts on that body (``Rotor.stations``), and
every node of a spinning beam (``SpinningShaft.stations``, casefile.flexible3d).

Whirl of the mode: ``none`` when the mode hardly moves the rotor laterally: its lateral
fraction (below) is at most ``NONE_FRACTION`` = 0.1 (axial and torsional modes); otherwise the
stations whose orbit
turns (|κ| > ``line_tol``) decide: ``forward`` when all turn with the spin, ``backward`` when
all turn against it, ``mixed`` when they disagree (ROSS's convention) — and ``mixed`` too when
every orbit is a straight line (a planar mode, the sum of equal forward and backward whirls,
e.g. the cylindrical modes of a symmetric rotor on anisotropic bearings; ROSS names these by the
sign of a rounding residue).

Lateral fraction.  The motion of a rotor splits into lateral motion (station translations
normal to a, and tilts: node rotations θ normal to a, times the model's length scale ℓ) and
motion along and about the axis (axial translation a·X, twist ℓ a·θ); the node rotations come
from the frame's unit vectors, θ = ½ Σᵢ eᵢ × δeᵢ.  The fraction is
‖lateral‖ / ‖whole motion‖ (2-norms over every station and node of every rotor).  A bending
mode has a fraction of order 1 (≥ 0.9999998 for every bending mode of the shared overhung rotor's
12-element mesh, examples/overhung_rotor.toml); a torsional or axial mode of a straight shaft
has none, except through the static sag under gravity, which couples it to lateral motion in
proportion to the sag's slope (3.1e-4 for the torsion mode, 1.9e-3–7.6e-3 for the axial modes
of that rotor).  An orbit of a tenth of the motion carries 1 % of the mode's kinetic energy in
lateral motion: below that it is coupling, not whirl, and its 1x crossing is no critical
speed.  The threshold 0.1 lies a decade below the bending modes and 13x above the largest
coupling of that example.
"""

from __future__ import annotations

import numpy as np

from .spatial_forces import Rotor
from .spatial_joints import normal_pair

__all__ = ["NONE_FRACTION", "WHIRLS", "lateral_fraction", "lateral_fractions", "rotors",
           "station_orbits", "whirl", "whirls", "rotor_geometry"]

WHIRLS = ("forward", "backward", "mixed", "none")
NONE_FRACTION = 0.1  # whirl "none" at or below this lateral fraction (module docstring)


def rotors(model) -> list:
    """The rotor elements of a model, then its spinning 3-D beams
    (:class:`mbseig.model.beam3d.SpinningShaft`: the same fields) (empty without either)."""
    shafts = (model.flexible or {}).get("shafts", ())
    return [f for f in getattr(model, "forces", ()) if isinstance(f, Rotor)] + list(shafts)


def rotor_geometry(model, q0) -> list:
    """Per rotor at the equilibrium q0, what every mode's whirl reads: (rotor, unit axis a, the
    normal pair e₁, e₂, σ = sign Ω, the frames' unit vectors E (node, vector, xyz) and the
    offsets of their triads in the frame's values).  Formed once for all the modes of a point
    (:func:`whirls`)."""
    out = []
    for r in rotors(model):
        a = r.axis_map()(q0)
        a = a / np.linalg.norm(a)
        e1, e2 = normal_pair(a)
        F0 = np.asarray(r.frame(q0))  # [r; u; v; w] then the triads [u; v; w] of further nodes
        starts = [3, *range(12, len(F0), 9)]
        E = np.stack([F0[k:k + 9] for k in starts]).reshape(-1, 3, 3)
        out.append((r, a, e1, e2, -1.0 if r.speed < 0 else 1.0, E, starts))
    return out


def station_orbits(model, q0, shape, s=1j, *, geometry=None) -> list[dict]:
    """Per rotor station: ``rotor``, ``station``, ``kappa``, ``lateral`` (orbit size |X₁|+|X₂|
    in the plane normal to the axis) and ``amplitude`` (|X|, axial motion included), for the
    mode shape ``shape`` (full coordinates) of eigenvalue ``s`` (a shape of Im s < 0 is taken
    as its conjugate, so that the orbit's sense is that of e^{st} with ω > 0).  ``geometry``:
    :func:`rotor_geometry` at q0, where the caller has it."""
    x = np.asarray(shape, complex)
    if complex(s).imag < 0:
        x = x.conj()
    out = []
    for r, _, e1, e2, sigma, _, _ in (geometry or rotor_geometry(model, q0)):
        smap = r.station_map  # a spinning beam: (idx, sparse rows) of all
        if smap is None:                         # its stations, its nodes' coordinates
            frame = r.frame.C @ x[r.frame.idx]
            body_motion = float(model.length_scale * np.max(np.abs(frame[3:]), initial=0.0))
            X_all = None
        else:
            body_motion = float(model.length_scale * np.max(np.abs(x[r.motion_idx]), initial=0.0))
            X_all = (smap[1] @ x[smap[0]]).reshape(-1, 3)
        for j, (label, aff) in enumerate(r.stations):
            X = aff.C @ x[aff.idx] if X_all is None else X_all[j]
            X1, X2 = e1 @ X, e2 @ X
            rf, rb = abs(X1 + 1j * X2) / 2, abs(X1 - 1j * X2) / 2
            out.append({"rotor": r.name, "station": label,
                        "kappa": sigma * (rf - rb) / (rf + rb) if rf + rb > 0 else 0.0,
                        "lateral": float(abs(X1) + abs(X2)),
                        "amplitude": float(np.linalg.norm(X)),
                        "body_motion": body_motion})
    return out


def lateral_fraction(model, q0, shape, *, geometry=None) -> float:
    """‖lateral motion‖ / ‖whole motion‖ of the rotors in a mode (module docstring); 0 for a
    mode that does not move them (and without rotor).  ``geometry``: as in
    :func:`station_orbits`.  :func:`lateral_fractions` of one mode."""
    x = np.asarray(shape, complex).reshape(-1, 1)
    return float(lateral_fractions(model, q0, x, geometry=geometry)[0])


def lateral_fractions(model, q0, shapes, *, geometry=None) -> np.ndarray:
    """:func:`lateral_fraction` of every column of ``shapes`` (full coordinates), at once."""
    X_all = np.asarray(shapes, complex)
    K = X_all.shape[1]
    lat2, tot2 = np.zeros(K), np.zeros(K)
    for r, a, _, _, _, E, starts in (geometry or rotor_geometry(model, q0)):
        ell = float(model.length_scale)
        smap = r.station_map
        if smap is None:
            X = np.stack([aff.C @ X_all[aff.idx] for _, aff in r.stations])  # (station, xyz, mode)
        else:
            X = (smap[1] @ X_all[smap[0]]).reshape(-1, 3, K)
        ax = np.einsum("sim,i->sm", X, a)
        lat2 += np.sum(np.abs(X - ax[:, None, :] * a[None, :, None]) ** 2, axis=(0, 1))
        tot2 += np.sum(np.abs(X) ** 2, axis=(0, 1))
        dF = r.frame.C @ X_all[r.frame.idx]  # the frames' motion, triads as in E
        dE = np.stack([dF[k:k + 9] for k in starts]).reshape(-1, 3, 3, K)
        # every node's rotation θ = ½ Σᵢ eᵢ × δeᵢ in every mode: (node, xyz, mode)
        th = 0.5 * sum(np.cross(E[:, i, :, None], dE[:, i], axisa=1, axisb=1, axisc=1)
                       for i in range(3))
        tw = np.einsum("nim,i->nm", th, a)
        lat2 += ell ** 2 * np.sum(np.abs(th - tw[:, None, :] * a[None, :, None]) ** 2,
                                  axis=(0, 1))
        tot2 += ell ** 2 * np.sum(np.abs(th) ** 2, axis=(0, 1))
    with np.errstate(invalid="ignore", divide="ignore"):
        return np.where(tot2 > 0, np.sqrt(lat2 / np.where(tot2 > 0, tot2, 1.0)), 0.0)


def whirls(model, q0, shapes, eigenvalues, **options) -> list:
    """:func:`whirl` of every mode (the columns of ``shapes``, full coordinates, with their
    eigenvalues), the rotors' geometry at q0 formed once."""
    geometry = rotor_geometry(model, q0)
    if not geometry:  # (no rotor: no whirl)
        return [None] * shapes.shape[1]
    fractions = lateral_fractions(model, q0, shapes, geometry=geometry)
    return _whirls(model, shapes, np.asarray(eigenvalues, complex), geometry, fractions,
                   **options)


def _whirls(model, shapes, s, geometry, fractions, *, line_tol: float = 1e-6,
            none_tol: float = 1e-6, none_fraction: float = NONE_FRACTION):
    """:func:`whirl` of every mode at once: the orbits of :func:`station_orbits` as arrays
    (station, mode) and the same rules, mode by mode."""
    X = np.array(shapes, complex)
    X[:, s.imag < 0] = X[:, s.imag < 0].conj()
    K = X.shape[1]
    ell = float(model.length_scale)
    kap, lat, amp, body = [], [], [], []
    for r, _, e1, e2, sigma, _, _ in geometry:
        smap = r.station_map
        if smap is None:
            frame = r.frame.C @ X[r.frame.idx]
            motion = ell * (np.max(np.abs(frame[3:]), axis=0) if frame.shape[0] > 3
                            else np.zeros(K))
            Xs = (np.stack([aff.C @ X[aff.idx] for _, aff in r.stations])
                  if r.stations else np.zeros((0, 3, K)))
        else:
            mi = r.motion_idx
            motion = ell * (np.max(np.abs(X[mi]), axis=0) if len(mi) else np.zeros(K))
            Xs = (smap[1] @ X[smap[0]]).reshape(-1, 3, K)
        X1, X2 = np.einsum("i,sim->sm", e1, Xs), np.einsum("i,sim->sm", e2, Xs)
        rf, rb = np.abs(X1 + 1j * X2) / 2, np.abs(X1 - 1j * X2) / 2
        tot = rf + rb
        with np.errstate(invalid="ignore", divide="ignore"):
            kap.append(np.where(tot > 0, sigma * (rf - rb) / np.where(tot > 0, tot, 1.0), 0.0))
        lat.append(np.abs(X1) + np.abs(X2))
        amp.append(np.sqrt(np.sum(np.abs(Xs) ** 2, axis=1)))
        body.append(np.broadcast_to(motion, (Xs.shape[0], K)))
    kap, lat, amp, body = (np.concatenate(a) for a in (kap, lat, amp, body))
    if kap.shape[0] == 0:
        return [None] * K
    lateral = lat.max(axis=0)
    ref = np.maximum(amp.max(axis=0), body.max(axis=0))
    out = []
    for k in range(K):
        if ref[k] == 0 or lateral[k] <= none_tol * ref[k] or fractions[k] <= none_fraction:
            out.append("none")
        elif abs(s[k].imag) <= line_tol * abs(s[k]):
            out.append("mixed")  # a real eigenvalue: the orbit does not turn
        else:
            keep = (lat[:, k] > none_tol * lateral[k]) & (np.abs(kap[:, k]) > line_tol)
            senses = set(np.sign(kap[keep, k]).tolist())
            out.append("forward" if senses == {1.0} else "backward" if senses == {-1.0}
                       else "mixed")
    return out


def whirl(model, q0, shape, s=1j, *, line_tol: float = 1e-6, none_tol: float = 1e-6,
          none_fraction: float = NONE_FRACTION, geometry=None, fraction=None):
    """forward / backward / mixed / none for one mode (module docstring); None without rotor.
    ``geometry``: :func:`rotor_geometry` at q0, and ``fraction`` the mode's
    :func:`lateral_fraction`, where the caller has them (:func:`whirls`)."""
    geometry = geometry if geometry is not None else rotor_geometry(model, q0)
    orbits = station_orbits(model, q0, shape, s, geometry=geometry)
    if not orbits:
        return None
    lateral = max(o["lateral"] for o in orbits)
    ref = max(max(o["amplitude"] for o in orbits), max(o["body_motion"] for o in orbits))
    if fraction is None and not (ref == 0 or lateral <= none_tol * ref):
        fraction = lateral_fraction(model, q0, shape, geometry=geometry)
    if ref == 0 or lateral <= none_tol * ref or fraction <= none_fraction:
        return "none"
    if abs(complex(s).imag) <= line_tol * abs(complex(s)):
        return "mixed"  # a real eigenvalue: the orbit does not turn
    senses = {np.sign(o["kappa"]) for o in orbits
              if o["lateral"] > none_tol * lateral and abs(o["kappa"]) > line_tol}
    if senses == {1.0}:
        return "forward"
    if senses == {-1.0}:
        return "backward"
    return "mixed"
