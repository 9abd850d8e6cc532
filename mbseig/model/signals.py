"""Named inputs and outputs of a model (``[[inputs]]``, ``[[outputs]]`` of a case file).

An input u adds u·b(q) to the generalized forces,

    M q̈ + Φ_qᵀ λ = g(q, q̇) + Σ_i b_i(q) u_i,

with b_i per unit of u_i (docs/design.md, "Inputs and outputs"):

* ``element``: a spring, damper or actuator along its line, tension positive: b = −Dᵀe
  (D the map of d = r_b − r_a, e = d/|d|); a torsional element's moment: b = −∇θ (u adds to
  the element's moment τ, which acts against θ); a force's magnitude along its unit vector
  (``force`` and ``follower`` types): b = C_Pᵀ v̂(q);
* ``point`` with ``direction``: a force u along a fixed unit vector d̂ at the point: b = C_Pᵀ d̂;
* a moment u on body 2 and its reaction on body 1: b = ∇θ of the relative angle θ in the given
  sense (2-D), or the generalized force of the moment vector u·â on body 2 and −u·â on body 1
  (3-D, â fixed in space).

An output is a function y(q, q̇, λ, u) of the state; linearized about the equilibrium (q̇ = 0,
u = 0) it is y − y₀ = J_q δq + J_v δq̇ + J_λ δλ + D u.  Only a constraint's reaction uses δλ;
:mod:`mbseig.linear` eliminates it exactly through the linearized dynamics.

Outputs evaluate the model's elements by their labels at evaluation time, so that an element
an inverse-statics command has set (an actuator's free length) is read as set.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from ..errors import CaseError
from .affine import Affine
from .elements import (
    DistanceConstraint,
    FollowerForce,
    LinearConstraint,
    SpringDamper,
    TorsionalSpringDamper,
    relative_angle,
)

__all__ = ["Input", "Output", "find_element", "input_forces", "output_value", "output_rows",
           "OUTPUT_QUANTITIES"]

#: quantities per kind of output (docs/design.md, "Inputs and outputs")
OUTPUT_QUANTITIES = {
    "point": ("position", "velocity"),
    "spring": ("length", "rate", "force"),
    "torsional": ("angle", "rate", "moment"),
    "constraint": ("force",),
    "angle": ("angle", "rate"),
}
UNITS = {"position": "m", "velocity": "m/s", "length": "m", "force": "N", "moment": "N m",
         "angle": "rad"}


@dataclass(frozen=True, eq=False)
class Signal:
    """What an input or an output acts on: its ``name``, ``kind`` and the element, point,
    direction or bodies (``dirs`` [a; b], ``sense``) of that kind."""

    name: str
    kind: str
    label: str = ""
    element: str = ""
    point: Affine = None
    direction: np.ndarray = None
    dirs: Affine = None
    sense: float = 1.0


@dataclass(frozen=True, eq=False)
class Input(Signal):
    """One named input; ``kind`` is ``element`` (``element`` = a force element's label),
    ``point`` (``point`` Affine, unit ``direction``), ``moment2`` (``dirs`` [a; b] of the two
    bodies, ``sense``) or ``moment3`` (``frames`` (frame of b1 or None, frame of b2), ``axis``)."""

    frames: tuple = ()
    axis: np.ndarray = None

    def unit(self, model) -> str:
        """The unit of u: N m for a moment (a body-pair input or a torsional element's), N
        otherwise."""
        if self.kind in ("moment2", "moment3"):
            return "N m"
        if self.kind == "element":
            el = find_element(model, self.element, "force", self.label)
            return "N m" if isinstance(el, TorsionalSpringDamper) else "N"
        return "N"

    def generalized_force(self, model, q) -> np.ndarray:
        """b(q) of the module docstring (n-vector, per unit of u)."""
        b = np.zeros(model.n)
        if self.kind == "point":
            np.add.at(b, self.point.idx, self.point.C.T @ self.direction)
        elif self.kind == "moment2":
            _, g, _ = relative_angle(self.dirs, q, self.sense, self.label)
            np.add.at(b, self.dirs.idx, self.dirs.C.T @ g)
        elif self.kind == "moment3":
            from .spatial_forces import moment_force

            for frame, sign in zip(self.frames, (-1.0, 1.0), strict=True):
                if frame is not None and frame.idx.size:
                    gz = moment_force(frame(q), sign * self.axis)[0]
                    np.add.at(b, frame.idx, frame.C.T @ gz)
        else:
            el = find_element(model, self.element, "force", self.label)
            np.add.at(b, el.idx, _element_direction(el, q, self.label))
        return b


def _element_direction(el, q, label):
    """b of an ``element`` input on the element's own indices."""
    if isinstance(el, SpringDamper):
        D = el.diff.C
        d = el.diff(q)
        if d.size == 1:
            return -D[0]
        return -(D.T @ _line(el, d, label)[1])
    if isinstance(el, TorsionalSpringDamper):  # planar and spatial (same torque_parts contract)
        W, g = el.torque_parts(q, np.zeros_like(q))[:2]
        return -(W.T @ g)
    if isinstance(el, FollowerForce):
        Cp = el.stacked.C[:2]
        u = el.stacked(q)[2:]
        return Cp.T @ (u / _norm(u, label))
    try:
        from .spatial_forces import PointFollowerForce
    except ImportError:  # pragma: no cover
        PointFollowerForce = ()
    if isinstance(el, PointFollowerForce):
        C = el.stacked.C
        F = el.stacked(q)[3:]
        return C[:3].T @ (F / _norm(F, label))
    raise CaseError(f"element {el.name!r} ({type(el).__name__}) takes no input (a spring, damper, "
                    f"actuator, torsional element or force)", element=label)


def _norm(v, label):
    n = float(np.linalg.norm(v))
    if n == 0.0:
        raise CaseError("the force's direction has zero length", element=label)
    return n


@dataclass(frozen=True, eq=False)
class Output(Signal):
    """One named output; ``kind`` is ``point`` (``point``, unit ``direction``), ``spring`` or
    ``torsional`` (``element`` = the force element's label), ``constraint`` (``element`` = the
    constraint's label; ``direction`` picks a component of a vector reaction) or ``angle``
    (``dirs``, ``sense``: a relative angle of two planar bodies)."""

    quantity: str = ""
    inputs: tuple = field(default=())  # names of the inputs acting on the same element

    @property
    def unit(self) -> str:
        return "rad/s" if (self.quantity == "rate" and self.kind in ("torsional", "angle")) \
            else "m/s" if self.quantity == "rate" else UNITS[self.quantity]


def find_element(model, label, kind, where):
    """The force (``kind = "force"``) or constraint of ``model`` with this label."""
    pool = model.forces if kind == "force" else model.constraints
    for el in pool:
        if el.name == label:
            return el
    raise CaseError(f"element {label} is not in the model (disabled, or set by a command)",
                    element=where)


def input_forces(model, q) -> np.ndarray:
    """n × n_u matrix [b_1(q) … b_k(q)] of the model's inputs."""
    inputs = getattr(model, "inputs", ()) or ()
    if not inputs:
        return np.zeros((model.n, 0))
    return np.column_stack([i.generalized_force(model, q) for i in inputs])


def _line(el, d, label):
    """(length, unit direction) of a spring-damper's line; at zero length the line (and the
    derivative of the length) is undefined, so an input or output on it is refused."""
    length = float(np.linalg.norm(d))
    if length == 0.0:
        raise CaseError(f"{el.name} has zero length at the equilibrium: its line of action "
                        f"(and the derivative of its length) is undefined", element=label)
    return length, d / length


def _spring_parts(el, q, qd, label=None):
    D = el.diff.C
    d = el.diff(q)
    if d.size == 1:
        e = np.ones(1)
        length = float(d[0])
    else:
        length, e = _line(el, d, label or el.name)
    grad = e @ D  # ∂l/∂q[idx]
    rate = float(grad @ qd[el.idx])
    return length, rate, grad


def _torsional_parts(el, q, qd):
    W, g = el.torque_parts(q, qd)[:2]
    theta = el.angle(q)
    grad = g @ W
    rate = float(grad @ qd[el.idx])
    return theta, rate, grad


def _angle_parts(out, q, qd):
    theta, g, _ = relative_angle(out.dirs, q, out.sense, out.label)
    grad = g @ out.dirs.C
    return theta, float(grad @ qd[out.dirs.idx]), grad


def output_value(model, out: Output, q, qd, lam=None, u=None) -> float:
    """The nonlinear value y(q, q̇, λ, u) (not a deviation): for tests and time-domain runs."""
    u = {} if u is None else u
    if out.kind == "point":
        r = out.point(q) if out.quantity == "position" else out.point.rate(qd)
        return float(out.direction @ r)
    if out.kind == "angle":
        theta, rate, _ = _angle_parts(out, q, qd)
        return theta if out.quantity == "angle" else rate
    if out.kind == "constraint":
        c = find_element(model, out.element, "constraint", out.label)
        off = np.cumsum([0] + [k.n_eq for k in model.constraints])
        k = next(i for i, k_ in enumerate(model.constraints) if k_ is c)
        return float(_reaction_rows(c, out) @ lam[off[k]:off[k + 1]])
    el = find_element(model, out.element, "force", out.label)
    extra = sum(u.get(nm, 0.0) for nm in out.inputs)
    if out.kind == "spring":
        length, rate, _ = _spring_parts(el, q, qd)
        if out.quantity == "length":
            return length
        if out.quantity == "rate":
            return rate
        return el.stiffness * (length - el.free_length) + el.damping * rate + extra
    theta, rate, _ = _torsional_parts(el, q, qd)
    if out.quantity == "angle":
        return theta
    if out.quantity == "rate":
        return rate
    wrapped = (theta - el.angle0 + math.pi) % (2 * math.pi) - math.pi
    return el.stiffness * wrapped + el.damping * rate + extra


def _reaction_rows(c, out):
    """Row r with reaction value = r·λ_c (the reactions used are linear in λ and do not depend
    on q); refuses constraints whose reaction is not of that form."""
    from .driver import AngleDriver

    if isinstance(c, DistanceConstraint):  # axial force 2λL, tension positive
        return np.array([2.0 * c.length])
    if isinstance(c, AngleDriver):  # torque −λ
        return np.array([-1.0])
    if isinstance(c, LinearConstraint):  # force −Gᵀλ on its point, component along direction
        if out.direction is None or out.direction.size != c.G.shape[1]:
            raise CaseError(f"the reaction of {c.name} is a vector: give direction (a unit vector "
                            f"of {c.G.shape[1]} components) to choose its component",
                            element=out.label)
        return -(out.direction @ c.G.T)
    raise CaseError(f"a reaction output of a {type(c).__name__} is not offered (its reaction "
                    f"depends on the configuration); offered: distance joints, rigid lengths, "
                    f"fixed, slider and attach joints, angle drivers", element=out.label)


def output_rows(model, out: Output, q):
    """(J_q (n), J_v (n), J_λ (m) or None, {input name: D entry}) of the module docstring at
    q̇ = 0, u = 0."""
    n = model.n
    Jq, Jv = np.zeros(n), np.zeros(n)
    Jl, Du = None, {}
    if out.kind == "point":
        row = out.direction @ out.point.C
        np.add.at(Jq if out.quantity == "position" else Jv, out.point.idx, row)
    elif out.kind == "angle":
        _, _, grad = _angle_parts(out, q, np.zeros(n))
        np.add.at(Jq if out.quantity == "angle" else Jv, out.dirs.idx, grad)
    elif out.kind == "constraint":
        c = find_element(model, out.element, "constraint", out.label)
        off = np.cumsum([0] + [k.n_eq for k in model.constraints])
        k = next(i for i, k_ in enumerate(model.constraints) if k_ is c)
        Jl = np.zeros(model.n_constraints)
        Jl[off[k]:off[k + 1]] = _reaction_rows(c, out)
    else:
        el = find_element(model, out.element, "force", out.label)
        parts = _spring_parts if out.kind == "spring" else _torsional_parts
        _, _, grad = parts(el, q, np.zeros(n))
        if out.quantity in ("length", "angle"):
            np.add.at(Jq, el.idx, grad)
        elif out.quantity == "rate":
            np.add.at(Jv, el.idx, grad)
        else:  # force / moment: k δl + c δl̇ + u (the spring's tangent at the equilibrium)
            np.add.at(Jq, el.idx, el.stiffness * grad)
            np.add.at(Jv, el.idx, el.damping * grad)
            Du = {nm: 1.0 for nm in out.inputs}
    return Jq, Jv, Jl, Du
