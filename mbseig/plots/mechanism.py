"""Planar mechanisms and their mode shapes: bodies, joints, springs, guides and loads drawn at the
equilibrium and moved along each mode, projected back onto the constraints."""

from __future__ import annotations

import math

import numpy as np

from ..numerics import element_name, min_norm_projection
from .common import (
    figure,
    styled,
)


# ---------------------------------------------------------------------------------------------
# mechanism drawings
def project_constraints(model, q, *, tol=1e-12, max_iter=30):
    """q moved onto the constraint manifold Φ(q) = 0 by Gauss–Newton with minimum-norm steps
    (:func:`mbseig.numerics.min_norm_projection`); returns (q, max |Φ_k| / scale_k).  Displaying
    a mode by moving along it and projecting back keeps rigid bodies rigid (a linear
    displacement q₀ + a·v stretches them by O(a²))."""
    q = np.array(q, dtype=float)
    phi_fn, jac_fn = getattr(model, "phi", None), getattr(model, "phi_q", None)
    if phi_fn is None or jac_fn is None or not getattr(model, "n_constraints", 0):
        return q, 0.0
    scales = np.asarray(model.constraint_scales(), float)
    q, res, _, _ = min_norm_projection(phi_fn, jac_fn, q, scales, tol=tol, max_iter=max_iter)
    return q, res


def plane_point(p):
    """A point of a 1-D or 2-D model as (x, y) (a chain along x has y = 0)."""
    p = np.asarray(p, float).ravel()
    return np.pad(p, (0, 2 - p.size)) if p.size < 2 else p[:2]


def _point_pair(model, element):
    """Names (a, b) of the points ``element`` acts between (r_b − r_a), as the reader recorded
    them (:mod:`mbseig.model.assembly`), or None."""
    ends = getattr(model, "element_ends", {}).get(element.name)
    if not ends or ends[0] == "bodies" or len(ends) != 2:
        return None
    return ends if all(p in model.points for p in ends) else None


def mechanism_layout(model, q0):
    """What a planar drawing shows, from each element's declared glyph: bodies (basic points and
    body markers), fixed points, springs and dampers between named points, rods, lines that
    points slide on, torsional springs at the points their bodies share, and follower forces.
    Each entry names the element as the user did."""
    q0 = np.asarray(q0, float)
    out = {"bodies": [], "springs": [], "rods": [], "guides": [], "torsional": [], "loads": [],
           "fixed": [n for n, a in model.points.items() if a.idx.size == 0 and "." not in n]}
    for name, b in model.bodies.items():
        pts = list(b.get("points", ()))
        markers = [n for n in model.points if n.startswith(name + ".")]
        out["bodies"].append({"name": name, "points": pts, "markers": markers})
    body_dirs = {}
    for name, b in model.bodies.items():
        pts = list(b.get("points", ()))
        if len(pts) == 2:
            body_dirs[name] = pts
    for e in model.forces:  # each element's glyph is declared on its class (mbseig.model.base)
        user = element_name(e.name, part=False)
        if e.glyph == "spring":
            ends = _point_pair(model, e)
            if ends:
                out["springs"].append({"name": user, "ends": ends,
                                       "spring": float(e.stiffness) != 0,
                                       "damper": float(e.damping) != 0})
        elif e.glyph == "torsional":
            at = _torsion_point(model, e, body_dirs)
            if at is not None:
                out["torsional"].append({"name": user, "at": at})
        elif e.glyph == "load":
            out["loads"].append({"name": user, "element": e})
    for c in model.constraints:
        user = element_name(c.name, part=False)
        if c.glyph == "rod":
            if any(user == b["name"] for b in out["bodies"]):
                continue  # a body's rigid length: the body is drawn
            ends = _point_pair(model, c)
            if ends:
                out["rods"].append({"name": user, "ends": ends})
        elif c.glyph == "guide" and np.shape(c.G) == (1, 2):
            g = np.asarray(c.G[0], float)
            out["guides"].append({"name": user, "normal": g / np.linalg.norm(g),
                                  "offset": float(c.b[0]) / float(np.linalg.norm(g)),
                                  "point": c.point})
    return out


def _torsion_point(model, e, body_dirs):
    """The point shared by the two bodies a torsional element acts between (the joint), from
    the bodies the reader recorded (:mod:`mbseig.model.assembly`); with the ground as the
    first body, a fixed point of the second."""
    ends = getattr(model, "element_ends", {}).get(e.name)
    if not ends or ends[0] != "bodies":
        return None
    b1, b2 = ends[1], ends[2]
    if b2 not in body_dirs or (b1 is not None and b1 not in body_dirs):
        return None
    pts2 = set(body_dirs[b2])
    shared = pts2 & set(body_dirs[b1]) if b1 else {p for p in pts2 if model.points[p].idx.size == 0}
    return min(shared) if shared else body_dirs[b2][0]


def _zigzag(p, q, n=8, width=0.06):
    """Points of a spring symbol from p to q."""
    d = q - p
    L = np.linalg.norm(d)
    if L == 0:
        return np.array([p, q])
    t = d / L
    nrm = np.array([-t[1], t[0]])
    xs = [p, p + 0.2 * d]
    for k in range(n):
        xs.append(p + (0.2 + 0.6 * (k + 0.5) / n) * d + (1 if k % 2 == 0 else -1) * width * L * nrm)
    xs += [p + 0.8 * d, q]
    return np.array(xs)


def draw_mechanism(ax, model, layout, q, *, colour, lw, alpha=1.0, labels=False, ms=3,
                   label_size=None):
    """Draw the layout at q; with ``labels``, the elements' and points' names at
    ``label_size`` points (default 6, fixed points 7)."""
    small, big = (label_size, label_size) if label_size else (6, 7)

    def pt(n):  # a named point in mm
        return plane_point(model.points[n](q)) * 1e3

    free = [n for n, a in model.points.items() if a.idx.size and "." not in n]
    if free:  # every moving point (a point mass, a body end, a slider) as a dot
        r = np.array([pt(n) for n in free])
        ax.plot(r[:, 0], r[:, 1], "o", color=colour, ms=ms, alpha=alpha, zorder=3)
    for b in layout["bodies"]:
        if len(b["points"]) != 2:
            continue
        r = np.array([pt(b["points"][0]), pt(b["points"][1])])
        ax.plot(r[:, 0], r[:, 1], "-o", color=colour, lw=lw, ms=ms, alpha=alpha, zorder=3)
        for m in b["markers"]:  # a body marker (cuff): drawn as a rigid bracket of the body
            tri = np.array([r[0], pt(m), r[1]])
            ax.plot(tri[:, 0], tri[:, 1], "-", color=colour, lw=max(lw * 0.4, 0.5), alpha=alpha,
                    zorder=2)
    for rd in layout["rods"]:
        r = np.array([pt(rd["ends"][0]), pt(rd["ends"][1])])
        ax.plot(r[:, 0], r[:, 1], "-", color=colour, lw=lw * 0.6, alpha=alpha, zorder=2)
    for s in layout["springs"]:
        a, b = pt(s["ends"][0]), pt(s["ends"][1])
        z = _zigzag(a, b) if s["spring"] else np.array([a, b])
        ax.plot(z[:, 0], z[:, 1], "-", color=colour, lw=max(lw * 0.45, 0.6), alpha=alpha, zorder=2)
        if labels:
            mid = 0.5 * (a + b)
            kind = ("spring-damper" if s["spring"] and s["damper"] else
                    "spring" if s["spring"] else "damper")
            ax.annotate(f"{s['name']} ({kind})", mid, textcoords="offset points", xytext=(6, 0),
                        fontsize=small, color="0.3")
    for g in layout["guides"]:
        r = np.asarray(g["point"](q), float) * 1e3
        ax.plot(r[0], r[1], "s", color=colour, ms=ms + 3, mfc="none", alpha=alpha, zorder=3)
        if labels:
            ax.annotate(f"{g['name']} (slider)", r, textcoords="offset points",
                        xytext=(6, -8), fontsize=small, color="0.3")
    if labels:
        for t in layout["torsional"]:
            r = pt(t["at"])
            ax.plot(r[0], r[1], "o", ms=9, mfc="none", mec="0.5", mew=0.8, zorder=1)
        for n in layout["fixed"]:
            r = pt(n)
            ax.plot(r[0], r[1], "ks", ms=5, zorder=4)
            ax.annotate(n, r, textcoords="offset points", xytext=(-9, 3), fontsize=big)
        tors = {t["at"]: t["name"] for t in layout["torsional"]}
        for n, a in model.points.items():
            if a.idx.size and "." not in n:
                r = pt(n)
                extra = f" ({tors[n]} spring)" if n in tors else ""
                ax.annotate(n + extra, r, textcoords="offset points", xytext=(4, -9),
                            fontsize=small, color="0.25")
        for n in layout["fixed"]:
            if n in tors:
                ax.annotate(f"{tors[n]} spring", pt(n), textcoords="offset points",
                            xytext=(-9, -10), fontsize=small, color="0.25")


def draw_guides(ax, layout, q, extent):
    """Each guide as a dashed line across the drawing (the line the point slides on)."""
    for g in layout["guides"]:
        nrm = g["normal"]
        t = np.array([-nrm[1], nrm[0]])
        base = nrm * g["offset"] * 1e3
        ax.plot(*np.array([base - extent * t, base + extent * t]).T, "--", color="0.55", lw=0.8,
                zorder=1)


def _draw_loads(ax, model, layout, q, L_mm):
    for ld in layout["loads"]:
        e = ld["element"]
        v = np.asarray(e.stacked(q), float)
        r, u = v[:2] * 1e3, v[2:4]
        mag = float(e.magnitude)
        d = (np.sign(mag) if mag else 1.0) * u / max(np.linalg.norm(u), 1e-300) * 0.25 * L_mm
        ax.annotate("", xy=r + d, xytext=r,
                    arrowprops={"arrowstyle": "->", "color": "tab:green", "lw": 1.2,
                                "ls": "-" if mag else "--"}, zorder=4)
        ax.annotate(f"{ld['name']} ({mag:g} N, follower)", r + d, fontsize=6, color="tab:green",
                    textcoords="offset points", xytext=(3, -8))


@styled
def mechanism_modes(model, q0, shapes, labels, *, amplitude=0.12, title="", eigenvalues=None,
                    kinds=None):
    """The mechanism at equilibrium (black) with each mode shape superposed (one panel a mode).

    Every element the layout finds is drawn (bodies, body markers, rods, springs and dampers as
    zigzags, sliders on their dashed guides, torsional springs at their joints, follower loads
    as arrows).  A displaced configuration is q₀ + a·L·Re(e^{−iφ} v)/max|v| (a = ``amplitude``,
    L the model's size, φ the phase of the largest component) projected back onto Φ(q) = 0
    (:func:`project_constraints`), so rigid bodies stay rigid.  An oscillatory mode is drawn at
    ±a (red/blue); a real mode (``eigenvalues`` given, Im s = 0) is not an oscillation: it is
    drawn as its decay (or growth) e^{st} at t = 0, τ, 2τ, 3τ with τ = 1/|s|, fading.  With
    ``kinds`` (the modes' kinds), only "overdamped" and "divergence" modes are drawn so (a
    rigid-body mode's s ≈ 0 is not a decay).
    """
    def is_real(k):
        if eigenvalues is None:
            return False
        s = complex(eigenvalues[k])
        if kinds is not None:
            return kinds[k] in ("overdamped", "divergence") and s.real != 0
        return s.imag == 0.0 and s.real != 0.0

    n = len(labels)
    cols = min(n, 3) or 1
    rows = max(1, math.ceil(n / cols))
    L = float(model.length_scale)
    q0 = np.asarray(q0, float)
    layout = mechanism_layout(model, q0)
    pts0 = np.array([plane_point(model.points[nm](q0)) for nm in model.points]) * 1e3
    span = np.ptp(pts0, axis=0) + 0.5 * float(np.max(np.ptp(pts0, axis=0)))
    ratio = float(span[0] / max(span[1], 1e-300))  # panel width / height of the drawing
    panel_h = 3.9
    panel_w = min(max(panel_h * ratio, 2.4), 6.0) + 1.0
    fig = figure(layout="constrained", figsize=(panel_w * cols, (panel_h + 0.5) * rows + 0.7))
    axes = fig.subplots(rows, cols, squeeze=False)
    extent = 2.0 * float(np.max(np.ptp(pts0, axis=0))) + 1.0
    for k in range(rows * cols):
        ax = axes[k // cols][k % cols]
        if k >= n:
            ax.axis("off")
            continue
        v = np.asarray(shapes[:, k])
        j = int(np.argmax(np.abs(v)))
        vr = (v * np.exp(-1j * np.angle(v[j]))).real if np.iscomplexobj(v) else v
        vr = vr / max(np.max(np.abs(vr)), 1e-300)
        draw_guides(ax, layout, q0, extent)
        s = None if eigenvalues is None else complex(eigenvalues[k])
        if is_real(k):
            # a real mode: the shape decays (s < 0) or grows (s > 0) without oscillating
            growth = s.real > 0
            for i, t in enumerate((0.0, 1.0, 2.0, 3.0)):
                a = amplitude * math.exp((1 if growth else -1) * (t - (3.0 if growth else 0.0)))
                qd, _ = project_constraints(model, q0 + a * L * vr)
                draw_mechanism(ax, model, layout, qd, colour="tab:purple", lw=1.1,
                                alpha=0.9 - 0.2 * (i if not growth else 3 - i))
        else:
            for sign, col in ((1.0, "tab:red"), (-1.0, "tab:blue")):
                qd, _ = project_constraints(model, q0 + sign * amplitude * L * vr)
                draw_mechanism(ax, model, layout, qd, colour=col, lw=1.1, alpha=0.85)
        draw_mechanism(ax, model, layout, q0, colour="k", lw=2.2, labels=True)
        _draw_loads(ax, model, layout, q0, L * 1e3)
        lim_x = (pts0[:, 0].min(), pts0[:, 0].max())
        lim_y = (pts0[:, 1].min(), pts0[:, 1].max())
        pad = 0.25 * max(lim_x[1] - lim_x[0], lim_y[1] - lim_y[0])
        ax.set_xlim(lim_x[0] - pad, lim_x[1] + pad)
        ax.set_ylim(lim_y[0] - pad, lim_y[1] + pad)
        ax.set_aspect("equal", adjustable="box")
        ax.set_title(labels[k], fontsize=8)
        ax.set_xlabel("x [mm]")
        ax.set_ylabel("y [mm]")
        ax.grid(True, lw=0.3)
    from matplotlib.lines import Line2D

    handles = [Line2D([], [], color="k", lw=2.2, label="equilibrium"),
               Line2D([], [], color="tab:red", lw=1.1, label="+ mode (oscillatory)"),
               Line2D([], [], color="tab:blue", lw=1.1, label="− mode (half a period later)")]
    if any(is_real(k) for k in range(n)):
        handles.append(Line2D([], [], color="tab:purple", lw=1.1,
                              label="real mode: e^{st} at t = 0, τ, 2τ, 3τ (fading)"))
    if layout["guides"]:
        handles.append(Line2D([], [], color="0.55", ls="--", lw=0.8, label="slider guide"))
    if layout["torsional"]:
        handles.append(Line2D([], [], ls="none", marker="o", mfc="none", mec="0.5", ms=8,
                              label="torsional spring-damper"))
    fig.legend(handles=handles, loc="outside lower center", ncol=min(len(handles), 2 * cols),
               fontsize=7, frameon=False)
    if title:
        fig.suptitle(title)
    return fig
