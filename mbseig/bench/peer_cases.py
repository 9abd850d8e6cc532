"""The case files of the spatial peer models, written for mbseig as a user would (the same
bodies, joints and dashpots EXUDYN is given), through :class:`mbseig.CaseBuilder`."""

from __future__ import annotations

from ..casefile.writer import CaseBuilder


def _builder(p, source):
    case = CaseBuilder(dimension=3, source=source, gravity=[0.0, 0.0, -p["g"]])
    return case.point("O", [0.0, 0.0, 0.0], fixed=True)


def pendulum_case(p):
    """A body hung from the fixed point O by a spherical joint, rotational dashpots there."""
    case = _builder(p, "bench: spherical pendulum with rotational dashpots at the pivot "
                       "(non-proportional)")
    case.body("bob", mass=p["m"], com=[0.0, 0.0, -p["l"]], inertia=[p["Jx"], p["Jy"], p["Jz"]])
    pivot = {"bodies": ["ground", "bob"], "at": [0.0, 0.0, 0.0]}
    case.joint("spherical", "pivot", **pivot)
    case.force("bushing", "pivot dashpots", **pivot, stiffness=[0.0] * 6,
               damping=[0.0, 0.0, 0.0, p["cx"], p["cy"], p["cz"]])
    return case.to_toml()


def double_case(p):
    """Two links sharing basic points O (fixed) and A: spherical joints without [[joints]]."""
    case = _builder(p, "bench: spatial double pendulum (cases/spatial_double_pendulum.toml)")
    case.point("A", [0.0, 0.0, -p["l1"]])
    case.body("upper", mass=p["m1"], com=[0.0, 0.0, -p["c1"]], inertia=[p["J1"], p["J1"], p["Ja"]],
              points=["O", "A"])
    case.body("lower", mass=p["m2"], com=[0.0, 0.0, -(p["l1"] + p["c2"])],
              inertia=[p["J2"], p["J2"], p["Ja"]], points=["A"])
    return case.to_toml()
