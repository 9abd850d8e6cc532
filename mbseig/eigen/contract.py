"""The solver contract: a problem, a request, and the one registry of paths (docs/design.md,
"Solvers").

Every caller solves through :func:`solve`::

    sol = solve(Problem(M, P, Q), Request(solver="auto"))                 # all eigenvalues
    sol = solve(Problem(M, P, Q, G=Phi_q), Request(n_modes=20))           # a few, sparse

A path is a :class:`SolverPath`: its name, its family (``dense``: every eigenvalue; ``partial``:
the modes a request selects from a sparse problem), the structure it needs in words, a test
``applies(structure)`` and the ``kernel`` that runs it.  A family is a driver (one function of
``(problem, request)``) that does what all its paths share (checks, scaling, structure, the
backward-error verification) and calls the kernel of the path it chose.  Adding a path is one
:func:`register` call; adding a family (a descriptor pencil, a GPU path) is one
:func:`register_family` call and the paths that belong to it.  Every path returns a
:class:`~mbseig.eigen.base.QEPSolution`, which says which path ran and why.

The structure a driver found is a :class:`Structure`: the path ``auto`` takes, the reason in
words, path options found on the way (the Rayleigh coefficients), whether M is symmetric
positive definite.  ``applies`` returns ``None`` when the path can run on it, else the message
of the refusal.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from types import MappingProxyType
from collections.abc import Callable, Mapping

from ..errors import SolverError

__all__ = ["Problem", "Request", "Structure", "SolverPath", "SOLVERS", "FAMILIES", "register",
           "register_family", "solve", "select_path", "dense_solvers", "partial_solvers"]


@dataclass(frozen=True, eq=False)
class Problem:
    """(M s² + P s + Q) x = 0, with the constraint rows G = Φ_q kept beside it (partial paths:
    a bordered pencil) when M, P, Q are in full coordinates.  P may be None (no damping)."""

    M: object
    P: object
    Q: object
    G: object = None


@dataclass(frozen=True)
class Request:
    """What to compute: the path (``auto`` or a name of :data:`SOLVERS`), the selection of a
    partial spectrum (``n_modes`` nearest ``target`` rad/s, or every mode with ω_n in ``band``)
    and the path options (``sym_tol``, ``rayleigh_tol``, ``verify_tol``, ...; see the drivers
    :func:`mbseig.eigen.solve_qep` and :func:`mbseig.eigen.solve_partial`)."""

    solver: str = "auto"
    n_modes: int | None = None
    target: float | None = None
    band: tuple | None = None
    options: Mapping = field(default_factory=dict)

    def __post_init__(self):
        object.__setattr__(self, "options", MappingProxyType(dict(self.options)))

    @property
    def selects(self) -> bool:
        """A partial spectrum is asked for by the selection."""
        return self.n_modes is not None or self.target is not None or self.band is not None

    def family(self, problem: Problem | None = None) -> str:
        """The family that serves the request: ``partial`` when a selection, constraint rows or
        a partial path is asked for, else ``dense``."""
        path = SOLVERS.get(self.solver)
        if path is not None:
            return path.family
        if self.selects or (problem is not None and problem.G is not None):
            return "partial"
        return "dense"


@dataclass(frozen=True)
class Structure:
    """What a driver found of a problem: the path ``auto`` takes and why, options found on the
    way (``extras``), and facts that paths need (``mass_pd``: M symmetric positive definite,
    ``complex_problem``)."""

    path: str
    reason: str
    extras: Mapping = field(default_factory=dict)
    mass_pd: bool = True
    complex_problem: bool = False


@dataclass(frozen=True)
class SolverPath:
    """One eigensolver path (module docstring)."""

    name: str
    family: str
    needs: str  # the structure it requires, in words
    applies: Callable = field(repr=False, compare=False)  # Structure -> None or refusal text
    kernel: Callable = field(repr=False, compare=False)  # the family driver's call of the path
    #: what the driver must know of a path, declared here instead of tested by name:
    #: M must be symmetric positive definite (checked before the kernel runs)
    needs_definite_mass: bool = False
    #: M, P, Q must be real
    real_only: bool = False
    #: the kernel divides by the mass (mass normalization): a problem scaled for its range
    #: takes the general path instead
    divides_by_mass: bool = False
    #: the pencil's regularity is checked before the kernel (a singular pencil named)
    checks_regularity: bool = False

    @property
    def partial(self) -> bool:
        return self.family == "partial"


SOLVERS: dict[str, SolverPath] = {}
FAMILIES: dict[str, Callable] = {}


def register(name, *, family, needs, kernel, applies=None, **traits):
    """Add the path ``name`` of ``family`` to :data:`SOLVERS` (``applies`` defaults to
    "always"; ``traits``: the fields of :class:`SolverPath` the driver reads)."""
    SOLVERS[name] = SolverPath(name, family, needs, applies or (lambda structure: None), kernel,
                               **traits)


def register_family(name, driver):
    """``driver(problem, request) -> QEPSolution`` serves every path of family ``name``."""
    FAMILIES[name] = driver


def dense_solvers():
    return [k for k, v in SOLVERS.items() if v.family == "dense"]


def partial_solvers():
    return [k for k, v in SOLVERS.items() if v.family == "partial"]


def select_path(solver: str, structure: Structure, family: str, what="solver"):
    """(name, reason, extras) of the path to run: ``auto``'s choice, or the requested path of
    ``family`` when it applies to ``structure`` (else :class:`SolverError` with its refusal)."""
    if solver == "auto":
        return structure.path, structure.reason, dict(structure.extras)
    path = SOLVERS.get(solver)
    if path is None or path.family != family:
        names = [k for k, v in SOLVERS.items() if v.family == family]
        raise SolverError(f"unknown {what} {solver!r} (auto, {', '.join(names)})")
    refusal = path.applies(structure)
    if refusal is not None:
        raise SolverError(refusal)
    extras = dict(structure.extras)
    if path.name.removeprefix("partial-") == "proportional" and "alpha" not in extras:
        extras = {"alpha": 0.0, "beta": 0.0}  # undamped: the proportional path with α = β = 0
    return solver, f"requested ({structure.reason})", extras


def solve(problem: Problem, request: Request = Request()):
    """Solve ``problem`` as ``request`` asks, by the family that serves it."""
    family = request.family(problem)
    driver = FAMILIES.get(family)
    if driver is None:
        raise SolverError(f"no solver family {family!r} is registered ({', '.join(FAMILIES)})")
    return driver(problem, request)


def structured_applies(kind):
    """``applies`` of the structured paths ``eigh`` and ``proportional`` (dense or partial):
    eigh needs P = 0, proportional Rayleigh damping (or none), both a symmetric problem."""

    def applies(structure: Structure):
        auto = structure.path.removeprefix("partial-")
        prefix = "partial-" if structure.path.startswith("partial-") else ""
        if auto not in ("eigh", "proportional"):
            return f"solver {prefix + kind!r} does not apply: {structure.reason}"
        if kind == "eigh" and auto == "proportional":
            return f"solver {prefix + kind!r} does not apply: P is not zero"
        return None

    return applies
