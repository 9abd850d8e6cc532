"""Typed access to case-file tables: fields, name templates, ``repeat`` and ``enabled``.

One helper validates every element table (style: name the element, echo the bad value): a
:class:`Fields` reads numbers (or whitelisted expressions, :mod:`~mbseig.casefile.expr`),
vectors, strings and flags, and :meth:`Fields.done` rejects unknown keys.
"""

from __future__ import annotations

import re

import numpy as np

from ..errors import CaseError, MbseigError
from .expr import evaluate

__all__ = ["Fields", "REQUIRED", "MAX_REPEAT", "template", "expand", "enabled"]

MAX_REPEAT = 2_000_000
REQUIRED = object()


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
            raise self.error(f"{key} must be a list of {size} numbers, got {value!r}")
        try:
            return np.array([evaluate(v, self.names) for v in value])
        except MbseigError as exc:
            raise exc.located(element=f"{self.label}.{key}") from None

    def text(self, key, default=REQUIRED):
        value = self.raw(key, default)
        if value is None:
            return None
        if not isinstance(value, str):
            raise self.error(f"{key} must be a string, got {value!r}")
        return template(value, self.names, self)

    def flag(self, key, default):
        value = self.raw(key, default)
        if not isinstance(value, bool):
            raise self.error(f"{key} must be true or false, got {value!r}")
        return value

    def done(self):
        extra = sorted(set(self.t) - self.used)
        if extra:
            raise self.error(f"unknown field {extra[0]!r}")


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
        if not (first.is_integer() and last.is_integer()):
            raise CaseError("repeat bounds must be integers", element=label)
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
