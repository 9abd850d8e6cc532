"""Figures of spatial models: mode shapes in a true-aspect 3-D view beside three orthographic
views (the Campbell diagram is in :mod:`mbseig.plots.rotor`, re-exported here).

Like :mod:`mbseig.plots`, every function returns a :class:`matplotlib.figure.Figure` built
without pyplot (no backend switch, no global state) and drawn in a local rc context;
:func:`mbseig.plots.save` writes it.  Nothing here imports a stage: the model and results are
read by their attributes (duck typing):

- ``model.points``: name → affine map (callable on q, ``.idx`` empty for a fixed point);
- ``model.bodies``: name → record with ``carried`` (the user's basic points the body carries),
  ``markers`` (names in ``model.points``: its centre of mass first, then every point where a
  joint, spring or bushing acts on it, in the order the reader recorded them), ``mass`` and
  ``frame`` (the affine map of [r₀; u; v; w]); planar bodies have ``points`` instead;
- rotor elements (``body``, ``frame`` the carrier's frame map, ``axis`` in the carrier's
  axes, ``polar_inertia``, ``stations``: the (label, map) of the carrier's centre (or station)
  and of the body's other markers in the same order);
- ``model.flexible["bodies"]``: the 3-D beams (``type`` "beam", ``dimension`` 3, ``points``
  its end points, ``elements``, ``ends``); their nodes are the points ``BEAM.nK`` and their
  triads the coordinates ``BEAM.nK.u.x`` ... ``BEAM.nK.w.z`` (global axes at the reference).

A beam is drawn as a curve: between its nodes the cubic Hermite interpolation of the nodes'
displaced positions and tangents (each node's triad turning the reference axis; a clamped end
keeps it; where a node has no triad of its own, the chord), the deformed shape of the element's
own bending interpolation.  A body is drawn rigid: the displaced configuration
q₀ ± a·L·Re(e^{−iφ} x) is projected back
onto the constraints Φ(q) = 0 (:func:`mbseig.plots.project_constraints`), and its points are
affine maps of the body's frame, so they move together.  Each body is drawn as the segments
from its centre of mass to every point it carries and every joint or spring station on it (a
pendulum link is the line through its pivots); a body carrying a rotor element is drawn with
its disc (the circle of the uniform disc of the body's mass and the rotor's polar inertia,
radius √(2 J_p/m), normal to the spin axis); joints are open circles, fixed points black
squares, rotor stations (bearings) triangles; in the 3-D view each body's frame axes u (solid)
and v (dotted) show its rotation about its own line.
"""

from __future__ import annotations

import math

import numpy as np

from .common import SPATIAL_STYLE, figure, save
from .mechanism import project_constraints
from .rotor import WHIRL_COLOURS, campbell_diagram, campbell_range, speed_unit

__all__ = ["VIEWS", "WHIRL_COLOURS", "campbell_diagram", "campbell_range", "save",
           "spatial_modes", "spatial_layout", "draw_spatial", "view_limits", "speed_unit",
           "beam_curve", "SEGMENT_POINTS", "motion_views", "spin_axes"]

SEGMENT_POINTS = 8  # points drawn along each beam element (its Hermite interpolation)

#: (horizontal axis, vertical axis, title) of the three orthographic views
VIEWS = ((0, 1, "top (x, y)"), (0, 2, "front (x, z)"), (1, 2, "side (y, z)"))


def _vec3(p):
    p = np.asarray(p, float).ravel()
    return np.pad(p, (0, 3 - p.size)) if p.size < 3 else p[:3]


def spatial_layout(model):
    """What a spatial drawing shows, from the records the reader left on the model: per body
    its point names (centre of mass first), the rotor discs, the joints (points carried by two
    bodies or by a body and the ground, and the bodies' joint stations), the fixed points and
    the rotor stations (bearings), each with its name."""
    bodies, discs, stations = [], [], []
    carried_by = {}
    for name, b in model.bodies.items():
        markers = list(b.get("markers") or ())
        carried = [p for p in b.get("carried", ()) if p in model.points]
        if not markers and not carried:
            markers = list(b.get("points", ()))
        names = list(dict.fromkeys(markers[:1] + carried + markers[1:]))
        bodies.append({"name": name, "points": names})
        for p in carried:
            carried_by.setdefault(p, []).append(name)
    fixed = [n for n, a in model.points.items() if a.idx.size == 0 and "." not in n]
    joints = [p for p, bs in carried_by.items() if len(bs) > 1 or p in fixed]
    for _name, b in model.bodies.items():
        joints += list(b.get("markers") or ())[1:]
    for e in model.forces:
        if e.glyph != "rotor":
            continue
        if not e.stations:
            continue
        b = model.bodies.get(e.body) or {}
        mass = float(b.get("mass", 0.0) or 0.0)
        jp = float(e.polar_inertia)
        # the uniform disc of the carrier's mass; a carrier without a mass of its own (a beam
        # station) has no disc radius to show, and its station is drawn as a joint instead
        radius = math.sqrt(2 * jp / mass) if mass > 0 and jp > 0 else None
        discs.append({"body": e.body, "axis": np.asarray(e.axis, float), "radius": radius,
                      "frame": e.frame, "centre": e.stations[0][1]})
        markers = list(b.get("markers") or ())
        for k, (label, _) in enumerate(e.stations):
            if 0 < k < len(markers):
                stations.append({"name": label, "point": markers[k]})
    station_points = {s["point"] for s in stations}
    joints = [j for j in dict.fromkeys(joints) if j not in station_points]
    return {"bodies": bodies, "discs": discs, "joints": joints, "fixed": fixed,
            "stations": stations, "beams": _beams(model), "springs": _springs(model)}


def _springs(model):
    """(end, end) of every spring-like force whose two ends the reader recorded as points of
    the model (``model.element_ends``): drawn as a coil between them, or as a bushing symbol
    where the two ends meet."""
    ends = getattr(model, "element_ends", {}) or {}
    out = []
    for e in getattr(model, "forces", ()):
        pts = ends.get(e.name) or ()
        if len(pts) == 2 and all(p in model.points for p in pts):
            out.append(tuple(pts))
    return out


def _coil(a, b, turns=6, width=0.08):
    """A zigzag from a to b in 3-D, across a direction normal to b − a (``width`` of |b − a|)."""
    d = b - a
    length = float(np.linalg.norm(d))
    axis = np.eye(3)[int(np.argmin(np.abs(d)))]
    n = np.cross(d, axis)
    n *= width * length / (float(np.linalg.norm(n)) or 1.0)
    t = np.linspace(0.0, 1.0, 2 * turns + 1)
    side = np.zeros(t.size)
    side[1:-1:2], side[2:-1:2] = 1.0, -1.0
    return a[None, :] + t[:, None] * d[None, :] + side[:, None] * n[None, :]


def _beams(model):
    """The 3-D beams: node point names (start, BEAM.n1 ..., end), each node's triad
    coordinates (None without one), the reference axis and which ends are clamped."""
    index = {n: i for i, n in enumerate(getattr(model, "coordinate_names", ()) or ())}
    records = (model.flexible or {}).get("bodies") or {}
    q_ref = getattr(model, "q_init", None)
    out = []
    for name, rec in records.items():
        if rec.get("type") != "beam" or rec.get("dimension") != 3 or q_ref is None:
            continue
        # n node intervals (an order-p element spans p of them: "nodes" lists every node)
        ends, n = list(rec.get("points") or ()), len(rec.get("nodes") or ()) - 1
        if len(ends) != 2 or n < 1:
            continue
        nodes = [ends[0]] + [f"{name}.n{k}" for k in range(1, n)] + [ends[1]]
        if not all(p in model.points for p in nodes):
            continue
        chord = _vec3(model.points[ends[1]](q_ref)) - _vec3(model.points[ends[0]](q_ref))
        triads = []
        for k in range(n + 1):
            keys = [f"{name}.n{k}.{a}.{c}" for a in "uvw" for c in "xyz"]
            triads.append([index[c] for c in keys] if all(c in index for c in keys) else None)
        out.append({"name": name, "nodes": nodes, "triads": triads,
                    "axis": chord / max(np.linalg.norm(chord), 1e-300),
                    "clamped": [e == "clamped" for e in (rec.get("ends") or ("", ""))]})
    return out


def beam_curve(model, beam, q, n=SEGMENT_POINTS):
    """Points (m, 3) of a beam at configuration q: per element the cubic Hermite curve through
    its end nodes with their tangents R t₀ (R = [u v w] of the node's triad, t₀ the reference
    axis; a clamped end node keeps t₀; a node without a triad takes the element's chord)."""
    q = np.asarray(q, float)
    P = np.array([_vec3(model.points[p](q)) for p in beam["nodes"]])
    t0, last = beam["axis"], len(P) - 1

    def tangent(k, chord):
        idx = beam["triads"][k]
        if idx is not None:
            u, v, w = q[idx[0:3]], q[idx[3:6]], q[idx[6:9]]
            return t0[0] * u + t0[1] * v + t0[2] * w
        if (k == 0 and beam["clamped"][0]) or (k == last and beam["clamped"][1]):
            return t0
        return chord / max(np.linalg.norm(chord), 1e-300)

    s = np.linspace(0.0, 1.0, n + 1)[:, None]
    h00, h10 = 2 * s**3 - 3 * s**2 + 1, s**3 - 2 * s**2 + s
    h01, h11 = -2 * s**3 + 3 * s**2, s**3 - s**2
    pts = [P[:1]]
    for k in range(last):
        chord = P[k + 1] - P[k]
        ell = np.linalg.norm(chord)
        ta, tb = tangent(k, chord), tangent(k + 1, chord)
        pts.append((h00 * P[k] + h10 * ell * ta + h01 * P[k + 1] + h11 * ell * tb)[1:])
    return np.vstack(pts)


def _disc_circle(model, q, disc, n=48):
    """Points (n, 3) of a rotor's disc circle at configuration q: centred on the rotor's first
    station, normal to its spin axis (given in the carrier's axes u, v, w)."""
    f = np.asarray(disc["frame"](q), float)
    u, v, w = f[3:6], f[6:9], f[9:12]
    a = disc["axis"]
    axis = a[0] * u + a[1] * v + a[2] * w
    axis = axis / max(np.linalg.norm(axis), 1e-300)
    ref = np.eye(3)[int(np.argmin(np.abs(axis)))]
    e1 = np.cross(axis, ref)
    e1 /= np.linalg.norm(e1)
    e2 = np.cross(axis, e1)
    c = _vec3(disc["centre"](q))
    t = np.linspace(0, 2 * math.pi, n)
    return c + disc["radius"] * (np.outer(np.cos(t), e1) + np.outer(np.sin(t), e2))


def draw_spatial(ax, model, layout, q, project, *, colour, lw, alpha=1.0, symbols=False,
                 triads=None):
    """Draw the layout at configuration q on ``ax``; ``project`` maps an (n, 3) array to the
    tuple of coordinate arrays the axes plot (two for a projection, three for a 3-D axes).
    With ``triads`` (a length), each body's frame axes u (solid) and v (dotted) are drawn that
    long from its centre of mass, so a spin about a body's own line shows."""
    def xyz(names):
        return np.array([_vec3(model.points[n](q)) for n in names])

    if triads:
        for b in layout["bodies"]:
            rec = model.bodies.get(b["name"], {})
            if "frame" not in rec or not b["points"]:
                continue
            f = np.asarray(rec["frame"](q), float)
            c = _vec3(model.points[b["points"][0]](q))
            for axis, style in ((f[3:6], "-"), (f[6:9], ":")):
                ax.plot(*project(np.array([c, c + triads * axis])), style, color=colour,
                        lw=max(lw * 0.5, 0.6), alpha=alpha)

    for beam in layout.get("beams", ()):
        ax.plot(*project(beam_curve(model, beam, q)), "-", color=colour, lw=lw, alpha=alpha,
                solid_capstyle="round")
        if symbols:  # the nodes, small, on the equilibrium
            ax.plot(*project(xyz(beam["nodes"])), ".", color=colour, ms=2, alpha=alpha)
    for b in layout["bodies"]:
        P = xyz(b["points"])
        if len(P) == 1:
            ax.plot(*project(P), "o", color=colour, ms=3, alpha=alpha)
            continue
        for k in range(1, len(P)):
            ax.plot(*project(P[[0, k]]), "-", color=colour, lw=lw, alpha=alpha,
                    solid_capstyle="round")
        ax.plot(*project(P[:1]), "o", color=colour, ms=2.5, alpha=alpha)
    for a, b in layout.get("springs", ()):
        P = xyz([a, b])
        if float(np.linalg.norm(P[1] - P[0])) > 1e-9 * (float(np.abs(P).max()) or 1.0):
            ax.plot(*project(_coil(P[0], P[1])), "-", color=colour, lw=lw * 0.5, alpha=alpha)
        elif symbols:  # a bushing: its two ends meet at the reference
            ax.plot(*project(P[:1]), "x", ms=6, mec=colour, mew=0.9, alpha=alpha)
    for d in layout["discs"]:
        if d["radius"]:
            ax.plot(*project(_disc_circle(model, q, d)), "-", color=colour, lw=lw * 0.7,
                    alpha=alpha)
    if not symbols:
        return
    if layout["joints"]:
        ax.plot(*project(xyz(layout["joints"])), "o", ms=6, mfc="none", mec=colour, mew=0.9,
                alpha=alpha)
    if layout["stations"]:
        ax.plot(*project(xyz([s["point"] for s in layout["stations"]])), "^", ms=6, mfc="none",
                mec="tab:green", mew=0.9)
    if layout["fixed"]:
        ax.plot(*project(xyz(layout["fixed"])), "ks", ms=4)


def spin_axes(model, layout, q):
    """Global unit vectors of the spin axes at configuration q: each rotor element's axis
    (given in its carrier's axes) and each spinning beam's chord."""
    out = []
    for d in layout["discs"]:
        f = np.asarray(d["frame"](q), float)
        a = d["axis"]
        out.append(a[0] * f[3:6] + a[1] * f[6:9] + a[2] * f[9:12])
    records = (model.flexible or {}).get("bodies") or {}
    for beam in layout.get("beams", ()):
        if (records.get(beam["name"]) or {}).get("spin"):
            out.append(np.asarray(beam["axis"], float))
    return [a / max(float(np.linalg.norm(a)), 1e-300) for a in out]


def motion_views(model, layout, q0, qs):
    """The two orthographic views (horizontal axis, vertical axis, title) that show every
    direction a mode moves in.  A rotor (:func:`spin_axes`; the first one's nearest global
    axis a): the end view along a, whose two axes are both lateral directions (the whirl
    orbit), and the side view through a and the lateral axis the frames ``qs`` move more
    along.  Otherwise top (x, y) and front (x, z), which between them show x, y and z."""
    axes = spin_axes(model, layout, q0)
    if not axes:
        return [VIEWS[0], VIEWS[1]]
    a = int(np.argmax(np.abs(axes[0])))
    lat = [k for k in range(3) if k != a]
    ref = all_points(model, layout, [q0])
    move = np.zeros(3)
    for q in qs:
        move = np.maximum(move, np.max(np.abs(all_points(model, layout, [q]) - ref), axis=0))
    side = max(lat, key=lambda k: (move[k], -k))
    x = "xyz"
    return [(lat[0], lat[1], f"end ({x[lat[0]]}, {x[lat[1]]}): along the spin axis"),
            (a, side, f"side ({x[a]}, {x[side]})")]


def all_points(model, layout, qs):
    pts = []
    for q in qs:
        for b in layout["bodies"]:
            pts += [_vec3(model.points[n](q)) for n in b["points"]]
        for d in layout["discs"]:
            if d["radius"]:
                pts += list(_disc_circle(model, q, d, n=12))
        pts += [_vec3(model.points[n](q)) for n in layout["fixed"]]
        for beam in layout.get("beams", ()):
            pts += list(beam_curve(model, beam, q, n=2))
        pts += [_vec3(model.points[n](q)) for ends in layout.get("springs", ()) for n in ends]
    return np.array(pts)


def view_limits(points, min_span):
    """(centre, half-width) per axis: one half-width for all three (a true-aspect box), at
    least ``min_span``/2, so a view along a body's line is not blown up to rounding residues."""
    lo, hi = points.min(axis=0), points.max(axis=0)
    centre = 0.5 * (lo + hi)
    half = max(0.5 * float(np.max(hi - lo)) * 1.12, 0.5 * min_span)
    return centre, half


def set_view(ax, centre, half, h, v):
    ax.set_xlim(centre[h] - half, centre[h] + half)
    ax.set_ylim(centre[v] - half, centre[v] + half)
    ax.set_aspect("equal", adjustable="box")  # square limits: nothing for matplotlib to override


def set_view3d(ax, centre, half):
    ax.set_xlim(centre[0] - half, centre[0] + half)
    ax.set_ylim(centre[1] - half, centre[1] + half)
    ax.set_zlim(centre[2] - half, centre[2] + half)
    ax.set_box_aspect((1, 1, 1))  # equal limits in a cube: true aspect
    ax.set_xlabel("x [m]", labelpad=-6)
    ax.set_ylabel("y [m]", labelpad=-6)
    ax.set_zlabel("z [m]", labelpad=-6)
    ax.tick_params(labelsize=6, pad=0)
    ax.view_init(elev=22, azim=-58)


def _real_shape(v):
    v = np.asarray(v)
    j = int(np.argmax(np.abs(v)))
    vr = (v * np.exp(-1j * np.angle(v[j]))).real if np.iscomplexobj(v) else v
    return vr / max(np.max(np.abs(vr)), 1e-300)


def spatial_modes(model, q0, shapes, labels, *, amplitude=0.15, title="",
                  reference_label="equilibrium"):
    """One row a mode: a true-aspect 3-D view and the three orthographic views of the model at
    its reference (``reference_label``: the equilibrium, a steady motion; black) and displaced
    by ± the mode shape (red/blue), bodies drawn rigid (module docstring)."""
    import matplotlib
    from matplotlib.lines import Line2D

    with matplotlib.rc_context(SPATIAL_STYLE):
        n = max(len(labels), 1)
        fig = figure(figsize=(12.4, 3.1 * n + 0.5))  # laid out below (faster than constrained)
        gs = fig.add_gridspec(n, 4, width_ratios=[1.5, 1, 1, 1])
        L = float(getattr(model, "length_scale", 1.0))
        q0 = np.asarray(q0, float)
        layout = spatial_layout(model)
        for k in range(len(labels)):
            d = amplitude * L * _real_shape(shapes[:, k])
            # moved along the mode and projected back onto Φ(q) = 0: unit vectors stay unit
            # and rigid bodies rigid (a linear displacement stretches them by O(a²))
            q_plus = project_constraints(model, q0 + d)[0]
            q_minus = project_constraints(model, q0 - d)[0]
            centre, half = view_limits(all_points(model, layout, (q0, q_plus, q_minus)),
                                       0.2 * L)
            ax3 = fig.add_subplot(gs[k, 0], projection="3d")
            for q, col, lw, sym in ((q0, "k", 2.0, True), (q_plus, "tab:red", 1.0, False),
                                    (q_minus, "tab:blue", 1.0, False)):
                draw_spatial(ax3, model, layout, q, lambda P: (P[:, 0], P[:, 1], P[:, 2]),
                             colour=col, lw=lw, alpha=1.0 if sym else 0.8, symbols=sym,
                             triads=0.08 * L)
            set_view3d(ax3, centre, half)
            ax3.set_title(f"{labels[k]} — 3-D", fontsize=8)
            for c, (h, v, name) in enumerate(VIEWS):
                ax = fig.add_subplot(gs[k, c + 1])

                def proj(P, h=h, v=v):
                    return P[:, h], P[:, v]
                for q, col, lw, sym in ((q0, "k", 2.0, True), (q_plus, "tab:red", 1.0, False),
                                        (q_minus, "tab:blue", 1.0, False)):
                    draw_spatial(ax, model, layout, q, proj, colour=col, lw=lw,
                                 alpha=1.0 if sym else 0.8, symbols=sym)
                set_view(ax, centre, half, h, v)
                ax.set_xlabel("xyz"[h] + " [m]")
                ax.set_ylabel("xyz"[v] + " [m]")
                ax.set_title(name, fontsize=8)
                ax.grid(True, lw=0.3)
        handles = [Line2D([], [], color="k", lw=2, label=reference_label),
                   Line2D([], [], color="tab:red", lw=1, label="+ mode"),
                   Line2D([], [], color="tab:blue", lw=1, label="− mode (half a period later)"),
                   Line2D([], [], ls="none", marker="o", mfc="none", mec="k", ms=6,
                          label="joint"),
                   Line2D([], [], ls="none", marker="s", color="k", ms=4, label="fixed point")]
        if layout["beams"]:
            handles.append(Line2D([], [], color="0.3", lw=1.5, marker=".", ms=3,
                                  label="beam (nodes joined by the element's curve)"))
        if layout["stations"]:
            handles.append(Line2D([], [], ls="none", marker="^", mfc="none", mec="tab:green",
                                  ms=6, label="bearing / spring station"))
        if layout["discs"]:
            handles.append(Line2D([], [], color="0.3", lw=0.8, label="rotor disc"))
        fig.legend(handles=handles, loc="lower center", ncol=len(handles), fontsize=7,
                   frameon=False)
        if title:
            fig.suptitle(title)
        # plots.save widens the figure when the legend's row or the title is wider than it
        fig.subplots_adjust(left=0.03, right=0.99, bottom=0.35 / (3.1 * n + 0.5) + 0.06,
                            top=1 - (0.75 if title else 0.35) / (3.1 * n + 0.5), wspace=0.3,
                            hspace=0.45)
        return fig
