"""Synchronous unbalance response of a spinning rotor (DESIGN §8, flexible rotors; docs/beams3d.md).

An unbalance m·e at a station P (a beam station ``"BEAM.NAME"``, a body point, any point of the
case) spinning at Ω about the axis a exerts the rotating force

    F(t) = m e Ω² (cos(Ωt + φ) e₁ + sin(Ωt + φ) e₂) = Re(F̂ e^{iΩt}),   F̂ = m e Ω² e^{iφ} (e₁ − i e₂)

((e₁, e₂, a) right-handed, φ the unbalance's angle).  About the equilibrium at that speed the
reduced linear model M ẍ + P ẋ + Q x = Nᵀ C_Pᵀ F gives the steady response
x̂ = (Q − Ω² M + iΩ P)⁻¹ Nᵀ C_Pᵀ F̂; every station S of the case's rotors moves along
Re(X̂ e^{iΩt}), X̂ = C_S N x̂, reported as the amplitude and phase of its two lateral components
(along e₁, e₂) and the orbit's major semi-axis r_f + r_b (forward and backward circles, as for
the whirl).  Ω is the rotor speed of the model at each swept value (the first rotor's
``speed``), so the swept parameter may be any quantity the speed depends on.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..errors import CaseError
from ..linear import linearize
from ..model.spatial_joints import normal_pair
from ..model.spatial_whirl import rotors
from ..numerics import jsonable
from ..statics import equilibrium, solved
from .point import as_spec

__all__ = ["UnbalanceResponse", "unbalance_response"]


@dataclass(frozen=True, eq=False)
class UnbalanceResponse:
    """Response per speed (rows) and station (columns): complex lateral amplitudes along e₁ and
    e₂ [m], orbit major semi-axis [m]; ``speeds`` Ω [rad/s] at each ``values`` of ``parameter``."""

    case: str
    parameter: str
    values: np.ndarray
    speeds: np.ndarray
    stations: tuple
    X1: np.ndarray
    X2: np.ndarray
    unbalance: float
    at: str

    @property
    def major(self) -> np.ndarray:
        rf = np.abs(self.X1 + 1j * self.X2) / 2
        rb = np.abs(self.X1 - 1j * self.X2) / 2
        return rf + rb

    def to_json(self) -> dict:
        rows = []
        for j, st in enumerate(self.stations):
            rows.append({"station": st,
                         "amplitude_1": [float(x) for x in np.abs(self.X1[:, j])],
                         "phase_1": [float(x) for x in np.angle(self.X1[:, j])],
                         "amplitude_2": [float(x) for x in np.abs(self.X2[:, j])],
                         "phase_2": [float(x) for x in np.angle(self.X2[:, j])],
                         "major": [float(x) for x in self.major[:, j]]})
        return jsonable({"case": self.case, "parameter": self.parameter,
                         "values": [float(v) for v in self.values],
                         "speed": [float(v) for v in self.speeds], "unbalance": self.unbalance,
                         "at": self.at, "stations": rows})

    def table(self) -> str:
        """A text table: speed, then the major semi-axis at every station."""
        head = ["speed [rad/s]"] + [f"{s} [m]" for s in self.stations]
        lines = ["  ".join(f"{h:>16s}" for h in head)]
        for k, w in enumerate(self.speeds):
            lines.append("  ".join([f"{w:16.6g}"] + [f"{x:16.6e}" for x in self.major[k]]))
        return "\n".join(lines)


def _point(model, at):
    try:
        return model.points[at]
    except (KeyError, TypeError):
        raise CaseError(f"unbalance: unknown point or station {at!r}", element="unbalance") from None


def unbalance_response(case, parameter, values, *, at, unbalance, phase=0.0, config=None,
                       fixed=None) -> UnbalanceResponse:
    """Synchronous response to the unbalance ``unbalance`` = m·e [kg m] at the point ``at`` over
    ``parameter`` = ``values`` (module docstring)."""
    spec = as_spec(case)
    values = np.asarray(values, float)
    speeds, X1, X2, names = [], [], [], None
    for v in values:
        model = spec.build(config, **{**(fixed or {}), parameter: float(v)})
        eq = equilibrium(model)
        model = solved(model, eq)
        rs = rotors(model)
        if not rs:
            raise CaseError("unbalance response needs a rotor or a spinning beam",
                            element="unbalance")
        lin = linearize(model, eq)
        if lin.constraint_jacobian is not None:
            raise CaseError("unbalance response needs the dense reduced model (a smaller case)",
                            element="unbalance")
        W = float(rs[0].speed)
        axis = rs[0].axis_map()(eq.q)
        e1, e2 = normal_pair(axis / np.linalg.norm(axis))
        P = _point(model, at)
        F = unbalance * W**2 * np.exp(1j * phase) * (e1 - 1j * e2)
        g = np.zeros(model.n, complex)
        np.add.at(g, P.idx, P.C.T @ F)
        Z = lin.Q - W**2 * lin.M + 1j * W * lin.P
        x = lin.N @ np.linalg.solve(Z, lin.N.T @ g)
        stations = [(f"{r.name}: {lab}", aff) for r in rs for lab, aff in r.stations]
        names = names or tuple(s for s, _ in stations)
        Xs = [aff.C @ x[aff.idx] for _, aff in stations]
        speeds.append(W)
        X1.append([e1 @ X for X in Xs])
        X2.append([e2 @ X for X in Xs])
    return UnbalanceResponse(case=spec.name, parameter=parameter, values=values,
                             speeds=np.array(speeds), stations=names, X1=np.array(X1),
                             X2=np.array(X2), unbalance=float(unbalance), at=at)
