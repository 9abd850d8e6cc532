"""Campbell diagrams of spinning rotors (docs/spatial.md, "Campbell diagrams").

Over a swept parameter p (usually the rotor speed itself), every point is an independent pure
computation (:func:`campbell_point`: load → equilibrium → linearize → listed modes, plus the
whirl of each mode from :func:`mbseig.model.spatial_whirl.whirl`).  Along p:

- the listed eigenvalues (ω ≥ 0) are tracked by MAC (:func:`mbseig.studies.sweep.track_line`);
- per track and point: frequency ω = Im s, whirl (forward / backward / mixed / none),
  logarithmic decrement Λ = 2π δ / ω (δ = −Re s) and stability;
- the excitation line ω = h·|Ω| (h = ``harmonic``, 1 for unbalance; Ω the rotor element's speed
  in rad/s at that point, so the swept parameter may be any quantity Ω depends on);
- critical speeds: wherever ω_j(p) − h|Ω(p)| changes sign between grid points of a track with
  lateral motion (whirl ≠ none, not a rigid-body mode), the crossing is located by Brent's
  method to ``xtol = xtol_rel × span``, each evaluation re-solving the model and following the
  track by MAC.  Each is reported as ``{value, speed, mode, whirl, frequency}``: ``value`` the
  parameter, ``speed`` Ω there [rad/s], ``mode`` the track, ``whirl`` its whirl at the crossing.
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass, field

import numpy as np

from ..errors import CaseError, MbseigError
from ..linear import linearize
from ..modal import modes
from ..model.spatial_whirl import rotors, whirls
from ..numerics import jsonable
from ..statics import equilibrium, solved
from .point import as_spec
from .records import CampbellPoint
from .runners import Runner
from .sweep import mac_matrix, track_line
from .unbalance import spinning_beams

__all__ = ["CampbellResult", "campbell", "campbell_point", "speed_parameter", "spinning_beams",
           "RotorStudy", "rotor_study", "default_unbalance_point", "is_rotor"]


def campbell_point(case, config, params):
    """Listed modes, their whirl and the rotor speed at one parameter point (picklable)."""
    try:
        model = case.build(config, **params)
        eq = equilibrium(model)
        md = modes(linearize(model, eq))
    except MbseigError as exc:
        return CampbellPoint(params=dict(params), error=exc.one_line())
    model = solved(model, eq)
    rs = rotors(model)
    if not rs and not spinning_beams(case):
        return CampbellPoint(params=dict(params), error=f"{model.name}: the model has no rotor")
    # a beam with ``spin`` is a rotor only at a non-zero speed: at rest it has no whirl
    # stations, and its modes no whirl (None: not determined at Ω = 0)
    return CampbellPoint(params=dict(params), error=None, eigenvalues=md.eigenvalues,
                         shapes=md.shapes, tol=md.tolerance, kind=list(md.kind),
                         stability=list(md.stability), speed=float(rs[0].speed) if rs else 0.0,
                         whirl=whirls(model, eq.q, md.shapes, md.eigenvalues))


class SpeedLine:
    """The points of a Campbell sweep from one build (issue "Flexible models as lean as an FE
    code": reuse across a sweep what does not change with the speed).

    Where the swept parameter enters only the beams' spin and the rotors' speed
    (:class:`~mbseig.casefile.speed_update.SpeedUpdate`), the case is built, solved for its
    equilibrium and linearized once; each point takes the model with its speeds replaced
    (equal, element by element, to a full build), the first point's equilibrium (the gyroscopic
    forces vanish at rest, so it is every point's), its null-space basis, its rigid-body
    directions by construction (geometry: the speed moves none), and its reduced mass and
    stiffness (the speeds enter neither: the beams' K leaves out the gyroscopic ∂/∂q, which
    vanishes at rest, and a rotor's force is ∝ q̇); only P = Nᵀ C N is formed again, as
    :func:`mbseig.linearize` forms it, and the modes solved.  A sparse (large) model is
    linearized again whole.  ``reason`` says why a line cannot (then every point is built:
    :func:`campbell_point`)."""

    def __init__(self, spec, config, params, axis):
        from ..casefile.speed_update import SpeedUpdate

        self.spec, self.config, self.axis, self.reason = spec, config, axis, None
        try:
            model0 = spec.build(config, **params)
            self.update = SpeedUpdate(spec.data, config, params, axis, model0)
            self.reason = self.update.reason
            if self.reason is None:
                self.eq = equilibrium(model0)
                if model0.commands:  # inverse statics: settings resolved per value
                    self.reason = "the case has inverse-statics commands"
                else:
                    lin = linearize(model0, self.eq, signals=False)
                    self.lin0 = lin
                    self.basis = (lin.N, lin.rank, lin.independent,
                                  lin.tolerances.get("basis_min_cosine"))
                    self.rigid, self.sparse = lin.rigid, lin.constraint_jacobian is not None
                    self.display = lin.display  # the names of the coordinates: one geometry
        except MbseigError as exc:  # the points report it, each as its full build does
            self.reason = exc.one_line()

    def point(self, params):
        """:func:`campbell_point` at ``params`` (the same record)."""
        try:
            model = self.update.make(params[self.axis])
            if self.sparse:
                eq = dataclasses.replace(self.eq, model=model)  # this value's model at rest
                lin = linearize(model, eq, signals=False)
            else:  # only the damping changes: P = Nᵀ C N as linearize forms it, M and Q kept
                _, C = model.force_jacobians(self.eq.q, dense=True)
                N = self.lin0.N
                P = C if model.n_constraints == 0 else N.T @ C @ N
                lin = dataclasses.replace(self.lin0, P=P, parameters=model.parameters)
            md = modes(lin, rigid=self.rigid, display=self.display)
        except MbseigError as exc:
            return CampbellPoint(params=dict(params), error=exc.one_line())
        rs = rotors(model)
        return CampbellPoint(params=dict(params), error=None, eigenvalues=md.eigenvalues,
                             shapes=md.shapes, tol=md.tolerance, kind=list(md.kind),
                             stability=list(md.stability),
                             speed=float(rs[0].speed) if rs else 0.0,
                             whirl=whirls(model, self.eq.q, md.shapes, md.eigenvalues))


def speed_parameter(case, name, values, *, config=None, fixed=None) -> bool:
    """Whether parameter ``name`` sets the speed of a rotor of the case (the rotor speed
    differs between the first and last value)."""
    spec = as_spec(case)
    speeds, spinning = [], spinning_beams(spec)
    for v in (values[0], values[-1]):
        rs = rotors(spec.build(config, **{**(fixed or {}), name: float(v)}))
        if not rs and not spinning:
            return False
        speeds.append(rs[0].speed if rs else 0.0)
    return speeds[0] != speeds[1]


def _match(pt, ref_shape):
    """Column of a point's listed modes best matching ``ref_shape`` by MAC."""
    return int(np.argmax(mac_matrix(ref_shape[:, None], pt["shapes"])[0]))


def _crossing(case, config, params, axis, lo, hi, ref_shape, harmonic, xtol, f_lo, f_hi,
              line=None):
    from scipy.optimize import brentq

    seen = {}  # the points solved: Brent's root is its last iterate, solved already

    def at(p):
        if p not in seen:
            seen[p] = (line.point({**params, axis: p}) if line is not None
                       else campbell_point(case, config, {**params, axis: p}))
        return seen[p]

    def f(p):
        if p == lo:
            return f_lo
        if p == hi:
            return f_hi
        pt = at(p)
        if pt["error"]:
            raise MbseigError(f"critical speed search at {axis} = {p!r}: {pt['error']}",
                              element="campbell")
        c = _match(pt, ref_shape)
        return float(abs(pt["eigenvalues"][c].imag) - harmonic * abs(pt["speed"]))

    root = brentq(f, lo, hi, xtol=xtol)
    pt = at(root)
    c = _match(pt, ref_shape)
    return {"value": float(root), "speed": pt["speed"], "whirl": pt["whirl"][c],
            "frequency": float(abs(pt["eigenvalues"][c].imag))}


@dataclass(frozen=True, eq=False)
class CampbellResult:
    """Tracked modes against the swept parameter, with whirl, log decrement, the excitation
    line and the critical speeds (module docstring)."""

    case: str
    parameter: str
    values: np.ndarray
    speeds: np.ndarray  # Ω [rad/s] at each point
    tracks: np.ndarray  # (points, tracks) complex eigenvalues, NaN where absent
    whirl: list  # per point, per track: str or None
    kind: list
    critical_speeds: list
    harmonic: float = 1.0
    tolerances: dict = field(default_factory=dict)
    tolerance: np.ndarray = None  # (points, tracks): each eigenvalue's stability tolerance [1/s]
    units: dict = field(default_factory=dict)  # parameter → unit, for the figures' axes
    reuse: str = ""  # how the points were made (SpeedLine)

    @property
    def frequency(self):
        return np.abs(self.tracks.imag)

    @property
    def log_decrement(self):
        """Λ = 2π δ/ω per point and track (NaN for real eigenvalues)."""
        with np.errstate(divide="ignore", invalid="ignore"):
            w = self.frequency
            return np.where(w > 0, 2 * math.pi * (-self.tracks.real) / w, np.nan)

    @property
    def log_decrement_bound(self):
        """The log decrement's error bound 2π tol/ω per point and track (tol: the eigenvalue's
        stability tolerance; NaN where not known or ω = 0): |Λ| within it is 0 to the
        eigensolver's accuracy (drawn as 0 with the band)."""
        if self.tolerance is None:
            return np.full(self.tracks.shape, np.nan)
        with np.errstate(divide="ignore", invalid="ignore"):
            w = self.frequency
            return np.where(w > 0, 2 * math.pi * np.asarray(self.tolerance, float) / w, np.nan)

    def to_json(self) -> dict:
        tracks = []
        bound = self.log_decrement_bound
        for j in range(self.tracks.shape[1]):
            col = self.tracks[:, j]
            tracks.append({
                "track": j,
                "frequency": [None if np.isnan(v) else float(abs(v.imag)) for v in col],
                "delta": [None if np.isnan(v) else float(-v.real) for v in col],
                "log_decrement": [None if np.isnan(x) else float(x)
                                  for x in self.log_decrement[:, j]],
                "log_decrement_bound": [None if np.isnan(x) else float(x) for x in bound[:, j]],
                "whirl": [self.whirl[k][j] for k in range(len(self.values))],
                "kind": [self.kind[k][j] for k in range(len(self.values))],
            })
        return jsonable({"case": self.case, "parameter": self.parameter,
                         "values": [float(v) for v in self.values],
                         "speed": [float(v) for v in self.speeds], "harmonic": self.harmonic,
                         "excitation": [float(self.harmonic * abs(v)) for v in self.speeds],
                         "tracks": tracks, "critical_speeds": self.critical_speeds,
                         "tolerances": self.tolerances})


def campbell(case, parameter, values, *, config=None, fixed=None, harmonic=1.0, jobs=1,
             xtol_rel=1e-10) -> CampbellResult:
    """Campbell diagram of ``case`` (a path or :class:`~mbseig.casefile.CaseSpec`) over
    ``parameter`` = ``values`` (module docstring)."""
    spec = as_spec(case)
    values = np.asarray(values, float)
    if values.size < 2:
        raise CaseError("a Campbell diagram needs at least two parameter values",
                        element="campbell")
    fixed = dict(fixed or {})
    calls = [((spec, config, {**fixed, parameter: float(v)}), {}) for v in values]
    xtol = xtol_rel * abs(float(values[-1] - values[0]))
    line = SpeedLine(spec, config, {**fixed, parameter: float(values[0])}, parameter)
    line = line if line.reason is None else None
    with Runner(jobs=jobs if line is None else 1) as runner:
        if line is not None:  # one build, in this process (module docstring of SpeedLine)
            points = [line.point(args[2]) for args, _ in calls]
        else:
            points = runner.map(campbell_point, calls, "points")
        bad = next((p["error"] for p in points if p["error"]), None)
        if bad:
            raise MbseigError(bad, element="campbell")
        S, _, _ = track_line(points)
        n_pts, n_tr = S.shape
        col = np.full((n_pts, n_tr), -1)
        for k, pt in enumerate(points):
            for j in range(n_tr):
                if not np.isnan(S[k, j]):
                    col[k, j] = int(np.flatnonzero(pt["eigenvalues"] == S[k, j])[0])
        whirls = [[points[k]["whirl"][col[k, j]] if col[k, j] >= 0 else None for j in range(n_tr)]
                  for k in range(n_pts)]
        kinds = [[points[k]["kind"][col[k, j]] if col[k, j] >= 0 else None for j in range(n_tr)]
                 for k in range(n_pts)]
        speeds = np.array([p["speed"] for p in points])
        tol = np.array([[float(np.asarray(points[k]["tol"])[col[k, j]]) if col[k, j] >= 0
                         else np.nan for j in range(n_tr)] for k in range(n_pts)])
        F = np.abs(S.imag) - harmonic * np.abs(speeds)[:, None]
        searches, meta = [], []
        for j in range(n_tr):
            for k in range(n_pts - 1):
                a, b = F[k, j], F[k + 1, j]
                if (np.isnan(a) or np.isnan(b) or (a < 0) == (b < 0)
                        or "rigid-body" in (kinds[k][j], kinds[k + 1][j])
                        or "none" in (whirls[k][j], whirls[k + 1][j])):
                    continue
                # the shape followed: at the bracket's end farther from rest (at Ω = 0 a
                # forward/backward pair is one double eigenvalue, its shapes any mixture)
                e = k + 1 if abs(speeds[k + 1]) > abs(speeds[k]) else k
                shape = points[e]["shapes"][:, col[e, j]]
                searches.append(((spec, config, fixed, parameter, float(values[k]),
                                  float(values[k + 1]), shape, harmonic, xtol, float(a), float(b)),
                                 {}))
                meta.append(j)
        if line is not None:
            found = [_crossing(*args, line=line) for args, _ in searches]
        else:
            found = runner.map(_crossing, searches, "critical speeds")
    critical = []
    for c in sorted(({**res, "mode": j} for j, res in zip(meta, found, strict=True)),
                    key=lambda c: c["value"]):
        # two tracks that followed one mode to the same crossing give it once
        if not any(abs(c["value"] - d["value"]) <= 10 * xtol and c["whirl"] == d["whirl"]
                   and abs(c["frequency"] - d["frequency"]) <= 1e-6 * abs(d["frequency"])
                   for d in critical):
            critical.append(c)
    return CampbellResult(case=spec.name, parameter=parameter, values=values, speeds=speeds,
                          tracks=S, whirl=whirls, kind=kinds, critical_speeds=critical,
                          harmonic=harmonic, tolerances={"xtol": xtol, "xtol_rel": xtol_rel},
                          tolerance=tol, reuse="one build, the speeds replaced at each point"
                          if line is not None else "built at every point")


@dataclass(frozen=True, eq=False)
class RotorStudy:
    """What a report shows of a rotor over a speed sweep: the Campbell diagram (with the
    critical speeds) and the unbalance response to ``me`` [kg m] at ``at`` (``unbalance``)."""

    parameter: str
    campbell: CampbellResult
    unbalance: object
    at: str
    me: float
    default_unbalance: bool


def default_unbalance_point(case, config=None, fixed=None, parameter=None, value=None) -> str:
    """Where a report puts its unbalance when the case names none: the body of the first rotor
    element (a disk), else the middle station of the first spinning beam."""
    from .unbalance import station_names

    spec = as_spec(case)
    params = {**(fixed or {}), **({parameter: float(value)} if parameter else {})}
    model = spec.build(config, **params)
    rs = rotors(model)
    body = next((r.body for r in rs if r.body), None)
    if body is not None:
        return body
    names = [n for n, _ in station_names(model, rs) if n in model.points]
    if not names:
        raise CaseError("no rotor station for the unbalance response", element="unbalance",
                        file=spec.source)
    return names[len(names) // 2]


def rotor_study(case, parameter, values, *, config=None, fixed=None, jobs=1, unbalance=None,
                xtol_rel=1e-10):
    """The Campbell diagram over ``parameter`` = ``values`` and the unbalance response over
    the same values: ``unbalance`` = (point, m·e [kg m]), default m·e = 1 kg m (the response is
    proportional to it) at :func:`default_unbalance_point`.  None when the parameter does not
    set a rotor's speed."""
    from .unbalance import unbalance_response

    spec = as_spec(case)
    values = np.asarray(values, float)
    if not speed_parameter(spec, parameter, values, config=config, fixed=fixed):
        return None
    camp = campbell(spec, parameter, values, config=config, fixed=fixed, jobs=jobs or 1,
                    xtol_rel=xtol_rel)
    default = unbalance is None
    at, me = unbalance if unbalance else (default_unbalance_point(
        spec, config, fixed, parameter, values[-1]), 1.0)
    ub = unbalance_response(spec, parameter, values, at=at, unbalance=me, config=config,
                            fixed=fixed)
    return RotorStudy(parameter=parameter, campbell=camp, unbalance=ub, at=at, me=float(me),
                      default_unbalance=default)


def is_rotor(case, model) -> bool:
    """Whether the model has a rotor element or a spinning beam (or the case a beam with
    ``spin``, a rotor at any non-zero speed)."""
    return bool(rotors(model)) or spinning_beams(as_spec(case))
