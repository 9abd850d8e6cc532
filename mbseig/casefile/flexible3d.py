"""Spatial beams in ``dimension = 3`` case files (DESIGN §8, "3-D flexible bodies and flexible
rotors"; docs/beams3d.md).

Called by :mod:`mbseig.casefile.flexible` for a 3-D case, in the same two steps as the planar
beams: :func:`allocate` reads every ``[[beams]]`` table and adds the node coordinates right after
the points, :func:`assemble` adds the elements, masses, rigid-triad conditions and the frames of
the stations once the bodies exist.

Mesh: the arc lengths {0, stations, L} split the beam into spans; ``elements`` are distributed
over the spans in proportion to their length (largest remainder, at least one each), so every
station is a node.  Node k is a frame [r; u; v; w] like a spatial rigid body
(:mod:`mbseig.model.spatial_body`, :class:`mbseig.model.beam3d.Beam3DElement`): r the end's
basic point (end nodes) or new coordinates ``BEAM.nK.x|y|z``, u, v, w unit vectors equal to the
global axes at the reference: new coordinates ``BEAM.nK.u.x`` … ``BEAM.nK.w.z`` with the six
rigid-triad conditions, the constant global axes (a ``"clamped"`` end) or the triad of the body
the end is welded to (an end naming a body).

Stations are frames ``"BEAM.NAME"`` usable wherever a body name is (joints, bushings, torques,
rotors, ``{body, at}`` point references) and points ``"BEAM.NAME"``; interior nodes are points
``"BEAM.nK"``.  ``spin`` makes every element gyroscopic and records the beam's nodes as whirl
stations (:class:`mbseig.model.beam3d.SpinningShaft`).
"""

from __future__ import annotations

import math
import re
import warnings
from dataclasses import dataclass, field

import numpy as np

from ..model.affine import Affine, combine
from ..model.beam3d_batch import group_of
from ..model.beam3d_lagrange import ELEMENT_ORDERS, LagrangeBeam3DElement, load_weights
from ..model.beam3d import (
    THEORIES,
    Beam3DElement,
    BeamProperties3D,
    SpinningShaft,
    section_frame,
    section_properties,
)
from ..model.spatial_body import frame_of, frame_point
from ..model.spatial_joints import triad_constraint
from .fields import (
    Fields,
    beam_end_points,
    check_range,
    element_count,
    expand,
    slenderness_warnings,
    template,
)

__all__ = ["allocate", "assemble", "span_elements"]

STATION_TOL = 1e-12  # relative to the length: stations closer than this are the same node
_NODE_NAME = re.compile(r"n\d+$")
_IDENTITY = np.eye(3).ravel()


@dataclass
class Beam3DSpec:
    name: str
    label: str
    points: tuple
    length: float
    props: BeamProperties3D
    depth: float
    R0: np.ndarray
    n_elements: int
    auto: bool
    ends: tuple
    spin: float
    stations: dict  # name → arc length
    element: str = "ross"  # "ross" (the standard element) or a name of ELEMENT_ORDERS
    arcs: np.ndarray = None  # node arc lengths (an order-p element spans p + 1 of them)
    node_pos: list = field(default_factory=list)
    pos: list = field(default_factory=list)  # Affine of each node's point (None: set later)
    triad: list = field(default_factory=list)  # triad coordinate indices, "clamped" or a body
    warnings: list = field(default_factory=list)
    spinning: bool = False  # spin given: whirl stations even at zero speed


def span_elements(lengths, n: int) -> list[int]:
    """Elements per span: n shared in proportion to the span lengths by largest remainder, at
    least one per span (more than n when there are more spans than n)."""
    lengths = np.asarray(lengths, float)
    ideal = n * lengths / lengths.sum()
    counts = np.maximum(np.floor(ideal).astype(int), 1)
    rest = n - int(counts.sum())
    if rest > 0:
        order = np.argsort(-(ideal - np.floor(ideal)), kind="stable")
        for j in order[:rest]:
            counts[j] += 1
    return [int(c) for c in counts]


def _ends(b, f):
    ends = f.raw("ends", ["free", "free"])
    if (not isinstance(ends, list) or len(ends) != 2
            or not all(isinstance(e, str) for e in ends)):
        raise f.error('ends must be [start, end], each "free", "clamped" or a body name')
    ends = tuple(template(e, f.names, f) for e in ends)
    for e in ends:
        if e not in ("free", "clamped") and e not in b.bodies:
            raise f.error(f'end {e!r} is neither "free", "clamped" nor a body')
    return ends


def _section(f, E):
    """(A, Iy, Iz, J, κ, depth, G) from ``section`` or A, Iy, Iz, J, and G or nu."""
    G = f.num("G", None, positive=True)
    nu = f.num("nu", None)
    if G is not None and nu is not None:
        raise f.error("give either G or nu, not both")
    if G is None:
        nu = 0.3 if nu is None else nu
        if not -1.0 < nu < 0.5:
            raise f.error(f"nu must lie in (−1, 0.5), got {nu:g}")
        G = check_range(E / (2.0 * (1.0 + nu)), "G = E/(2(1 + nu))", f.label)
    else:
        nu = E / (2.0 * G) - 1.0
    sec = f.raw("section", None)
    if sec is not None:
        if any(f.has(k) for k in ("A", "Iy", "Iz", "J")):
            raise f.error("give either section = {...} or A, Iy, Iz and J, not both")
        sf = Fields(sec, f"{f.label}.section", f.names)
        shape = sf.text("shape")
        keys = {"circle": ("d",), "tube": ("d", "d_inner"), "rectangle": ("b", "h")}
        if shape not in keys:
            raise sf.error(f"shape must be 'circle' (d), 'tube' (d, d_inner) or 'rectangle' "
                           f"(b, h), got {shape!r}")
        dims = {k: sf.num(k, positive=True) for k in keys[shape]}
        sf.done()
        if not -1.0 < nu < 0.5:
            raise f.error(f"Poisson's ratio E/(2G) − 1 = {nu:g} is outside (−1, 0.5): "
                          "Cowper's shear coefficient is undefined")
        p = section_properties(shape=shape, dims=dims, nu=nu, element=sf.label)
        A, Iy, Iz, J, kappa, depth = (p[k] for k in ("A", "Iy", "Iz", "J", "kappa", "depth"))
        for k, v in (("A", A), ("Iy", Iy), ("Iz", Iz), ("J", J)):
            if not v >= float(np.finfo(float).tiny):
                raise sf.error(f"the section's {k} = {v:g} vanishes below the double-precision "
                               "range: the section is too small")
    else:
        A, Iy, Iz, J = (f.num(k, positive=True) for k in ("A", "Iy", "Iz", "J"))
        kappa = 5.0 / 6.0
        depth = math.sqrt(12.0 * max(Iy, Iz) / A)
    return A, Iy, Iz, J, kappa, depth, G


def _spec(b, f, override, rules):
    name = f.text("name")
    if "." in name or name in b.point_index or name in b.bodies or name == "ground":
        raise f.error(f"beam name {name!r} is used already, is 'ground' or contains '.'")
    pa, pb = beam_end_points(b, f)
    xa, xb = b.point_pos[pa], b.point_pos[pb]
    chord = float(np.linalg.norm(xb - xa))
    if chord == 0:
        raise f.error("the end points coincide in the case: the beam's direction is undefined")
    length = f.num("length", chord, positive=True)
    E = f.num("E", positive=True)
    rho = f.num("rho", positive=True)
    theory = f.text("theory", "euler-bernoulli")
    if theory not in THEORIES:
        raise f.error(f"theory must be one of {', '.join(THEORIES)}, got {theory!r}")
    A, Iy, Iz, J, kappa, depth, G = _section(f, E)
    kappa = f.num("shear_coefficient", kappa, positive=True)
    orientation = f.vec("orientation", 3, None)
    if orientation is None and abs(Iy - Iz) > 1e-12 * max(Iy, Iz):
        raise f.error("orientation is needed: the section's Iy and Iz differ")
    R0 = section_frame(xa, xb, orientation, element=f.label)
    n, auto = element_count(f, rules["auto_start"], rules["max_elements"], override)
    ends = _ends(b, f)
    table = f.raw("stations", {})
    if not isinstance(table, dict):
        raise f.error("stations must be a table NAME = arc length")
    sf = Fields(table, f"{f.label}.stations", f.names)
    stations = {}
    for sname in table:
        if "." in sname or _NODE_NAME.match(sname):
            raise sf.error(f"station name {sname!r} must not contain '.' nor be a node name nK")
        s = sf.num(sname)
        tol = STATION_TOL * length
        if not (-tol <= s <= length + tol):
            raise sf.error(f"station {sname!r} at s = {s:g} is outside the beam [0, {length:g}]")
        stations[sname] = min(max(s, 0.0), length)
    spinning = f.raw("spin", None) is not None  # a spinning shaft, even at zero speed
    spin = f.num("spin", 0.0)
    element = _element(f, theory, auto)
    f.done()
    props = f.formed("the beam's section properties", lambda: BeamProperties3D(
        E=E, G=G, rho=rho, A=A, Iy=Iy, Iz=Iz, J=J, kappa_y=kappa, kappa_z=kappa, theory=theory))
    spec = Beam3DSpec(name=name, label=f.label, points=(pa, pb), length=length, props=props,
                      depth=depth, R0=R0, n_elements=n, auto=auto, ends=ends, spin=spin,
                      spinning=spinning, stations=stations, element=element)
    spec.warnings.extend(slenderness_warnings(theory, length / depth, rules["eb_slenderness"],
                                              rules["min_slenderness"]))
    return spec


def _element(f, theory, auto):
    """``element``: "ross" (the standard element; the default for a given count) or
    "quartic" (the default of ``elements = "auto"`` with the Timoshenko theory)."""
    names = ("ross", *ELEMENT_ORDERS)
    default = "quartic" if auto and theory == "timoshenko" else "ross"
    element = f.text("element", default)
    if element not in names:
        raise f.error(f"element must be one of {', '.join(names)}, got {element!r}")
    if element != "ross" and theory != "timoshenko":
        raise f.error(f'element = "{element}" needs theory = "timoshenko" (Euler–Bernoulli '
                      'bending needs a continuous slope: use element = "ross")')
    return element


def order_of(spec) -> int:
    """Polynomial order of the beam's element: 1 node interval an element for "ross"."""
    return ELEMENT_ORDERS.get(spec.element, 1)


def _mesh(spec):
    """Node arc lengths: the stations are nodes, elements shared over the spans, an order-p
    element's p + 1 nodes equally spaced."""
    L = spec.length
    cuts = sorted({0.0, L, *spec.stations.values()})
    merged = [cuts[0]]
    for c in cuts[1:]:
        if c - merged[-1] > STATION_TOL * L:
            merged.append(c)
    merged[-1] = L
    spans = np.diff(merged)
    counts = span_elements(spans, spec.n_elements)
    p = order_of(spec)
    arcs = [0.0]
    for a, n in zip(merged[:-1], counts, strict=True):
        h = (merged[merged.index(a) + 1] - a) / (n * p)
        arcs += [a + h * (j + 1) for j in range(n * p)]
    arcs[-1] = L
    spec.arcs = np.array(arcs)
    spec.n_elements = (len(arcs) - 1) // p


def allocate(b, mesh, **rules):
    """Read ``[[beams]]`` of a 3-D case and add their node coordinates to the builder ``b``.
    ``rules``: auto_start, max_elements, eb_slenderness, min_slenderness (the limits of
    :mod:`mbseig.casefile.flexible`) and warning (its BeamTheoryWarning)."""
    b.beam_specs = []
    names = set()
    for k, (item, label, params) in enumerate(expand("beams", b.data.get("beams", []), b.params)):
        f = Fields(item, label, params)
        nm = item.get("name")
        spec = _spec(b, f, mesh.get(k, mesh.get(nm) if isinstance(nm, str) else None), rules)
        if spec.name in names:
            raise f.error(f"duplicate beam name {spec.name!r}")
        names.add(spec.name)
        _mesh(spec)
        pa, pb = spec.points
        xa, xb = b.point_pos[pa], b.point_pos[pb]
        n = len(spec.arcs) - 1  # the last node
        for i, s in enumerate(spec.arcs):
            x = xa + (xb - xa) * (s / spec.length)
            spec.node_pos.append(x)
            if i in (0, n):
                spec.pos.append(b.affine_of(pa if i == 0 else pb))
            else:
                idx = b.assembly.coordinates([f"{spec.name}.n{i}.{a}" for a in "xyz"], x, "length")
                spec.pos.append(Affine.select(idx))
            end = spec.ends[0] if i == 0 else spec.ends[1] if i == n else "free"
            if end == "free":
                spec.triad.append(b.assembly.coordinates(
                    [f"{spec.name}.n{i}.{v}.{a}" for v in "uvw" for a in "xyz"], _IDENTITY,
                    "direction"))
            else:
                spec.triad.append(end)
        for msg in spec.warnings:
            warnings.warn(f"{label}: {msg}", rules["warning"], stacklevel=4)
        b.beam_specs.append(spec)


def _node_frame(b, spec, k):
    t = spec.triad[k]
    if isinstance(t, str) and t == "clamped":
        triad = Affine.constant(_IDENTITY)
    elif isinstance(t, str):  # welded to a body: the node's triad is the body's
        body = b.frames[t]
        triad = Affine(body.idx, body.C[3:], body.d[3:])
    else:
        return frame_of(spec.pos[k], t)
    return combine([(1.0, spec.pos[k]), (1.0, triad)], stack=True)


def _elements(spec, frames):
    """The beam's elements that have coordinates."""
    els = []
    p = order_of(spec)
    for j in range(spec.n_elements):
        k = j * p
        l0 = float(spec.arcs[k + p] - spec.arcs[k])
        w = combine([(1.0, frames[i]) for i in range(k, k + p + 1)], stack=True)
        if spec.element == "ross":
            el = Beam3DElement(f"{spec.label} element {j + 1}", w, spec.props, l0, spec.R0,
                               spec.spin)
        else:
            el = LagrangeBeam3DElement(f"{spec.label} element {j + 1}", w, spec.props, l0,
                                       spec.R0, p, spec.spin)
        if el.idx.size:
            els.append(el)
    return els


def _frozen(a):
    """A read-only copy of ``a``."""
    a = np.array(a)
    a.setflags(write=False)
    return a


def _masses(group, els, q0):
    """The elements' masses at q₀ in one batch (one alone where the batch gave its error)."""
    got = group.evaluate_all("mass", els, q0, None)
    return [el.mass(q0) if isinstance(m, Exception) else m
            for el, m in zip(els, got, strict=True)]


def assemble(b, forces, constraints, mass_elements, mass_blocks, g_const, gravity):
    """Add the elements of every 3-D beam; return ({name: record}, [SpinningShaft])."""
    b.bind()
    q0 = np.array(b.q_init)
    b.mass_reference = q0  # (every M_ref below is evaluated here)
    record, shafts = {}, []
    for spec in b.beam_specs:
        n_nodes = len(spec.arcs)
        frames = [_node_frame(b, spec, k) for k in range(n_nodes)]
        for k in range(n_nodes):
            if not isinstance(spec.triad[k], str):
                constraints.append(triad_constraint(f"{spec.label} node {k} (rigid triad)",
                                                    frames[k]))
        f = Fields({}, spec.label, {})
        # (one guarded computation for all the beam's elements: its error names the beam, as
        # each element's would)
        els = f.formed("the beam element's matrices",
                           lambda spec=spec, frames=frames: _elements(spec, frames))
        if spec.element == "ross":
            # the masses at the reference, all elements of the beam in one batch (a member's
            # numbers do not depend on its batch: mbseig.model.beam3d_batch)
            masses = f.formed("the beam element's mass matrix",
                              lambda els=els, p=spec.props: _masses(group_of(p), els, q0))
            # equal masses kept once, read-only (the elements of a uniform mesh: a few distinct
            # arrays for thousands of elements; a view would keep its whole batch alive)
            distinct = {}
            masses = [distinct.setdefault(M.tobytes(), _frozen(M)) for M in masses]
        else:  # constant masses (mbseig.model.beam3d_lagrange)
            masses = [None] * len(els)
        p_order = order_of(spec)
        shares = np.full(2, 0.5) if spec.element == "ross" else load_weights(p_order)
        for el, M_ref in zip(els, masses, strict=True):
            forces.append(el)
            if M_ref is None:
                mass_blocks.append((el.idx, el.idx, el.mass_matrix()))
            else:
                mass_elements.append((el, M_ref))
                mass_blocks.append((el.idx, el.idx, M_ref))
        if gravity is not None:
            for j in range(spec.n_elements):
                k = j * p_order
                w_el = spec.props.rho * spec.props.A * float(
                    spec.arcs[k + p_order] - spec.arcs[k]) * gravity
                for i, share in enumerate(shares):
                    r = spec.pos[k + i]
                    if r.idx.size:
                        np.add.at(g_const, r.idx, r.C.T @ (share * w_el))
        points = [frame_point(fr, np.zeros(3)) for fr in frames]
        node_of = {s: int(np.argmin(np.abs(spec.arcs - a))) for s, a in spec.stations.items()}
        for s, k in node_of.items():
            b.register_station(f"{spec.name}.{s}", frames[k], spec.node_pos[k], points[k])
        for k in range(1, n_nodes - 1):
            b.markers[f"{spec.name}.n{k}"] = points[k]
        if spec.spinning:  # at Ω = 0 too: its gyroscopic matrix is zero, its whirl stations not
            stack = combine([(1.0, frames[0])] + [(1.0, Affine(fr.idx, fr.C[3:], fr.d[3:]))
                                                  for fr in frames[1:]], stack=True)
            shafts.append(SpinningShaft(
                spec.label, stack, spec.R0[:, 0].copy(), float(spec.spin),
                stations=tuple((f"{spec.name} at s = {spec.arcs[k]:.4g} m", p)
                              for k, p in enumerate(points))))
        p = spec.props
        Phi_y, Phi_z = p.shear_parameters(spec.length)
        record[spec.name] = {
            "type": "beam", "dimension": 3, "theory": p.theory, "elements": spec.n_elements,
            "element": spec.element,
            "auto": spec.auto, "length": spec.length, "depth": spec.depth,
            "slenderness": spec.length / spec.depth, "shear_parameter": max(Phi_y, Phi_z),
            "E": p.E, "G": p.G, "rho": p.rho, "A": p.A, "Iy": p.Iy, "Iz": p.Iz, "J": p.J,
            "shear_coefficient": p.kappa_y, "orientation": [float(c) for c in spec.R0[:, 1]],
            "ends": list(spec.ends), "spin": spec.spin, "warnings": list(spec.warnings),
            "stations": {s: float(spec.arcs[k]) for s, k in node_of.items()},
            "nodes": [f"{spec.name}.n{k}" for k in range(n_nodes)],
            "points": list(spec.points),
        }
    return record, shafts
