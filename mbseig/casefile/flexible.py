"""Flexible bodies in case files: ``[[beams]]`` and ``[[fe_bodies]]``.

Called by the case builder (:mod:`mbseig.casefile.builder`) in two steps: :func:`allocate` adds the
extra coordinates right after the points (interior beam nodes ``beam.n3.x``/``.y``, node angles
``beam.n3.theta``, FE interface angles ``body.A.theta`` and modal coordinates ``body.eta1``), and
:func:`assemble` adds elements, masses and constraints once bodies exist (a beam end may be
clamped to a rigid body).

Beam ends (``ends = [start, end]``): ``"free"`` (the node's rotation is a free coordinate: a pin
or a free end), ``"clamped"`` (rotation fixed to ground) or the name of a planar rigid body (the
node's rotation follows that body: a weld).  Translation is whatever the end point is: fixed,
free, or shared with bodies and joints.

Theory guidance (recorded per beam and issued as :class:`BeamTheoryWarning`): Euler–Bernoulli
below slenderness L/d = ``EB_SLENDERNESS`` neglects shear and rotary inertia that matter, and
below ``MIN_SLENDERNESS`` neither beam theory describes the body well.

FE bodies: reduced mass and stiffness matrices (Craig–Bampton or modal) on the coordinates
z = [interface dofs; modal coordinates], the interface dofs being (u_x, u_y, θ) per interface node
(``interface_dofs = 3``) or (u_x, u_y) (``= 2``), displacements from the reference positions in
the case's frame.  The body is linear about that reference (small motion; no geometric
stiffness): U = ½ zᵀ K z, T = ½ żᵀ M ż, z = C q + d.
"""

from __future__ import annotations

import math
import warnings
from dataclasses import dataclass, field

import numpy as np

from ..errors import CaseError, ReportedWarning
from ..model.affine import Affine, combine
from ..model.beams import (
    THEORIES,
    BeamElement,
    BeamSection,
    RotationLock,
    section_properties,
)
from .fe_bodies import assemble_fe, fe_spec
from .fields import (Fields, beam_end_points, check_range, element_count, expand,
                     slenderness_warnings)

__all__ = ["BeamTheoryWarning", "EB_SLENDERNESS", "MIN_SLENDERNESS", "AUTO_START_ELEMENTS",
           "allocate", "assemble", "parse_refinement"]

EB_SLENDERNESS = 10.0  # below this, Euler–Bernoulli neglects shear that matters
MIN_SLENDERNESS = 5.0  # below this, no beam theory is adequate
AUTO_START_ELEMENTS = 2  # elements of an "auto" beam before refinement
MAX_ELEMENTS = 100_000  # elements of one beam (a stated limit: README, "Input rules")
MIN_NORMAL = float(np.finfo(float).tiny)  # smallest normal double


class BeamTheoryWarning(ReportedWarning):
    """A beam theory used outside the slenderness range where it is accurate."""


def _flexible3d():
    from . import flexible3d  # 3-D cases only

    return flexible3d


@dataclass
class _BeamSpec:
    name: str
    label: str
    points: tuple
    length: float
    section: BeamSection
    depth: float
    n_elements: int
    auto: bool
    ends: tuple
    node_pos: list = field(default_factory=list)  # initial (x, y) per node
    pos_idx: list = field(default_factory=list)  # coordinate indices (−1 fixed) per node
    theta_idx: list = field(default_factory=list)  # coordinate index or −1 per node
    theta0: float = 0.0
    warnings: list = field(default_factory=list)


# ---------------------------------------------------------------------------------------------
def _new_coord(b, name, value, kind):
    return b.assembly.coordinate(name, value, kind)


def _parse_ends(f):
    ends = f.raw("ends", ["free", "free"])
    if (not isinstance(ends, list) or len(ends) != 2
            or not all(isinstance(e, str) for e in ends)):
        raise f.error('ends must be [start, end], each "free", "clamped" or a body name')
    return tuple(ends)


def _beam_spec(b, f, mesh_override):
    name = f.text("name")
    if "." in name or name in b.point_index:
        raise f.error(f"beam name {name!r} is used already or contains '.'")
    pa, pb = beam_end_points(b, f)
    init_len = float(np.linalg.norm(b.point_pos[pb] - b.point_pos[pa]))
    length = f.num("length", init_len, positive=True)
    if init_len == 0:
        raise f.error("the end points coincide in the case: the beam's direction is undefined")
    E = f.num("E", positive=True)
    rho = f.num("rho", positive=True)
    theory = f.text("theory", "euler-bernoulli")
    if theory not in THEORIES:
        raise f.error(f"theory must be one of {', '.join(THEORIES)}, got {theory!r}")
    sec = f.raw("section", None)
    kappa_default = 5.0 / 6.0
    if sec is not None:
        if f.has("A") or f.has("I"):
            raise f.error("give either section = {...} or A and I, not both")

        sf = Fields(sec, f"{f.label}.section", f.names)
        shape = sf.text("shape")
        if shape == "rectangle":
            dims = {"b": sf.num("b", positive=True), "h": sf.num("h", positive=True)}
        elif shape == "circle":
            dims = {"d": sf.num("d", positive=True)}
        else:
            raise sf.error(f"shape must be 'rectangle' (b, h) or 'circle' (d), got {shape!r}")
        sf.done()
        props = sf.formed("the section's area and second moment",
                          lambda: section_properties(shape=shape, dims=dims))
        A, I_area, depth, kappa_default = (props["A"], props["I"], props["depth"],
                                           props["kappa"])
        if not (A >= MIN_NORMAL and I_area >= MIN_NORMAL):
            raise sf.error(f"the section's area {A:g} or second moment {I_area:g} vanishes below "
                           f"the double-precision range: the section is too small")
        f.raw("depth", None)
    else:
        A = f.num("A", positive=True)
        I_area = f.num("I", positive=True)
        depth = f.num("depth", f.formed("the depth sqrt(12 I/A)",
                                        lambda: math.sqrt(12.0 * I_area / A)),
                      positive=True)
    kappa = f.num("shear_coefficient", kappa_default, positive=True)
    G = f.num("G", None)
    nu = f.num("nu", None)
    if G is not None and nu is not None:
        raise f.error("give either G or nu, not both")
    if G is None:
        if nu is None:
            if theory == "timoshenko":
                raise f.error("a Timoshenko beam needs the shear modulus G or Poisson's ratio nu")
            nu = 0.3
        if not -1.0 < nu < 0.5:
            raise f.error(f"nu must lie in (−1, 0.5), got {nu:g}")
        G = check_range(E / (2.0 * (1.0 + nu)), "G = E/(2(1 + nu))", f.label)
    elif not G > 0:
        raise f.error(f"G must be positive, got {G:g}")
    n, auto = element_count(f, AUTO_START_ELEMENTS, MAX_ELEMENTS, mesh_override)
    ends = _parse_ends(f)
    f.done()
    section = BeamSection(E=E, G=G, A=A, I=I_area, rho=rho, kappa=kappa, theory=theory)
    spec = _BeamSpec(name=name, label=f.label, points=(pa, pb), length=length, section=section,
                     depth=depth, n_elements=n, auto=auto, ends=ends)
    spec.warnings.extend(slenderness_warnings(theory, length / depth, EB_SLENDERNESS,
                                              MIN_SLENDERNESS))
    return spec


def allocate(b, mesh=None):
    """Parse ``[[beams]]`` and ``[[fe_bodies]]`` and add their coordinates to the builder ``b``."""
    mesh = mesh or {}
    b.beam_specs, b.fe_specs = [], []
    items = b.data.get("beams", [])
    if items and b.dim == 3:  # spatial beams: their own reader (DESIGN §8, 3-D flexible bodies)
        _flexible3d().allocate(b, mesh, auto_start=AUTO_START_ELEMENTS, max_elements=MAX_ELEMENTS,
                               eb_slenderness=EB_SLENDERNESS, min_slenderness=MIN_SLENDERNESS,
                               warning=BeamTheoryWarning)
        items = []
    elif items and b.dim != 2:
        raise CaseError("beams need dimension = 2 or 3", element="beams")
    names = set()
    for k, (item, label, params) in enumerate(expand("beams", items, b.params)):
        f = Fields(item, label, params)
        name = item.get("name")  # any TOML value; a non-string is refused by _beam_spec
        spec = _beam_spec(b, f, mesh.get(k, mesh.get(name) if isinstance(name, str) else None))
        if spec.name in names:
            raise f.error(f"duplicate beam name {spec.name!r}")
        names.add(spec.name)
        pa, pb = spec.points
        xa, xb = b.point_pos[pa], b.point_pos[pb]
        chord = xb - xa
        spec.theta0 = math.atan2(chord[1], chord[0])
        n = spec.n_elements
        for i in range(n + 1):
            if i == 0 or i == n:
                p = pa if i == 0 else pb
                spec.node_pos.append(b.point_pos[p])
                spec.pos_idx.append(b.point_index[p])
            else:
                r = xa + chord * (i / n)
                idx = [_new_coord(b, f"{spec.name}.n{i}.{ax}", r[a], "length")
                       for a, ax in enumerate("xy")]
                spec.node_pos.append(r)
                spec.pos_idx.append(np.array(idx, dtype=np.intp))
            end = 0 if i == 0 else 1 if i == n else None
            if end is not None and spec.ends[end] == "clamped":
                spec.theta_idx.append(-1)
            else:
                spec.theta_idx.append(_new_coord(b, f"{spec.name}.n{i}.theta", spec.theta0,
                                                 "angle"))
        for msg in spec.warnings:
            warnings.warn(f"{label}: {msg}", BeamTheoryWarning, stacklevel=4)
        b.beam_specs.append(spec)
    items = b.data.get("fe_bodies", [])
    if items and b.dim not in (2, 3):
        raise CaseError("fe_bodies need dimension = 2 or 3", element="fe_bodies")
    for item, label, params in expand("fe_bodies", items, b.params):
        b.fe_specs.append(fe_spec(b, Fields(item, label, params), _new_coord))


# ---------------------------------------------------------------------------------------------
def assemble(b, forces, constraints, mass_blocks, mass_elements, g_const, gravity):
    """Add beam and FE-body elements; return the model's ``flexible`` record."""
    q_init = np.array(b.q_init)
    record = {}
    refinement = parse_refinement(b.data.get("refinement"), b.params)
    if refinement and not any(s.auto for s in b.beam_specs):
        raise CaseError('[refinement] needs a beam with elements = "auto"', element="refinement")
    shafts = []  # spinning 3-D beams: whirl stations (mbseig.model.spatial_whirl.rotors)
    if b.dim == 3 and b.beam_specs:
        record, shafts = _flexible3d().assemble(b, forces, constraints, mass_elements,
                                                mass_blocks, g_const, gravity)
    for spec in (b.beam_specs if b.dim == 2 else ()):
        b.mass_reference = q_init  # (every M_ref of a 2-D beam is evaluated here)
        record[spec.name] = _assemble_beam(b, spec, q_init, forces, constraints, mass_blocks,
                                           mass_elements, g_const, gravity)
    for spec in b.fe_specs:
        record[spec["name"]] = assemble_fe(b, spec, constraints, forces, mass_blocks, _lock,
                                           _ErrorOnly)
    if not record:
        return {}
    out = {"bodies": record, "refinement": refinement}
    return {**out, "shafts": tuple(shafts)} if shafts else out


def parse_refinement(table, params):
    """``[refinement]``: modes (count), f_max [Hz], accuracy, max_elements → dict or {}."""
    if table is None:
        return {}
    f = Fields(table, "refinement", params)
    out = {"modes": f.num("modes", None), "f_max": f.num("f_max", None, positive=True),
           "accuracy": f.num("accuracy", 1e-3, positive=True),
           "max_elements": f.num("max_elements", 256, positive=True)}
    f.done()
    if out["modes"] is None and out["f_max"] is None:
        raise f.error("name the modes of interest: modes = K (the lowest K) and/or f_max [Hz]")
    if out["modes"] is not None:
        if not (float(out["modes"]).is_integer() and out["modes"] >= 1):
            raise f.error(f"modes must be a positive integer, got {out['modes']:g}")
        out["modes"] = int(out["modes"])
    n = out["max_elements"]
    if not (float(n).is_integer() and AUTO_START_ELEMENTS <= n <= MAX_ELEMENTS):
        raise f.error(f"max_elements must be an integer in {AUTO_START_ELEMENTS}..{MAX_ELEMENTS}, "
                      f"got {n:g}")
    out["max_elements"] = int(n)
    return {k: v for k, v in out.items() if v is not None}


def _node_affines(spec, k):
    pos = Affine.select(spec.pos_idx[k], spec.node_pos[k])
    t = spec.theta_idx[k]
    theta = Affine.select([t], [spec.theta0])
    return pos, theta


def _lock(b, label, body, theta):
    if body not in b.bodies:
        raise CaseError(f'end {body!r} is neither "free", "clamped" nor a body', element=label)
    u = b.body_dir(body)
    stacked = combine([(1.0, u), (1.0, theta)], stack=True)
    ux, uy, th = stacked(np.array(b.q_init))
    return RotationLock(f"{label} (rotation follows {body})", stacked, th - math.atan2(uy, ux))


def _assemble_beam(b, spec, q_init, forces, constraints, mass_blocks, mass_elements, g_const,
                   gravity):
    n = spec.n_elements
    l0 = spec.length / n
    nodes = [_node_affines(spec, k) for k in range(n + 1)]
    for k in range(n):
        (r1, t1), (r2, t2) = nodes[k], nodes[k + 1]
        w = combine([(1.0, r1), (1.0, t1), (1.0, r2), (1.0, t2)], stack=True)
        f = _ErrorOnly(spec.label)
        el = f.formed("the beam element's stiffness and mass",
                      lambda k=k, w=w: BeamElement(f"{spec.label} element {k + 1}", w,
                                                   spec.section, l0))
        if el.idx.size == 0:
            continue
        M_ref = f.formed("the beam element's mass matrix", lambda el=el: el.mass(q_init))
        forces.append(el)
        mass_elements.append((el, M_ref))
        mass_blocks.append((el.idx, el.idx, M_ref))
    if gravity is not None:
        s = spec.section
        for k, (r, _) in enumerate(nodes):
            share = 0.5 if k in (0, n) else 1.0
            np.add.at(g_const, r.idx, r.C.T @ (share * s.rho * s.A * l0 * gravity))
    for end, k in ((0, 0), (1, n)):
        what = spec.ends[end]
        if what in ("free", "clamped"):
            continue
        c = _lock(b, spec.label, what, nodes[k][1])
        b.add_constraint(constraints, c, _ErrorOnly(spec.label))
    for k in range(1, n):
        b.markers[f"{spec.name}.n{k}"] = nodes[k][0]
    s = spec.section
    return {
        "type": "beam", "theory": s.theory, "elements": n, "auto": spec.auto,
        "length": spec.length, "depth": spec.depth, "slenderness": spec.length / spec.depth,
        "shear_parameter": s.shear_parameter(spec.length), "E": s.E, "G": s.G, "A": s.A,
        "I": s.I, "rho": s.rho, "shear_coefficient": s.kappa, "ends": list(spec.ends),
        "warnings": list(spec.warnings), "nodes": [f"{spec.name}.n{k}" for k in range(n + 1)],
        "points": list(spec.points),
    }


class _ErrorOnly(Fields):
    """The error helpers of :class:`Fields` for an element whose table was read already."""

    def __init__(self, label):
        super().__init__({}, label, {})
