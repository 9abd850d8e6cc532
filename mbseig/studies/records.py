"""The typed results of sweeps (:class:`mbseig.records.Record`: frozen, read by field name,
written to JSON in field order), each built here and only here.

- :class:`SweepPoint`: one grid point of a sweep (all eigenpairs, their tolerances, verdict);
- :class:`CampbellPoint`: one speed of a Campbell diagram (listed modes and their whirl);
- :class:`Boundary`: a loss or recovery of stability, located along the first axis (an
  eigenvalue crossing Re s = 0, or a fold or branch point of the followed branch);
- :class:`Fold`: a fold or branch point of a followed branch;
- :class:`BoundaryCurve`: a boundary followed across the second axis.
"""

from __future__ import annotations

from dataclasses import dataclass

from ..records import Record, internal, optional

__all__ = ["SweepPoint", "CampbellPoint", "Boundary", "Fold", "BoundaryCurve"]


@dataclass(frozen=True, eq=False)
class PointRecord(Record):
    """What every study point has: its parameters, the one-line error of a failed point, and
    (when it did not fail) its eigenvalues, their unit shapes and stability tolerances."""

    params: dict
    error: str | None = None
    eigenvalues: object = optional()
    shapes: object = optional()
    tol: object = optional()


@dataclass(frozen=True, eq=False)
class SweepPoint(PointRecord):
    """One point of a sweep.  A failed point has ``params`` and the one-line ``error`` only.

    eigenvalues, shapes (unit, full coordinates), tol : every eigenpair and the stability
        tolerance of each; verdict : the worst stability; out_of_range : joints outside their
        range of motion; solver; q, iterations : the equilibrium; static : its static verdict;
    statics : how the equilibrium was found ("continuation", "batch": the line's points solved
        together, or "cold"); segment, branch_kind,
        corrector_iterations : where the followed branch put it.
    """

    verdict: str | None = optional()
    out_of_range: list | None = optional()
    solver: str | None = optional()
    q: object = optional()
    iterations: int | None = optional()
    static: str | None = optional()
    statics: str | None = optional()
    segment: int | None = optional()
    branch_kind: str | None = optional()
    corrector_iterations: int | None = optional()

    @classmethod
    def failed(cls, params, error: str) -> SweepPoint:
        return cls(params=dict(params), error=error)


@dataclass(frozen=True, eq=False)
class CampbellPoint(PointRecord):
    """One speed of a Campbell diagram: the listed modes, their kinds, stability and whirl."""

    kind: list | None = optional()
    stability: list | None = optional()
    speed: float | None = optional()
    whirl: list | None = optional()


@dataclass(frozen=True, eq=False)
class Boundary(Record):
    """A loss or recovery of stability along the first axis of line ``line``.

    value : the parameter there; kind : flutter (a complex pair crosses) or divergence (a real
    eigenvalue, a fold, a branch point); stability : loss or recovery; eigenvalue : [re, im] at
    the boundary; band : the bracket the located value is known to lie in; event : crossing,
    fold or branch point; method and test : how it was located; shape, q : the crossing mode
    and equilibrium (for following it across a second axis; never written).
    """

    line: int
    fixed: dict
    parameter: str
    value: float
    track: int | None
    bracket: list | None
    eigenvalue: list
    kind: str
    stability: str
    converged: bool
    function_calls: int
    xtol: float
    event: str
    branch: str | None = optional()
    method: str = ""
    test: str | None = optional()
    band: list | None = None
    tolerance: float = 0.0
    shape: object = internal()
    q: object = internal()

    @classmethod
    def crossing(cls, *, line, fixed, parameter, track, bracket, kind, stability, xtol, found):
        """An eigenvalue crossing Re s = 0, from the result ``found`` of the boundary search."""
        return cls(line=line, fixed=fixed, parameter=parameter, value=found["value"],
                   track=track, bracket=bracket, eigenvalue=found["eigenvalue"], kind=kind,
                   stability=stability, converged=found["converged"],
                   function_calls=found["function_calls"], xtol=xtol, event="crossing",
                   method=found["method"], test=found["test"], band=found["band"],
                   tolerance=found["tolerance"], shape=found["shape"], q=found["q"])

    @classmethod
    def at_event(cls, fold: Fold, *, stability, xtol):
        """A fold or branch point of the branch that changes its stability (a divergence)."""
        method = ("fold of the branch: dp/ds = 0 by Brent's method on the arclength"
                  if fold.type == "fold" else
                  "branch point: det of the bordered Jacobian changes sign (bisection)")
        return cls(line=fold.line, fixed=fold.fixed, parameter=fold.parameter, value=fold.value,
                   track=None, bracket=None, eigenvalue=[0.0, 0.0], kind="divergence",
                   stability=stability, converged=True, function_calls=0, xtol=xtol,
                   event=fold.type, branch=fold.branch, method=method,
                   band=[fold.value, fold.value], tolerance=0.0)


@dataclass(frozen=True, eq=False)
class Fold(Record):
    """A fold or branch point located on the branch of line ``line``: what the branch does
    there, the stability before and after, the degrees of freedom and the named angles."""

    line: int
    fixed: dict
    parameter: str
    value: float
    type: str
    branch: str
    before: str | None
    after: str | None
    dof: int | None
    angles: dict | None


@dataclass(frozen=True, eq=False)
class BoundaryCurve(Record):
    """A boundary of the first line followed across the second axis ``along``: ``points``
    (p2, value, band, test), with the bend and insertion rules that placed them."""

    parameter: str
    along: str
    stability: str
    kind: str
    start: float
    points: list
    bend: float
    max_insert: int
    xtol: float
