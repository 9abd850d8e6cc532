"""The model of a T-periodic case as a function of time (DESIGN §8, "Periodic motions").

    M q̈ + Φ_qᵀ(q, t) λ = g(q, q̇, t),        Φ(q, t) = 0,        Φ(q, t + T) = Φ(q, t)

A periodic case writes ``t`` in numeric fields of points, joints, drivers and forces.  The
reader builds an ordinary :class:`~mbseig.model.system.Model` at any instant; a
:class:`TimedModel` holds the model at t = 0 and, for every number of an element that changes
with time (a driver's target angle, a moving pivot's position, a force's vector), its samples
at N equally spaced instants of one period as a trigonometric interpolant

    f(t) = s t / T + Σ_|k|<N/2 c_k exp(2πi k t / T)

whose secular part s is zero except for a driver angle, where it is a whole number of turns
(w·t over a period 2π/w).  The interpolant is exact for trigonometric polynomials of degree
below N/2 (A cos ωt, w t); :func:`sample_time` doubles N until the interpolant reproduces the
model at off-grid instants and records that error (``interpolation_error``).

Time derivatives at fixed q (Φ_t, Φ_tt, Φ_qt) are five-point differences along the quadratic
Taylor curve of an element's numbers in t (exact for constraints at most quadratic in them, as
every natural-coordinate constraint is, rounding ≈ 1e-13 with the step 1e-2 T); the
constraint velocity and acceleration terms of a rheonomic constraint follow from them:

    Φ_q q̇ = −Φ_t,        Φ_q q̈ = γ(q, q̇) − 2 Φ_qt q̇ − Φ_tt.
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass, field

import numpy as np

from ..errors import CaseError
from ..numerics import DOUBLE_RANGE
from .trig_series import TrigSeries, in_range as _in_range

__all__ = ["TimedModel", "TrigSeries", "sample_time", "TIME_STEP", "PERIOD_MIN", "PERIOD_MAX"]

TIME_STEP = 1e-2  # step along the Taylor curve of the numbers, as a fraction of the period
_DRIFTING = {"angle_target"}  # element numbers that may advance by whole turns per period
# element numbers that only judge residuals (a constraint's scale, from the extent of the
# case's points): held at their value at t = 0, never sampled (a moving anchor would make them
# vary with kinks, which no interpolant of the period meets to 1e-12)
_MEASURES = {"length_scale"}
_MAX_SAMPLES = 512
# the shortest period the model holds: the interpolant's highest angular frequency
# 2π (N/2) / T, squared in a second time derivative, stays a double at N = _MAX_SAMPLES (and so
# does 1/(TIME_STEP T)² of the differences)
PERIOD_MIN = 2 * math.pi * (_MAX_SAMPLES // 2) / math.sqrt(np.finfo(float).max)
# the longest: the differences' 12 h² (h = TIME_STEP T) stays a double
PERIOD_MAX = math.sqrt(np.finfo(float).max / 12) / TIME_STEP


@dataclass(frozen=True)
class _Leaf:
    """One time-dependent number (or array) of an element: where it is, its interpolant."""

    where: tuple  # ("constraints" | "forces", index, field[, subfield]) or ("g_const",)
    element: str
    series: TrigSeries


def _leaves_of(obj, prefix):
    """(path, value) of every float or float-array field of an element (one nested level)."""
    out = []
    for f in dataclasses.fields(obj):
        v = getattr(obj, f.name)
        if isinstance(v, float) and not isinstance(v, bool):
            out.append(((*prefix, f.name), v))
        elif isinstance(v, np.ndarray) and v.dtype.kind == "f":
            out.append(((*prefix, f.name), v))
        elif dataclasses.is_dataclass(v) and not isinstance(v, type):
            out.extend(((*prefix, f.name, g.name), getattr(v, g.name))
                       for g in dataclasses.fields(v)
                       if isinstance(getattr(v, g.name), (float, np.ndarray)))
    return out


def _get(model, where):
    if where == ("g_const",):
        return model.g_const
    obj = getattr(model, where[0])[where[1]]
    for name in where[2:]:
        obj = getattr(obj, name)
    return obj


def _replace(element, path, value):
    if len(path) == 1:
        return dataclasses.replace(element, **{path[0]: value})
    inner = getattr(element, path[0])
    return dataclasses.replace(element, **{path[0]: _replace(inner, path[1:], value)})


def _differs(a, b):
    a, b = np.asarray(a, dtype=float), np.asarray(b, dtype=float)
    return a.shape != b.shape or not np.array_equal(a, b)


@dataclass(frozen=True, eq=False)
class TimedModel:
    """Model(t) of a T-periodic case (module docstring): ``at(t)`` gives the model at t, and
    phi, phi_q, hessian, g, force Jacobians and the rheonomic terms are evaluated at (q, t)."""

    base: object  # the Model at t = 0
    period: float
    leaves: tuple
    interpolation_error: float
    samples: int
    _kept: dict = field(default_factory=dict, repr=False, compare=False)

    @property
    def n(self):
        return self.base.n

    @property
    def time_dependent(self):
        """Names of the elements that change with time."""
        return tuple(dict.fromkeys(leaf.element for leaf in self.leaves))

    def _element_at(self, kind, k, t):
        el = getattr(self.base, kind)[k]
        values = self._leaf_values(t, 0)
        for j in self._by_element().get((kind, k), ()):
            leaf, value = self.leaves[j], values[j]
            if isinstance(_get(self.base, leaf.where), float):
                value = float(value)
            el = _replace(el, leaf.where[2:], value)
        return el

    def _by_element(self):
        if "by_element" not in self._kept:
            by = self._kept["by_element"] = {}
            for j, leaf in enumerate(self.leaves):
                by.setdefault(leaf.where[:2], []).append(j)
        return self._kept["by_element"]

    def _leaf_values(self, t, order):
        """Every leaf's value (order 0) or time derivative at t, by one product over the
        stacked coefficients of all leaves (the last few instants kept)."""
        kept = self._kept.setdefault("values", {})
        key = (float(t), order)
        if key not in kept:
            if len(kept) > 24:
                kept.clear()
            series = [leaf.series for leaf in self.leaves]  # one N and T (sample_time)
            if "stacked" not in self._kept:
                parts = [s._real for s in series]
                cuts = np.cumsum([0] + [p[0].shape[1] for p in parts])
                drift = np.concatenate([np.broadcast_to(np.asarray(s.drift, dtype=float),
                                                        s.coeffs.shape[1:]).ravel()
                                        for s in series])
                self._kept["stacked"] = (TrigSeries(np.hstack([p[0] + 1j * p[1] for p in parts]),
                                                    series[0].samples, series[0].period, drift),
                                         cuts)
            stacked, cuts = self._kept["stacked"]
            flat = stacked(t, order)
            kept[key] = [flat[a:b].reshape(s.coeffs.shape[1:]) for a, b, s
                         in zip(cuts[:-1], cuts[1:], series, strict=True)]
        return kept[key]

    @property
    def _timed_constraints(self):
        return sorted({leaf.where[1] for leaf in self.leaves if leaf.where[0] == "constraints"})

    def at(self, t):
        """The Model at time t (elements with the interpolated numbers; the last few kept)."""
        t = float(t)
        models = self._kept.setdefault("models", {})
        if t in models:
            return models[t]
        if not self.leaves:
            return self.base
        groups = {"constraints": list(self.base.constraints), "forces": list(self.base.forces)}
        for kind, k in {leaf.where[:2] for leaf in self.leaves if leaf.where[0] != "g_const"}:
            groups[kind][k] = self._element_at(kind, k, t)
        g_const = self.base.g_const
        for leaf in self.leaves:
            if leaf.where == ("g_const",):
                g_const = leaf.series(t)
        model = dataclasses.replace(self.base, constraints=tuple(groups["constraints"]),
                                    forces=tuple(groups["forces"]), g_const=g_const)
        if len(models) > 16:
            models.clear()
        models[t] = model
        return model

    def phi_q(self, q, t):
        """Φ_q(q, t), dense (assembled here: small models, many instants)."""
        m = self.at(t)
        J = np.zeros((m.n_constraints, self.n))
        r = 0
        for c in m.constraints:
            J[r:r + c.n_eq, c.idx] += c.jac(q)
            r += c.n_eq
        return J

    # ---- time derivatives at fixed q (only the elements that change with time) -------------
    def _rows(self):
        off = np.cumsum([0] + [c.n_eq for c in self.base.constraints])
        return [(k, off[k], off[k + 1]) for k in self._timed_constraints]

    def _taylor_all(self, t):
        """{k: constraint k on the Taylor curve ℓ(ε) = ℓ + ε ℓ' + ε² ℓ''/2 of its numbers about t
        at ε = −2h … 2h (h = TIME_STEP · T)} of every time-dependent k: five-point differences
        along it give Φ_t, Φ_tt exactly when Φ is at most quadratic in its numbers (natural
        coordinates; a driver angle, a pivot's position enter linearly)."""
        key = float(t)
        kept = self._kept.setdefault("taylor", {})
        if key in kept:
            return kept[key]
        if len(kept) > 8:
            kept.clear()
        h = TIME_STEP * self.period
        out = {}
        values = [self._leaf_values(t, order) for order in (0, 1, 2)]
        for where, idx in self._by_element().items():
            if where[0] != "constraints":  # (forces, and ("g_const",): no element to follow)
                continue
            k = where[1]
            jets = [(self.leaves[i], [v[i] for v in values]) for i in idx]
            els = []
            for j in (-2, -1, 0, 1, 2):
                el, e = (self.at(t) if j == 0 else self.base).constraints[k], j * h
                for leaf, (v, v1, v2) in jets if j else ():  # j = 0: the element at t
                    value = v + e * v1 + 0.5 * e * e * v2
                    if isinstance(_get(self.base, leaf.where), float):
                        value = float(value)
                    el = _replace(el, leaf.where[2:], value)
                els.append(el)
            out[k] = els
        kept[key] = (h, out)
        return h, out

    @staticmethod
    def _differences(h, f):
        return ((f[0] - 8 * f[1] + 8 * f[3] - f[4]) / (12 * h),
                (-f[0] + 16 * f[1] - 30 * f[2] + 16 * f[3] - f[4]) / (12 * h * h))

    def phi_time(self, q, t):
        """(Φ, Φ_t, Φ_tt) at (q, t) (the five-point differences of every time-dependent
        constraint at once)."""
        phi = self.at(t).phi(q)
        dt, dtt = np.zeros_like(phi), np.zeros_like(phi)
        rows = self._rows()
        if rows:
            h, els = self._taylor_all(t)
            at = np.concatenate([np.arange(a, b) for _, a, b in rows])
            f = [phi[at] if j == 2 else np.concatenate([els[k][j].phi(q) for k, _, _ in rows])
                 for j in range(5)]
            dt[at], dtt[at] = self._differences(h, f)
        return phi, dt, dtt

    @property
    def _jac_timed(self):
        """The time-dependent constraints whose Φ_q changes with time too (a moving pivot or
        a driver angle only shift Φ: their Φ_qt = 0), found once at a generic q."""
        if "jac_timed" not in self._kept:
            rng = np.random.default_rng(0)
            q = self.base.q_init + 0.1 * self.base.length_scale * rng.standard_normal(self.n)
            out = []
            for k, _, _ in self._rows():
                J0 = self._element_at("constraints", k, 0.0).jac(q)
                J1 = self._element_at("constraints", k, 0.3 * self.period).jac(q)
                if not np.array_equal(J0, J1):
                    out.append(k)
            self._kept["jac_timed"] = out
        return self._kept["jac_timed"]

    def phi_qt(self, q, t):
        """∂Φ_q/∂t at (q, t) (dense; the differences of every constraint at once)."""
        out = np.zeros((self.base.n_constraints, self.n))
        timed = set(self._jac_timed)
        rows = [row for row in self._rows() if row[0] in timed]
        if not rows:
            return out
        h, els = self._taylor_all(t)
        blocks = [[els[k][j].jac(q) for k, _, _ in rows] for j in (0, 1, 3, 4)]
        f = [np.concatenate([x.ravel() for x in blk]) for blk in blocks]
        d1 = self._differences(h, [f[0], f[1], 0.0, f[2], f[3]])[0]  # Φ_qt: no middle term
        start = 0
        for (k, a, b), x in zip(rows, blocks[0], strict=True):
            out[a:b, self.base.constraints[k].idx] += d1[start:start + x.size].reshape(x.shape)
            start += x.size
        return out


def sample_time(build_at, period, *, samples=16, check=3):
    """The :class:`TimedModel` of a periodic case: ``build_at(t)`` builds the Model at t.

    Samples one period at N instants (N doubled from ``samples`` until the interpolant matches
    ``check`` off-grid builds to 1e-12 relative, at most 512); a number that does not come back
    after one period (a driver angle may come back a whole number of turns further) is refused
    in one line naming the element: the motion does not repeat with the stated period."""
    T = float(period)
    if not T >= PERIOD_MIN:
        raise CaseError(f"period {T:.6g} s is shorter than {PERIOD_MIN:.3g} s: the second time "
                        f"derivatives of the motion (frequencies up to 2π·{_MAX_SAMPLES // 2}/T) "
                        f"would leave {DOUBLE_RANGE}", element="motion.period")
    if not T <= PERIOD_MAX:
        raise CaseError(f"period {T:.6g} s is longer than {PERIOD_MAX:.3g} s: the squared step "
                        f"(T/{1 / TIME_STEP:g})² of its time differences would leave "
                        f"{DOUBLE_RANGE}",
                        element="motion.period")
    base = build_at(0.0)
    end = build_at(T)
    leaves_at = {}
    for kind in ("constraints", "forces"):
        a, b = getattr(base, kind), getattr(end, kind)
        if len(a) != len(b):
            raise CaseError("the model's elements change with time", element="motion")
        for _k, (ea, eb) in enumerate(zip(a, b, strict=True)):
            if type(ea) is not type(eb):
                raise CaseError("the model's elements change with time", element=ea.name)
    probe = build_at(0.37 * T)  # which numbers move at all
    # (t = T repeats t = 0 in a periodic case: the mass is compared at the probe instant too)
    for other in (end, probe):
        if base.mass.shape != other.mass.shape or _differs(base.mass.toarray(),
                                                           other.mass.toarray()):
            raise CaseError("the mass matrix changes with time (t in a mass or a body, or a "
                            "body's geometry taken from a point moved with t: hold the body's "
                            "point on that path with a fixed joint instead)", element="motion")
    candidates = [("g_const",)] if _differs(base.g_const, probe.g_const) else []
    for kind in ("constraints", "forces"):
        for k, el in enumerate(getattr(base, kind)):
            if not dataclasses.is_dataclass(el):
                continue
            for path, v in _leaves_of(el, (kind, k)):
                if path[-1] not in _MEASURES and _differs(v, _get(probe, path)):
                    candidates.append(path)
    for path in candidates:
        v0, vT = np.asarray(_get(base, path), float), np.asarray(_get(end, path), float)
        drift = vT - v0
        name = "gravity and point forces" if path == ("g_const",) else _get(base, path[:2]).name
        scale = max(1.0, float(np.max(np.abs(v0))) if v0.size else 1.0)
        if path[-1] in _DRIFTING:
            turns = np.round(drift / (2 * math.pi))
            ok = np.all(np.abs(drift - 2 * math.pi * turns) <= 1e-9 * max(scale, abs(drift).max()))
            drift = 2 * math.pi * turns
        else:
            ok = np.all(np.abs(drift) <= 1e-9 * scale)
            drift = np.zeros_like(drift)
        if not ok:
            raise CaseError(f"the motion does not repeat with period T = {T:.6g}: {path[-1]} "
                            f"changes from {_fmt(v0)} at t = 0 to {_fmt(vT)} at t = T",
                            element=name)
        leaves_at[path] = (name, drift)
    if not leaves_at:
        return TimedModel(base, T, (), 0.0, 0)
    N = samples
    while True:
        times = np.arange(N) * T / N
        models = [base] + [build_at(t) for t in times[1:]]
        leaves = []
        for path, (name, drift) in leaves_at.items():
            vals = np.array([np.asarray(_get(m, path), float) for m in models])
            leaves.append(_Leaf(path, name, _in_range(TrigSeries.fit(vals, T, drift=drift),
                                                      name)))
        err = 0.0
        for j in range(check):
            t = T * (j + 0.5 + 0.123 * j) / (check + 1)
            ref = build_at(t)
            for leaf in leaves:
                want = np.asarray(_get(ref, leaf.where), float)
                got = leaf.series(t)
                err = max(err, float(np.max(np.abs(got - want)))
                          / max(1.0, float(np.max(np.abs(want)))))
        if err <= 1e-12 or N >= _MAX_SAMPLES:
            return TimedModel(base, T, tuple(leaves), err, N)
        N *= 2


def _fmt(v):
    return f"{float(v):.6g}" if v.size == 1 else np.array2string(v, precision=6)
