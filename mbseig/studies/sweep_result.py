"""The result of a sweep (:class:`SweepResult`): the grid, every point, the eigenvalues tracked by
MAC along each line, the stability boundaries, folds, branches and boundary curves; its JSON,
its DataFrame and the mode numbers every table and figure of the sweep uses."""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from ..errors import MbseigError
from ..numerics import jsonable


# ---------------------------------------------------------------------------------------------
@dataclass(frozen=True, eq=False)
class SweepResult:
    """A sweep: grid, per-point results, tracked eigenvalues per line, stability boundaries, and
    the followed branches (continuation), folds and two-parameter boundary curves.

    ``tracks[l]`` is (n_points × n_tracks) complex for line l (the first axis varying, the other
    axes fixed at ``lines[l]``); ``boundaries`` lists every loss or recovery of stability;
    ``branches[l]`` the branch points of line l for the bifurcation diagram; ``folds`` every
    fold located on a branch; ``curves`` the boundaries followed across the second axis.
    """

    case: str
    config: str | None
    fixed: dict
    axes: list  # [(name, values), ...]
    lines: list  # per line: dict of the other axes' values
    points: list  # per line: list of point dicts
    tracks: list
    tolerances_track: list
    boundaries: list
    tolerances: dict = field(default_factory=dict)
    runner: str = "serial"
    branches: list = field(default_factory=list)
    events: list = field(default_factory=list)
    folds: list = field(default_factory=list)
    curves: list = field(default_factory=list)
    records: list = field(default_factory=list)
    diagram: dict = field(default_factory=dict)
    units: dict = field(default_factory=dict)  # parameter → unit, for the plots' axis labels

    @property
    def axis(self):
        return self.axes[0][0]

    @property
    def values(self):
        return self.axes[0][1]

    def abscissa_grid(self):
        """Spectral abscissa max Re s on the grid, shape (len(axis 0), len(lines))."""
        out = np.full((len(self.values), len(self.lines)), np.nan)
        for li, line in enumerate(self.points):
            for k, pt in enumerate(line):
                if not pt.get("error") and pt["eigenvalues"].size:
                    out[k, li] = float(np.max(pt["eigenvalues"].real))
        return out

    @staticmethod
    def listed_tracks(S):
        """Tracks to list: drop the mirror image (Im < 0 on average) of a complex-pair track."""
        keep = []
        for j in range(S.shape[1]):
            col = S[:, j]
            im = col.imag[~np.isnan(col)]
            if im.size and np.mean(im) < 0 and np.any(np.abs(im) > 0):
                continue
            keep.append(j)
        return keep

    def mode_numbers(self, line=0) -> dict:
        """Track → mode number along ``line``, numbered as the mode tables (``mbseig modes``)
        at the line's first point where the track exists: listed tracks sorted by ω_n = |s|,
        then by δ; tracks that appear later are numbered after them in order of appearance.
        Every plot and table of the sweep uses these numbers."""
        S = self.tracks[line]
        listed = self.listed_tracks(S)
        first = {}
        for j in listed:
            ok = np.flatnonzero(~np.isnan(S[:, j]))
            if ok.size:
                first[j] = int(ok[0])
        k0 = min(first.values(), default=0)
        at_start = sorted((j for j in first if first[j] == k0),
                          key=lambda j: (abs(S[k0, j]), -S[k0, j].real, j))
        later = sorted((j for j in first if first[j] != k0),
                       key=lambda j: (first[j], abs(S[first[j], j]), j))
        return {j: i + 1 for i, j in enumerate(at_start + later)}

    def to_dataframe(self):
        """The tracked eigenvalues as a long pandas DataFrame, one row per (line, point, mode):
        the other axes' values, the swept parameter, ``mode`` (:meth:`mode_numbers`), ``track``,
        ``re``, ``im``, ``delta`` [1/s], ``omega_n`` [rad/s], ``omega_d`` [rad/s], ``fn_hz``
        (ω_n/2π), ``fd_hz`` (ω_d/2π), ``zeta``, ``stable`` (δ + tol ≥ 0), the point's
        ``verdict`` and ``out_of_range``.  pandas is optional: it is imported here."""
        try:
            import pandas as pd
        except ImportError:
            raise MbseigError("SweepResult.to_dataframe needs pandas (pip install pandas)",
                              element="to_dataframe") from None
        others = [n for n, _ in self.axes[1:]]
        rows = []
        for li, line in enumerate(self.lines):
            S, T = self.tracks[li], self.tolerances_track[li]
            numbers = self.mode_numbers(li)
            for k, v in enumerate(self.values):
                pt = self.points[li][k]
                for j in self.listed_tracks(S):
                    s = S[k, j]
                    if np.isnan(s):
                        continue
                    wn = abs(s)
                    rows.append({**{n: float(line[n]) for n in others}, self.axis: float(v),
                                 "mode": numbers.get(j), "track": int(j), "re": float(s.real),
                                 "im": float(s.imag), "delta": float(-s.real),
                                 "omega_n": float(wn), "omega_d": float(abs(s.imag)),
                                 "fn_hz": float(wn / (2 * math.pi)),
                                 "fd_hz": float(abs(s.imag) / (2 * math.pi)),
                                 "zeta": float(-s.real / wn) if wn > 0 else 0.0,
                                 "stable": bool(-s.real + T[k, j] >= 0),
                                 "verdict": pt.get("verdict"),
                                 "out_of_range": ", ".join(pt.get("out_of_range") or [])})
        cols = others + [self.axis, "mode", "track", "re", "im", "delta", "omega_n", "omega_d",
                         "fn_hz", "fd_hz", "zeta", "stable", "verdict", "out_of_range"]
        return pd.DataFrame(rows, columns=cols)

    def __repr__(self) -> str:
        n_pts = sum(len(p) for p in self.points)
        failed = sum(1 for line in self.points for pt in line if pt.get("error"))
        axes = ", ".join(f"{n} {float(v[0]):g}…{float(v[-1]):g} ({len(v)})" for n, v in self.axes)
        losses = [b for b in self.boundaries if b["stability"] == "loss"]
        first = (f", first loss at {self.axis} = {min(b['value'] for b in losses):.6g}"
                 if losses else "")
        return (f"<SweepResult {Path(str(self.case)).stem}"
                + (f" [{self.config}]" if self.config else "")
                + f": {axes}; {n_pts} points ({failed} failed), {len(self.boundaries)} "
                  f"boundaries{first}, {len(self.folds)} folds, {len(self.curves)} curves; "
                  f"runner {self.runner}>")

    __str__ = __repr__

    def _repr_html_(self) -> str:
        import html

        return f"<pre>{html.escape(repr(self))}</pre>"

    def to_json(self) -> dict:
        lines = []
        for li, fixed in enumerate(self.lines):
            S = self.tracks[li]
            tracks = [{"track": int(j),
                       "eigenvalue": [[None, None] if np.isnan(v)
                                      else [float(v.real), float(v.imag)]
                                      for v in S[:, j]]}
                      for j in self.listed_tracks(S)]
            pts = [{"params": {k: float(v) for k, v in pt["params"].items()},
                    "verdict": pt.get("verdict"), "error": pt.get("error"),
                    "out_of_range": pt.get("out_of_range", []),
                    "statics": pt.get("statics"), "static": pt.get("static"),
                    "iterations": pt.get("iterations"), "segment": pt.get("segment")}
                   for pt in self.points[li]]
            branch = [{k: b[k] for k in ("p", "kind", "segment", "static", "verdict", "angles")}
                      | {"value": b.get("value")}
                      for b in (self.branches[li] if self.branches else [])]
            lines.append({"fixed": {k: float(v) for k, v in fixed.items()}, "points": pts,
                          "tracks": tracks, "branch": branch,
                          "continuation": self.records[li] if self.records else None})
        bounds = [b.to_json() for b in self.boundaries]
        return jsonable({
            "case": self.case, "config": self.config,
            "fixed": {k: v for k, v in self.fixed.items()},
            "axes": [{"name": n, "values": [float(x) for x in v]} for n, v in self.axes],
            "lines": lines, "boundaries": bounds, "folds": [f.to_json() for f in self.folds],
            "curves": [c.to_json() for c in self.curves],
            "diagram": self.diagram, "tolerances": self.tolerances,
        })
