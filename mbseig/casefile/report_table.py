"""The ``[report]`` table of a case (README, "Case files"): joint angles with their range of
motion, pins, actuator elements and studies, validated against the model being built."""

from __future__ import annotations

from ..errors import CaseError
from ..model.driver import AngleDriver
from .fields import Fields, in_range

MAX_STUDY_POINTS = 10_000  # points of one [[report.studies]] sweep (a stated limit)

__all__ = ["parse_report"]

_REPORT_KEYS = {"actuator", "angles", "pins", "studies"}
_STUDY_KEYS = {"title", "config", "sweep", "range", "count", "lines", "xtol_rel", "compare",
               "unbalance"}
_UNBALANCE_KEYS = {"at", "me"}


def parse_report(table, builder) -> dict:
    """Validate a ``[report]`` table against the model being built (``case._Builder``)."""
    if not isinstance(table, dict):
        raise CaseError("[report] must be a table", element="report")
    unknown = sorted(set(table) - _REPORT_KEYS)
    if unknown:
        raise CaseError(f"unknown field {unknown[0]!r} ({', '.join(sorted(_REPORT_KEYS))})",
                        element="report")
    names = builder.params
    out = {"angles": [], "pins": [], "actuator": [], "studies": [], "gravity": builder.gravity(),
           "element_body": dict(builder.element_body)}
    act = table.get("actuator", [])
    act = [act] if isinstance(act, str) else act
    if not isinstance(act, list) or not all(isinstance(a, str) for a in act):
        raise CaseError("actuator must be an element name or a list of names",
                        element="report.actuator")
    declared = builder.declared_names()
    for a in act:
        if a in builder.named:
            out["actuator"].append(builder.named[a])
        elif a not in declared:
            raise CaseError(f"unknown element {a!r}", element="report.actuator")
    for k, item in enumerate(_table_list(table.get("angles", []), "report.angles")):
        f = Fields(item, f"report.angles[{k}]", names)
        name = f.text("name")
        stacked, sense = builder.angle_pair(f)
        rng = f.vec("range", 2, None)
        f.done()
        if rng is not None and not rng[0] < rng[1]:
            raise f.error(f"range must be [min, max] in degrees with min < max, got {list(rng)}")
        out["angles"].append({"name": name, "driver": AngleDriver(name, stacked, 0.0, sense),
                              "range_deg": None if rng is None else (float(rng[0]), float(rng[1]))})
    for k, item in enumerate(_table_list(table.get("pins", []), "report.pins")):
        f = Fields(item, f"report.pins[{k}]", names)
        name = f.text("name")
        point = f.text("point")
        outboard = f.raw("outboard")
        f.done()
        if point not in builder.point_index:
            raise f.error(f"unknown point {point!r}")
        if not isinstance(outboard, list) or not outboard:
            raise f.error("outboard must be a non-empty list of body names")
        for b in outboard:
            builder.body(f, b)
        out["pins"].append({"name": name, "point": point, "outboard": list(outboard)})
    configs = builder.data.get("configurations", {})
    for k, item in enumerate(_table_list(table.get("studies", []), "report.studies")):
        label = f"report.studies[{k}]"
        unknown = sorted(set(item) - _STUDY_KEYS)
        if unknown:
            raise CaseError(f"unknown field {unknown[0]!r}", element=label)
        config = item.get("config")
        if config is not None and (not isinstance(config, str) or config not in configs):
            raise CaseError(f"unknown configuration {config!r}", element=label)
        if "compare" in item:
            if item["compare"] != "constraint_stiffness":
                raise CaseError("compare must be \"constraint_stiffness\"", element=label)
        else:
            sweep = item.get("sweep")
            if not isinstance(sweep, str) or sweep not in builder.params:
                raise CaseError(f"sweep must name a parameter, got {sweep!r}", element=label)
            rng, count = item.get("range"), item.get("count")
            if (not isinstance(rng, list) or len(rng) != 2 or not all(_number(x) for x in rng)
                    or rng[0] == rng[1]):
                raise CaseError("range must be [start, stop] of case numbers with start ≠ stop",
                                element=label)
            if not isinstance(count, int) or isinstance(count, bool) or not (
                    2 <= count <= MAX_STUDY_POINTS):
                raise CaseError(f"count must be an integer in 2..{MAX_STUDY_POINTS}", element=label)
            lines = item.get("lines", {})
            if not isinstance(lines, dict) or not all(
                    n in builder.params and isinstance(v, list) and v and all(map(_number, v))
                    for n, v in lines.items()):
                raise CaseError("lines must be {parameter = [values, ...]}", element=label)
            xtol = item.get("xtol_rel", 1e-10)
            if not (_number(xtol) and 0 < xtol < 1):
                raise CaseError("xtol_rel must be a number in (0, 1)", element=label)
            if "unbalance" in item:
                _check_unbalance(item["unbalance"], f"{label}.unbalance")
        out["studies"].append(dict(item))
    return out


def _check_unbalance(ub, label):
    """``unbalance = {at = "POINT, STATION or BODY", me = m·e [kg m] > 0}`` of a rotor study
    (whether ``at`` names a point of the built model is checked when the study runs)."""
    if not isinstance(ub, dict):
        raise CaseError("must be a table {at = \"POINT\", me = m·e [kg m]}", element=label)
    unknown = sorted(set(ub) - _UNBALANCE_KEYS)
    if unknown:
        raise CaseError(f"unknown field {unknown[0]!r} (at, me)", element=label)
    if not isinstance(ub.get("at"), str) or not ub["at"]:
        raise CaseError("at must name a point, beam station or body", element=label)
    if not (_number(ub.get("me")) and ub["me"] > 0):
        raise CaseError(f"me must be a number m·e > 0 [kg m], got {ub.get('me')!r}", element=label)


def _number(x) -> bool:
    """A number that obeys the case's number rule (finite, 0 or 1e-100 ≤ |x| ≤ 1e100)."""
    return isinstance(x, (int, float)) and not isinstance(x, bool) and in_range(x)


def _table_list(value, label):
    if not isinstance(value, list) or not all(isinstance(v, dict) for v in value):
        raise CaseError("must be an array of tables", element=label)
    return value
