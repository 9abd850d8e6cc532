"""Units of a case's parameters, for reports: every number the report prints carries one.

A case's ``[parameters]`` hold plain numbers and expressions; their units are found, in order:

1. the comment on the parameter's line, when it starts with a unit (``k_a = 1000.0  # N/m``):
   the leading words of the comment that are all unit words (m, s, N, kg, rad, deg, Hz, ...,
   with ``/``, ``^``, powers and ``*``);
2. the fields that use the parameter alone (``stiffness = "k_pip"`` of a torsional element is
   N m/rad; ``angle0 = "deg(theta0_pip)"`` is in deg; a body's ``mass`` is kg ...);
3. an angle written with ``deg(...)`` (``a1 = "-deg(mcp_target)"``, ``a2 = "a1 - deg(x)"``) is
   in rad; a factor of a product whose other factor already has the field's unit is dimensionless
   (``damping = "c_mcp * damping_scale"``), and the other way round; a configuration's alias
   (``actuator_damping_scale = "damping_scale"``) has its target's unit.

A parameter none of these reach has no unit (``None``): the report says so rather than guess.
"""

from __future__ import annotations

import re
from pathlib import Path

__all__ = ["parameter_units", "with_unit"]

_UNIT_WORDS = {"m", "mm", "cm", "km", "s", "ms", "min", "h", "N", "kN", "mN", "kg", "g", "rad",
               "deg", "Hz", "Pa", "kPa", "MPa", "GPa", "J", "W", "V", "A", "1", "-", "–", "%",
               "rpm", "Nm", "N·m", "m²", "m³", "s²"}
_UNIT_TOKEN = re.compile(r"^(?:[A-Za-z]+|1)(?:\^-?\d+|\*\*-?\d+|[²³])?$")

# (table, element type or None for any) → {field: unit}
_FIELD_UNITS = {
    ("forces", "torsional"): {"stiffness": "N m/rad", "damping": "N m s/rad", "angle0": "rad"},
    ("forces", "spring"): {"stiffness": "N/m", "free_length": "m"},
    ("forces", "damper"): {"damping": "N s/m"},
    ("forces", "spring_damper"): {"stiffness": "N/m", "damping": "N s/m", "free_length": "m"},
    ("forces", "follower"): {"magnitude": "N"},
    ("forces", "force"): {"magnitude": "N"},
    ("forces", "rotor"): {"speed": "rad/s", "polar_inertia": "kg m^2"},
    ("bodies", None): {"mass": "kg", "inertia": "kg m^2", "length": "m", "com": "m"},
    ("masses", None): {"mass": "kg"},
    ("points", None): {"position": "m"},
    ("joints", "angle_driver"): {"angle": "rad"},
    ("joints", "rolling"): {"radius": "m"},
    ("joints", None): {"at": "m"},
    ("beams", None): {"spin": "rad/s", "E": "Pa", "G": "Pa", "rho": "kg/m^3"},
}
# top-level fields and the [motion] table (a moving case: DESIGN §8)
_TOP_UNITS = {"gravity": "m/s^2"}
_MOTION_UNITS = {"speed": "m/s", "yaw_rate": "rad/s", "period": "s"}


def _is_unit_token(tok: str) -> bool:
    tok = tok.strip(",;:.")
    if not tok:
        return False
    parts = re.split(r"[/·*]", tok)
    return all(p in _UNIT_WORDS
               or (_UNIT_TOKEN.match(p) and re.sub(r"(\^-?\d+|\*\*-?\d+|[²³])$", "", p)
                   in _UNIT_WORDS) for p in parts if p)


def _comment_units(text: str) -> dict:
    """Units from the comments of the [parameters] table (rule 1)."""
    out, inside = {}, False
    for line in text.splitlines():
        stripped = line.strip()
        if stripped.startswith("["):
            inside = stripped.split("#")[0].strip() == "[parameters]"
            continue
        if not inside:
            continue
        m = re.match(r"^\s*([A-Za-z_]\w*)\s*=\s*[^#]*#\s*(.*)$", line)
        if not m:
            continue
        comment = m.group(2).strip()
        words, ended = [], False
        for tok in re.split(r"\s+", comment):
            end = tok[-1:] in ",;"
            if not _is_unit_token(tok):
                break
            words.append(tok.strip(",;"))
            if end:
                ended = True
                break
        # one letter then prose after a single space ("A factor for the load", "g is ...")
        # is an English word, not a unit; a unit stands alone, before a comma or semicolon,
        # or before two spaces ("N     fingertip force")
        rest = comment[len(words[0]):] if words else ""
        if (len(words) == 1 and len(words[0]) == 1 and not ended and rest
                and re.match(r" \S", rest)):
            words = []
        if words:
            out[m.group(1)] = " ".join(words)
    return out


def _elements(data):
    for table, kind in _FIELD_UNITS:
        for el in data.get(table, []) or []:
            if isinstance(el, dict) and (kind is None or el.get("type") == kind):
                yield _FIELD_UNITS[(table, kind)], el
    yield _TOP_UNITS, data
    if isinstance(data.get("motion"), dict):
        yield _MOTION_UNITS, data["motion"]


def _leaves(value):
    """The expression strings of a field: itself, or every entry of a vector or matrix; a
    leading sign dropped (``"-zB"`` has the unit of zB)."""
    if isinstance(value, str):
        e = value.replace(" ", "")
        yield e[1:] if re.fullmatch(r"[+-]\w+", e) else e
    elif isinstance(value, list):
        for v in value:
            yield from _leaves(v)


def parameter_units(spec) -> dict:
    """``{parameter: unit or None}`` of a parsed case (module docstring); "1" is dimensionless."""
    params = list(getattr(spec, "parameters", {}) or {})
    units: dict = {}
    try:
        text = Path(spec.source).read_text(encoding="utf-8")
    except (OSError, TypeError, ValueError):
        text = ""
    units.update({k: v for k, v in _comment_units(text).items() if k in params})
    data = getattr(spec, "data", {}) or {}
    products = []
    for fields, el in _elements(data):
        for key, unit in fields.items():
            for e in _leaves(el.get(key)):
                _field_rule(e, unit, params, units, products)
    if isinstance(data.get("motion"), dict) and "period" in data["motion"]:
        units["t"] = "s"  # the time of a periodic case (its fields' t; 0 at the reference)
        params = params + ["t"]
    return _derived_rules(spec, data, params, units, products)


def _field_rule(e, unit, params, units, products):
    """Rule 2 (and the products of rule 3) for one expression ``e`` of a field of ``unit``."""
    if e in params:
        units.setdefault(e, unit)
    elif (m := re.fullmatch(r"deg\((\w+)\)", e)) and m.group(1) in params and unit == "rad":
        units.setdefault(m.group(1), "deg")
    elif (m := re.fullmatch(r"(\w+)\*(\w+)", e)) and {m.group(1), m.group(2)} <= set(params):
        products.append((m.group(1), m.group(2), unit))


def _derived_rules(spec, data, params, units, products):
    """Rules 3 over the units found so far; returns {parameter: unit or None}."""
    aliases = []
    for cfg in (data.get("configurations") or {}).values():
        for k, v in (cfg or {}).items():
            if isinstance(v, str) and v.strip() in params and k in params:
                aliases.append((k, v.strip()))
    sums = []  # derived parameters that are sums of terms NAME or deg(NAME) (angles in rad)
    for k, v in (getattr(spec, "parameters", {}) or {}).items():
        if isinstance(v, str):
            terms = [t.strip() for t in re.split(r"(?<![eE(])[+-]", v) if t.strip()]
            if terms and all(re.fullmatch(r"deg\(\w+\)|\w+", t) for t in terms) and any(
                    t.startswith("deg(") for t in terms):
                sums.append((k, [t for t in terms if not t.startswith("deg(")]))
    for _ in range(3):  # rules 3, until nothing changes
        for k, names in sums:
            if all(units.get(n) == "rad" for n in names if n in params):
                units.setdefault(k, "rad")
        for a, b, unit in products:
            if units.get(a) == unit:
                units.setdefault(b, "1")
            elif units.get(b) == unit:
                units.setdefault(a, "1")
            elif units.get(a) == "1":
                units.setdefault(b, unit)
            elif units.get(b) == "1":
                units.setdefault(a, unit)
        for k, v in aliases:
            if v in units:
                units.setdefault(k, units[v])
    return {p: units.get(p) for p in params}


def with_unit(value: str, unit) -> str:
    """``"1000 N/m"``; a dimensionless value stays bare; an unknown unit is marked."""
    if unit in ("1", "-", "–"):
        return f"{value}"
    if not unit:
        return f"{value} (unit not given)"
    return f"{value} {unit}"
