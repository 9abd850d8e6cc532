"""Typed access to case-file tables: fields, name templates, ``repeat`` and ``enabled``.

One helper validates every element table (style: name the element, echo the bad value): a
:class:`Fields` reads numbers (or whitelisted expressions, :mod:`~mbseig.casefile.expr`),
vectors, strings and flags, and :meth:`Fields.done` rejects unknown keys.

The input rules (README, "Input rules"), each refused with the file, the element, the value and
the rule:

- a number is finite, and 0 or of magnitude MIN_MAGNITUDE … MAX_MAGNITUDE (1e-100 … 1e100):
  then its square and cube, the powers the elements form of one value (L², L³ of a beam
  element, d⁴ of a section), stay normal double-precision numbers.  Quantities formed from
  several values (a section's I, a body's mass matrix, a beam's stiffness) are checked where
  they are formed, and every stage boundary checks what comes out (mbseig.studies.point);
- ``factor`` scales a matrix and follows the matrix rule instead (finite entries, a finite
  sum; the eigensolver scales M, P, Q);
- a name is a string; a number is a number or an expression string, never a boolean, a list or
  a table;
- ``repeat`` bounds are integers of magnitude ≤ MAX_INDEX, and a case repeats at most
  MAX_REPEAT elements in all.
"""

from __future__ import annotations

import ast
import re

import numpy as np

from ..errors import CaseError, MbseigError
from .expr import evaluate, parse

__all__ = ["Fields", "REQUIRED", "MAX_REPEAT", "MAX_INDEX", "MAX_MAGNITUDE", "MIN_MAGNITUDE",
           "RANGE_RULE", "in_range", "check_range", "template", "expand", "enabled", "uses_time",
           "two_names", "element_count",
           "TIME"]

TIME = "t"  # the name of time in a periodic case (DESIGN §8, "Periodic motions")

MAX_REPEAT = 2_000_000  # repeated elements in one case
MAX_INDEX = 1e15  # |first|, |last| of a repeat range: exact integers, formatted exactly
MAX_MAGNITUDE = 1e100
MIN_MAGNITUDE = 1e-100
RANGE_RULE = f"a case number must be 0 or of magnitude {MIN_MAGNITUDE:g} to {MAX_MAGNITUDE:g}"
UNRANGED = {"factor"}  # scales a matrix: the matrix rule applies (module docstring)
REQUIRED = object()


def in_range(x) -> bool:
    """The number rule: finite, and 0 or MIN_MAGNITUDE ≤ |x| ≤ MAX_MAGNITUDE (arrays: all)."""
    if type(x) is float or type(x) is int or isinstance(x, np.floating):  # a scalar (most fields)
        a = abs(float(x))
        return a == 0 or MIN_MAGNITUDE <= a <= MAX_MAGNITUDE  # (False for inf and NaN)
    a = np.asarray(x, dtype=float)
    if a.size <= 16:  # a vector of a few numbers (most fields): the scalar rule, each
        return all(v == 0 or MIN_MAGNITUDE <= abs(v) <= MAX_MAGNITUDE for v in a.ravel().tolist())
    a = np.abs(a)
    return bool(np.all((a == 0) | ((a >= MIN_MAGNITUDE) & (a <= MAX_MAGNITUDE))))


def check_range(x, what, label):
    """``x`` if it obeys the number rule, else a CaseError naming ``what`` and the rule."""
    if not in_range(x):
        raise CaseError(f"{what} = {float(x)!r} is out of range: {RANGE_RULE}", element=label)
    return x


class Fields:
    """Typed access to one element table; unknown keys are rejected by :meth:`done`."""

    def __init__(self, table, label, names):
        if not isinstance(table, dict):
            raise CaseError("each element must be a table", element=label)
        self.t, self.label, self.names, self.used = table, label, names, {"repeat", "enabled"}

    def error(self, message):
        return CaseError(message, element=self.label)

    def has(self, key):
        return key in self.t

    def raw(self, key, default=REQUIRED):
        self.used.add(key)
        if key not in self.t:
            if default is REQUIRED:
                raise self.error(f"missing field {key!r}")
            return default
        return self.t[key]

    def num(self, key, default=REQUIRED, *, positive=False, nonnegative=False):
        value = self.raw(key, default)
        if value is None:
            return None
        try:
            x = evaluate(value, self.names)
        except MbseigError as exc:
            raise exc.located(element=f"{self.label}.{key}") from None
        if key not in UNRANGED:
            check_range(x, key if key in self.t else f"{key} (not given; its default from the "
                        f"case's other values)", self.label)
        if positive and not x > 0:
            raise self.error(f"{key} must be positive, got {x:g}")
        if nonnegative and not x >= 0:
            raise self.error(f"{key} must not be negative, got {x:g}")
        return x

    def vec(self, key, size, default=REQUIRED):
        if key not in self.t and default is not REQUIRED:
            self.used.add(key)
            return None if default is None else np.asarray(default, dtype=float)
        value = self.raw(key, default)
        if value is None:
            return None
        if not isinstance(value, list) or len(value) != size:
            raise self.error(f"{key} must be a list of {size} numbers, got {_short(value)}")
        try:
            out = np.array([evaluate(v, self.names) for v in value])
        except MbseigError as exc:
            raise exc.located(element=f"{self.label}.{key}") from None
        if not in_range(out):  # (the element that breaks the rule, named)
            for k, x in enumerate(out):
                check_range(x, f"{key}[{k}]", self.label)
        return out

    def text(self, key, default=REQUIRED):
        value = self.raw(key, default)
        if value is None:
            return None
        if not isinstance(value, str):
            raise self.error(f"{key} must be a string, got {_short(value)}")
        return template(value, self.names, self)

    def flag(self, key, default):
        value = self.raw(key, default)
        if not isinstance(value, bool):
            raise self.error(f"{key} must be true or false, got {_short(value)}")
        return value

    def formed(self, what, compute):
        """``compute()``: a quantity formed from several of the element's values (``what``,
        e.g. "the body's mass matrix").  An overflow, a division by zero or a non-finite number
        in the result (an array, a number, or a tuple or dict of them) is this element's error,
        named, instead of an inf or a traceback downstream."""
        try:
            with np.errstate(all="raise", under="ignore"):
                value = compute()
        except ArithmeticError:
            ok = False
        else:
            ok = all(_finite(v) for v in _numbers(value))
        if not ok:
            raise self.error(f"{what} leaves the double-precision range (2.2e-308 to 1.8e308): "
                             "the element's values are too large or too small together")
        return value

    def done(self):
        extra = sorted(set(self.t) - self.used)
        if extra:
            raise self.error(f"unknown field {extra[0]!r}")


def uses_time(value) -> bool:
    """Whether a field's value (a number, an expression, or a list or table of them) names the
    time ``t``: only numeric fields of points, joints, drivers and forces of a periodic case
    may (mbseig.studies.periodic checks the others)."""
    if isinstance(value, str):
        try:
            tree = parse(value)
        except MbseigError:
            return False  # not an expression: its own field reports it
        return any(isinstance(n, ast.Name) and n.id == TIME for n in ast.walk(tree))
    if isinstance(value, list):
        return any(uses_time(v) for v in value)
    if isinstance(value, dict):
        return any(uses_time(v) for v in value.values())
    return False


def _numbers(value):
    if isinstance(value, dict):
        value = tuple(value.values())
    if isinstance(value, tuple):
        return [x for v in value for x in _numbers(v)]
    return [value] if isinstance(value, (int, float, np.ndarray, np.generic)) else []


def _finite(value) -> bool:
    a = np.asarray(value)
    return a.dtype.kind not in "fc" or bool(np.all(np.isfinite(a)))


def _short(value, limit=80):
    """repr of a value, cut to ``limit`` characters (an echo, not a dump)."""
    text = repr(value)
    return text if len(text) <= limit else text[:limit - 3] + "..."


def template(text, names, fields):
    def sub(match):
        try:
            x = evaluate(match.group(1), names)
        except MbseigError as exc:
            raise fields.error(f"bad template {text!r}: {exc.message}") from None
        return str(int(x)) if float(x).is_integer() else repr(x)

    return re.sub(r"\{([^{}]*)\}", sub, text)


def expand(section, items, params, batch=None):
    """Yield (item, label, names) for every element of a section, expanding ``repeat``."""
    if not isinstance(items, list):
        raise CaseError(f"[[{section}]] must be an array of tables", element=section)
    total = 0
    for k, item in enumerate(items):
        if not isinstance(item, dict):
            raise CaseError("each element must be a table", element=f"{section}[{k}]")
        label = f"{section}[{k}]"
        if "name" in item and isinstance(item["name"], str):
            label += f" {item['name']!r}"
        rep = item.get("repeat")
        if rep is None:
            if enabled(item, label, params):
                yield item, label, params
            continue
        if not isinstance(rep, dict) or len(rep) != 1:
            raise CaseError("repeat must be a table {index = [first, last]}", element=label)
        (var, bounds), = rep.items()
        if var in params or not re.fullmatch(r"[A-Za-z_]\w*", var):
            raise CaseError(f"repeat index {var!r} clashes with a parameter or is not a name",
                            element=label)
        if not isinstance(bounds, list) or len(bounds) != 2:
            raise CaseError("repeat bounds must be [first, last]", element=label)
        try:
            first, last = (evaluate(b, params) for b in bounds)
        except MbseigError as exc:
            raise exc.located(element=label) from None
        if not (first.is_integer() and last.is_integer()
                and max(abs(first), abs(last)) <= MAX_INDEX):
            raise CaseError(f"repeat bounds must be integers of magnitude at most {MAX_INDEX:g}, "
                            f"got [{first:g}, {last:g}]", element=label)
        count = int(last) - int(first) + 1
        total += max(count, 0)
        if total > MAX_REPEAT:
            raise CaseError(f"more than {MAX_REPEAT} repeated elements", element=label)
        if batch is not None and batch(section, item, label, var,
                                       np.arange(int(first), int(last) + 1, dtype=float), params):
            continue  # expanded at once by mbseig.casefile.batch
        for i in range(int(first), int(last) + 1):
            names = {**params, var: float(i)}
            if enabled(item, f"{label} ({var}={i})", names):
                yield item, f"{label} ({var}={i})", names


def enabled(item, label, names):
    """``enabled = expr``: the element exists only where expr ≠ 0 (e.g. set by a configuration)."""
    if "enabled" not in item:
        return True
    value = item["enabled"]
    if isinstance(value, bool):
        return value
    try:
        return evaluate(value, names) != 0
    except MbseigError as exc:
        raise exc.located(element=f"{label}.enabled") from None


def two_names(f, key, message):
    """The two names of the list ``key`` (templates expanded); ``message`` if it is not one."""
    pair = f.raw(key)
    if not isinstance(pair, list) or len(pair) != 2 or not all(isinstance(p, str) for p in pair):
        raise f.error(message)
    return tuple(template(p, f.names, f) for p in pair)


def element_count(f, auto_start, max_elements, override=None):
    """(n, auto) of a beam's ``elements``: an integer in 1..max_elements, or ``"auto"`` (start
    from ``auto_start`` and let refinement decide); ``override`` (a refinement's mesh) wins."""
    auto = f.raw("elements", "auto") == "auto"
    if auto:
        n = auto_start
    else:
        n = f.num("elements")
        if not (float(n).is_integer() and 1 <= n <= max_elements):
            raise f.error(f'elements must be an integer in 1..{max_elements} or "auto", got {n!r}')
        n = int(n)
    return (int(override) if override is not None else n), auto


def beam_end_points(b, f):
    """(start, end) of a beam's ``points``: two different basic points of the builder ``b``."""
    pa, pb = two_names(f, "points", "points must be a list of two basic point names [start, end]")
    for p in (pa, pb):
        if p not in b.point_index:
            raise f.error(f"unknown point {p!r}")
    if pa == pb:
        raise f.error("a beam needs two different end points")
    return pa, pb


def slenderness_warnings(theory, slender, eb_slenderness, min_slenderness) -> list:
    """The beam-theory guidance for a beam of slenderness L/d (planar and spatial beams)."""
    out = []
    if theory == "euler-bernoulli" and slender < eb_slenderness:
        out.append(f"Euler–Bernoulli theory at slenderness L/d = {slender:.6g} < "
                   f"{eb_slenderness:g}: shear deformation and rotary inertia matter; use "
                   "theory = \"timoshenko\"")
    if slender < min_slenderness:
        out.append(f"slenderness L/d = {slender:.6g} < {min_slenderness:g}: beam theory is "
                   "inaccurate for so stubby a body; use a 2-D/3-D FE model (import it as an "
                   "fe_body)")
    return out


def square_matrix(f, key, size, default=None):
    """Field ``key`` of ``f``: ``size`` numbers (a diagonal) or a size × size matrix (a list of
    rows); zeros when absent with ``default`` None."""
    value = f.raw(key, default)
    if value is None:
        return np.zeros((size, size))
    if (isinstance(value, list) and len(value) == size
            and all(isinstance(r, list) for r in value)):
        rows = [Fields({"row": r}, f"{f.label}.{key}[{i}]", f.names).vec("row", size)
                for i, r in enumerate(value)]
        return np.array(rows)
    if not isinstance(value, list) or len(value) != size:
        raise f.error(f"{key} must be {size} numbers or a {size}x{size} matrix, got {value!r}")
    return np.diag(f.vec(key, size))
