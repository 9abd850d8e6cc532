"""Synchronous unbalance response of a spinning rotor (DESIGN §8, flexible rotors; docs/beams3d.md).

An unbalance m·e at a point P (a beam station ``"BEAM.NAME"``, a body — its centre of mass —,
any point of the case) spinning at Ω about the axis a exerts the rotating force

    F(t) = m e Ω² (cos(Ωt + φ) e₁ + sin(Ωt + φ) e₂) = Re(F̂ e^{iΩt}),   F̂ = m e Ω² e^{iφ} (e₁ − i e₂)

((e₁, e₂, a) right-handed, φ the unbalance's angle from e₁ at t = 0).  About the equilibrium at
that speed the reduced linear model M ẍ + P ẋ + Q x = Nᵀ C_Pᵀ F gives the steady response
x̂ = (Q − Ω² M + iΩ P)⁻¹ Nᵀ C_Pᵀ F̂; every station S of the case's rotors moves along
Re(X̂ e^{iΩt}), X̂ = C_S N x̂, reported as the amplitude and phase of its two lateral components
(along e₁, e₂: x₁(t) = |X₁| cos(Ωt + ∠X₁)) and the orbit's major semi-axis r_f + r_b (forward
and backward circles, as for the whirl); every named output y = C [x; ẋ] of ``[[outputs]]``
likewise, Ŷ = C [x̂; iΩ x̂].  Ω is the rotor speed of the model at each swept value (the first
rotor's ``speed``), so the swept parameter may be any quantity the speed depends on.

For the Jeffcott rotor (a disk m on an isotropic support k, c at its centre of mass)
X₁ = m e Ω² e^{iφ} / (k − m Ω² + i c Ω), X₂ = −i X₁ (tests/test_unbalance.py).

At Ω = 0 the force vanishes and the response is exactly 0 (no solve: Z = Q is singular for a
rotor free to turn).  Elsewhere Z may be singular: at an undamped critical speed on the grid
(a resonance when the unbalance drives that mode: no steady response, every amplitude NaN,
``null`` with ``"resonance": true`` in the JSON) or along a mode it does not load (the rigid
rotor's axial mode at √(kx/m): the finite response).  Both are decided by
:func:`mbseig.studies.harmonic.solve_harmonic` from the singular values of Z with stated bounds;
each speed's decision, σ_min/w, backward error and error bound are in ``solves`` (JSON
``"solve"``).
"""

from __future__ import annotations

import math
import re
from dataclasses import dataclass

import numpy as np
import scipy.sparse as sp

from ..eigen.structure import fro
from ..errors import CaseError, MbseigError
from ..linear import linearize
from ..model.spatial_joints import normal_pair
from ..model.spatial_whirl import rotors
from ..numerics import jsonable
from ..statics import equilibrium, solved
from .harmonic import Harmonic, accuracy, solve_harmonic, weight
from .point import as_spec

__all__ = ["UnbalanceResponse", "unbalance_response", "unbalance_point", "require_rotor",
           "station_names", "spinning_beams", "UNITS"]

UNITS = {"speed": "rad/s", "amplitude": "m", "phase": "deg", "unbalance": "kg m",
         "angle": "deg"}


@dataclass(frozen=True, eq=False)
class UnbalanceResponse:
    """Response per speed (rows) and station (columns): complex lateral amplitudes along e₁ and
    e₂ [m] (``X1``, ``X2``), the orbit major semi-axis [m] (``major``); per named output its
    complex amplitude ``Y`` (rows: speeds) in ``output_units``; ``speeds`` Ω [rad/s] at each
    ``values`` of ``parameter``; ``unbalance`` m·e [kg m] at ``at``, ``angle`` φ [rad]."""

    case: str
    parameter: str
    values: np.ndarray
    speeds: np.ndarray
    stations: tuple
    X1: np.ndarray
    X2: np.ndarray
    unbalance: float
    at: str
    angle: float = 0.0
    outputs: tuple = ()
    output_units: tuple = ()
    Y: np.ndarray = None
    directions: dict = None
    source: str = ""
    solves: tuple = ()

    @property
    def resonance(self) -> np.ndarray:
        """Per speed: a resonance (the unbalance drives an undamped mode at its own frequency:
        no steady response; every amplitude NaN, null in the JSON)."""
        return np.array([s is not None and s.resonance for s in self.solves]
                        if len(self.solves) == len(self.speeds) else [False] * len(self.speeds),
                        bool)

    def resonance_values(self) -> list:
        """The swept values where the response is a resonance."""
        return [float(v) for v, r in zip(self.values, self.resonance, strict=True) if r]

    @property
    def major(self) -> np.ndarray:
        rf = np.abs(self.X1 + 1j * self.X2) / 2
        rb = np.abs(self.X1 - 1j * self.X2) / 2
        return rf + rb

    def to_json(self) -> dict:
        def deg(z):
            return [float(x) for x in np.degrees(np.angle(z))]

        rows = [{"station": st,
                 "amplitude_1": [float(x) for x in np.abs(self.X1[:, j])],
                 "phase_1": deg(self.X1[:, j]),
                 "amplitude_2": [float(x) for x in np.abs(self.X2[:, j])],
                 "phase_2": deg(self.X2[:, j]),
                 "major": [float(x) for x in self.major[:, j]]}
                for j, st in enumerate(self.stations)]
        outs = [{"output": name, "unit": unit,
                 "amplitude": [float(x) for x in np.abs(self.Y[:, j])],
                 "phase": deg(self.Y[:, j])}
                for j, (name, unit) in enumerate(zip(self.outputs, self.output_units, strict=True))]
        return jsonable({"case": self.case, "parameter": self.parameter,
                         "values": [float(v) for v in self.values],
                         "speed": [float(v) for v in self.speeds],
                         "unbalance": {"at": self.at, "m_e": self.unbalance,
                                       "angle": math.degrees(self.angle)},
                         "directions": self.directions or {}, "units": UNITS,
                         "resonance": [bool(r) for r in self.resonance],
                         "solve": [None if s is None else s.to_json() for s in self.solves],
                         "stations": rows, "outputs": outs})

    def rows(self):
        """(value, Ω, name, complex amplitudes (X₁, X₂) or (Y, None), major or |Y|, unit) per
        speed and station, then per speed and output."""
        major = self.major
        for j, st in enumerate(self.stations):
            for k in range(len(self.speeds)):
                yield (self.values[k], self.speeds[k], st, self.X1[k, j], self.X2[k, j],
                       major[k, j], "m")
        for j, (name, unit) in enumerate(zip(self.outputs, self.output_units, strict=True)):
            for k in range(len(self.speeds)):
                yield (self.values[k], self.speeds[k], name, self.Y[k, j], None,
                       abs(self.Y[k, j]), unit)

    def peaks(self) -> list:
        """Per station and output, the row of :meth:`rows` of its largest amplitude."""
        best = {}
        for row in self.rows():
            if np.isfinite(row[5]) and (row[2] not in best or row[5] > best[row[2]][5]):
                best[row[2]] = row
        return list(best.values())

    def table(self) -> str:
        """A text table: speed, then the major semi-axis at every station."""
        head = ["speed [rad/s]"] + [f"{s} [m]" for s in self.stations]
        lines = ["  ".join(f"{h:>16s}" for h in head)]
        for k, w in enumerate(self.speeds):
            lines.append("  ".join([f"{w:16.6g}"] + [_amplitude_text(x, 16, ".6e")
                                                      for x in self.major[k]]))
        return "\n".join(lines)

    def listing(self, unit=None) -> str:
        """A text table, one line a speed and station (then output): the parameter, Ω, the
        amplitude and phase of each lateral component and the orbit's major semi-axis (for an
        output: its amplitude and phase).  ``unit``: the parameter's unit for its header."""
        p = f"{self.parameter} [{unit}]" if unit and unit != "1" else self.parameter
        same = np.array_equal(np.asarray(self.values, float), np.asarray(self.speeds, float))
        head = [f"{p:>14s}"] + ([] if same else [f"{'Omega [rad/s]':>14s}"]) + [
                f"{'station/output':<28s}",
                f"{'|X1|':>12s}", f"{'phase X1 [deg]':>14s}", f"{'|X2|':>12s}",
                f"{'phase X2 [deg]':>14s}", f"{'major':>12s}", "unit"]
        lines = ["  ".join(head)]
        for v, w, name, a, b, big, u in self.rows():
            second = (["–".rjust(12), "–".rjust(14)] if b is None else
                      [_amplitude_text(abs(b), 12), _phase_text(b)])
            lines.append("  ".join([f"{v:14.6g}"] + ([] if same else [f"{w:14.6g}"])
                                   + [f"{name:<28s}", _amplitude_text(abs(a), 12),
                                      _phase_text(a)]
                                   + second + [_amplitude_text(big, 12), u or "–"]))
        return "\n".join(lines)

    def write_csv(self, path):
        """The table as CSV (complex amplitudes as amplitude and phase in degrees)."""
        import csv

        with open(path, "w", newline="") as fh:
            w = csv.writer(fh)
            w.writerow([self.parameter, "Omega_rad_s", "station", "amplitude_1", "phase_1_deg",
                         "amplitude_2", "phase_2_deg", "major", "unit", "resonance"])
            res = {float(v) for v in self.resonance_values()}
            for v, om, name, a, b, big, u in self.rows():
                w.writerow([repr(float(v)), repr(float(om)), name, _cell(abs(a)), _cell(_deg(a)),
                            "" if b is None else _cell(abs(b)),
                            "" if b is None else _cell(_deg(b)), _cell(big), u or "",
                            "true" if float(v) in res else "false"])
        return path


def _cell(x) -> str:
    """A CSV number; empty where it is not finite (a resonance: no steady response)."""
    return repr(float(x)) if np.isfinite(x) else ""


def _amplitude_text(x, width, spec=".5e") -> str:
    """An amplitude, or "resonance" where it is not finite (no steady response)."""
    return format(x, f"{width}{spec}") if np.isfinite(x) else "resonance".rjust(width)


def _deg(z) -> float:
    return float(np.degrees(np.angle(z)))


def _phase_text(z) -> str:
    """The phase in degrees, "–" where the amplitude is 0 (Ω = 0: no force, no phase); as
    printed (3 decimals) −0.000 reads 0.000 and −180.000 reads 180.000 (the same angle: the sign
    was rounding's, the solve's phase error being ~1e-9 degrees)."""
    if z == 0 or not np.isfinite(z):
        return "–".rjust(14)
    text = f"{_deg(z):.3f}"
    text = {"-0.000": "0.000", "-180.000": "180.000"}.get(text, text)
    return text.rjust(14)


def _map_key(aff):
    """A canonical key of an affine point map r = C q[idx] + d (columns sorted and summed, zero
    columns dropped), so two maps of the same point compare equal however they were built."""
    idx = np.asarray(aff.idx, int)
    C = np.asarray(aff.C.toarray() if sp.issparse(aff.C) else aff.C, float)
    cols = {}
    for j, i in enumerate(idx):
        cols[int(i)] = cols.get(int(i), 0.0) + C[:, j]
    keep = sorted(i for i, c in cols.items() if np.any(c != 0))
    return (tuple(keep), np.array([cols[i] for i in keep]).tobytes(),
            np.asarray(getattr(aff, "d", 0.0), float).tobytes())


def station_names(model, rs):
    """Readable names of the rotors' stations: a rotor's as ``BODY: label``; a beam node as the
    case's name of that point (a basic point, ``BEAM.STATION``), else its station label
    (``BEAM at s = 0.25 m``), never its node index."""
    by_map = {}
    for name, aff in model.points.items():
        key = _map_key(aff)
        auto = re.search(r"\.n\d+$", name) is not None
        if key not in by_map or (by_map[key][1] and not auto):
            by_map[key] = (name, auto)
    out = []
    for r in rs:
        for label, aff in r.stations:
            if r.body:  # a rigid rotor on its body (a spinning beam has none)
                out.append((f"{r.body}: {label}", aff))
                continue
            name, auto = by_map.get(_map_key(aff), (label, True))
            out.append((label if auto else name, aff))  # never a node index (BEAM.nK)
    seen, unique = set(), []
    for name, aff in out:  # a point named twice (a rotor's station on a beam node) listed once
        if name not in seen:
            seen.add(name)
            unique.append((name, aff))
    return unique


def unbalance_point(model, at):
    """The affine map of the point where the unbalance acts: a point of the case (a basic
    point, ``BEAM.STATION``, ``BEAM.nK``) or a body name (its centre of mass); a
    :class:`CaseError` naming ``--at`` otherwise."""
    if isinstance(at, str) and at in model.points:
        return model.points[at]
    body = model.bodies.get(at) if isinstance(at, str) else None
    markers = list((body or {}).get("markers") or ())
    if markers and markers[0] in model.points:
        return model.points[markers[0]]
    stations = [n for n in model.points if "." in n and not re.search(r"\.(n?\d+)$", n)]
    known = ", ".join(sorted(set(stations) | set(model.bodies))[:12]) or "none"
    raise CaseError(f"unknown point, station or body {at!r} for the unbalance (stations and "
                    f"bodies: {known})", element="--at", file=model.source)


def spinning_beams(case) -> bool:
    """Whether the case has a beam with ``spin`` (a rotor at every non-zero speed)."""
    beams = (getattr(case, "data", None) or {}).get("beams") or []
    return any(isinstance(b, dict) and b.get("spin") is not None for b in beams)


def require_rotor(model, case=None):
    """The model's rotors (rotor elements, spinning beams), or a one-line :class:`CaseError`
    (an empty list for a case whose beams spin, at rest)."""
    rs = rotors(model)
    if not rs and not (case is not None and spinning_beams(case)):
        raise CaseError("the case has no spinning rotor (a [[forces]] rotor element or a beam "
                        "with spin): no unbalance response", element="unbalance",
                        file=model.source)
    return rs


def unbalance_response(case, parameter, values, *, at, unbalance, phase=0.0, config=None,
                       fixed=None) -> UnbalanceResponse:
    """Synchronous response to the unbalance ``unbalance`` = m·e [kg m] at the point ``at`` (at
    the angle ``phase`` [rad] from e₁) over ``parameter`` = ``values`` (module docstring)."""
    spec = as_spec(case)
    values = np.asarray(values, float)
    speeds, per_speed, Ys, solves = [], [], [], []
    lin = directions = None
    for v in values:
        model = spec.build(config, **{**(fixed or {}), parameter: float(v)})
        spinning = require_rotor(model, spec)
        P = unbalance_point(model, at)
        if not spinning:  # a spinning beam at rest: no force, no response
            speeds.append(0.0)
            per_speed.append({})
            Ys.append(None)
            solves.append(None)
            continue
        try:
            eq = equilibrium(model)
            model = solved(model, eq)
            rs = rotors(model)
            lin = linearize(model, eq)
        except MbseigError as exc:
            raise exc.located(file=spec.source, element=f"{parameter} = {v:g}") from None
        if lin.constraint_jacobian is not None:
            raise CaseError("unbalance response needs the dense reduced model (a smaller case)",
                            element="unbalance", file=spec.source)
        W = float(rs[0].speed)
        axis = rs[0].axis_map()(eq.q)
        axis = axis / np.linalg.norm(axis)
        e1, e2 = normal_pair(axis)
        directions = {"axis": axis.tolist(), "e1": e1.tolist(), "e2": e2.tolist()}
        F = unbalance * W**2 * np.exp(1j * phase) * (e1 - 1j * e2)
        g = np.zeros(model.n, complex)
        np.add.at(g, P.idx, P.C.T @ F)
        sol = _steady(lin, g, W)
        solves.append(sol)
        xr = np.full(lin.dof, np.nan, complex) if sol.x is None else sol.x
        x = lin.N @ xr
        Xs = {name: aff.C @ x[aff.idx] for name, aff in station_names(model, rs)}
        speeds.append(W)
        per_speed.append({name: (e1 @ X, e2 @ X) for name, X in Xs.items()})
        n = lin.dof
        Ys.append(lin.C[:, :n] @ xr + 1j * W * (lin.C[:, n:] @ xr) if lin.C is not None
                  else np.zeros(0, complex))
    # a beam spins (is a rotor) only at a non-zero speed: where a station is missing the
    # response is 0 at Ω = 0 (no unbalance force), else not known (NaN)
    names = tuple(dict.fromkeys(n for d in per_speed for n in d))
    X1 = np.array([[d[n][0] if n in d else (0.0 if w == 0 else np.nan) for n in names]
                   for d, w in zip(per_speed, speeds, strict=True)], complex)
    X2 = np.array([[d[n][1] if n in d else (0.0 if w == 0 else np.nan) for n in names]
                   for d, w in zip(per_speed, speeds, strict=True)], complex)
    if lin is None:
        raise CaseError(f"no speed of the sweep spins the rotor ({parameter} = "
                        f"{values[0]:g} … {values[-1]:g})", element="unbalance",
                        file=spec.source)
    outputs = tuple(lin.output_names) if lin.C is not None else ()
    units = tuple(lin.output_units) if outputs and lin.output_units else ("",) * len(outputs)
    Ys = [np.zeros(len(outputs), complex) if y is None else y for y in Ys]
    return UnbalanceResponse(case=spec.name, parameter=parameter, values=values,
                             speeds=np.array(speeds), stations=names, X1=X1, X2=X2,
                             unbalance=float(unbalance), at=at,
                             angle=float(phase), outputs=outputs, output_units=units,
                             Y=np.array(Ys).reshape(len(values), len(outputs)),
                             directions=directions, source=str(spec.source),
                             solves=tuple(solves))


def _steady(lin, g, W) -> Harmonic:
    """The reduced response x̂ to the full-coordinate force ``g`` at the speed W: 0 at rest
    (the force m e Ω² vanishes: no solve), else :func:`~mbseig.studies.harmonic.solve_harmonic`
    on Z = Q − Ω²M + iΩP (regular, singular and not excited, or a resonance)."""
    if W == 0:
        return Harmonic(np.zeros(lin.dof, complex), "rest", 0.0, accuracy(lin.N.shape[0]),
                        0.0, 0, 0.0)
    f = lin.N.T @ g
    M, P, Q = (A.toarray() if sp.issparse(A) else np.asarray(A, float)
               for A in (lin.M, lin.P, lin.Q))
    Z = Q - W**2 * M + 1j * W * P
    return solve_harmonic(Z, f, weight((fro(M), fro(P), fro(Q)), W), n=lin.N.shape[0])
