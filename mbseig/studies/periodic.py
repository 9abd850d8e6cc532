"""Floquet analysis of a periodic case (DESIGN §8, "Periodic motions").

    case with [motion] period ─► TimedModel ─► reference motion ─► linearization along it
        (t in points, joints,      (time-       (kinematics or      (M, C(t), K(t), Φ_q(t):
         drivers, forces)           sampled)     shooting)           trigonometric series)
    ─► monodromy of the projected variational equations ─► multipliers, bounds, verdict

The linearization along the reference (C = −∂g/∂q̇, K = −∂g/∂q + Σ λ*_k ∇²Φ_k, Φ_q) is
sampled at N instants of the period and held as a trigonometric series on the entries that are
nonzero at some sample (:mod:`mbseig.studies.floquet_sparse`); Φ̇_q is the series' derivative.
The monodromy integrates the Chebyshev interpolants of the projected A(t) on each segment of
the null-space path (:mod:`mbseig.studies.floquet_chebyshev`).  The two monodromy estimates of
:mod:`mbseig.studies.floquet` differ in both tolerance (1e-12, 1e-10) and samples (the second
on the grid shifted by half a step, with its own interpolants), so their difference also
measures the sampling and the interpolation; N is doubled until the two series agree to 1e-10.
"""

from __future__ import annotations

import json
import math
from dataclasses import dataclass, field

import numpy as np
import scipy.sparse as sp

from ..casefile.expr import evaluate
from ..casefile.fields import TIME, uses_time
from ..errors import CaseError, MbseigError
from ..model.timed import sample_time
from .floquet import FloquetError, FloquetResult, analyze, monodromy
from .floquet_chebyshev import chebyshev_system
from . import floquet_descriptor
from .floquet_descriptor import StepsNotSettled, descriptor_monodromy
from .floquet_paths import constrained_system
from .floquet_sparse import as_operator
from .periodic_motion import reference_motion, sample_linearization

__all__ = ["PeriodicAnalysis", "periodic_analysis", "PeriodicLinearization",
           "periodic_linearization", "linearize_periodic", "timed_model", "period_of",
           "check_time_fields", "forget_kept", "TIMED_SECTIONS"]

TIMED_SECTIONS = ("points", "joints", "forces")  # where a numeric field may use t
_UNTIMED_KEYS = {"name", "type", "repeat", "enabled", "fixed", "points", "bodies", "point",
                 "joint", "body", "sets", "sense", "follower"}
RTOLS = (1e-10, 1e-12)
SAMPLES = 16  # first sampling of the linearization; doubled until two samplings agree
#: from this many degrees of freedom on, the monodromy is integrated in the model's own sparse
#: coordinates (mbseig.studies.floquet_descriptor.descriptor_monodromy), below on the projected
#: system's Chebyshev interpolants (benchmarks/periodic_scaling.py, docs/periodic.md)
DESCRIPTOR_FROM_DOF = 100


def check_time_fields(data):
    """Refuse ``t`` where it cannot be: every section but points, joints, drivers and forces
    (parameters, masses, bodies, gravity, beams, ...), ``repeat``/``enabled``/names anywhere,
    and a point's ``position`` only (one line naming the element)."""
    for key, value in data.items():
        if key in TIMED_SECTIONS and isinstance(value, list):
            for k, item in enumerate(value):
                if not isinstance(item, dict):
                    continue
                for fname, fval in item.items():
                    bad = fname in _UNTIMED_KEYS or (key == "points" and fname != "position")
                    if bad and uses_time(fval):
                        raise CaseError(f"{fname} uses t, but it cannot depend on time",
                                        element=_label(key, k, item))
        elif (key not in ("motion", "expected", "source", "description", "title")
              and uses_time(value)):
            if isinstance(value, list):
                for k, item in enumerate(value):
                    if uses_time(item):
                        raise CaseError("uses t, but a field here cannot depend on time (only "
                                        "points, joints, drivers and forces may)",
                                        element=_label(key, k, item))
            if isinstance(value, dict):
                for name, item in value.items():
                    if uses_time(item):
                        raise CaseError("uses t, but a field here cannot depend on time (only "
                                        "points, joints, drivers and forces may)",
                                        element=f"{key}.{name}")
            raise CaseError("uses t, but it cannot depend on time", element=key)


def _label(section, k, item):
    label = f"{section}[{k}]"
    if isinstance(item, dict) and isinstance(item.get("name"), str):
        label += f" {item['name']!r}"
    return label


def period_of(data, parameters) -> float:
    """T from ``[motion] period`` (an expression of the parameters), positive and finite."""
    motion = data.get("motion", {})
    raw = motion.get("period")
    if uses_time(raw):
        raise CaseError("the period uses t, but it cannot depend on time", element="motion.period")
    extra = sorted(set(motion) - {"period"})
    if extra:
        raise CaseError(f"unknown field {extra[0]!r} with period (a periodic motion takes "
                        "period only)", element="motion")
    try:
        T = evaluate(raw, parameters)
    except MbseigError as exc:
        raise exc.located(element="motion.period") from None
    if not (math.isfinite(T) and T > 0):
        raise CaseError(f"period must be positive, got {T:g}", element="motion.period")
    return T


def timed_model(spec, *, config=None, params=None, samples=16):
    """The :class:`~mbseig.model.timed.TimedModel` of a periodic case at these parameters
    (and the parameters' values); every problem names the case file and the element."""
    try:
        return _timed_model(spec, config, params, samples)
    except MbseigError as exc:
        raise exc.located(file=spec.source) from None


def _timed_model(spec, config, params, samples):
    data = spec.data
    check_time_fields(data)
    table = data.get("parameters", {})
    if isinstance(table, dict) and TIME in table:
        raise CaseError("t is the time of a periodic case and cannot be a parameter",
                        element="parameters.t")
    timed_data = {**data, "parameters": {TIME: 0.0, **(table if isinstance(table, dict) else {})}}
    tspec = type(spec)(timed_data, spec.name, spec.source, spec.base_dir)
    params = dict(params or {})
    if TIME in params:
        raise CaseError("t is the time of a periodic case, not a parameter", element="--param")
    base = tspec.build(config, **params)
    if base.mass_elements:
        raise CaseError("periodic motions of co-rotational beams are not supported (their mass "
                        "depends on the configuration)", element="motion")
    parameters = {k: v for k, v in base.parameters.items() if k != TIME}
    T = period_of(data, parameters)

    def build_at(t):
        return tspec.build(config, **params, **{TIME: repr(float(t))})

    return sample_time(build_at, T, samples=samples), parameters


@dataclass(frozen=True)
class PeriodicAnalysis:
    """A periodic case analysed: the timed model, the reference motion, the sampled
    linearization (``samples`` instants) and the Floquet result; ``basis`` maps the Floquet
    state (y, p) at t = 0 to (δq, δq̇) in full coordinates."""

    #: the reference motion this belongs to (mbseig.studies.reference): a periodic orbit
    kind = "periodic"

    name: str
    parameters: dict
    timed: object = field(repr=False)
    reference: object = field(repr=False)
    floquet: FloquetResult
    samples: int
    sampling_difference: float
    dof: int
    basis: np.ndarray = field(repr=False)
    system: object = field(repr=False)

    @property
    def verdict(self) -> str:
        """The stability verdict of the Floquet multipliers."""
        return self.floquet.verdict

    def to_json(self) -> dict:
        """The ``mbseig modes --json`` object of a periodic case
        (:func:`mbseig.studies.periodic_listing.periodic_json`)."""
        from .periodic_listing import periodic_json

        return periodic_json(self)


def _system(M, fit, T, *, start=None):
    (C, K, J), Ms = fit, as_operator(M)
    return constrained_system(lambda t: Ms, C, K, J, lambda t: J(t, 1), T, start=start)


def _relative_difference(a, b):
    """max |a − b| / max(1, max |a|) of two samples (dense, CSR or None for zero)."""
    a = 0.0 if a is None else (a.toarray() if sp.issparse(a) else np.asarray(a))
    b = 0.0 if b is None else (b.toarray() if sp.issparse(b) else np.asarray(b))
    return (float(np.max(np.abs(a - b), initial=0.0))
            / max(1.0, float(np.max(np.abs(a), initial=0.0))))


@dataclass(frozen=True)
class PeriodicLinearization:
    """The linearization along the reference motion, sampled twice (on N instants and on
    the grid shifted by half a step) as trigonometric series, and its projected systems."""

    #: the reference motion this belongs to (mbseig.studies.reference): sampled A(t), the
    #: monodromy map
    kind = "periodic"

    timed: object
    parameters: dict
    reference: object
    samples: int
    sampling_difference: float
    system: object  # ConstrainedLinearization on the first sampling
    check: object  # the same on the shifted sampling, from the same basis at t = 0
    #: the two samplings' series (C, K, Φ_q) themselves, for the products in the model's own
    #: coordinates (mbseig.studies.floquet_descriptor)
    fits: tuple = field(default=(), repr=False)


_KEPT: dict = {}  # the last few results of one process (a report, a test runs a case twice)


def _kept(kind, spec, config, params, extra, compute):
    try:
        key = (kind, spec.source, json.dumps(spec.data, sort_keys=True, default=repr), config,
               tuple(sorted((params or {}).items())), extra)
    except (TypeError, ValueError):
        return compute()
    if key not in _KEPT:
        if len(_KEPT) >= 8:
            _KEPT.pop(next(iter(_KEPT)))
        _KEPT[key] = compute()
    return _KEPT[key]


def forget_kept():
    """Drop the results kept in this process (a benchmark measures cold runs)."""
    _KEPT.clear()


def periodic_linearization(spec, *, config=None, params=None, samples=SAMPLES,
                           max_samples=1024) -> PeriodicLinearization:
    """Reference motion and sampled linearization of a periodic case (module docstring)."""
    return _kept("linearization", spec, config, params, (samples, max_samples),
                 lambda: _periodic_linearization(spec, config, params, samples, max_samples))


def _periodic_linearization(spec, config, params, samples, max_samples):
    timed, parameters = timed_model(spec, config=config, params=params)
    try:
        ref = reference_motion(timed)
    except MbseigError as exc:
        raise exc.located(file=spec.source) from None
    except (np.linalg.LinAlgError, ArithmeticError) as exc:
        raise FloquetError(f"the reference motion failed: {exc}", element="motion",
                           file=spec.source) from None
    return linearize_periodic(timed, ref, samples=samples, max_samples=max_samples,
                              parameters=parameters, file=spec.source)


def linearize_periodic(timed, ref, *, samples=SAMPLES, max_samples=1024, parameters=None,
                       file=None) -> PeriodicLinearization:
    """The linearization of a timed model along its periodic reference motion ``ref``
    (:func:`mbseig.studies.periodic_motion.reference_motion`), sampled on ``samples`` instants a
    period, doubled up to ``max_samples`` until the shifted sampling agrees to 1e-10."""
    try:
        T = timed.period
        M = ref.partition.M
        N = samples
        while True:
            fit = sample_linearization(ref, N, 0.0, sparse=True)
            fit2 = sample_linearization(ref, N, 0.5 * T / N, sparse=True)
            probe = np.linspace(0.0, T, 7)[1:-1] + 0.01 * T
            diff = max(_relative_difference(a(t), b(t)) for a, b in zip(fit, fit2, strict=True)
                       for t in probe)
            if diff <= 1e-10 or 2 * N > max_samples:
                break
            N *= 2
        sys1 = _system(M, fit, T)
        sys2 = _system(M, fit2, T, start=sys1.path.bases[0])
    except MbseigError as exc:
        raise exc.located(file=file) from None
    except (np.linalg.LinAlgError, ArithmeticError) as exc:
        raise FloquetError(f"the linearization along the reference motion failed: {exc}",
                           element="motion", file=file) from None
    if parameters is None:
        parameters = {k: v for k, v in timed.base.parameters.items() if k != TIME}
    return PeriodicLinearization(timed, parameters, ref, N, diff, sys1, sys2, (fit, fit2))


def periodic_analysis(spec, *, config=None, params=None, rtols=RTOLS, samples=SAMPLES,
                      max_samples=1024) -> PeriodicAnalysis:
    """Floquet multipliers of a periodic case's reference motion (module docstring)."""
    return _kept("analysis", spec, config, params, (tuple(rtols), samples, max_samples),
                 lambda: _periodic_analysis(spec, config, params, rtols, samples, max_samples))


def _periodic_analysis(spec, config, params, rtols, samples, max_samples):
    lin = periodic_linearization(spec, config=config, params=params, samples=samples,
                                 max_samples=max_samples)
    T, M = lin.timed.period, lin.reference.partition.M
    sys1, sys2 = lin.system, lin.check
    N0, Nd0 = sys1.path.derivative(0.0, 0)
    r = N0.shape[1]
    G = np.linalg.inv(N0.T @ M @ N0)
    H = (M @ N0).T @ Nd0
    # (y, p) ↦ (δq, δq̇) at t = 0: the projected system's state in the model's coordinates
    basis = np.block([[N0, np.zeros((N0.shape[0], r))], [Nd0 - N0 @ G @ H, N0 @ G]])
    try:
        lo, hi = sorted(rtols)
        Phi, why = None, ""
        if r >= DESCRIPTOR_FROM_DOF:
            try:
                Phi, Phi2, steps = descriptor_monodromy(M, lin.fits, T, basis, rtol=hi)
                method = (f"variational equations in the model's coordinates, every column at "
                          f"once (index-1 form, sparse solves; Butcher's order-6 Runge–Kutta, "
                          f"{steps} fixed steps a period, the check at {max(steps // 2, 1)}); "
                          f"{lin.samples} samples of the linearization per period")
                tolerances = (hi,)
            except StepsNotSettled:  # too stiff for explicit steps: the projected system's
                Phi, why = None, (f"; the model's-coordinates integration, tried at {r} DOF, "
                                  f"did not settle within {floquet_descriptor.FULL_MAX_STEPS} "
                                  "steps a period")
        if Phi is None:
            cheb1, rec = chebyshev_system(sys1.system)
            cheb2, _ = chebyshev_system(sys2.system)
            Phi = monodromy(cheb1, rtol=lo)
            Phi2 = monodromy(cheb2, rtol=hi)
            method = (f"variational equations projected on the constraints (DOP853 on "
                      f"Chebyshev interpolants of A(t), degree ≤ {max(rec['degrees'])} on each "
                      f"of {len(rec['degrees'])} segments; {lin.samples} samples of the "
                      f"linearization per period{why})")
            tolerances = (lo, hi)
        res = analyze(Phi, Phi2, T, sys1.system.trace_integral(), method=method,
                      tolerances=tolerances)
    except MbseigError as exc:
        raise exc.located(file=spec.source) from None
    except (np.linalg.LinAlgError, ArithmeticError) as exc:
        raise FloquetError(f"the monodromy matrix failed: {exc}", element="monodromy",
                           file=spec.source) from None
    return PeriodicAnalysis(spec.name, lin.parameters, lin.timed, lin.reference, res,
                            lin.samples, lin.sampling_difference, r, basis, sys1)
