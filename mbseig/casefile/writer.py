"""Cases in Python (``mbseig.CaseBuilder``, ``mbseig.to_toml``): :class:`CaseBuilder` assembles the
plain dict of a case file (the structure of the TOML formats of the design notes, 2-D and 3-D), and
:func:`to_toml` writes any case dict back to TOML.

The dict is exactly what ``tomllib`` returns for the equivalent file, so a built case and a
written one are interchangeable: ``tomllib.loads(to_toml(case)) == case`` for every case dict
(round trip exact: floats written by ``repr``, strings escaped, nested tables, arrays of tables,
and inline tables where the formats use them, e.g. point references
``{ body = "b", at = [x, y, z] }``).  Nothing here validates the physics: the reader does that
when the case is loaded.

    case = CaseBuilder(dimension=2, title="Pendulum", gravity=[0.0, "-g"])
    case.parameter("g", 9.81)
    case.point("O", [0.0, 0.0], fixed=True)
    ...
    text = case.to_toml()
"""

from __future__ import annotations

import numpy as np

import datetime as _dt
import math
import re
from pathlib import Path

from ..arguments import check

__all__ = ["CaseBuilder", "point_ref", "to_toml"]

_BARE_KEY = re.compile(r"[A-Za-z0-9_-]+")
_ESCAPES = {"\\": "\\\\", '"': '\\"', "\b": "\\b", "\t": "\\t", "\n": "\\n", "\f": "\\f",
            "\r": "\\r"}


# ---------------------------------------------------------------------------------------------
# TOML writer
# ---------------------------------------------------------------------------------------------
def to_toml(case: dict) -> str:
    """TOML text of a case dict.

    Top-level dicts become ``[tables]``, lists of dicts ``[[arrays of tables]]``; inside an entry
    of an array of tables every dict is an inline table (the point references and parameter
    tables of the formats).  The round trip is exact: ``tomllib.loads(to_toml(case)) == case``.

    Parameters
    ----------
    case : dict
        Any dict of TOML values: str, int, float, bool, dates, lists, dicts (numpy scalars and
        arrays are written as numbers and lists).

    Returns
    -------
    str
        The TOML text.

    Raises
    ------
    TypeError
        A value TOML cannot hold.

    Examples
    --------
    >>> print(to_toml({"title": "x", "parameters": {"m": 1.0}}))
    title = "x"
    <BLANKLINE>
    [parameters]
    m = 1.0
    <BLANKLINE>
    """
    if not isinstance(case, dict):
        raise TypeError(f"a case must be a dict, got {type(case).__name__}")
    lines: list[str] = []
    _table(case, [], lines)
    text = "\n".join(lines).strip("\n")
    return text + "\n"


def _table(table: dict, path: list[str], lines: list[str], *, inline_dicts: bool = False):
    """Write the key/values of ``table`` and then its sub-tables and arrays of tables."""
    subtables, arrays = [], []
    for key, value in table.items():
        if not isinstance(key, str):
            raise TypeError(f"TOML keys must be strings, got {key!r}")
        if isinstance(value, dict) and not inline_dicts:
            subtables.append((key, value))
        elif _is_table_array(value) and not inline_dicts:
            arrays.append((key, value))
        else:
            lines.append(f"{_key(key)} = {_value(value)}")
    for key, value in subtables:
        sub = path + [key]
        # a table holding only tables needs no header of its own: its children name it
        if not value or any(not isinstance(v, dict) and not _is_table_array(v)
                            for v in value.values()):
            lines += ["", f"[{'.'.join(_key(k) for k in sub)}]"]
        _table(value, sub, lines)
    for key, value in arrays:
        sub = path + [key]
        for entry in value:
            lines += ["", f"[[{'.'.join(_key(k) for k in sub)}]]"]
            _table(entry, sub, lines, inline_dicts=True)


def _is_table_array(value) -> bool:
    return isinstance(value, list) and bool(value) and all(isinstance(v, dict) for v in value)


def _key(key: str) -> str:
    return key if _BARE_KEY.fullmatch(key) else _string(key)


def _string(text: str) -> str:
    out = []
    for ch in text:
        if ch in _ESCAPES:
            out.append(_ESCAPES[ch])
        elif ord(ch) < 0x20 or ord(ch) == 0x7F:
            out.append(f"\\u{ord(ch):04X}")
        else:
            out.append(ch)
    return '"' + "".join(out) + '"'


def _float(x: float) -> str:
    if math.isnan(x):
        return "nan"
    if math.isinf(x):
        return "inf" if x > 0 else "-inf"
    return repr(x)  # shortest repr: reads back to the same double


def _value(value) -> str:
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, int):
        return str(value)
    if isinstance(value, float):
        return _float(value)
    if isinstance(value, str):
        return _string(value)
    if isinstance(value, (_dt.datetime, _dt.date, _dt.time)):
        return value.isoformat()
    if isinstance(value, (list, tuple)):
        return "[" + ", ".join(_value(v) for v in value) + "]"
    if isinstance(value, dict):
        if not value:
            return "{}"
        return "{ " + ", ".join(f"{_key(k)} = {_value(v)}" for k, v in value.items()) + " }"
    raise TypeError(f"TOML cannot hold a value of type {type(value).__name__}: {value!r}")


# ---------------------------------------------------------------------------------------------
# CaseBuilder
# ---------------------------------------------------------------------------------------------
def point_ref(body: str, at) -> dict:
    """A 3-D point reference ``{ body = "b", at = [x, y, z] }`` (global position at the
    reference configuration)."""
    return {"body": str(body), "at": _vector(at, "at")}


def _vector(v, what):
    if isinstance(v, str):
        raise TypeError(f"{what} must be a list of numbers or expressions, got {v!r}")
    return [_number(x, what) for x in v]


def _number(x, what):
    """A number (kept as int or float) or an expression string, as the case files allow."""
    if isinstance(x, bool):
        raise TypeError(f"{what}: expected a number or an expression, got {x!r}")
    if isinstance(x, (int, float, str)):
        return x
    if isinstance(x, np.generic):  # numpy scalar
        return x.item()
    raise TypeError(f"{what}: expected a number or an expression, got {x!r}")


def _plain(value):
    """numpy arrays and scalars, tuples → lists and Python numbers (recursively)."""
    if isinstance(value, (np.ndarray, np.generic)):
        return value.tolist()
    if isinstance(value, (list, tuple)):
        return [_plain(v) for v in value]
    if isinstance(value, dict):
        return {str(k): _plain(v) for k, v in value.items()}
    return value


class CaseBuilder:
    """Assemble a case dict element by element (module docstring).

    Each method appends one entry to the matching table of the case format (``[[points]]``,
    ``[[masses]]``, ``[[bodies]]``, ``[[joints]]``, ``[[forces]]``, ``[[inputs]]``,
    ``[[outputs]]``, ``[[beams]]``) or sets a key of a table (``[parameters]``,
    ``[configurations]``, ``[expected]``, ``[report]``, ``[motion]``, ``[urdf]``); field names
    are those of the format, given as keyword arguments.  Returns ``self`` so calls chain.
    Values may be numbers, expression strings, lists, numpy arrays or point references
    (:func:`point_ref`).  :meth:`to_dict` gives the case; :meth:`to_toml` its text.
    """

    def __init__(self, *, dimension: int, title: str | None = None, gravity=None,
                 description: str | None = None, source: str | None = None,
                 schema_version: int = 1, kind: str | None = None):
        check("CaseBuilder", locals())
        if dimension not in (1, 2, 3):
            raise ValueError(f"dimension must be 1, 2 or 3, got {dimension!r}")
        self.dimension = dimension
        self._case: dict = {"schema_version": schema_version}
        for key, value in (("title", title), ("description", description), ("source", source),
                           ("kind", kind)):
            if value is not None:
                self._case[key] = str(value)
        self._case["dimension"] = dimension
        if gravity is not None:
            self._case["gravity"] = self._vec(gravity, "gravity")
        self._names: dict[str, set] = {}

    # -- helpers --------------------------------------------------------------------------
    def _vec(self, v, what, size=None):
        out = _vector(_plain(v), what)
        size = self.dimension if size is None else size
        if len(out) != size:
            raise ValueError(f"{what} must have {size} components, got {len(out)}")
        return out

    def _entry(self, section: str, fields: dict, *, unique: str | None = "name"):
        entry = {k: _plain(v) for k, v in fields.items() if v is not None}
        name = entry.get(unique) if unique else None
        if name is not None:
            seen = self._names.setdefault(section, set())
            if name in seen:
                raise ValueError(f"{section}: name {name!r} is used already")
            seen.add(name)
        self._case.setdefault(section, []).append(entry)
        return self

    def _set(self, table: str, key: str, value):
        self._case.setdefault(table, {})[str(key)] = _plain(value)
        return self

    # -- tables ---------------------------------------------------------------------------
    def parameter(self, name: str, value):
        """``[parameters] name = value`` (a number or an expression)."""
        return self._set("parameters", name, _number(value, f"parameter {name}"))

    def parameters(self, **values):
        for name, value in values.items():
            self.parameter(name, value)
        return self

    def configuration(self, name: str, **values):
        """``[configurations.name]``: a named set of parameter values (and ``description``)."""
        self._case.setdefault("configurations", {})[name] = _plain(values)
        return self

    def expected(self, **values):
        self._case.setdefault("expected", {}).update(_plain(values))
        return self

    def table(self, key: str, value):
        """Set any top-level key (``report``, ``motion``, ``urdf``, ``matrices``, ...)."""
        self._case[key] = _plain(value)
        return self

    # -- elements -------------------------------------------------------------------------
    def point(self, name: str, position, *, fixed: bool = False, **fields):
        entry = {"name": name, "position": self._vec(position, f"points {name!r}: position")}
        if fixed:
            entry["fixed"] = True
        return self._entry("points", {**entry, **fields})

    def mass(self, point: str, mass, *, name: str | None = None, **fields):
        return self._entry("masses", {"name": name, "point": point, "mass": _number(mass, "mass"),
                                      **fields})

    def body(self, name: str, **fields):
        """A planar body (``points``, ``length``, ``mass``, ``inertia``, ``com``, ``markers``)
        or a spatial one (``mass``, ``com``, ``inertia`` [3 numbers or 3×3], ``points``)."""
        if self.dimension == 3 and "com" in fields:
            fields["com"] = self._vec(fields["com"], f"bodies {name!r}: com")
        return self._entry("bodies", {"name": name, **fields})

    def joint(self, type: str, name: str | None = None, **fields):
        return self._entry("joints", {"type": type, "name": name, **fields})

    def force(self, type: str, name: str | None = None, **fields):
        return self._entry("forces", {"type": type, "name": name, **fields})

    def beam(self, name: str, **fields):
        return self._entry("beams", {"name": name, **fields})

    def input(self, name: str, **fields):
        return self._entry("inputs", {"name": name, **fields})

    def output(self, name: str, **fields):
        return self._entry("outputs", {"name": name, **fields})

    # -- results --------------------------------------------------------------------------
    def to_dict(self) -> dict:
        """The case (a deep copy: later calls do not change it)."""
        import copy

        return copy.deepcopy(self._case)

    def to_toml(self) -> str:
        return to_toml(self._case)

    def write(self, path) -> Path:
        path = Path(path)
        path.write_text(self.to_toml(), encoding="utf-8")
        return path
