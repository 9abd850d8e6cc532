"""FE bodies in case files (``[[fe_bodies]]``): reduced mass and stiffness matrices on
[interface dofs; modal coordinates] (:mod:`mbseig.casefile.flexible`, its module docstring).

Planar: 2 or 3 rows per interface point (u_x, u_y[, θ]).  3-D (DESIGN §8): 6 rows per interface
point, u_x, u_y, u_z, θ_x, θ_y, θ_z in global axes at the reference; ``rotations`` per point as
beam ``ends``: ``"free"`` adds three small-rotation coordinates ``FE.P.theta_x|y|z``,
``"clamped"`` holds θ = 0, a body name welds θ to that body's rotation,
θ = ½ Σₖ Eₖ⁰ × eₖ(q) (Eₖ⁰ its unit vectors at the reference: exact to first order, and the
body is linear about its reference like the planar one).
"""

from __future__ import annotations

import numpy as np

from ..model.affine import Affine, combine
from ..model.fe_body import LinearFEBody
from .fields import template
from .matrices import matrix_value

__all__ = ["assemble_fe", "fe_spec"]


def fe_spec(b, f, new_coord):
    name = f.text("name")
    if "." in name or name in b.point_index:
        raise f.error(f"FE body name {name!r} is used already or contains '.'")
    M = matrix_value(f.raw("mass"), f"{f.label}.mass", f.names, b.files)
    K = matrix_value(f.raw("stiffness"), f"{f.label}.stiffness", f.names, b.files)
    f.formed("the mass and stiffness matrices", lambda: (M, K))
    if M.shape != K.shape:
        raise f.error(f"mass is {M.shape[0]}×{M.shape[0]} but stiffness {K.shape[0]}×{K.shape[0]}")
    iface = f.raw("interface")
    if not isinstance(iface, list) or not iface or not all(isinstance(p, str) for p in iface):
        raise f.error("interface must be a non-empty list of point names (matrix node order)")
    iface = [template(p, f.names, f) for p in iface]
    for p in iface:
        if p not in b.point_index:
            raise f.error(f"unknown interface point {p!r}")
    if b.dim == 3:
        return _spec3d(b, f, name, M, K, iface, new_coord)
    ndof = f.num("interface_dofs", 3.0)
    if ndof not in (2.0, 3.0):
        raise f.error("interface_dofs must be 2 (u_x, u_y) or 3 (u_x, u_y, θ)")
    ndof = int(ndof)
    rots = f.raw("rotations", ["free"] * len(iface)) if ndof == 3 else []
    if ndof == 3 and (not isinstance(rots, list) or len(rots) != len(iface)):
        raise f.error("rotations must list one of \"free\", \"clamped\" or a body per interface "
                      "point")
    f.done()
    n_if = ndof * len(iface)
    if M.shape[0] < n_if:
        raise f.error(f"matrices are {M.shape[0]}×{M.shape[0]}, fewer than the {n_if} interface "
                      "dofs")
    for key, A in (("mass", M), ("stiffness", K)):
        if not np.allclose(A, A.T, rtol=1e-9, atol=1e-12 * np.abs(A).max()):
            raise f.error(f"{key} matrix is not symmetric")
    theta_idx = []
    for p, rot in zip(iface, rots, strict=False):  # rots is [] (no θ rows) when ndof == 2
        theta_idx.append(-1 if rot == "clamped"
                         else new_coord(b, f"{name}.{p}.theta", 0.0, "angle"))
    eta_idx = [new_coord(b, f"{name}.eta{k + 1}", 0.0, "modal") for k in range(M.shape[0] - n_if)]
    return {"name": name, "label": f.label, "M": M, "K": K, "interface": iface, "ndof": ndof,
            "rotations": list(rots), "theta_idx": theta_idx, "eta_idx": eta_idx}


def _spec3d(b, f, name, M, K, iface, new_coord):
    ndof = f.num("interface_dofs", 6.0)
    if ndof != 6.0:
        raise f.error("interface_dofs must be 6 (u_x, u_y, u_z, θ_x, θ_y, θ_z) in 3-D")
    rots = f.raw("rotations", ["free"] * len(iface))
    if (not isinstance(rots, list) or len(rots) != len(iface)
            or not all(isinstance(r, str) for r in rots)):
        raise f.error("rotations must list one of \"free\", \"clamped\" or a body per interface "
                      "point")
    rots = [template(r, f.names, f) for r in rots]
    for r in rots:
        if r not in ("free", "clamped") and r not in b.bodies:
            raise f.error(f'rotation {r!r} is neither "free", "clamped" nor a body')
    f.done()
    n_if = 6 * len(iface)
    if M.shape[0] < n_if:
        raise f.error(f"matrices are {M.shape[0]}×{M.shape[0]}, fewer than the {n_if} interface "
                      "dofs")
    for key, A in (("mass", M), ("stiffness", K)):
        if not np.allclose(A, A.T, rtol=1e-9, atol=1e-12 * np.abs(A).max()):
            raise f.error(f"{key} matrix is not symmetric")
    theta_idx = [[new_coord(b, f"{name}.{p}.theta_{a}", 0.0, "angle") for a in "xyz"]
                 if r == "free" else r for p, r in zip(iface, rots, strict=True)]
    eta_idx = [new_coord(b, f"{name}.eta{k + 1}", 0.0, "modal") for k in range(M.shape[0] - n_if)]
    return {"name": name, "label": f.label, "M": M, "K": K, "interface": iface, "ndof": 6,
            "rotations": list(rots), "theta_idx": theta_idx, "eta_idx": eta_idx}


def _rotation3d(b, t):
    """The small rotation θ (3 rows, Affine) of a 3-D interface point (module docstring)."""
    if isinstance(t, list):
        return Affine.select(t, [0.0, 0.0, 0.0])
    if t == "clamped":
        return Affine.constant(np.zeros(3))
    fr = b.frames[t]
    E0 = (fr.C[3:12] @ np.asarray(b.q_init)[fr.idx] + fr.d[3:12]).reshape(3, 3)
    S = 0.5 * np.hstack([np.array([[0.0, -e[2], e[1]], [e[2], 0.0, -e[0]], [-e[1], e[0], 0.0]])
                         for e in E0])
    return Affine(fr.idx, S @ fr.C[3:12], S @ fr.d[3:12])


def assemble_fe(b, spec, constraints, forces, mass_blocks, lock, error_only):
    if spec["ndof"] == 6:
        return _assemble3d(b, spec, forces, mass_blocks)
    terms = []
    for p, t in zip(spec["interface"], spec["theta_idx"] or [None] * len(spec["interface"]),
                    strict=True):
        pos0 = b.point_pos[p]
        terms.append((1.0, b.affine_of(p) - Affine.constant(pos0)))
        if spec["ndof"] == 3:
            terms.append((1.0, Affine.select([t], [0.0])))
    _attach(spec, terms, forces, mass_blocks)
    # rotations and theta_idx are [] when ndof == 2: nothing to lock then
    for _p, rot, t in zip(spec["interface"], spec["rotations"], spec["theta_idx"], strict=False):
        if rot in ("free", "clamped"):
            continue
        theta = Affine.select([t], [0.0])
        c = lock(b, spec["label"], rot, theta)
        b.add_constraint(constraints, c, error_only(spec["label"]))
    return {"type": "fe_body", "interface": list(spec["interface"]),
            "interface_dofs": spec["ndof"], "modal_coordinates": len(spec["eta_idx"]),
            "size": int(spec["M"].shape[0])}


def _attach(spec, terms, forces, mass_blocks):
    """The FE body's coordinates z (interface motions, then its modal coordinates) as one affine
    map of q, its stiffness as a force and its mass as a block of the model's mass matrix."""
    if spec["eta_idx"]:
        terms.append((1.0, Affine.select(spec["eta_idx"])))
    z = combine(terms, stack=True)
    body = LinearFEBody(spec["label"], z, spec["K"])
    if body.idx.size:
        forces.append(body)
        mass_blocks.append((z.idx, z.idx, z.C.T @ spec["M"] @ z.C))


def _assemble3d(b, spec, forces, mass_blocks):
    b.bind()  # the bodies' frames (idempotent; a weld reads them)
    terms = []
    for p, t in zip(spec["interface"], spec["theta_idx"], strict=True):
        terms.append((1.0, b.affine_of(p) - Affine.constant(b.point_pos[p])))
        terms.append((1.0, _rotation3d(b, t)))
    _attach(spec, terms, forces, mass_blocks)
    return {"type": "fe_body", "dimension": 3, "interface": list(spec["interface"]),
            "interface_dofs": 6, "rotations": list(spec["rotations"]),
            "modal_coordinates": len(spec["eta_idx"]), "size": int(spec["M"].shape[0])}
