"""Small example cases built in Python, for documentation examples and quick trials (as ROSS's
``rotor_example()``): each returns a read case (:class:`~mbseig.casefile.CaseSpec`) that every
function taking a case accepts, with a closed form to compare against.

>>> import mbseig
>>> a = mbseig.analyze(pendulum())
>>> a.kind, a.verdict
('rest', 'critical')
>>> round(float(a.modes.omega_n[0]), 10)   # sqrt(g/l)
3.1320919527
"""

from __future__ import annotations

from . import CaseSpec
from .writer import CaseBuilder

__all__ = ["pendulum", "damped_pendulum"]


def pendulum(*, m: float = 1.0, length: float = 1.0, g: float = 9.81) -> CaseSpec:
    """A planar pendulum: a point mass on a massless rod to a fixed pivot, gravity along −y.

    Parameters
    ----------
    m : float
        The bob's mass [kg].
    length : float
        The rod's length l [m] (the case's parameter ``l``).
    g : float
        Gravity [m/s²].

    Returns
    -------
    CaseSpec
        The case "pendulum": one undamped mode, ω_n = √(g/l) (closed form), verdict "critical"
        (no damping: δ = 0 within its bound).

    Examples
    --------
    >>> spec = pendulum(length=2.0)
    >>> sorted(spec.parameters)
    ['g', 'l', 'm']
    """
    return CaseSpec(_pendulum(m, length, g, c=None).to_dict(), "pendulum", None)


def damped_pendulum(*, m: float = 1.0, length: float = 1.0, g: float = 9.81,
                    c: float = 0.1) -> CaseSpec:
    """:func:`pendulum` with a translational dashpot c from the bob to a fixed point beside it.

    Parameters
    ----------
    m, length, g : float
        As :func:`pendulum`.
    c : float
        The dashpot's damping [N s/m], horizontal at the bob.

    Returns
    -------
    CaseSpec
        The case "damped_pendulum": one mode with δ = c/(2m) and ω_n = √(g/l) (the dashpot acts
        along the bob's motion), verdict "stable" for c > 0.

    Examples
    --------
    >>> import mbseig
    >>> a = mbseig.analyze(damped_pendulum(c=0.2))
    >>> a.verdict, round(float(a.modes.delta[0]), 12)
    ('stable', 0.1)
    """
    return CaseSpec(_pendulum(m, length, g, c=c).to_dict(), "damped_pendulum", None)


def _pendulum(m, length, g, c):
    case = CaseBuilder(dimension=2, title="Pendulum (point mass on a massless rod)",
                       gravity=[0.0, "-g"])
    case.parameters(m=float(m), l=float(length), g=float(g))
    case.point("O", [0.0, 0.0], fixed=True)
    case.point("P", [0.0, "-l"])
    case.mass("P", "m")
    case.joint("distance", "rod", points=["O", "P"], length="l")
    if c is not None:
        case.parameter("c", float(c))
        case.point("A", ["-l", "-l"], fixed=True)
        case.force("damper", "dashpot", points=["A", "P"], damping="c")
    return case
