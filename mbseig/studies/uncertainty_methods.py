"""The statistical methods of ``mbseig uncertainty``: the probability that a model is unstable
when its parameters are random, seen through one vectorized function.

The model is ``evaluate(X, stage) -> (delta, bound, code)``: for each row of ``X`` (physical
values of the inputs, in the order of ``inputs``) the least damping δ (NaN where the evaluation
failed), its error bound and the verdict code (:data:`CODES`: stable, critical, unstable,
failed).  ``stage`` names what asked for the rows (``"monte-carlo"``, ``"form"``,
``"form gradient"``, ``"subset level k"`` ...): every row evaluated is kept, in order, in
:class:`Evaluated`.

The inputs are independent (:class:`Input`: normal, lognormal or uniform).  Each has an exact
iso-probabilistic transform to a standard normal variable u; the origin of the standard space
(u = 0) is the inputs at their medians (for the normal and the uniform inputs also their
means).  The methods (:func:`estimate`):

- **monte-carlo**: ``samples`` draws of u ~ N(0, I) from ``numpy.random.default_rng(seed)``;
  P(unstable) = k/n with the exact (Clopper–Pearson) 95 % interval, the failed samples counted
  as possibly unstable at its upper end; the least-damping statistics; the drivers: first-order
  variance shares of δ from the same sample (SALib's given-data estimator);
- **form**: the first-order reliability method (OpenTURNS) on the event {δ < 0}: the design
  point (the point of the boundary δ = 0 nearest the origin of the standard space), the signed
  reliability index β (negative where the origin itself is unstable), P = Φ(−β) and the
  importance factors α_i² as drivers;
- **subset**: subset simulation (OpenTURNS) for small probabilities, ``samples`` per level
  (each level in blocks of at most its number of seeds, so that every Markov chain advances
  from the state the previous block left); a point already solved is not solved again.  Its
  estimate is taken only where the last level reached δ < 0; where the levels stop above it,
  P(unstable) is 0 with the last level's probability as the upper end of the interval.  Where
  the origin is unstable, or the first level already ends the simulation, the answer is a
  plain Monte Carlo;
- **auto**: Monte Carlo, then subset simulation where Monte Carlo found fewer than
  :data:`AUTO_MIN_UNSTABLE` unstable samples.

Monte Carlo needs neither OpenTURNS nor SALib: both are imported inside the functions that use
them (``pip install 'mbseig[uncertainty]'``).  The same seed gives the same result, bit for bit.
"""

from __future__ import annotations

import contextlib
import math
import re
import warnings
from dataclasses import dataclass, field

import numpy as np
from scipy.special import ndtr, ndtri

from ..errors import MbseigError

__all__ = ["CODES", "Input", "parse_input", "Evaluated", "UncertaintyResult", "estimate",
           "METHODS", "DISTRIBUTIONS"]

#: the verdict codes of ``evaluate`` (0, 1, 2, 3)
CODES = ("stable", "critical", "unstable", "failed")
STABLE, CRITICAL, UNSTABLE, FAILED = range(4)
#: the methods of :func:`estimate`
METHODS = ("auto", "monte-carlo", "form", "subset")
#: the distributions and the names of their two arguments
DISTRIBUTIONS = {"normal": ("MU", "SIGMA"), "lognormal": ("MEDIAN", "SIGMA_LOG"),
                 "uniform": ("A", "B")}
#: the one-line hint where an optional library is missing
INSTALL_HINT = "pip install 'mbseig[uncertainty]'"

#: confidence level of every interval
CONFIDENCE = 0.95
#: auto: the Monte Carlo estimate stands where it found at least this many unstable samples
#: (its coefficient of variation is then at most about 1/sqrt(10) = 0.32)
AUTO_MIN_UNSTABLE = 10
#: drivers: the fewest non-failed samples the variance shares are estimated from
DRIVERS_MIN_SAMPLES = 100
#: drivers: bootstrap resamples of SALib's confidence of each share (its cost is linear in
#: them: 100 took 6.5 s of a 10⁵-sample study, 20 take 1.3 s; the interval is the bootstrap's
#: spread, a confidence of the share, not a value the verdicts use)
DRIVERS_RESAMPLES = 20
#: FORM: the centred finite-difference step of input i is this times max(|mean_i|, std_i)
#: (relative: the inputs' scales may differ by many orders of magnitude)
FORM_GRADIENT_STEP = 1e-5
#: FORM: the solvers' tolerances in the standard space (dimensionless): on the last step
#: (absolute and relative to |u|), and on the distance of the design point from the boundary
#: (|δ| there at most this times |∇_u δ| at the mean)
FORM_TOLERANCE = 1e-6
#: FORM: the solvers' largest number of iterations and of limit-state evaluations
FORM_MAX_ITERATIONS = 100
FORM_MAX_CALLS = 1000
#: subset simulation: the limit state given to a failed sample (no least damping): on the
#: unstable side of every threshold, so that a failed sample is never taken for stable
SUBSET_FAILED_VALUE = -1e300
#: subset simulation stops when the probability of an intermediate level falls below this
#: without reaching δ < 0 (the model is then unstable nowhere the levels could find)
SUBSET_MIN_PROBABILITY = 1e-10

_QUANTILES = ("0.01", "0.05", "0.5", "0.95", "0.99")
_CALL = re.compile(r"\s*([A-Za-z_][A-Za-z0-9_]*)\s*\((.*)\)\s*\Z", re.S)


# ---------------------------------------------------------------------------------------------
# inputs
# ---------------------------------------------------------------------------------------------
def _argument_problem(distribution: str, arguments: tuple) -> str | None:
    """What is wrong with the arguments of a distribution, or None."""
    names = DISTRIBUTIONS[distribution]
    for n, v in zip(names, arguments, strict=True):
        if not math.isfinite(v):
            return f"{n} must be a finite number, got {v!r}"
    a, b = arguments
    if distribution == "normal" and b <= 0:
        return f"SIGMA must be > 0, got {b!r}"
    if distribution == "lognormal" and a <= 0:
        return f"MEDIAN must be > 0, got {a!r}"
    if distribution == "lognormal" and b <= 0:
        return f"SIGMA_LOG must be > 0, got {b!r}"
    if distribution == "uniform" and b <= a:
        return f"B must exceed A, got A = {a!r}, B = {b!r}"
    return None


def _forms() -> str:
    return ", ".join(f"{d}({','.join(a)})" for d, a in DISTRIBUTIONS.items())


@dataclass(frozen=True)
class Input:
    """One random input: a real parameter of the case and its distribution.

    Parameters
    ----------
    name : str
        The parameter's name.
    distribution : {"normal", "lognormal", "uniform"}
    arguments : tuple of float
        ``(mu, sigma)``; ``(median, sigma_log)`` (ln X is normal with mean ln median and
        standard deviation sigma_log); ``(a, b)``.

    Raises
    ------
    ValueError
        An unknown distribution or arguments it cannot take (one line).
    """

    name: str
    distribution: str
    arguments: tuple

    def __post_init__(self):
        if self.distribution not in DISTRIBUTIONS:
            raise ValueError(f"unknown distribution {self.distribution!r}: expected {_forms()}")
        args = tuple(float(a) for a in self.arguments)
        if len(args) != 2:
            raise ValueError(f"{self.distribution} takes 2 arguments, got {len(args)}")
        problem = _argument_problem(self.distribution, args)
        if problem:
            raise ValueError(problem)
        object.__setattr__(self, "arguments", args)

    def to_x(self, u):
        """Physical values of standard normal values ``u`` (the exact iso-probabilistic
        transform: mu + sigma u; median exp(sigma_log u); a + (b − a) Φ(u))."""
        u = np.asarray(u, float)
        a, b = self.arguments
        if self.distribution == "normal":
            return a + b * u
        if self.distribution == "lognormal":
            return a * np.exp(b * u)
        return a + (b - a) * ndtr(u)

    def to_u(self, x):
        """Standard normal values of physical values ``x`` (the inverse of :meth:`to_x`)."""
        x = np.asarray(x, float)
        a, b = self.arguments
        if self.distribution == "normal":
            return (x - a) / b
        if self.distribution == "lognormal":
            with np.errstate(divide="ignore", invalid="ignore"):
                return np.log(x / a) / b
        return ndtri((x - a) / (b - a))

    @property
    def mean(self) -> float:
        """The distribution's mean (lognormal: median exp(sigma_log² / 2))."""
        a, b = self.arguments
        if self.distribution == "normal":
            return a
        if self.distribution == "lognormal":
            return a * math.exp(0.5 * b * b)
        return 0.5 * (a + b)

    @property
    def std(self) -> float:
        """The distribution's standard deviation."""
        a, b = self.arguments
        if self.distribution == "normal":
            return b
        if self.distribution == "lognormal":
            return self.mean * math.sqrt(math.expm1(b * b))
        return (b - a) / math.sqrt(12.0)

    def to_json(self) -> dict:
        return {"name": self.name, "distribution": self.distribution,
                "arguments": [float(a) for a in self.arguments]}


def parse_input(name: str, text: str) -> Input:
    """The :class:`Input` ``name`` of a distribution written as ``text``.

    Parameters
    ----------
    name : str
    text : str
        ``normal(MU,SIGMA)``, ``lognormal(MEDIAN,SIGMA_LOG)`` or ``uniform(A,B)``; spaces
        allowed; the numbers in Python's float syntax (nothing is evaluated).

    Raises
    ------
    ValueError
        One line saying what is wrong, with ``text``: an unknown distribution, a wrong number
        of arguments, a number that is not one or not finite, sigma ≤ 0, sigma_log ≤ 0,
        median ≤ 0, a uniform with b ≤ a.
    """
    m = _CALL.match(text)
    if not m:
        raise ValueError(f"expected {_forms()}, got {text!r}")
    dist = m.group(1).lower()
    if dist not in DISTRIBUTIONS:
        raise ValueError(f"unknown distribution {m.group(1)!r} in {text!r}: expected "
                         f"{_forms()}")
    body = m.group(2).strip()
    parts = body.split(",") if body else []
    names = DISTRIBUTIONS[dist]
    if len(parts) != len(names):
        raise ValueError(f"{dist} takes {len(names)} arguments {dist}({','.join(names)}), "
                         f"got {len(parts)} in {text!r}")
    values = []
    for n, part in zip(names, parts, strict=True):
        s = part.strip()
        try:
            values.append(float(s))
        except ValueError:
            raise ValueError(f"{n} is not a number: {s!r} in {text!r}") from None
    problem = _argument_problem(dist, tuple(values))
    if problem:
        raise ValueError(f"{problem} in {text!r}")
    return Input(name, dist, tuple(values))


# ---------------------------------------------------------------------------------------------
# results
# ---------------------------------------------------------------------------------------------
@dataclass
class Evaluated:
    """Every model evaluation, in the order made (one row each).

    Attributes
    ----------
    x : ndarray (n, d)
        The inputs.
    delta : ndarray (n,)
        The least damping; NaN where the evaluation failed.
    bound : ndarray (n,)
        The error bound of each δ; NaN where failed.
    code : ndarray (n,) of int
        The verdict codes (:data:`CODES`).
    stage : list of str
        What asked for each row.
    """

    x: np.ndarray
    delta: np.ndarray
    bound: np.ndarray
    code: np.ndarray
    stage: list


@dataclass
class UncertaintyResult:
    """The estimate of :func:`estimate` (see :meth:`to_json` for the fields).

    ``notes`` are one-line sentences: what was chosen and why, the estimator's coefficient of
    variation, how failed samples were counted, adjustments of the drivers.  ``details`` holds
    each method's numbers (levels, thresholds, iterations, the tolerances used).
    """

    inputs: list
    method: str
    seed: int
    evaluations: int
    p_unstable: float
    ci95: tuple | None
    p_not_stable: float
    verdicts: dict
    least_damping: dict | None
    drivers: list
    design_point: dict | None
    reliability_index: float | None
    evaluated: Evaluated
    notes: list = field(default_factory=list)
    details: dict = field(default_factory=dict)

    def to_json(self) -> dict:
        """The result as plain JSON values (floats, ints, lists, dicts; None for NaN):
        method, evaluations, seed, p_unstable, ci95 ([lo, hi] or None), p_not_stable,
        verdicts, least_damping, drivers, design_point, reliability_index, inputs, notes,
        details."""
        return _plain({
            "method": self.method, "evaluations": int(self.evaluations), "seed": int(self.seed),
            "p_unstable": self.p_unstable,
            "ci95": None if self.ci95 is None else list(self.ci95),
            "p_not_stable": self.p_not_stable, "verdicts": dict(self.verdicts),
            "least_damping": self.least_damping, "drivers": list(self.drivers),
            "design_point": self.design_point, "reliability_index": self.reliability_index,
            "inputs": [i.to_json() for i in self.inputs],
            "notes": list(self.notes), "details": self.details})


def _plain(v):
    """``v`` with numpy values as Python ones and non-finite floats as None."""
    if isinstance(v, dict):
        return {str(k): _plain(x) for k, x in v.items()}
    if isinstance(v, (list, tuple, np.ndarray)):
        return [_plain(x) for x in v]
    if isinstance(v, (bool, np.bool_)):
        return bool(v)
    if isinstance(v, (int, np.integer)):
        return int(v)
    if isinstance(v, (float, np.floating)):
        v = float(v)
        return v if math.isfinite(v) else None
    return v


# ---------------------------------------------------------------------------------------------
# the model, recorded
# ---------------------------------------------------------------------------------------------
class _Recorder:
    """``evaluate`` with every row kept in order, its output checked (a non-finite δ with a
    verdict becomes failed), and for the methods that may ask for one point twice (FORM,
    subset simulation) a cache: a point already solved is not solved again."""

    def __init__(self, inputs, evaluate):
        self.d = len(inputs)
        self.evaluate = evaluate
        self.parts: list = []
        self.count = 0
        self.cache: dict = {}
        self.coerced = 0
        #: an exception raised inside a callback of OpenTURNS, re-raised as it was
        self.raised: BaseException | None = None

    def __call__(self, X, stage, *, cached=False):
        X = np.ascontiguousarray(np.asarray(X, float).reshape(-1, self.d))
        if not cached:
            return self._solve(X, stage)
        keys = [row.tobytes() for row in X]
        todo, seen = [], set()
        for i, k in enumerate(keys):
            if k not in self.cache and k not in seen:
                seen.add(k)
                todo.append(i)
        if todo:
            d, b, c = self._solve(X[todo], stage)
            for j, i in enumerate(todo):
                self.cache[keys[i]] = (d[j], b[j], c[j])
        got = [self.cache[k] for k in keys]
        return (np.array([g[0] for g in got], float), np.array([g[1] for g in got], float),
                np.array([g[2] for g in got], int))

    def _solve(self, X, stage):
        n = X.shape[0]
        out = self.evaluate(X, stage)
        delta, bound, code = (np.array(a, float).reshape(-1) for a in out)
        if not (delta.size == bound.size == code.size == n):
            raise ValueError(f"evaluate returned {delta.size}, {bound.size}, {code.size} values "
                             f"for {n} samples")
        if not np.all(np.isin(code, (STABLE, CRITICAL, UNSTABLE, FAILED))):
            raise ValueError(f"evaluate returned codes outside 0..3: {np.unique(code)}")
        code = code.astype(int)
        bad = (code != FAILED) & ~np.isfinite(delta)
        if bad.any():
            code[bad] = FAILED
            self.coerced += int(bad.sum())
        delta[code == FAILED] = np.nan
        bound[code == FAILED] = np.nan
        self.parts.append((X.copy(), delta, bound, code, [stage] * n))
        self.count += n
        return delta, bound, code

    def evaluated(self) -> Evaluated:
        if not self.parts:
            return Evaluated(np.zeros((0, self.d)), np.zeros(0), np.zeros(0), np.zeros(0, int),
                             [])
        return Evaluated(np.concatenate([p[0] for p in self.parts]),
                         np.concatenate([p[1] for p in self.parts]),
                         np.concatenate([p[2] for p in self.parts]),
                         np.concatenate([p[3] for p in self.parts]),
                         [s for p in self.parts for s in p[4]])


def _point(inputs, x) -> str:
    return ", ".join(f"{i.name} = {float(v):.6g}" for i, v in zip(inputs, x, strict=True))


def _seed32(seed: int) -> int:
    """A seed the libraries' generators take (32 bits): ``seed`` itself where it fits."""
    return int(seed) if seed < 2 ** 32 else int(np.random.SeedSequence(seed).generate_state(1)[0])


def _verdicts(code) -> dict:
    code = np.asarray(code, int)
    return {name: int(np.sum(code == k)) for k, name in enumerate(CODES)}


# ---------------------------------------------------------------------------------------------
# the pieces every method shares
# ---------------------------------------------------------------------------------------------
def _clopper_pearson(k: int, n: int) -> tuple:
    """The exact (Clopper–Pearson) interval of k successes of n at :data:`CONFIDENCE`; at
    k = 0 its upper end in closed form, 1 − (α/2)^(1/n)."""
    from scipy.stats import binomtest

    lo, hi = binomtest(int(k), int(n)).proportion_ci(CONFIDENCE, method="exact")
    if k == 0:
        lo, hi = 0.0, -math.expm1(math.log((1.0 - CONFIDENCE) / 2.0) / n)
    return float(lo), float(hi)


def _monte_carlo_estimate(code, notes, details, *, label="Monte Carlo",
                          key="monte_carlo") -> tuple:
    """(p_unstable, ci95, p_not_stable) of a plain sample's verdicts, with notes (and its
    numbers in ``details[key]``)."""
    v = _verdicts(code)
    n = int(np.asarray(code).size)
    ku, kf = v["unstable"], v["failed"]
    p = ku / n
    lo = _clopper_pearson(ku, n)[0]
    hi = _clopper_pearson(ku + kf, n)[1]
    se = math.sqrt(p * (1.0 - p) / n)
    if ku:
        notes.append(f"{label}: {ku} unstable of {n} samples; standard error {se:.3g} "
                     f"(coefficient of variation {se / p:.3g})")
    else:
        notes.append(f"{label}: no unstable sample of {n}: the estimate is 0 and the 95 % "
                     f"interval's upper end {hi:.3g} (exact binomial; not [0, 0])")
    if kf:
        notes.append(f"{label}: {kf} failed samples (no least damping): counted in 'failed' "
                     f"and in P(not stable), counted as possibly unstable at the upper end of "
                     f"the interval, left out of the least-damping statistics and drivers")
    details[key] = {"samples": n, "unstable": ku, "failed": kf, "p": p, "standard_error": se,
                    "interval": "Clopper-Pearson (exact binomial): lower end of the unstable "
                                "count, upper end of unstable + failed"}
    return p, (lo, hi), (v["critical"] + ku + kf) / n


def _damping_stats(delta, code) -> dict | None:
    """Mean, standard deviation and quantiles of δ over the samples that did not fail."""
    d = np.asarray(delta, float)[(np.asarray(code) != FAILED)]
    d = d[np.isfinite(d)]
    if d.size == 0:
        return None
    q = np.quantile(d, [float(k) for k in _QUANTILES])
    return {"mean": float(d.mean()), "std": float(d.std(ddof=1)) if d.size > 1 else 0.0,
            "quantiles": {k: float(v) for k, v in zip(_QUANTILES, q, strict=True)}}


def _drivers(inputs, X, delta, code, seed, notes, details, *, label="") -> list:
    """First-order variance shares of δ (SALib's given-data estimator, ``S1`` of
    ``SALib.analyze.delta.analyze``) over the samples that did not fail; [] with a note where
    SALib is missing, too few samples are left or δ does not vary.

    Estimator noise can make a share slightly negative or their sum exceed 1: negatives are
    set to 0 and then, where the sum exceeds 1, the shares are scaled to sum 1 (noted; the raw
    values in ``details["drivers"]``)."""
    try:
        from SALib.analyze import delta as salib_delta
    except ImportError:
        notes.append(f"drivers need SALib: {INSTALL_HINT}")
        return []
    ok = (np.asarray(code) != FAILED) & np.isfinite(delta)
    n_ok, n_failed = int(ok.sum()), int((~ok).sum())
    where = f" ({label})" if label else ""
    if n_ok < DRIVERS_MIN_SAMPLES:
        notes.append(f"drivers left out{where}: {n_ok} samples did not fail, fewer than "
                     f"{DRIVERS_MIN_SAMPLES}")
        return []
    Y = np.asarray(delta, float)[ok]
    Xo = np.asarray(X, float)[ok]
    if np.ptp(Y) == 0.0:
        notes.append(f"drivers left out{where}: the least damping does not vary")
        return []
    d = len(inputs)
    # SALib refuses some name suffixes: neutral names, mapped back below
    problem = {"num_vars": d, "names": [f"x{j}" for j in range(d)],
               "bounds": [[float(Xo[:, j].min()), float(Xo[:, j].max())] for j in range(d)]}
    # SALib draws its resamples from NumPy's global generator and changes the warning filters
    # and format: all saved and restored around the call
    state = np.random.get_state()
    fmt = warnings.formatwarning
    try:
        with warnings.catch_warnings(record=True):
            np.random.seed(_seed32(seed))
            res = salib_delta.analyze(problem, Xo, Y, num_resamples=DRIVERS_RESAMPLES,
                                      conf_level=CONFIDENCE, print_to_console=False,
                                      seed=None, method="sobol")
    finally:
        np.random.set_state(state)
        warnings.formatwarning = fmt
    raw = np.asarray(res["S1"], float)
    conf = np.asarray(res["S1_conf"], float)
    names = [i.name for i in inputs]
    info = {"estimator": "SALib.analyze.delta.analyze S1 (first-order, given data)",
            "samples": n_ok, "failed_left_out": n_failed, "resamples": DRIVERS_RESAMPLES,
            "raw": dict(zip(names, raw.tolist(), strict=True)),
            "conf95": dict(zip(names, conf.tolist(), strict=True))}
    if label:
        info["sample"] = label
    details["drivers"] = info
    if not np.all(np.isfinite(raw)):
        notes.append(f"drivers left out{where}: SALib could not estimate every share")
        return []
    shares = np.clip(raw, 0.0, None)
    total = shares.sum()
    if total > 1.0:
        shares = shares / total
    what = ([f"negative shares of {', '.join(n for n, r in zip(names, raw, strict=True) if r < 0)}"
             " (set to 0)"] if np.any(raw < 0) else [])
    if total > 1.0:
        what.append(f"shares summing to {total:.4g} (scaled to sum 1)")
    info["adjusted"] = bool(what)
    if what:
        notes.append(f"drivers: estimator noise gave {' and '.join(what)}; the raw values in "
                     f"details")
    if n_failed:
        notes.append(f"drivers from the {n_ok} samples that did not fail ({n_failed} left out)")
    order = sorted(range(d), key=lambda j: (-shares[j], j))
    return [{"name": names[j], "share": float(shares[j])} for j in order]


def _nearest(inputs, rec, *, unstable: bool):
    """(design point, |u|) of the evaluated sample nearest the origin of the standard space
    among those with δ < 0 (``unstable``) or δ > 0, failed ones left out; (None, None) if
    there is none."""
    ev = rec.evaluated()
    if ev.delta.size == 0:
        return None, None
    side = ev.delta < 0 if unstable else ev.delta > 0
    mask = (ev.code != FAILED) & np.isfinite(ev.delta) & side
    if not mask.any():
        return None, None
    U = np.column_stack([inp.to_u(ev.x[:, j]) for j, inp in enumerate(inputs)])[mask]
    with np.errstate(invalid="ignore", over="ignore"):
        r = np.sqrt(np.sum(U * U, axis=1))
    r = np.where(np.isfinite(r), r, np.inf)
    k = int(np.argmin(r))
    if not np.isfinite(r[k]):
        return None, None
    x = ev.x[mask][k]
    return {i.name: float(v) for i, v in zip(inputs, x, strict=True)}, float(r[k])


# ---------------------------------------------------------------------------------------------
# OpenTURNS
# ---------------------------------------------------------------------------------------------
def _openturns(what: str):
    try:
        import openturns as ot
    except ImportError:
        raise MbseigError(f"{what} needs OpenTURNS: {INSTALL_HINT}") from None
    return ot


@contextlib.contextmanager
def _ot_session(ot, seed=None):
    """OpenTURNS quiet (its warnings are reported in the notes and details instead) and, with
    a seed, its generator seeded; both restored after."""
    flags = ot.Log.Flags()
    state = ot.RandomGenerator.GetState()
    ot.Log.Show(ot.Log.NONE)
    if seed is not None:
        ot.RandomGenerator.SetSeed(_seed32(seed))
    try:
        yield
    finally:
        ot.Log.Show(flags)
        ot.RandomGenerator.SetState(state)


def _ot_distribution(ot, inputs):
    """The inputs' joint distribution (independent copula)."""
    marginals = []
    for inp in inputs:
        a, b = inp.arguments
        if inp.distribution == "normal":
            marginals.append(ot.Normal(a, b))
        elif inp.distribution == "lognormal":
            marginals.append(ot.LogNormal(math.log(a), b, 0.0))  # ln X ~ N(ln median, b)
        else:
            marginals.append(ot.Uniform(a, b))
    joint = getattr(ot, "JointDistribution", None) or ot.ComposedDistribution
    return joint(marginals)


def _ot_event(ot, inputs, function):
    """The event {δ < 0} of the limit state ``function`` of the inputs."""
    vector = ot.CompositeRandomVector(function, ot.RandomVector(_ot_distribution(ot, inputs)))
    return ot.ThresholdEvent(vector, ot.Less(), 0.0)


def _ot_message(exc) -> str:
    """The first line of an OpenTURNS exception, without its exception-class prefix and with
    its points printed as lists."""
    first = (str(exc).strip().splitlines() or [type(exc).__name__])[0]
    first = re.sub(r"^\w*Exception\s*:\s*", "", first)
    return re.sub(r"class=Point name=\S+ dimension=\d+ values=", "", first)


def _ot_failure(rec, exc, what):
    """The exception to raise for ``exc`` out of OpenTURNS: one raised by the model or by a
    rule of these methods inside a callback as it was, else a one-line MbseigError."""
    if rec.raised is not None:
        return rec.raised
    return MbseigError(f"{what} failed: {_ot_message(exc)}")


# ---------------------------------------------------------------------------------------------
# the methods
# ---------------------------------------------------------------------------------------------
def _monte_carlo_sample(inputs, rec, samples, seed):
    """(U, X, δ, bound, code) of ``samples`` standard normal draws, evaluated in one call."""
    rng = np.random.default_rng(seed)
    U = rng.standard_normal((samples, len(inputs)))
    X = np.column_stack([inp.to_x(U[:, j]) for j, inp in enumerate(inputs)])
    delta, bound, code = rec(X, "monte-carlo")
    return U, X, delta, bound, code


def _monte_carlo(inputs, rec, samples, seed, notes, details, sample=None) -> dict:
    """The fields of a Monte Carlo result (of ``sample`` where it is already evaluated)."""
    U, X, delta, bound, code = (sample if sample is not None
                                else _monte_carlo_sample(inputs, rec, samples, seed))
    p, ci, pns = _monte_carlo_estimate(code, notes, details)
    return {"method": "monte-carlo", "p_unstable": p, "ci95": ci, "p_not_stable": pns,
            "least_damping": _damping_stats(delta, code),
            "drivers": _drivers(inputs, X, delta, code, seed, notes, details),
            "design_point": None, "reliability_index": None}


def _dx_du(inp, u: float) -> float:
    """dx/du of the transform of ``inp`` at ``u``."""
    a, b = inp.arguments
    if inp.distribution == "normal":
        return b
    if inp.distribution == "lognormal":
        return a * b * math.exp(b * u)
    return (b - a) * math.exp(-0.5 * u * u) / math.sqrt(2.0 * math.pi)


def _form_scale(inputs, rec, x0, steps, delta0) -> tuple:
    """(scale, what it is) of the tolerance on |δ| at the design point: |∇_u δ| at the mean
    (the same finite differences as the solvers'), so that |δ| ≤ FORM_TOLERANCE · scale is a
    distance of FORM_TOLERANCE from the boundary in the standard space; |δ(mean)| (or 1) where
    that gradient vanishes."""
    d = len(inputs)
    H = np.diag(steps)
    X = np.vstack([x0 + H, x0 - H])
    dd, _, cc = rec(X, "form gradient", cached=True)
    bad = np.flatnonzero(cc == FAILED)
    if bad.size:
        raise MbseigError(f"FORM: the model failed at {_point(inputs, X[bad[0]])} (no least "
                          f"damping there, next to the mean): FORM needs every point it asks "
                          f"for; try --method subset or monte-carlo")
    grad_x = (dd[:d] - dd[d:]) / (2.0 * steps)
    dxdu = np.array([_dx_du(i, float(i.to_u(v))) for i, v in zip(inputs, x0, strict=True)])
    grad_u = float(np.linalg.norm(grad_x * dxdu))
    if math.isfinite(grad_u) and grad_u > 0:
        return grad_u, "|grad_u delta| at the mean"
    return (abs(delta0) or 1.0), "|delta| at the mean (zero gradient there)"


def _form(inputs, rec, notes, details) -> dict:
    """FORM on {δ < 0} from the mean (module docstring)."""
    ot = _openturns("FORM")
    d = len(inputs)
    names = [i.name for i in inputs]
    x0 = np.array([i.mean for i in inputs])
    steps = FORM_GRADIENT_STEP * np.array([max(abs(i.mean), i.std) for i in inputs])
    d0, _, c0 = rec(x0[None, :], "form", cached=True)
    if c0[0] == FAILED:
        raise MbseigError(f"FORM: the model failed at the mean ({_point(inputs, x0)}): FORM "
                          f"starts there; try --method monte-carlo or subset")
    scale, scale_from = _form_scale(inputs, rec, x0, steps, float(d0[0]))
    # the stage of the solver's points, and the last value of the limit state it was given
    # (the residual reported where it does not converge)
    stage = {"now": "form", "last": None}

    def limit_state(label):
        def g(X):
            try:
                X = np.asarray(X, float).reshape(-1, d)
                delta, _, code = rec(X, stage["now"] if label is None else label, cached=True)
                if label is None and delta.size:
                    stage["last"] = float(delta[-1])
                bad = np.flatnonzero(code == FAILED)
                if bad.size:
                    rec.raised = MbseigError(
                        f"FORM: the model failed at {_point(inputs, X[bad[0]])} (no least "
                        f"damping there): FORM needs every point it asks for; try --method "
                        f"subset or monte-carlo")
                    raise rec.raised
                return delta.reshape(-1, 1)
            except BaseException as exc:
                if rec.raised is None:
                    rec.raised = exc
                raise
        return ot.PythonFunction(d, 1, func_sample=g)

    function = limit_state(None)
    gradient = limit_state("form gradient").getEvaluation()
    function.setGradient(ot.CenteredFiniteDifferenceGradient(steps.tolist(), gradient))
    event = _ot_event(ot, inputs, function)
    tol_c = FORM_TOLERANCE * scale
    attempts, result, used = [], None, None
    for name, make, label in (("AbdoRackwitz", ot.AbdoRackwitz, "form"),
                              ("Cobyla", ot.Cobyla, "form cobyla")):
        stage["now"] = label
        solver = make()
        solver.setMaximumAbsoluteError(FORM_TOLERANCE)
        solver.setMaximumRelativeError(FORM_TOLERANCE)
        # AbdoRackwitz's residual |u + λ∇g| is 0 after any full step, so its residual criterion
        # holds wherever a step lands on the boundary, converged or not: the step criterion
        # alone decides (a residual tolerance of 0 is never met)
        solver.setMaximumResidualError(0.0 if name == "AbdoRackwitz" else FORM_TOLERANCE)
        solver.setMaximumConstraintError(tol_c)
        solver.setMaximumIterationNumber(FORM_MAX_ITERATIONS)
        solver.setMaximumCallsNumber(FORM_MAX_CALLS)
        solver.setCheckStatus(False)
        solver.setStartingPoint(x0.tolist())
        algo = ot.FORM(solver, event)
        before = rec.count
        error = None
        with _ot_session(ot):
            try:
                algo.run()
            except Exception as exc:
                if rec.raised is not None:
                    raise rec.raised from None
                error = _ot_message(exc)
        opt = None
        with contextlib.suppress(Exception):
            opt = algo.getResult().getOptimizationResult()
        info = {"solver": name, "evaluations": rec.count - before, "last_delta": stage["last"]}
        if opt is not None and opt.getInputSample().getSize():
            ae, re_, rese, ce = (opt.getAbsoluteError(), opt.getRelativeError(),
                                 opt.getResidualError(), opt.getConstraintError())
            info.update(iterations=int(opt.getIterationNumber()),
                        solver_calls=int(opt.getCallsNumber()), status=opt.getStatusMessage(),
                        absolute_error=ae, relative_error=re_, residual_error=rese,
                        constraint_error=ce)
        if error is None and opt is not None:
            converged = opt.getStatus() == ot.OptimizationResult.SUCCESS
            if name == "AbdoRackwitz":  # (it ends at its iteration limit without a failure)
                converged = converged and (0 <= info["absolute_error"] < FORM_TOLERANCE
                                           and info["relative_error"] < FORM_TOLERANCE)
            if not converged:
                error = f"not converged ({opt.getStatusMessage() or 'iteration limit'})"
        info["converged"] = error is None
        if error is not None:
            info["reason"] = error
        attempts.append(info)
        if error is None:
            result, used = algo.getResult(), name
            break
    details["form"] = {"start": dict(zip(names, x0.tolist(), strict=True)),
                       "gradient_steps": dict(zip(names, steps.tolist(), strict=True)),
                       "gradient_step_relative": FORM_GRADIENT_STEP,
                       "tolerance": FORM_TOLERANCE, "limit_state_scale": scale,
                       "limit_state_scale_is": scale_from,
                       "limit_state_tolerance": tol_c,
                       "max_iterations": FORM_MAX_ITERATIONS, "max_calls": FORM_MAX_CALLS,
                       "attempts": attempts, "solver": used}
    if result is None:
        last = attempts[-1]
        residual = last.get("constraint_error", last["last_delta"])
        why = "; ".join(f"{a['solver']}: {a['reason']}" for a in attempts)
        raise MbseigError(f"FORM did not converge from the mean ({_point(inputs, x0)}): {why}; "
                          f"last residual |delta| = "
                          + (f"{abs(residual):.3g}" if residual is not None else "unknown"))
    u = np.array(result.getStandardSpaceDesignPoint(), float)
    r = float(np.linalg.norm(u))
    origin_unstable = bool(result.getIsStandardPointOriginInFailureSpace())
    beta = -r if origin_unstable else r
    p = float(ndtr(-beta))
    x = [float(i.to_x(uj)) for i, uj in zip(inputs, u, strict=True)]
    details["form"].update(design_point_u=dict(zip(names, u.tolist(), strict=True)),
                           origin_unstable=origin_unstable,
                           iterations=attempts[-1].get("iterations"))
    if used != "AbdoRackwitz":
        notes.append(f"FORM: AbdoRackwitz did not converge ({attempts[0]['reason']}); Cobyla "
                     f"did")
    notes.append("FORM gives no interval: its error is the curvature of the boundary, not "
                 "sampling")
    notes.append(f"FORM: P(unstable) = Phi(-beta) on the event least damping < 0 (first "
                 f"order); P(not stable) the same (the critical band has no width to first "
                 f"order); {rec.count} models solved")
    if origin_unstable:
        notes.append("FORM: the inputs at their medians (the origin of the standard space) "
                     "are unstable: beta is negative, the design point is the nearest stable "
                     "point, P(unstable) > 0.5")
    if r > 0:
        alpha2 = (u / r) ** 2
        order = sorted(range(d), key=lambda j: (-alpha2[j], j))
        drivers = [{"name": names[j], "share": float(alpha2[j])} for j in order]
        notes.append("drivers: the FORM importance factors alpha_i^2, the variance shares of "
                     "the limit state linearized at the design point")
    else:
        drivers = []
        notes.append("drivers left out: the design point is the origin (beta = 0)")
    return {"method": "form", "p_unstable": p, "ci95": None, "p_not_stable": p,
            "least_damping": None, "drivers": drivers,
            "design_point": dict(zip(names, x, strict=True)), "reliability_index": beta}


def _level_block(samples: int, p0: float) -> tuple:
    """(seeds, block, blocks): OpenTURNS keeps int(p0 N) seeds of a level of N samples; a
    block of at most that many makes each of its Markov chains advance from the state the
    previous block left (a larger block restarts chains from their seeds); N = block × blocks
    exactly."""
    seeds = int(p0 * samples)
    block = max(b for b in range(1, max(seeds, 1) + 1) if samples % b == 0)
    return seeds, block, samples // block


def _subset(inputs, rec, samples, seed, notes, details, *, origin=None):
    """Subset simulation on {δ < 0} with ``samples`` per level; None where the origin of the
    standard space is unstable (the caller falls back to Monte Carlo: subset simulation is for
    small probabilities).  ``origin``: (δ, code) at the origin where already known."""
    ot = _openturns("subset simulation")
    d = len(inputs)
    names = [i.name for i in inputs]
    x_origin = np.array([float(i.to_x(0.0)) for i in inputs])
    if origin is None:
        d0, _, c0 = rec(x_origin[None, :], "subset origin", cached=True)
        origin = (float(d0[0]), int(c0[0]))
    info = {"origin": dict(zip(names, x_origin.tolist(), strict=True)),
            "origin_least_damping": origin[0], "origin_verdict": CODES[origin[1]]}
    details["subset"] = info
    if origin[1] == FAILED or origin[0] < 0:
        info["origin_unstable"] = True
        return None
    info["origin_unstable"] = False
    p0 = float(ot.ResourceMap.GetAsScalar("SubsetSampling-DefaultConditionalProbability"))
    seeds, block, blocks = _level_block(samples, p0)
    if seeds < 1:
        raise MbseigError(f"subset simulation needs at least {math.ceil(1 / p0)} samples per "
                          f"level (--samples), got {samples}")
    calls = {"n": 0}
    start = rec.count
    per_level: dict = {}

    def g(X):
        try:
            X = np.asarray(X, float).reshape(-1, d)
            level = calls["n"] // blocks
            calls["n"] += 1
            before = rec.count
            delta, _, code = rec(X, f"subset level {level}", cached=True)
            per_level[level] = per_level.get(level, 0) + rec.count - before
            out = np.where(code == FAILED, SUBSET_FAILED_VALUE, delta)
            return out.reshape(-1, 1)
        except BaseException as exc:
            rec.raised = exc
            raise

    event = _ot_event(ot, inputs, ot.PythonFunction(d, 1, func_sample=g))
    algo = ot.SubsetSampling(event)
    algo.setMaximumOuterSampling(blocks)
    algo.setBlockSize(block)
    algo.setMinimumProbability(SUBSET_MIN_PROBABILITY)
    below = False
    with _ot_session(ot, seed):
        try:
            algo.run()
        except Exception as exc:
            steps = list(algo.getProbabilityEstimatePerStep())
            if rec.raised is not None or not (steps and steps[-1] < SUBSET_MIN_PROBABILITY):
                raise _ot_failure(rec, exc, "subset simulation") from None
            below = True
    thresholds = list(algo.getThresholdPerStep())
    probabilities = list(algo.getProbabilityEstimatePerStep())
    covs = list(algo.getCoefficientOfVariationPerStep())
    gammas = list(algo.getGammaPerStep())
    levels = len(probabilities)
    info.update(samples_per_level=samples, conditional_probability=p0, seeds_per_level=seeds,
                block_size=block, blocks_per_level=blocks, levels=levels,
                failed_value=SUBSET_FAILED_VALUE, minimum_probability=SUBSET_MIN_PROBABILITY,
                evaluations=rec.count - start,
                per_level=[{"level": k, "threshold": thresholds[k] if k < len(thresholds)
                            else None, "probability": probabilities[k],
                            "coefficient_of_variation": covs[k] if k < len(covs) else None,
                            "gamma": gammas[k] if k < len(gammas) else None,
                            "evaluations": per_level.get(k, 0)} for k in range(levels)])
    if block < seeds:
        notes.append(f"subset: {samples} samples per level is not a multiple of "
                     f"{round(1 / p0)}: {blocks} blocks of {block} per level (more model calls)")
    ev = rec.evaluated()
    level0 = np.array([s == "subset level 0" for s in ev.stage], bool)
    out = {"level0": (ev.x[level0], ev.delta[level0], ev.code[level0]), "levels": levels}
    sub = ev.code[np.array([s.startswith("subset") for s in ev.stage], bool)]
    if np.any(sub == FAILED):
        notes.append(f"subset: {int(np.sum(sub == FAILED))} failed samples given the limit "
                     f"state {SUBSET_FAILED_VALUE:g}: counted on the unstable side "
                     f"(conservative)")
    z = float(ndtri(0.5 + CONFIDENCE / 2.0))
    if levels == 1 and not below:
        # one level: the estimate is the Monte Carlo of that level
        out["plain"] = True
        out["level0_unstable_fraction"] = float(np.mean(np.asarray(out["level0"][1]) < 0))
        return out
    info["reached"] = reached = (not below) and thresholds[-1] == 0.0
    if not reached:
        # the levels stopped above δ = 0: at the probability floor, or (OpenTURNS) where a
        # level's every sample fell below its threshold; its estimate is then P(δ < t_last),
        # an upper bound of P(δ < 0), not the estimate of it
        p_last, t_last = probabilities[-1], thresholds[-1]
        hi = min(1.0, p_last * math.exp(z * (covs[-1] if covs else 0.0)))
        levels_rows = np.array([s.startswith("subset level") for s in ev.stage], bool)
        hit = int(np.sum(((ev.delta < 0) | (ev.code == FAILED)) & levels_rows))
        why = (f"its probability fell below {SUBSET_MIN_PROBABILITY:g}" if below else
               "every sample of a level fell below its threshold")
        if hit == 0:
            out.update(p=0.0, ci=(0.0, hi), cov=None)
            notes.append(f"subset: no level reached least damping < 0 ({why}; last threshold "
                         f"{t_last:.4g}, P(least damping < {t_last:.4g}) = {p_last:.3g}): "
                         f"P(unstable) is estimated 0, at most {hi:.3g}")
        else:
            out.update(p=p_last, ci=(0.0, hi), cov=None)
            notes.append(f"subset: the levels stopped at threshold {t_last:.4g} > 0 ({why}) "
                         f"with {hit} samples below 0: P(unstable) is given as P(least "
                         f"damping < {t_last:.4g}) = {p_last:.3g}, an upper bound")
        return out
    res = algo.getResult()
    p = float(res.getProbabilityEstimate())
    cov = float(res.getCoefficientOfVariation())
    out.update(p=p, ci=(p * math.exp(-z * cov), min(1.0, p * math.exp(z * cov))), cov=cov)
    notes.append(f"subset: {levels} levels of {samples} samples, coefficient of variation "
                 f"{cov:.3g}; 95 % interval p exp(+-1.96 cov) (lognormal approximation)")
    notes.append("subset: P(not stable) = P(unstable): one event, least damping < 0, is "
                 "estimated")
    return out


def _subset_result(inputs, rec, samples, seed, notes, details, *, mc=None, origin=None):
    """The fields of a subset result; ``mc``: the Monte Carlo sample auto ran first (its
    least-damping statistics and drivers are reported)."""
    sub = _subset(inputs, rec, samples, seed, notes, details, origin=origin)
    if sub is None:
        what = ("the model failed at the inputs' medians (counted not stable)"
                if details["subset"]["origin_verdict"] == "failed"
                else "the inputs at their medians are unstable")
        notes.append(f"subset: {what}, so P(unstable) is not small (subset simulation is for "
                     f"small probabilities): Monte Carlo "
                     + ("above" if mc is not None else f"with {samples} samples") + " instead")
        out = _monte_carlo(inputs, rec, samples, seed, notes, details, sample=mc)
        dp, r = _nearest(inputs, rec, unstable=False)
        if dp is not None:
            out.update(design_point=dp, reliability_index=-r)
            notes.append("design point: the stable sample nearest the medians in the standard "
                         "space; beta = minus its distance")
        return out
    if mc is not None:
        _, X0, delta0, _, code0 = mc
        label = "the Monte Carlo sample"
    else:
        X0, delta0, code0 = sub["level0"]
        label = "subset level 0"
        notes.append("subset: least damping statistics and drivers from level 0 (a plain "
                     "Monte Carlo sample)")
    if sub.get("plain"):
        p, ci, pns = _monte_carlo_estimate(sub["level0"][2], notes, details,
                                           label="subset level 0", key="subset_level0")
        why = ("at least the conditional probability of its samples have least damping < 0"
               if sub["level0_unstable_fraction"] >= details["subset"]["conditional_probability"]
               else "its least damping does not vary enough to set a next level")
        notes.append(f"subset: simulation ended at level 0 ({why}): the Monte Carlo estimate "
                     f"of that level is the answer")
    else:
        p, ci, pns = sub["p"], sub["ci"], sub["p"]
    out = {"method": "subset", "p_unstable": p, "ci95": ci, "p_not_stable": pns,
           "least_damping": _damping_stats(delta0, code0),
           "drivers": _drivers(inputs, X0, delta0, code0, seed, notes, details, label=label),
           "design_point": None, "reliability_index": None}
    dp, r = _nearest(inputs, rec, unstable=True)
    if dp is not None:
        out.update(design_point=dp, reliability_index=r)
        notes.append("design point: the unstable sample nearest the medians in the standard "
                     "space (of all evaluated); beta its distance (at least the exact one)")
    return out


def estimate(inputs, evaluate, *, method="auto", samples=10_000, seed=0) -> UncertaintyResult:
    """The probability that the model is unstable under the random ``inputs``.

    Parameters
    ----------
    inputs : sequence of Input
        Independent random inputs, distinct names.
    evaluate : callable
        ``evaluate(X, stage) -> (delta, bound, code)``: X (n, d) physical values (columns in
        the order of ``inputs``); the least damping (NaN where failed), its error bound and the
        verdict codes (:data:`CODES`), each (n,).  Called on whole samples: once for Monte
        Carlo, once per block of a subset level, once per FORM point or gradient.
    method : {"auto", "monte-carlo", "form", "subset"}
    samples : int
        Monte Carlo samples; for subset simulation the samples per level.
    seed : int
        The seed: the same seed gives the same result.

    Returns
    -------
    UncertaintyResult

    Raises
    ------
    MbseigError
        FORM or subset simulation without OpenTURNS, FORM that does not converge or meets a
        failed evaluation, subset simulation that OpenTURNS cannot complete.
    ValueError
        Bad arguments, or an ``evaluate`` that breaks its contract.
    """
    inputs = list(inputs)
    if not inputs or not all(isinstance(i, Input) for i in inputs):
        raise ValueError("inputs must be a non-empty sequence of Input")
    names = [i.name for i in inputs]
    if len(set(names)) != len(names):
        raise ValueError(f"input names must be distinct, got {names}")
    if method not in METHODS:
        raise ValueError(f"method must be one of {', '.join(METHODS)}, got {method!r}")
    if isinstance(samples, bool) or int(samples) != samples or samples < 1:
        raise ValueError(f"samples must be a positive integer, got {samples!r}")
    if isinstance(seed, bool) or int(seed) != seed or seed < 0:
        raise ValueError(f"seed must be a non-negative integer, got {seed!r}")
    samples, seed = int(samples), int(seed)
    rec = _Recorder(inputs, evaluate)
    notes: list = []
    details: dict = {"settings": {"confidence": CONFIDENCE}}
    settings = details["settings"]
    if method in ("auto", "monte-carlo", "subset"):
        settings.update(drivers_min_samples=DRIVERS_MIN_SAMPLES,
                        drivers_resamples=DRIVERS_RESAMPLES)
    if method == "monte-carlo":
        out = _monte_carlo(inputs, rec, samples, seed, notes, details)
    elif method == "form":
        settings.update(form_gradient_step=FORM_GRADIENT_STEP, form_tolerance=FORM_TOLERANCE,
                        form_max_iterations=FORM_MAX_ITERATIONS, form_max_calls=FORM_MAX_CALLS)
        out = _form(inputs, rec, notes, details)
    elif method == "subset":
        settings.update(subset_failed_value=SUBSET_FAILED_VALUE,
                        subset_minimum_probability=SUBSET_MIN_PROBABILITY)
        out = _subset_result(inputs, rec, samples, seed, notes, details)
    else:
        settings.update(auto_min_unstable=AUTO_MIN_UNSTABLE)
        out = _auto(inputs, rec, samples, seed, notes, details)
    if rec.coerced:
        notes.insert(0, f"{rec.coerced} evaluations gave a non-finite least damping with a "
                        f"verdict: counted failed")
    ev = rec.evaluated()
    return UncertaintyResult(
        inputs=inputs, method=out["method"], seed=seed, evaluations=rec.count,
        p_unstable=float(out["p_unstable"]),
        ci95=None if out["ci95"] is None else tuple(float(c) for c in out["ci95"]),
        p_not_stable=float(out["p_not_stable"]), verdicts=_verdicts(ev.code),
        least_damping=out["least_damping"], drivers=out["drivers"],
        design_point=out["design_point"],
        reliability_index=(None if out["reliability_index"] is None
                           else float(out["reliability_index"])),
        evaluated=ev, notes=notes, details=details)


def _auto(inputs, rec, samples, seed, notes, details) -> dict:
    """Monte Carlo; subset simulation where it found fewer than AUTO_MIN_UNSTABLE unstable
    samples."""
    mc = _monte_carlo_sample(inputs, rec, samples, seed)
    ku = int(np.sum(mc[4] == UNSTABLE))
    if ku >= AUTO_MIN_UNSTABLE:
        notes.append(f"auto: Monte Carlo found {ku} unstable samples (at least "
                     f"{AUTO_MIN_UNSTABLE}): its estimate stands")
        return _monte_carlo(inputs, rec, samples, seed, notes, details, sample=mc)
    try:
        _openturns("subset simulation")
    except MbseigError as exc:
        notes.append(f"auto: Monte Carlo found {ku} unstable samples (fewer than "
                     f"{AUTO_MIN_UNSTABLE}); {exc.message}: the Monte Carlo estimate stands")
        return _monte_carlo(inputs, rec, samples, seed, notes, details, sample=mc)
    notes.append(f"auto: Monte Carlo found {ku} unstable samples (fewer than "
                 f"{AUTO_MIN_UNSTABLE}): subset simulation with {samples} samples per level; "
                 f"the least-damping statistics and drivers are the Monte Carlo sample's; "
                 f"evaluations count both")
    details["settings"].update(subset_failed_value=SUBSET_FAILED_VALUE,
                               subset_minimum_probability=SUBSET_MIN_PROBABILITY)
    out = _subset_result(inputs, rec, samples, seed, notes, details, mc=mc)
    if out["method"] == "subset":
        _monte_carlo_estimate(mc[4], [], details)  # (the Monte Carlo's own numbers, in details)
    return out
