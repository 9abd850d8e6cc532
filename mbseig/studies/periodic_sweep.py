"""A sweep of a periodic case over one parameter: the Floquet verdict at every grid point and
where it changes (DESIGN §8: ``flip`` at μ = −1, ``fold`` at μ = +1, ``secondary`` for a
complex pair on |μ| = 1), each located to a relative tolerance by Brent's method on the
characteristic function of its kind (:func:`mbseig.studies.floquet_sweep.verdict_changes`).

Over two parameters, :func:`periodic_chart` gives the stability chart: the verdict and the
spectral radius max|μ| on the grid (the Ince–Strutt chart of a Mathieu-type system), and where
the verdict changes along the first parameter: each grid bracket located as a sweep locates a
boundary, at the bracket's value of the second parameter."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .floquet import floquet
from .floquet_chebyshev import chebyshev_system
from .floquet_sweep import StabilityChart, verdict_changes
from .periodic import periodic_analysis, periodic_linearization

__all__ = ["PeriodicSweep", "periodic_sweep", "PeriodicChart", "periodic_chart", "CHART_RTOLS"]

CHART_RTOLS = (1e-7, 1e-9)  # the two monodromy estimates of a chart point (a map, not a boundary)


@dataclass(frozen=True)
class PeriodicSweep:
    """Grid points (value, FloquetResult) and the verdict changes between them."""

    case: str
    parameter: str
    values: np.ndarray
    results: tuple
    boundaries: tuple
    rel_tol: float

    def to_dict(self) -> dict:
        return {
            "case": self.case,
            "parameter": self.parameter,
            "points": [{"value": float(v), "verdict": r.verdict,
                        "spectral_radius": r.spectral_radius, "error_bound": r.error_bound,
                        "multipliers": [[float(m.real), float(m.imag)] for m in r.multipliers]}
                       for v, r in zip(self.values, self.results, strict=True)],
            "boundaries": [{"value": b.value, "kind": b.kind, "stability": b.stability,
                            "bracket": list(b.bracket), "method": b.method, "xtol": b.xtol,
                            "verdicts": list(b.verdicts)} for b in self.boundaries],
            "rel_tol": self.rel_tol,
        }


def _floquet_point(spec, config, params):
    """The Floquet result of one grid point (a pure task for the runners)."""
    return periodic_analysis(spec, config=config, params=params).floquet


def _chart_point(spec, config, params, rtols):
    """The two monodromy estimates of one chart point (a pure task for the runners)."""
    system = periodic_linearization(spec, config=config, params=params).system.system
    return floquet(chebyshev_system(system)[0], rtols=rtols)


def _runner(jobs, progress, resume, spec, kind, points, **inputs):
    """The runner of a periodic study's grid: ``progress(done, total)`` of its points, its
    checkpoint (``resume``: None, a directory or a Checkpoint) named by the study's inputs."""
    from .runners import Runner
    from .steady_sweep import _checkpoint

    shown = None if not progress else (
        lambda label, done, total: progress(done, total) if label == "points" else None)
    return Runner(jobs=jobs, progress=shown, points=points,
                  checkpoint=_checkpoint(resume, spec, kind, **inputs))


def periodic_sweep(spec, name, values, *, config=None, fixed=None, rel_tol=1e-8,
                   progress=None, jobs=None, resume=None) -> PeriodicSweep:
    """Floquet verdicts of a periodic case over ``values`` of parameter ``name`` and the
    parameter values where the verdict changes, located to ``rel_tol``.  The grid points run
    on a :class:`~mbseig.studies.runners.Runner` (``jobs``, ``resume`` as for
    :func:`mbseig.studies.sweep.run_sweep`; Ctrl-C raises
    :class:`~mbseig.studies.runners.Interrupted`); the boundaries are located in-process."""
    fixed = dict(fixed or {})
    values = np.sort(np.asarray(values, dtype=float))

    def params(p):
        return {**fixed, name: repr(float(p))}

    with _runner(jobs, progress, resume, spec, "periodic", len(values), config=config,
                 parameter=name, values=values, fixed=fixed, rel_tol=rel_tol) as runner:
        results = runner.map(_floquet_point, [((spec, config, params(p)), {}) for p in values],
                             "points", points=1)

    def build(p):
        system = periodic_linearization(spec, config=config, params=params(p)).system.system
        return chebyshev_system(system)[0], None

    found = verdict_changes(build, values, rel_tol=rel_tol, results=results)
    return PeriodicSweep(spec.name, name, values, tuple(results), found, rel_tol)


@dataclass(frozen=True)
class PeriodicChart:
    """A stability chart of a periodic case: ``chart.verdicts[i, j]``,
    ``chart.spectral_radius[i, j]`` and ``error_bounds[i, j]`` (the bound of the multiplier
    that decided the verdict) at (p1[i], p2[j]); ``edges`` are the grid brackets along p1 where
    the verdict changes, with the kind read from the dominant multiplier on the less stable side."""

    case: str
    chart: StabilityChart
    error_bounds: np.ndarray
    edges: tuple
    rtols: tuple
    fixed: dict
    rel_tol: float | None = None  # the edges located to this (None: grid brackets)

    def to_dict(self) -> dict:
        c = self.chart
        return {
            "case": self.case,
            "parameters": list(c.names),
            "fixed": dict(self.fixed),
            c.names[0]: [float(v) for v in c.p1],
            c.names[1]: [float(v) for v in c.p2],
            "values": {c.names[0]: [float(v) for v in c.p1],
                       c.names[1]: [float(v) for v in c.p2]},
            "axes": {"rows": c.names[0], "columns": c.names[1]},
            "verdicts": [[str(v) for v in row] for row in c.verdicts],
            "spectral_radius": c.spectral_radius.tolist(),
            "error_bounds": self.error_bounds.tolist(),
            "boundaries": list(self.edges),
            "tolerances": {"rtols": list(self.rtols),
                           "boundaries": (f"located along {c.names[0]} to {self.rel_tol:g} "
                                          "relative" if self.rel_tol is not None else
                                          "grid brackets, not located (value = bracket "
                                          "midpoint, xtol = half the bracket)")},
        }


_RANK = {"stable": 0, "critical": 1, "unstable": 2}


def _edge(name, other, value, ra, rb, a, b):
    worse = ra if _RANK[ra.verdict] > _RANK[rb.verdict] else rb
    k = int(np.argmax(np.abs(worse.multipliers)))
    mu, bound = worse.multipliers[k], worse.error_bounds[k]
    kind = ("secondary" if abs(mu.imag) > max(1e3 * bound, 1e-9 * abs(mu))
            else "flip" if mu.real < 0 else "fold")
    return {"value": 0.5 * (a + b), "kind": kind,
            "stability": "loss" if _RANK[rb.verdict] > _RANK[ra.verdict] else "recovery",
            "parameter": name, "at": {other: float(value)}, "bracket": [float(a), float(b)],
            "xtol": 0.5 * abs(b - a), "verdicts": [ra.verdict, rb.verdict],
            "method": "grid bracket (not located)"}


def periodic_chart(spec, first, second, *, config=None, fixed=None, rtols=CHART_RTOLS,
                   progress=None, rel_tol=1e-8, jobs=None, resume=None) -> PeriodicChart:
    """The Floquet verdict of a periodic case over the grid ``first`` × ``second`` (each a
    (name, values) pair), two monodromy estimates at ``rtols`` per point.  Each grid bracket
    along ``first`` where the verdict changes is located to ``rel_tol`` (relative) at its value
    of ``second``, as :func:`periodic_sweep` locates one (Brent on the characteristic
    function of the kind, each monodromy at rtol 1e-12; the kind and the verdicts at the ends
    from the chart's points); ``rel_tol=None`` keeps the brackets.  The points and the
    located brackets run on a :class:`~mbseig.studies.runners.Runner` (``jobs``, ``resume``
    as for :func:`periodic_sweep`)."""
    (n1, v1), (n2, v2) = first, second
    fixed = dict(fixed or {})
    v1, v2 = np.asarray(v1, dtype=float), np.asarray(v2, dtype=float)
    verdicts = np.empty((v1.size, v2.size), dtype=object)
    rho, bounds = np.empty(verdicts.shape), np.empty(verdicts.shape)
    results = np.empty(verdicts.shape, dtype=object)
    calls = [((spec, config, {**fixed, n1: repr(float(a)), n2: repr(float(b))}, tuple(rtols)), {})
             for a in v1 for b in v2]
    with _runner(jobs, progress, resume, spec, "periodic chart", len(calls), config=config,
                 first=(n1, v1), second=(n2, v2), fixed=fixed, rtols=tuple(rtols),
                 rel_tol=rel_tol) as runner:
        flat = runner.map(_chart_point, calls, "points", points=1)
        for k, res in enumerate(flat):
            i, j = divmod(k, v2.size)
            results[i, j], verdicts[i, j] = res, res.verdict
            rho[i, j], bounds[i, j] = res.spectral_radius, res.decided_by[2]
        edges = tuple(_edge(n1, n2, v2[j], results[i, j], results[i + 1, j], v1[i], v1[i + 1])
                      for j in range(v2.size) for i in range(v1.size - 1)
                      if results[i, j].verdict != results[i + 1, j].verdict)
        if rel_tol is not None:
            ends = {(float(v1[i]), float(v2[j])): results[i, j] for i in range(v1.size)
                    for j in range(v2.size)}
            calls = [((spec, config, fixed, n1, n2, e, rel_tol,
                       {k: ends[k] for k in ((e["bracket"][0], e["at"][n2]),
                                             (e["bracket"][1], e["at"][n2]))}), {})
                     for e in edges]
            edges = tuple(runner.map(_located, calls, "boundaries"))
    chart = StabilityChart(v1, v2, verdicts, rho, (n1, n2))
    return PeriodicChart(spec.name, chart, bounds, edges, tuple(rtols), fixed, rel_tol)


def _located(spec, config, fixed, n1, n2, edge, rel_tol, results):
    """A chart's grid bracket located along ``n1`` at its value of ``n2``: Brent on the
    characteristic function of its kind (monodromy at rtol 1e-12), the verdicts at its ends
    from the chart."""
    at = edge["at"][n2]

    def params(p):
        return {**fixed, n1: repr(float(p)), n2: repr(float(at))}

    def build(p):
        system = periodic_linearization(spec, config=config, params=params(p)).system.system
        return chebyshev_system(system)[0], None

    lo, hi = edge["bracket"]
    found = verdict_changes(build, [lo, hi], rel_tol=rel_tol,
                            results=[results[(lo, at)], results[(hi, at)]])
    b = found[0]
    return {**edge, "value": b.value, "kind": b.kind, "stability": b.stability, "xtol": b.xtol,
            "verdicts": list(b.verdicts), "method": b.method}
