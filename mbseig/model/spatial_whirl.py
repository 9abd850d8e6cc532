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

Whirl of the mode: ``none`` when no station moves laterally (lateral amplitude ≤ ``none_tol``
times the body's largest motion: axial and torsional modes); otherwise the stations whose orbit
turns (|κ| > ``line_tol``) decide: ``forward`` when all turn with the spin, ``backward`` when
all turn against it, ``mixed`` when they disagree (ROSS's convention) — and ``mixed`` too when
every orbit is a straight line (a planar mode, the sum of equal forward and backward whirls,
e.g. the cylindrical modes of a symmetric rotor on anisotropic bearings; ROSS names these by the
sign of a rounding residue).
"""

from __future__ import annotations

import numpy as np

from .spatial_forces import Rotor
from .spatial_joints import normal_pair

__all__ = ["WHIRLS", "rotors", "station_orbits", "whirl"]

WHIRLS = ("forward", "backward", "mixed", "none")


def rotors(model) -> list:
    """The rotor elements of a model, then its spinning 3-D beams
    (:class:`mbseig.model.beam3d.SpinningShaft`: the same fields) (empty without either)."""
    shafts = (getattr(model, "flexible", None) or {}).get("shafts", ())
    return [f for f in getattr(model, "forces", ()) if isinstance(f, Rotor)] + list(shafts)


def station_orbits(model, q0, shape, s=1j) -> list[dict]:
    """Per rotor station: ``rotor``, ``station``, ``kappa``, ``lateral`` (orbit size |X₁|+|X₂|
    in the plane normal to the axis) and ``amplitude`` (|X|, axial motion included), for the
    mode shape ``shape`` (full coordinates) of eigenvalue ``s`` (a shape of Im s < 0 is taken
    as its conjugate, so that the orbit's sense is that of e^{st} with ω > 0)."""
    x = np.asarray(shape, complex)
    if complex(s).imag < 0:
        x = x.conj()
    out = []
    for r in rotors(model):
        a = r.axis_map()(q0)
        a = a / np.linalg.norm(a)
        e1, e2 = normal_pair(a)
        sigma = -1.0 if r.speed < 0 else 1.0
        smap = getattr(r, "station_map", None)  # a spinning beam: (idx, sparse rows) of all
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


def whirl(model, q0, shape, s=1j, *, line_tol: float = 1e-6, none_tol: float = 1e-6):
    """forward / backward / mixed / none for one mode (module docstring); None without rotor."""
    orbits = station_orbits(model, q0, shape, s)
    if not orbits:
        return None
    lateral = max(o["lateral"] for o in orbits)
    ref = max(max(o["amplitude"] for o in orbits), max(o["body_motion"] for o in orbits))
    if ref == 0 or lateral <= none_tol * ref:
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
