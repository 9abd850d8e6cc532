"""Sweeps of steady motions and lift-off boundaries of contacts (DESIGN §8).

:func:`steady_sweep` solves the steady motion at every grid value of one parameter (the speed,
usually) and finds the boundaries between grid points:

- a stability boundary where the number of unstable modes changes: ``flutter`` (a Hopf
  crossing) when the mode that crosses is oscillatory, ``divergence`` when it is real.  It is
  refined by Brent's method on the largest real part of that kind when that changes sign
  continuously (kept only when it is small at the root: a real pair merging into a complex one
  makes the maximum jump); a pair that passes through s = 0 and turns imaginary (the rolling
  disk's lean at its critical speed: ±σ ↔ ±iω) by Brent's method on Σ s² over the eigenvalues
  nearest 0 (the pair and the undeclared zeros beside it: 2σ² on one side, −2ω² on the other,
  smooth through the crossing).  Σ s² is the trace of the square of the operator restricted to
  that cluster, accurate to the rounding of the pencil even where the individual eigenvalues of a
  defective zero are not (a count's bisection stops where σ first exceeds its own error bound, up
  to 2.5e-9 m/s early on the rolling disk); else by bisection on the count;
- ``lift-off``: the normal force of a wheel changes sign (Brent's method on the force).

``stability`` is ``loss`` when the motion becomes less stable (or a wheel pulls) as the
parameter grows, else ``recovery``.

Where the swept parameter enters the ``[motion]`` table alone (the speed, a yaw rate), the case
is built once and the grid's points are analysed together, in tasks of ``CHUNK`` points
(:mod:`mbseig.studies.steady_batch`; a point the batch does not cover is analysed on its own,
with the same result or the same error); elsewhere every value is built and analysed on its own.
The boundaries are refined by :func:`~mbseig.studies.roots.root_in_rounds`, which evaluates
``ROOT_POINTS`` parameter values together in each round where the points are batched, one where
they are not: Brent's method's guarantee (the root returned within xtol + rtol·|x| of a sign
change of the continuous function) with the batch's cost per round.

:func:`lift_off` is the lift-off value of one contact of a static case (the contacts held
active, :func:`mbseig.statics.contacts.held_active`): N(p) of the bilateral model is smooth
through it, so Brent's method on N is exact to ``xtol``; :func:`contact_boundaries` finds every
such value over a grid, each as a ``{"value", "kind": "lift-off", "stability", "contact"}``.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.optimize import brentq

from ..records import Record
from .roots import ROOT_POINTS
from .roots import root_in_rounds as _root

__all__ = ["SteadySweep", "contact_boundaries", "growth_rates", "lift_off", "steady_sweep"]

IMAG_TOL = 1e-9  # |Im s| above IMAG_TOL·max(1, |s|): an oscillatory eigenvalue
ROOT_TOL = 1e-7  # |f(root)| relative to the scale of the spectrum: a crossing, not a jump
#: grid points of one task of the sweep's runner where the points are analysed together (a
#: task's share of the grid: what a progress bar counts and an interruption keeps)
CHUNK = 64
#: analyse a line's points together where the batch applies; False analyses every point on its
#: own (the one-point path: its tests and comparisons)
BATCH_STEADY = True


@dataclass(frozen=True, eq=False)
class SteadySweep:
    """The grid (``parameter``, ``values``), per point its verdict, eigenvalues and contact
    forces, and the boundaries found; ``batch``: None where the points were analysed together
    (the case built once), else why they were analysed one at a time."""

    parameter: str
    values: np.ndarray
    points: tuple
    boundaries: tuple
    batch: str | None = None

    def as_dict(self) -> dict:
        return {"parameter": self.parameter, "values": [float(v) for v in self.values],
                "points": [dict(p) for p in self.points],
                "boundaries": [dict(b) for b in self.boundaries],
                "batch": "together" if self.batch is None else f"declined: {self.batch}"}


def zeros_left(a) -> int:
    """The eigenvalues of ``a`` within their bound of 0 that are not declared rigid-body
    directions (a zero the motion has but does not declare, as the rolling disk's steady-turn
    family, or a real eigenvalue passing through 0)."""
    return sum(1 for r in a.modes if r["kind"] == "rigid-body" and not r.get("rigid_body"))


def growth_rates(a, persistent=0) -> dict:
    """The largest real part of the oscillatory eigenvalues and of the real ones (None where it
    has none), from the solver's eigenvalues (the declared cyclic directions are deflated
    exactly, so a real eigenvalue passing through s = 0 stays continuous), and each wheel's
    pull (minus its normal force).  ``persistent``: zeros present at both ends of an interval
    (:func:`zeros_left`): that many real eigenvalues nearest 0 are left out, as they stay at 0
    and cross nothing (their computed real parts are rounding residue of either sign)."""
    s = np.asarray(a.eigenvalues)
    cplx = np.abs(s.imag) > IMAG_TOL * np.maximum(1.0, np.abs(s))
    osc, real = s[cplx].real, s[~cplx].real
    if persistent:
        real = real[np.argsort(np.abs(real), kind="stable")][persistent:]
    return {"flutter": float(osc.max()) if osc.size else None,
            "divergence": float(real.max()) if real.size else None,
            **{f"lift-off:{c['name']}": -c["force"] for c in a.contacts}}


def _unstable(a):
    return [r for r in a.modes if r["stability"] == "unstable"]


def _count(a):
    """Unstable eigenvalues (a pair, listed once, counts twice)."""
    return sum(2 if r["omega_d"] > 0 else 1 for r in _unstable(a))


@dataclass(frozen=True, eq=False)
class SteadyPoint(Record):
    """What a sweep keeps of the steady motion at one grid point: its verdict, the solver's
    eigenvalues, the number of declared rigid-body directions, each wheel's contact record and
    the mode rows (:class:`~mbseig.studies.steady_modes.SteadyAnalysis` without the model and
    matrices, so that a resume folder holds only these)."""

    verdict: str
    eigenvalues: np.ndarray
    n_rigid: int
    contacts: tuple
    modes: tuple


def _steady_point(spec, config, params, model=None):
    """The steady motion and its modes at one grid point (a pure task for the runners); the
    mode rows without their dominant coordinates, as the batch gives them (a sweep lists
    eigenvalues and verdicts, not shapes)."""
    from .steady_modes import analyze_steady

    a = analyze_steady(spec, config=config, params=params, model=model)
    return SteadyPoint(a.verdict, np.asarray(a.solution.eigenvalues),
                       len(a.cyclic.names) if a.cyclic is not None else 0,
                       tuple(dict(c) for c in a.state.contacts),
                       tuple({k: v for k, v in r.items() if k != "dominant"} for r in a.modes))


class SteadyLine:
    """The steady motions of a case along one parameter (module docstring): one model and its
    :class:`~mbseig.studies.steady_batch.SteadyStack` where the parameter enters the
    ``[motion]`` table alone, else a build at each value.  ``batch`` is None where the points
    are analysed together, else why not."""

    def __init__(self, spec, config, fixed, name, value):
        from ..casefile.element_readers import MotionUpdate
        from ..model.system import Model
        from .steady_batch import SteadyStack

        self.spec, self.config, self.fixed, self.name = spec, config, dict(fixed), name
        self.update, self.stack = None, None
        if not BATCH_STEADY:
            self.batch = "switched off"
            return
        model = spec.build(config, **self.params(value))
        if not isinstance(model, Model):
            self.batch = "not a multibody model"
            return
        update = MotionUpdate(spec.data, config, self.params(value), name, model)
        if update.reason is not None:
            self.batch = update.reason
            return
        stack = SteadyStack(model)
        self.batch = stack.reason
        if stack.reason is None:
            self.update, self.stack = update, stack

    def params(self, p):
        return {**self.fixed, self.name: repr(float(p))}

    def points(self, values):
        """The :class:`SteadyPoint` of every value (together where the batch applies)."""
        if self.stack is None:
            return [_steady_point(self.spec, self.config, self.params(p)) for p in values]
        from ..errors import MbseigError

        file = getattr(self.spec, "source", None)
        motions = [self.update.motion(repr(float(p)), file=file) for p in values]
        try:
            with np.errstate(all="ignore"):  # (a point whose numbers overflow is not covered)
                got = self.stack.analyse(motions)
        except (np.linalg.LinAlgError, ValueError, ArithmeticError, MbseigError) as exc:
            got = [f"the batch failed ({exc})"] * len(values)  # each on its own: its own error
        out = []
        for p, r in zip(values, got, strict=True):
            if isinstance(r, str) or r is None:  # not covered: on its own (its error, if any)
                out.append(_steady_point(self.spec, self.config, self.params(p),
                                         model=self.update.make(repr(float(p)))))
            else:
                out.append(SteadyPoint(r.verdict, np.asarray(r.eigenvalues), r.n_rigid,
                                       r.contacts, r.modes))
        return out


_LINES: dict = {}  # the last lines of this process (a task of the runner finds its model here)


def _line(spec, config, fixed, name, value):
    key = (id(spec), config, tuple(sorted(fixed.items())), name, BATCH_STEADY)
    hit = _LINES.get(key)
    if hit is None or hit[0] is not spec:
        while len(_LINES) >= 4:
            _LINES.pop(next(iter(_LINES)))
        hit = _LINES[key] = (spec, SteadyLine(spec, config, fixed, name, value))
    return hit[1]


def _steady_chunk(spec, config, fixed, name, values):
    """The :class:`SteadyPoint` of each of ``values`` (a task of the runner: the points of a
    chunk analysed together)."""
    return _line(spec, config, fixed, name, values[0]).points(values)


def steady_sweep(spec, name, values, *, config=None, fixed=None, xtol=1e-11, jobs=None,
                 progress=None, resume=None):
    """The sweep of ``name`` over ``values`` (module docstring).  The grid points run on a
    :class:`~mbseig.studies.runners.Runner` (``jobs``, ``progress``, and ``resume``: a
    directory or :class:`~mbseig.studies.resume.Checkpoint`, as for
    :func:`mbseig.studies.sweep.run_sweep`; Ctrl-C raises
    :class:`~mbseig.studies.runners.Interrupted`); the boundaries are refined in-process."""
    from .runners import Runner

    fixed = dict(fixed or {})
    values = np.asarray(values, float)
    line = _line(spec, config, fixed, name, values[0])
    memo = {}

    def at_many(ps):
        """The points at the parameter values ps (each computed once)."""
        new = [float(p) for p in dict.fromkeys(float(p) for p in ps) if float(p) not in memo]
        if new:
            memo.update(zip(new, line.points(new), strict=True))
        return [memo[float(p)] for p in ps]

    batched = line.stack is not None
    many = ROOT_POINTS if batched else 1
    checkpoint = _checkpoint(resume, spec, "steady", config=config, parameter=name,
                             values=values, fixed=fixed, xtol=xtol)
    chunks = [values[i:i + CHUNK] for i in range(0, len(values), CHUNK)]
    with Runner(jobs=jobs, progress=progress, checkpoint=checkpoint,
                points=len(values)) as runner:
        if batched:
            got = runner.map(_steady_chunk, [((spec, config, fixed, name, tuple(c)), {})
                                             for c in chunks], "chunks",
                             points=[len(c) for c in chunks])
            runs = [p for part in got for p in part]
        else:
            runs = runner.map(_steady_point, [((spec, config, line.params(v)), {})
                                              for v in values], "points", points=1)
    memo.update(zip((float(v) for v in values), runs, strict=True))
    points = []
    for v, a in zip(values, runs, strict=True):
        points.append({"value": float(v), "verdict": a.verdict,
                       "eigenvalues": [[float(s.real), float(s.imag)]
                                       for s in a.eigenvalues],
                       "n_rigid": a.n_rigid,
                       "contacts": [dict(c) for c in a.contacts]})
    boundaries = []
    for k in range(len(values) - 1):
        lo, hi = float(values[k]), float(values[k + 1])
        around = [(float(values[j]), runs[j]) for j in (k - 1, k + 2) if 0 <= j < len(values)]
        boundaries += _stability_crossing(at_many, lo, hi, runs[k], runs[k + 1], name, xtol,
                                          many, around)
        g0, g1 = growth_rates(runs[k]), growth_rates(runs[k + 1])
        for key in (x for x in g0 if x.startswith("lift-off:")):
            f0, f1 = g0[key], g1.get(key)
            if f1 is None or (f0 < 0) == (f1 < 0):
                continue
            root = _root(lambda ps, key=key: [growth_rates(a)[key] for a in at_many(ps)],
                         lo, hi, f0, f1, xtol, many)
            boundaries.append({"value": float(root), "kind": "lift-off",
                               "stability": "loss" if f1 > 0 else "recovery",
                               "contact": key.split(":", 1)[1], "parameter": name})
    boundaries.sort(key=lambda b: b["value"])
    return SteadySweep(name, np.asarray(values, float), tuple(points), tuple(boundaries),
                       line.batch)


def _checkpoint(resume, spec, kind, **inputs):
    """The checkpoint of a study's grid (``resume``: None, a directory or a Checkpoint)."""
    if resume is None:
        return None
    from .resume import Checkpoint, study_identity

    identity = study_identity(spec, study=kind, **inputs)
    return (resume.bind(identity) if isinstance(resume, Checkpoint)
            else Checkpoint(resume, identity))


def _stability_crossing(at_many, lo, hi, a0, a1, name, xtol, many=1, around=()):
    """The boundary between two grid points whose number of unstable modes differs: a root of
    the largest real part of the crossing kind where that changes sign continuously, else of
    Σ s² near 0 (a pair through s = 0), else the count's change located by sections.
    ``around``: (value, point) of the grid points beside the interval, whose values of the
    function start the root's interpolation where they continue it (same signs outside)."""
    n0, n1 = _count(a0), _count(a1)
    if n0 == n1:
        return []
    worse = a1 if n1 > n0 else a0
    crossing = min(_unstable(worse), key=lambda r: r["eigenvalue"][0])
    kind = "flutter" if crossing["omega_d"] > 0 else "divergence"
    base = min(zeros_left(a) for a in (a0, a1))
    f0, f1 = growth_rates(a0, base)[kind], growth_rates(a1, base)[kind]
    root = None
    if f0 is not None and f1 is not None and (f0 < 0) != (f1 < 0):
        def fun(ps):
            return [_value(growth_rates(a, base)[kind], f0) for a in at_many(ps)]

        known = []
        for x, a in around:
            g = growth_rates(a, base)[kind]
            if g is not None and (g < 0) == ((f0 < 0) if x < lo else (f1 < 0)):
                known.append((x, g))
        root = _root(fun, lo, hi, f0, f1, xtol, many, known=known)
        near = at_many([root])[0]
        g = growth_rates(near, base)[kind]
        scale = max(1.0, max(abs(s) for s in near.eigenvalues))
        if g is None or abs(g) > ROOT_TOL * scale:
            root = None  # the maximum jumped: fall back on the count
    if root is None and kind == "divergence":
        root = _pair_through_zero(at_many, lo, hi, base + 2, xtol, many)
    if root is None:
        a, b = lo, hi
        k = max(many, 1)
        while b - a > xtol * max(1.0, abs(b)):
            xs = a + (b - a) * np.arange(1, k + 1) / (k + 1)
            changed = [_count(p) != n0 for p in at_many(xs)] + [True]
            j = changed.index(True)
            a, b = ([a, *xs])[j], ([*xs, b])[j]
        root = 0.5 * (a + b)
    row = {"value": float(root), "kind": kind, "stability": "loss" if n1 > n0 else "recovery",
           "parameter": name}
    if kind == "flutter":
        near = at_many([root])[0]
        osc = [r for r in near.modes if r["omega_d"] > 0 and r["kind"] != "rigid-body"]
        if osc:
            row["frequency"] = float(max(osc, key=lambda r: r["eigenvalue"][0])["omega_d"])
    return [row]


def _cluster_square(a, count):
    """Σ s² over the ``count`` eigenvalues of ``a`` nearest 0 (declared directions are deflated
    and not among them), and the largest |s| of the spectrum (its scale)."""
    s = np.asarray(a.eigenvalues)
    s = s[np.isfinite(s)]
    if s.size < count:
        return None, 1.0
    near = s[np.argsort(np.abs(s), kind="stable")[:count]]
    return float(np.sum(near * near).real), max(1.0, float(np.abs(s).max()))


def _pair_through_zero(at_many, lo, hi, count, xtol, many=1):
    """The parameter where a real pair ±σ turns into ±iω through s = 0 (module docstring), or
    None when Σ s² of the ``count`` eigenvalues nearest 0 does not change sign on [lo, hi] or is
    not small at the root."""
    a_lo, a_hi = at_many([lo, hi])
    f0, _ = _cluster_square(a_lo, count)
    f1, _ = _cluster_square(a_hi, count)
    if f0 is None or f1 is None or (f0 < 0) == (f1 < 0):
        return None
    root = _root(lambda ps: [_value(_cluster_square(a, count)[0], f0) for a in at_many(ps)],
                 lo, hi, f0, f1, xtol, many)
    g, scale = _cluster_square(at_many([root])[0], count)
    return root if g is not None and abs(g) <= ROOT_TOL * scale ** 2 else None


def _value(v, fallback):
    return fallback if v is None else v


def _held_forces(spec, config, params):
    from .. import equilibrium
    from ..statics.contacts import contact_forces, held_active

    model = held_active(spec.build(config, **params))
    eq = equilibrium(model)
    return contact_forces(model, eq.lam)


def lift_off(spec, name, contact, lo, hi, *, config=None, fixed=None, xtol=1e-12):
    """The value of ``name`` in [lo, hi] where the normal force of ``contact`` crosses zero,
    every contact held active (module docstring); None without a sign change."""
    fixed = dict(fixed or {})

    def force(p):
        return _held_forces(spec, config, {**fixed, name: repr(float(p))})[contact]

    flo, fhi = force(lo), force(hi)
    if (flo < 0) == (fhi < 0):
        return None
    return float(brentq(force, lo, hi, xtol=xtol, rtol=4 * np.finfo(float).eps))


def contact_boundaries(spec, name, values, *, config=None, fixed=None, xtol=1e-12):
    """Every lift-off (and touch-down) of a static case's contacts over the grid ``values``."""
    fixed = dict(fixed or {})
    forces = [_held_forces(spec, config, {**fixed, name: repr(float(v))}) for v in values]
    out = []
    for k in range(len(values) - 1):
        for c, f0 in forces[k].items():
            f1 = forces[k + 1][c]
            if (f0 < 0) != (f1 < 0):
                root = lift_off(spec, name, c, float(values[k]), float(values[k + 1]),
                                config=config, fixed=fixed, xtol=xtol)
                if root is not None:
                    out.append({"value": root, "kind": "lift-off",
                                "stability": "loss" if f1 < 0 else "recovery", "contact": c,
                                "parameter": name})
    return tuple(sorted(out, key=lambda b: b["value"]))
