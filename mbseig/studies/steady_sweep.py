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

__all__ = ["SteadySweep", "contact_boundaries", "growth_rates", "lift_off", "steady_sweep"]

IMAG_TOL = 1e-9  # |Im s| above IMAG_TOL·max(1, |s|): an oscillatory eigenvalue
ROOT_TOL = 1e-7  # |f(root)| relative to the scale of the spectrum: a crossing, not a jump


@dataclass(frozen=True, eq=False)
class SteadySweep:
    """The grid (``parameter``, ``values``), per point its verdict, eigenvalues and contact
    forces, and the boundaries found."""

    parameter: str
    values: np.ndarray
    points: tuple
    boundaries: tuple

    def as_dict(self) -> dict:
        return {"parameter": self.parameter, "values": [float(v) for v in self.values],
                "points": [dict(p) for p in self.points],
                "boundaries": [dict(b) for b in self.boundaries]}


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


def _steady_point(spec, config, params):
    """The steady motion and its modes at one grid point (a pure task for the runners)."""
    from .steady_modes import analyze_steady

    a = analyze_steady(spec, config=config, params=params)
    return SteadyPoint(a.verdict, np.asarray(a.solution.eigenvalues),
                       len(a.cyclic.names) if a.cyclic is not None else 0,
                       tuple(dict(c) for c in a.state.contacts), a.modes)


def steady_sweep(spec, name, values, *, config=None, fixed=None, xtol=1e-11, jobs=None,
                 progress=None, resume=None):
    """The sweep of ``name`` over ``values`` (module docstring).  The grid points run on a
    :class:`~mbseig.studies.runners.Runner` (``jobs``, ``progress``, and ``resume``: a
    directory or :class:`~mbseig.studies.resume.Checkpoint`, as for
    :func:`mbseig.studies.sweep.run_sweep`; Ctrl-C raises
    :class:`~mbseig.studies.runners.Interrupted`); the boundaries are refined in-process."""
    from .runners import Runner

    fixed = dict(fixed or {})

    def params(p):
        return {**fixed, name: repr(float(p))}

    def at(p):
        return _steady_point(spec, config, params(p))

    checkpoint = _checkpoint(resume, spec, "steady", config=config, parameter=name,
                             values=np.asarray(values, float), fixed=fixed, xtol=xtol)
    with Runner(jobs=jobs, progress=progress, checkpoint=checkpoint,
                points=len(values)) as runner:
        runs = runner.map(_steady_point, [((spec, config, params(v)), {}) for v in values],
                          "points", points=1)
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
        boundaries += _stability_crossing(at, lo, hi, runs[k], runs[k + 1], name, xtol)
        g0, g1 = growth_rates(runs[k]), growth_rates(runs[k + 1])
        for key in (x for x in g0 if x.startswith("lift-off:")):
            f0, f1 = g0[key], g1.get(key)
            if f1 is None or (f0 < 0) == (f1 < 0):
                continue
            root = brentq(lambda p, key=key: growth_rates(at(p))[key], lo, hi, xtol=xtol,
                          rtol=4 * np.finfo(float).eps)
            boundaries.append({"value": float(root), "kind": "lift-off",
                               "stability": "loss" if f1 > 0 else "recovery",
                               "contact": key.split(":", 1)[1], "parameter": name})
    boundaries.sort(key=lambda b: b["value"])
    return SteadySweep(name, np.asarray(values, float), tuple(points), tuple(boundaries))


def _checkpoint(resume, spec, kind, **inputs):
    """The checkpoint of a study's grid (``resume``: None, a directory or a Checkpoint)."""
    if resume is None:
        return None
    from .resume import Checkpoint, study_identity

    identity = study_identity(spec, study=kind, **inputs)
    return (resume.bind(identity) if isinstance(resume, Checkpoint)
            else Checkpoint(resume, identity))


def _stability_crossing(at, lo, hi, a0, a1, name, xtol):
    """The boundary between two grid points whose number of unstable modes differs: Brent's
    method on the largest real part of the crossing kind when it changes sign continuously,
    else bisection on the count (a pair through s = 0, as the rolling disk's lean)."""
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
        def fun(p):
            return _value(growth_rates(at(p), base)[kind], f0)

        root = float(brentq(fun, lo, hi, xtol=xtol, rtol=4 * np.finfo(float).eps))
        g = growth_rates(at(root), base)[kind]
        scale = max(1.0, max(abs(s) for s in at(root).eigenvalues))
        if g is None or abs(g) > ROOT_TOL * scale:
            root = None  # the maximum jumped: fall back on the count
    if root is None and kind == "divergence":
        root = _pair_through_zero(at, lo, hi, base + 2, xtol)
    if root is None:
        a, b = lo, hi
        while b - a > xtol * max(1.0, abs(b)):
            mid = 0.5 * (a + b)
            if _count(at(mid)) == n0:
                a = mid
            else:
                b = mid
        root = 0.5 * (a + b)
    row = {"value": root, "kind": kind, "stability": "loss" if n1 > n0 else "recovery",
           "parameter": name}
    if kind == "flutter":
        near = at(root)
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


def _pair_through_zero(at, lo, hi, count, xtol):
    """The parameter where a real pair ±σ turns into ±iω through s = 0 (module docstring), or
    None when Σ s² of the ``count`` eigenvalues nearest 0 does not change sign on [lo, hi] or is
    not small at the root."""
    f0, _ = _cluster_square(at(lo), count)
    f1, _ = _cluster_square(at(hi), count)
    if f0 is None or f1 is None or (f0 < 0) == (f1 < 0):
        return None
    root = float(brentq(lambda p: _value(_cluster_square(at(p), count)[0], f0), lo, hi,
                        xtol=xtol, rtol=4 * np.finfo(float).eps))
    g, scale = _cluster_square(at(root), count)
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
