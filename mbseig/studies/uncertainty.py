"""The models of ``mbseig uncertainty``: the least damping and the verdict of many parameter
samples, solved together where they can be.

A sample is a point of the inputs' space (one value of each random parameter, the others as
the case and ``--param NAME=VALUE`` give them).  Its stability is what ``mbseig modes`` gives
at that point: the same reference motion, the same verdict rule (:mod:`mbseig.modal.scope`:
the rigid-body modes by construction left out).  Its **least damping** δ is

- at rest, δ = −Re s of the least-damped eigenvalue that is not rigid-body (a model whose only
  modes are rigid-body, or whose rigid-body modes the verdict counts, has δ = 0);
- in steady motion, the same over the mode rows that are not declared rigid-body;
- in periodic motion, δ = −max ln|μ| / T over the Floquet multipliers,

each with its error bound (the eigenvalue's stability tolerance; for a multiplier b/|μ|/T).

**Samples at rest are solved together** (:func:`~mbseig.studies.batch_line.batch_line` with
``samples=True``): a task's samples are ordered by their first input, so that neighbours are
close, and the model maker updates only the force scalars (or body masses) the random
parameters enter (:func:`~mbseig.studies.continuation.family_maker` over all of them at once).
Newton starts every sample from the nominal equilibrium (the inputs at their medians) and, in
rounds, from converged neighbours; every sample must then be reached again from its neighbour's
equilibrium (no sample on another branch).  The modes of all of them come from
:func:`~mbseig.studies.spectra.point_spectra`.  Where the batch declines (its reason), the task
is split in two and each half tried again, down to ``ALONE`` samples, which are solved one at a
time as ``mbseig modes`` solves them (from the case's positions; the model from the same maker,
which equals a build).

Steady and periodic samples are solved one at a time (the one-point pipelines), in parallel
where the runner decides it pays.  A sample whose reference motion or modes fail is ``failed``
with its one-line error: never dropped, never called stable.
"""

from __future__ import annotations

import numpy as np

from ..errors import MbseigError
from ..model import Model
from ..statics.family import Family
from .batch_line import batch_line
from .boundaries import _Start
from .continuation import family_maker
from .uncertainty_methods import CODES as WORDS
from .uncertainty_methods import FAILED

__all__ = ["CHUNK", "ALONE", "uncertainty_study", "UncertaintyStudy", "check_inputs",
           "sample_task", "SampleEvaluator", "least_damping", "nominal_start"]

#: samples one task solves together (the batch's stacked work grows with them; a declined
#: batch is split, so a larger task only delays the split)
CHUNK = 1000
#: a declined batch is split down to this many samples, which are then solved one at a time
ALONE = 8
#: the verdict codes of :mod:`~mbseig.studies.uncertainty_methods` by their words
CODES = {w: k for k, w in enumerate(WORDS)}


def least_damping(spectrum) -> tuple:
    """(δ, bound) of a :class:`~mbseig.studies.spectra.PointSpectrum` (module docstring)."""
    s = np.asarray(spectrum.eigenvalues)
    tol = np.asarray(spectrum.tol, float)
    rigid = (np.zeros(s.size, bool) if spectrum.rigid is None
             else np.asarray(spectrum.rigid, bool))
    d = -s.real
    other = ~rigid
    if other.any():
        k = int(np.argmin(np.where(other, d, np.inf)))
        delta, bound = float(d[k]), float(tol[k])
    else:  # no mode but rigid-body ones: critical (DESIGN §6)
        return 0.0, float(np.max(tol, initial=0.0))
    if rigid.any() and str.__str__(spectrum.verdict) == "critical" and delta > bound:
        # the rigid-body modes beyond the declared directions count as critical (δ = 0)
        return 0.0, float(np.max(tol[rigid]))
    return delta, bound


def _rest_one(spec, config, params, opts, make=None):
    """(δ, bound, code, error) of one sample at rest, as ``mbseig modes`` solves it: its model
    built (or ``make()``, the lean maker's model, equal to the build), its equilibrium from the
    case's positions, its modes."""
    from ..statics import equilibrium
    from .continuation import linear_point
    from .spectra import point_spectra

    try:
        model = spec.build(config, **params) if make is None else make()
        eq = equilibrium(model, offer_stable=False, self_stress="report")
        sp = point_spectra([linear_point(eq.model, eq)], **opts)[0]
        if isinstance(sp, BaseException):
            raise sp
    except MbseigError as exc:
        return np.nan, np.nan, FAILED, exc.one_line()
    d, b = least_damping(sp)
    return d, b, CODES[str.__str__(sp.verdict)], None


def _steady_one(spec, config, params, opts):
    from .steady_sweep import _steady_point

    try:
        pt = _steady_point(spec, config, params)
    except MbseigError as exc:
        return np.nan, np.nan, FAILED, exc.one_line()
    rows = [r for r in pt.modes if not r.get("rigid_body")]
    if rows:
        r = min(rows, key=lambda r: r["delta"])
        d, b = float(r["delta"]), float(r["tolerance"])
    else:
        d, b = 0.0, max((float(r["tolerance"]) for r in pt.modes), default=0.0)
    return d, b, CODES[str.__str__(pt.verdict)], None


def _periodic_one(spec, config, params, opts):
    from .periodic import periodic_analysis

    try:
        fl = periodic_analysis(spec, config=config, params=params).floquet
    except MbseigError as exc:
        return np.nan, np.nan, FAILED, exc.one_line()
    mod = np.abs(fl.multipliers)
    k = int(np.argmax(mod))
    T = float(fl.period)
    d = -float(np.log(mod[k])) / T
    b = float(fl.error_bounds[k]) / max(float(mod[k]), np.finfo(float).tiny) / T
    return d, b, CODES[str.__str__(fl.verdict)], None


_ONE = {"rest": _rest_one, "steady": _steady_one, "periodic": _periodic_one}


def _together(spec, config, fixed, names, X, q_start, opts, out):
    """The samples X (rows) at rest solved together where the batch takes them (module
    docstring), into ``out`` = (δ, bound, code, errors) at the rows' positions."""
    from .spectra import point_spectra

    B = X.shape[0]
    rows = [tuple(float(v) for v in x) for x in X]
    make, _ = family_maker(spec, config, fixed, tuple(names))

    def make_t(t):
        return make(rows[int(t)])

    def many(ts):
        return make.many([rows[int(t)] for t in ts])

    make_t.many = many
    # (without a nominal equilibrium there is no start for a batch: each sample on its own)
    pending = [np.arange(B)] if q_start is not None else [np.arange(i, i + 1) for i in range(B)]
    while pending:
        idx = pending.pop()
        got = None
        if idx.size > ALONE:
            try:
                got = _batch(make_t, idx, q_start)
            except (MbseigError, np.linalg.LinAlgError, ValueError, FloatingPointError):
                got = None
        if got is None and idx.size > ALONE:
            half = idx.size // 2
            pending += [idx[half:], idx[:half]]
            continue
        if got is None:
            for i in idx:
                _put(out, i, _rest_one(spec, config, {**fixed, **dict(zip(names, rows[i],
                                                                        strict=True))}, opts,
                                       make=lambda i=i: make_t(i)))
            continue
        spectra = point_spectra(got, **opts)
        for i, sp in zip(idx, spectra, strict=True):
            if isinstance(sp, BaseException):
                _put(out, i, (np.nan, np.nan, FAILED,
                              sp.one_line() if isinstance(sp, MbseigError) else str(sp)))
            else:
                d, b = least_damping(sp)
                _put(out, i, (d, b, CODES[str.__str__(sp.verdict)], None))


def _batch(make_t, idx, q_start):
    """The linear models of the samples ``idx`` solved together, or None where the batch
    declines."""
    values = idx.astype(float)
    model0 = make_t(values[0])
    if not isinstance(model0, Model):  # (a linear case: matrices, no equilibrium)
        return None
    fam = Family(make_t, float(idx.size), model0, q_start)
    eqs, lins, _ = batch_line(fam, values, _Start(q_start), samples=True)
    return lins


def _put(out, i, got):
    d, b, c, e = got
    out[0][i], out[1][i], out[2][i] = d, b, c
    out[3][i] = e


def sample_task(spec, config, fixed, names, X, q_start, kind, opts) -> tuple:
    """(δ, bound, code, errors) of the samples X (n, d) of the inputs ``names`` (a pure,
    picklable task for the runners; module docstring).  q_start: the nominal equilibrium (at
    rest; None solves every sample on its own)."""
    X = np.asarray(X, float)
    n = X.shape[0]
    out = (np.full(n, np.nan), np.full(n, np.nan), np.full(n, FAILED, int),
           [None] * n)
    if kind == "rest":
        order = np.argsort(X[:, 0], kind="stable")  # (neighbours close in the first input)
        sub = (np.empty(n), np.empty(n), np.empty(n, int), [None] * n)
        _together(spec, config, fixed, names, X[order], q_start, opts, sub)
        for j, i in enumerate(order):
            _put(out, i, (sub[0][j], sub[1][j], sub[2][j], sub[3][j]))
        return out
    one = _ONE[kind]
    for i in range(n):
        _put(out, i, one(spec, config, {**fixed, **dict(zip(names, X[i], strict=True))}, opts))
    return out


class SampleEvaluator:
    """``evaluate(X, stage) -> (δ, bound, code)`` of :func:`estimate
    <mbseig.studies.uncertainty_methods.estimate>` over a case: the samples cut into tasks of
    CHUNK (steady and periodic: smaller), run by ``runner`` (in-process, processes or Dask, with
    its checkpoint: ``--resume``), each call a stage of its own.  ``errors`` keeps each
    evaluation's one-line error (None where it succeeded), in the order evaluated."""

    def __init__(self, spec, config, fixed, names, runner, *, kind, q_start=None,
                 safety=10.0, stability_rtol=1e-12):
        self.spec, self.config, self.fixed, self.names = spec, config, dict(fixed), list(names)
        self.runner, self.kind, self.q_start = runner, kind, q_start
        self.opts = {"safety": safety, "stability_rtol": stability_rtol}
        self.errors: list = []
        self._stages: dict = {}

    def __call__(self, X, stage):
        X = np.asarray(X, float)
        n = X.shape[0]
        k = self._stages.get(stage, 0)
        self._stages[stage] = k + 1
        label = stage if k == 0 else f"{stage} ({k + 1})"
        size = CHUNK if self.kind == "rest" else 16
        cuts = list(range(0, n, size))
        calls = [((self.spec, self.config, self.fixed, self.names, X[a:a + size],
                   self.q_start, self.kind, self.opts), {}) for a in cuts]
        got = self.runner.map(sample_task, calls, label,
                              points=[min(size, n - a) for a in cuts]) if calls else []
        d = np.concatenate([g[0] for g in got]) if got else np.zeros(0)
        b = np.concatenate([g[1] for g in got]) if got else np.zeros(0)
        c = np.concatenate([g[2] for g in got]).astype(int) if got else np.zeros(0, int)
        for g in got:
            self.errors += list(g[3])
        return d, b, c


def nominal_start(spec, config, fixed, names, x0):
    """The equilibrium coordinates at the inputs' medians ``x0`` (the start of every batch at
    rest), or None where it has none (each sample then on its own)."""
    from ..statics import equilibrium

    try:
        model = spec.build(config, **{**fixed, **dict(zip(names, map(float, x0), strict=True))})
        if not isinstance(model, Model):
            return None
        return np.asarray(equilibrium(model, offer_stable=False, self_stress="report").q, float)
    except MbseigError:
        return None


#: points of the boundary grid of a two-input scatter, per input (at rest; steady and
#: periodic samples are solved one at a time, so their grid is coarser)
GRID = 25
GRID_MOVING = 9


class UncertaintyStudy:
    """``mbseig uncertainty``'s result: the estimate (:class:`~mbseig.studies.uncertainty_methods.
    UncertaintyResult`), each evaluation's error (None where it succeeded), the reference kind,
    the fixed parameters, and for two inputs the least damping on a grid over the samples'
    range (``grid`` = (g1, g2, δ, bound); its evaluations are counted in ``grid_evaluations``,
    not in the estimate's)."""

    def __init__(self, case, config, kind, fixed, result, errors, grid, runner):
        self.case, self.config, self.kind, self.fixed = case, config, kind, dict(fixed)
        self.result, self.errors, self.grid, self.runner = result, errors, grid, runner

    @property
    def grid_evaluations(self) -> int:
        return 0 if self.grid is None else int(self.grid[2].size)

    def to_json(self) -> dict:
        out = {"case": self.case, **self.result.to_json()}
        out["config"] = self.config
        out["reference"] = self.kind
        out["parameters"] = dict(self.fixed)
        out["boundary_grid_evaluations"] = self.grid_evaluations
        return out


def check_inputs(spec, config, fixed, inputs):
    """Every input a real parameter of the case's ``[parameters]`` (after the configuration and
    the fixed overrides: numbers written as floats), named once, not also fixed; else a
    one-line CaseError naming it."""
    from ..casefile import CaseError
    from .design import sensitivity_parameters

    real = sensitivity_parameters(spec, config, None)
    seen = set()
    for inp in inputs:
        name = inp.name
        if name in seen:
            raise CaseError(f"{name!r} is given two distributions", element="--param",
                            file=spec.source)
        seen.add(name)
        if name in fixed:
            raise CaseError(f"{name!r} is both fixed and random", element="--param",
                            file=spec.source)
        if name not in real:
            raw = dict(spec.parameters)
            if config is not None:
                raw.update(spec.configurations.get(config, {}))
            why = ("is not a parameter of the case" if name not in raw else
                   "is computed from others (an expression), not a number of its own"
                   if isinstance(raw[name], str) else
                   "is an integer count, not a real parameter")
            raise CaseError(f"{name!r} {why}: a random input must be a real parameter of "
                            f"[parameters]", element="--param", file=spec.source)


def uncertainty_study(case, inputs, *, config=None, fixed=None, samples=10_000, seed=0,
                      method="auto", jobs=None, scheduler=None, progress=None, resume=None,
                      safety=10.0, stability_rtol=1e-12, grid=True) -> UncertaintyStudy:
    """The probability of instability of ``case`` under the random ``inputs``
    (:class:`~mbseig.studies.uncertainty_methods.Input`, independent), by ``method``
    (auto, monte-carlo, form, subset: :func:`~mbseig.studies.uncertainty_methods.estimate`),
    each sample's stability as ``mbseig modes`` gives it (module docstring).

    Parameters
    ----------
    case : str, pathlib.Path or CaseSpec
    inputs : list of Input
    config : str, optional
    fixed : dict, optional
        Parameters held at other values than the case's {name: value or expression}.
    samples, seed : int
        Samples (subset simulation: per level), and the seed (the same seed, the same result).
    jobs, scheduler, progress, resume
        As :func:`mbseig.studies.sweep.run_sweep` takes them: every batch of samples is a task
        of the runner, kept in ``resume`` as it completes.
    safety, stability_rtol : float
        The stability tolerance of each eigenvalue (:func:`mbseig.modes`).
    grid : bool
        With two inputs, also the least damping on a GRID × GRID grid over the samples' range
        (the boundary of the scatter figure).
    """
    from .point import as_spec
    from .reference import reference_kind
    from .runners import Runner
    from .uncertainty_methods import estimate

    spec = as_spec(case)
    fixed = dict(fixed or {})
    inputs = list(inputs)
    check_inputs(spec, config, fixed, inputs)
    names = [i.name for i in inputs]
    kind = reference_kind(spec)
    # the case at the inputs' medians, built once here: a bad case fails fast with its message
    x0 = [float(i.to_x(np.zeros(1))[0]) for i in inputs]
    if kind != "periodic":  # (a periodic case is built at each instant of its period)
        spec.build(config, **{**fixed, **dict(zip(names, x0, strict=True))})
    q_start = nominal_start(spec, config, fixed, names, x0) if kind == "rest" else None
    checkpoint = None
    if resume is not None:
        from .resume import Checkpoint, study_identity

        identity = study_identity(
            spec, study="uncertainty", config=config, fixed=fixed,
            inputs=[i.to_json() for i in inputs], samples=int(samples), seed=int(seed),
            method=method, safety=safety, stability_rtol=stability_rtol, grid=bool(grid))
        checkpoint = (resume.bind(identity) if isinstance(resume, Checkpoint)
                      else Checkpoint(resume, identity))
    with Runner(jobs=jobs, scheduler=scheduler, progress=progress, checkpoint=checkpoint,
                points=int(samples)) as runner:
        ev = SampleEvaluator(spec, config, fixed, names, runner, kind=kind, q_start=q_start,
                             safety=safety, stability_rtol=stability_rtol)
        result = estimate(inputs, ev, method=method, samples=int(samples), seed=int(seed))
        errors = list(ev.errors)  # (before the grid: its evaluations are not the estimate's)
        box = None
        if grid and len(inputs) == 2 and result.evaluated.x.shape[0] >= 2:
            box = _grid(ev, inputs, result.evaluated.x, GRID if kind == "rest" else GRID_MOVING)
    return UncertaintyStudy(spec.name, config, kind, fixed, result, errors, box, runner.kind)


def _grid(ev, inputs, X, n):
    """(g1, g2, δ, bound): the least damping on an n × n grid spanning the samples' range
    (5 % margin), for the δ = 0 contour of the scatter."""
    lo, hi = X.min(axis=0), X.max(axis=0)
    pad = 0.05 * np.where(hi > lo, hi - lo, np.maximum(np.abs(lo), 1.0))
    g = [np.linspace(lo[j] - pad[j], hi[j] + pad[j], n) for j in range(2)]
    # (a lognormal input stays positive, a uniform one in its support)
    for j, inp in enumerate(inputs):
        if inp.distribution == "lognormal":
            g[j] = np.linspace(max(lo[j] - pad[j], 0.5 * lo[j]), hi[j] + pad[j], n)
        elif inp.distribution == "uniform":
            g[j] = np.linspace(inp.arguments[0], inp.arguments[1], n)
    G1, G2 = np.meshgrid(g[0], g[1], indexing="ij")
    d, b, _ = ev(np.column_stack([G1.ravel(), G2.ravel()]), "boundary grid")
    return g[0], g[1], d.reshape(n, n), b.reshape(n, n)
