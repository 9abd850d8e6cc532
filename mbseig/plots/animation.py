"""Animated mode shapes: one period of a mode as a looping GIF (matplotlib's PillowWriter; Pillow
is a dependency of matplotlib, so nothing else is needed).

Frame k of ``frames`` shows the configuration q₀ + a·L·Re(e^{iθ_k} v) with θ_k = 2πk/frames
(v the mode shape scaled so that its largest component is 1 and real, a = ``amplitude``, L the
model's size), projected back onto the constraints Φ(q) = 0
(:func:`mbseig.plots.project_constraints`), exactly as the still pictures: bodies stay rigid.
A real mode (overdamped, divergent, rigid-body) does not oscillate; it is shown as the same
shape moving to and fro, q₀ + a·L·sin θ_k · v, and the title says which.  The equilibrium is
drawn in grey under every frame.  The axes are the same in every frame (the union of all
frames' points), in true aspect, so the motion is not rescaled from frame to frame.  Planar
models are drawn like :func:`mbseig.plots.mechanism_modes`, spatial ones in a 3-D view and two
projections like :func:`mbseig.plots.spatial.spatial_modes`, with each body's frame axes, so a
rotation about a body's own line (a rigid-body spin) is seen; the projections show every
direction (a rotor: the end view along its spin axis, both lateral directions at once, and a
side view).  Text is set at GIF_FONT points at GIF_DPI (12.5 px high), legible at the GIF's
own size.
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np

from ..errors import CaseError
from .common import STYLE, figure, fit
from .mechanism import (
    draw_guides,
    draw_mechanism,
    mechanism_layout,
    plane_point,
    project_constraints,
)
from .spatial import (
    all_points,
    draw_spatial,
    motion_views,
    set_view,
    set_view3d,
    spatial_layout,
    view_limits,
)

__all__ = ["mode_frames", "mode_figure", "oscillates", "write_mode_gif", "GIF_DPI", "MIN_TEXT_PX"]


def oscillates(kind, eigenvalue) -> bool:
    """Whether a mode is animated as an oscillation (Im s ≠ 0 and not classified overdamped,
    divergent or rigid-body); a real mode is shown to and fro (module docstring)."""
    return kind not in ("overdamped", "divergence", "rigid-body") and complex(eigenvalue).imag != 0


def _blit_writer():
    from matplotlib.animation import PillowWriter
    from PIL import Image

    class BlitWriter(PillowWriter):
        """matplotlib's PillowWriter (its GIF output: every frame, loop=0) whose frames are
        the canvas as drawn (the still background restored and the moving drawing blitted on
        it) instead of a full redraw of the figure per frame."""

        def grab_frame(self, **savefig_kwargs):
            rgba = np.asarray(self.fig.canvas.buffer_rgba())
            self._frames.append(Image.fromarray(np.ascontiguousarray(rgba[..., :3])))

    return BlitWriter


def _BlitWriter(**kw):
    return _blit_writer()(**kw)


def _scaled(v):
    v = np.asarray(v, dtype=complex)
    j = int(np.argmax(np.abs(v)))
    return v * np.exp(-1j * np.angle(v[j])) / max(float(np.abs(v[j])), 1e-300)


def mode_frames(model, q0, shape, *, oscillatory=True, frames=16, amplitude=0.12):
    """The configurations of one period (module docstring), each projected onto Φ(q) = 0;
    returns a list of arrays q."""
    if frames < 2:
        raise ValueError(f"frames must be at least 2, got {frames}")
    q0 = np.asarray(q0, float)
    L = float(getattr(model, "length_scale", 1.0))
    v = _scaled(shape)
    vr = v.real / max(float(np.max(np.abs(v.real))), 1e-300)
    out = []
    for k in range(frames):
        th = 2 * math.pi * k / frames
        d = (np.exp(1j * th) * v).real if oscillatory else math.sin(th) * vr
        out.append(project_constraints(model, q0 + amplitude * L * d)[0])
    return out


#: GIF output: pixels per inch and the point size of its text; 9 pt at 100 dpi is 12.5 px
#: high, and no text of a GIF is smaller than MIN_TEXT_PX pixels (legible at the GIF's own size)
GIF_DPI = 100
GIF_FONT = 9
MIN_TEXT_PX = 11


def mode_figure(model, q0, qs, *, title=""):
    """The figure of an animation and what draws one frame on it: (fig, axes, draw) with
    ``draw(q)`` adding the moving drawing of configuration q.  A spatial model is shown in a
    3-D view and two projections chosen by :func:`mbseig.plots.spatial.motion_views` (a rotor:
    the end view along its spin axis, both lateral directions, and a side view); a planar one
    as :func:`mbseig.plots.mechanism_modes` draws it.  The limits are the union of all frames."""
    q0 = np.asarray(q0, float)
    spatial = int(getattr(model, "dimension", 2)) == 3
    L = float(getattr(model, "length_scale", 1.0))
    small = GIF_FONT - 1  # tick labels: 8 pt at 100 dpi = 11.1 px
    if spatial:
        layout = spatial_layout(model)
        views = motion_views(model, layout, q0, qs)
        fig = figure(layout="constrained", figsize=(3.2 * (1 + len(views)), 3.6))
        fig.get_layout_engine().set(wspace=0.12)  # the 3-D view's z label needs room
        centre, half = view_limits(all_points(model, layout, [q0, *qs]), 0.2 * L)
        ax3 = fig.add_subplot(1, 1 + len(views), 1, projection="3d")
        draw_spatial(ax3, model, layout, q0, lambda P: (P[:, 0], P[:, 1], P[:, 2]),
                     colour="0.7", lw=1.5, symbols=True)
        set_view3d(ax3, centre, half)
        ax3.tick_params(labelsize=small)
        for lab in (ax3.xaxis.label, ax3.yaxis.label, ax3.zaxis.label):
            lab.set_fontsize(GIF_FONT)
        axes, planes = [ax3], []
        for j, (h, v, name) in enumerate(views):
            ax = fig.add_subplot(1, 1 + len(views), 2 + j)

            def proj(P, h=h, v=v):
                return P[:, h], P[:, v]
            draw_spatial(ax, model, layout, q0, proj, colour="0.7", lw=1.5, symbols=True)
            set_view(ax, centre, half, h, v)
            ax.set_xlabel("xyz"[h] + " [m]")
            ax.set_ylabel("xyz"[v] + " [m]")
            ax.set_title(name, fontsize=GIF_FONT)
            ax.tick_params(labelsize=small)
            ax.grid(True, lw=0.3)
            axes.append(ax)
            planes.append(proj)

        def draw(q):  # the frame axes show a spin about a body's own line
            draw_spatial(ax3, model, layout, q, lambda P: (P[:, 0], P[:, 1], P[:, 2]),
                         colour="tab:red", lw=2.0, triads=0.12 * L)
            for ax, proj in zip(axes[1:], planes, strict=True):
                draw_spatial(ax, model, layout, q, proj, colour="tab:red", lw=2.0,
                             triads=0.12 * L)
    else:
        layout = mechanism_layout(model, q0)
        pts = np.array([plane_point(model.points[n](q))
                        for q in [q0, *qs] for n in model.points]) * 1e3
        centre, half = view_limits(np.pad(pts, ((0, 0), (0, 1))), 0.2 * L * 1e3)
        fig = figure(layout="constrained", figsize=(4.8, 4.8))
        ax = fig.subplots()
        draw_guides(ax, layout, q0, 4 * half)
        draw_mechanism(ax, model, layout, q0, colour="0.7", lw=1.5, labels=True,
                       label_size=small)
        set_view(ax, centre, half, 0, 1)
        ax.set_xlabel("x [mm]")
        ax.set_ylabel("y [mm]")
        ax.tick_params(labelsize=small)
        ax.grid(True, lw=0.3)
        axes = [ax]

        def draw(q):
            draw_mechanism(ax, model, layout, q, colour="tab:red", lw=2.0)
    if title:
        fig.suptitle(title, fontsize=GIF_FONT)
    return fig, axes, draw


def write_mode_gif(model, q0, shape, path, *, label="", oscillatory=True, frames=16, fps=12,
                   amplitude=0.12, dpi=GIF_DPI):
    """Write the looping GIF of one mode to ``path`` (module docstring); returns the path."""
    import matplotlib

    path = Path(path)
    qs = mode_frames(model, q0, shape, oscillatory=oscillatory, frames=frames,
                     amplitude=amplitude)
    title = label + ("" if oscillatory else " (real mode: shape shown to and fro)")
    with matplotlib.rc_context({**STYLE, "font.size": GIF_FONT}):
        fig, axes, draw = mode_figure(model, q0, qs, title=title)
        from matplotlib.backends.backend_agg import FigureCanvasAgg

        fig.set_dpi(dpi)
        canvas = FigureCanvasAgg(fig)
        fit(fig)
        writer = _BlitWriter(fps=fps)
        try:
            with writer.saving(fig, str(path), dpi):
                for ax in axes:  # the limits are the frames' union: fixed from here on
                    ax.set_autoscale_on(False)
                canvas.draw()
                fig.set_layout_engine("none")  # laid out once: frames drawn over it as it is
                background = canvas.copy_from_bbox(fig.bbox)
                base = [set(ax.get_children()) for ax in axes]
                for q in qs:
                    # the still background restored, the moving drawing drawn over it, removed
                    canvas.restore_region(background)
                    draw(q)
                    moving = [(ax, [a for a in ax.get_children() if a not in keep])
                              for ax, keep in zip(axes, base, strict=True)]
                    for ax, artists in moving:
                        for artist in artists:
                            ax.draw_artist(artist)
                    writer.grab_frame()
                    for _, artists in moving:
                        for artist in artists:
                            artist.remove()
        except OSError as exc:
            raise CaseError(f"cannot write: {exc.strerror or exc}", file=str(path),
                            element="animation") from None
    return path
