"""``[[inputs]]`` and ``[[outputs]]`` tables → :class:`~mbseig.model.signals.Input`,
:class:`~mbseig.model.signals.Output` (DESIGN §8, "Inputs, outputs"; docs/design.md "Inputs
and outputs").  Shared by the planar and the spatial reader; unknown fields are refused.

    [[inputs]]   name, and one of:  element = "E"
                                    point = P, direction = [..]         (force u, N)
                                    bodies = [b1, b2], sense             (2-D moment u, N m)
                                    body = "b" (or bodies = [b1, b2]), axis = [x, y, z]  (3-D)
    [[outputs]]  name, quantity, and one of:
                                    point = P, direction (position | velocity)
                                    element = "E" (spring/damper/actuator: length | rate | force;
                                                   torsional: angle | rate | moment;
                                                   a joint: force, its reaction; a vector
                                                   reaction takes direction)
                                    bodies = [b1, b2], sense (2-D: angle | rate)
"""

from __future__ import annotations

import numpy as np

from ..model.elements import FollowerForce, SpringDamper, TorsionalSpringDamper
from ..model.signals import OUTPUT_QUANTITIES, Input, Output
from .fields import Fields, expand, template

__all__ = ["read_signals", "UNIT_TOL"]

UNIT_TOL = 1e-6  # a direction or axis must have length 1 within this (relative)

_INPUT_WAYS = ("element", "point", "bodies", "body")
_OUTPUT_WAYS = ("element", "point", "bodies")


def read_signals(builder, forces, constraints):
    """(inputs, outputs) of the case, as tuples; every problem a CaseError naming the table."""
    inputs = tuple(_inputs(builder, forces))
    outputs = tuple(_outputs(builder, forces, constraints, inputs))
    return inputs, outputs


def _way(f, ways):
    given = [w for w in ways if f.has(w)]
    if len(given) != 1:
        raise f.error(f"give exactly one of {', '.join(ways)} (got "
                      f"{', '.join(given) if given else 'none'})")
    return given[0]


def _unit(f, key, dim):
    v = f.vec(key, dim)
    n = float(np.linalg.norm(v))
    if abs(n - 1.0) > UNIT_TOL:
        raise f.error(f"{key} must be a unit vector (its length is {n:.6g}); divide it by its "
                      f"length")
    return v / n


def _name(f, seen, what):
    name = f.text("name")
    if not name:
        raise f.error("name must not be empty")
    if name in seen:
        raise f.error(f"duplicate {what} name {name!r}")
    seen.add(name)
    return name


def _element(builder, f, forces, constraints):
    """(kind "force" | "joint" | "point_force", element or (point, vector)) named by element."""
    ename = f.text("element")
    if ename in builder.named:
        kind, index, _ = builder.named[ename]
        return kind, (forces[index] if kind == "force" else
                      constraints[index] if constraints else None)
    if ename in builder.point_forces:
        return "point_force", builder.point_forces[ename]
    declared = builder.declared_names()
    if ename in declared:
        raise f.error(f"element {ename!r} is not in the model (disabled, set by a command or "
                      f"between fixed points)")
    raise f.error(f"unknown element {ename!r} (a named joint or force)")


def _signal_items(builder, what, ways):
    """(fields, label, unique name, way) of each ``[[inputs]]`` or ``[[outputs]]`` entry."""
    seen = set()
    for item, label, names in expand(what + "s", builder.data.get(what + "s", []), builder.params):
        f = Fields(item, label, names)
        yield f, label, _name(f, seen, what), _way(f, ways)


def _inputs(builder, forces):
    for f, label, name, way in _signal_items(builder, "input", _INPUT_WAYS):
        if way == "element":
            kind, el = _element(builder, f, forces, ())
            f.done()
            if kind == "point_force":
                p, vec, _ = el
                n = float(np.linalg.norm(vec))
                if n == 0.0:
                    raise f.error("the force's vector is zero: its direction is undefined")
                yield Input(name, "point", label, point=p, direction=vec / n)
                continue
            if kind != "force" or not _input_element(el):
                raise f.error(f"element {f.t['element']!r} takes no input (a spring, damper, "
                              f"actuator, torsional element or force)")
            yield Input(name, "element", label, element=el.name)
        elif way == "point":
            p = builder.point_ref(f, "point")
            d = _unit(f, "direction", builder.dim)
            f.done()
            yield Input(name, "point", label, point=p, direction=d)
        elif builder.dim == 2:
            if way == "body":
                raise f.error("a planar moment input takes bodies = [b1, b2] and sense")
            dirs, sense = builder.angle_pair(f)
            f.done()
            yield Input(name, "moment2", label, dirs=dirs, sense=sense)
        elif builder.dim == 3:
            if way == "body":
                frames = (None, builder.frame(f, f.text("body")))
            else:
                pair = f.raw("bodies")
                if not isinstance(pair, list) or len(pair) != 2 or not all(
                        isinstance(b, str) for b in pair):
                    raise f.error('bodies must be [body1, body2]; use "ground" for the fixed frame')
                frames = tuple(builder.frame(f, template(b, f.names, f)) for b in pair)
            axis = _unit(f, "axis", 3)
            f.done()
            yield Input(name, "moment3", label, frames=frames, axis=axis)
        else:
            raise f.error("a moment input needs dimension 2 or 3")


def _input_element(el):
    if isinstance(el, (SpringDamper, TorsionalSpringDamper, FollowerForce)):
        return True
    try:
        from ..model.spatial_forces import PointFollowerForce
    except ImportError:  # pragma: no cover
        return False
    return isinstance(el, PointFollowerForce)


def _quantity(f, kind):
    q = f.text("quantity")
    allowed = OUTPUT_QUANTITIES[kind]
    if q not in allowed:
        what = {"point": "a point", "spring": "a spring, damper or actuator",
                "torsional": "a torsional element", "constraint": "a joint",
                "angle": "a body pair"}[kind]
        raise f.error(f"quantity {q!r} is not offered for {what} (one of {', '.join(allowed)})")
    return q


def _outputs(builder, forces, constraints, inputs):
    for f, label, name, way in _signal_items(builder, "output", _OUTPUT_WAYS):
        if way == "point":
            quantity = _quantity(f, "point")
            p = builder.point_ref(f, "point")
            d = _unit(f, "direction", builder.dim)
            f.done()
            yield Output(name, "point", label, quantity=quantity, point=p, direction=d)
        elif way == "bodies":
            quantity = _quantity(f, "angle")
            if builder.dim != 2:
                raise f.error("a body-pair angle output needs dimension = 2 (in 3-D use "
                              "element = a torsional element)")
            dirs, sense = builder.angle_pair(f)
            f.done()
            yield Output(name, "angle", label, quantity=quantity, dirs=dirs, sense=sense)
        else:
            kind, el = _element(builder, f, forces, constraints)
            if kind == "joint":
                quantity = _quantity(f, "constraint")
                d = _unit(f, "direction", builder.dim) if f.has("direction") else None
                f.done()
                yield Output(name, "constraint", label, quantity=quantity, element=el.name,
                             direction=d)
                continue
            if kind == "force" and isinstance(el, SpringDamper):
                okind = "spring"
            elif kind == "force" and isinstance(el, TorsionalSpringDamper):
                okind = "torsional"
            else:
                raise f.error(f"element {f.t['element']!r} has no output (a spring, damper, "
                              f"actuator, torsional element or joint)")
            quantity = _quantity(f, okind)
            f.done()
            acting = tuple(i.name for i in inputs if i.kind == "element" and i.element == el.name)
            yield Output(name, okind, label, quantity=quantity, element=el.name, inputs=acting)
