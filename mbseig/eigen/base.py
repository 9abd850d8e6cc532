"""The result every eigensolver path returns (:class:`QEPSolution`) and the refusal of a
singular pencil; the contract and registry of paths are in :mod:`mbseig.eigen.contract`."""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from ..errors import SolverError
from .measures import componentwise

__all__ = ["QEPSolution", "SingularPencilError"]


class SingularPencilError(SolverError):
    """det(M s² + P s + Q) ≡ 0: every s is an eigenvalue.  ``vector`` is a (numerical) null vector
    of the pencil in the coordinates of M, for the caller to name the coordinates."""

    def __init__(self, message, *, vector=None, **kw):
        super().__init__(message, **kw)
        self.vector = vector


@dataclass(frozen=True, eq=False)
class QEPSolution:
    """Finite eigenvalues of (M s² + P s + Q) x = 0 with their vectors and accuracy measures.

    eigenvalues : s (complex), all finite ones of the path (a partial path: those requested).
    vectors : unit right vectors x, one column per eigenvalue (the coordinates of M).
    left_vectors : conjugated left vectors ȳ (yᴴ = columns transposed), or None where the path
        did not form them.  For symmetric M, P, Q, y = x̄ exactly, and ``left_vectors`` is x.
    backward_error, condition : η and κ per pair (:mod:`mbseig.eigen.measures`).
    solver, reason : the path that ran and why it was chosen.
    n_infinite : infinite eigenvalues dropped (singular M).
    norms : (‖M‖_F, ‖P‖_F, ‖Q‖_F) of the problem the pairs were checked on.
    details : path-specific figures (scaling γ, shift, ARPACK sizes, ...).
    real_error : a sharper error bound of Re s where the path knows one (proportional damping).
    partial : True when only part of the spectrum was computed.
    n_dof : order n of the problem (2n eigenvalues, finite and infinite, for a dense path).
    complex_problem : M, P or Q complex: eigenvalues do not come in conjugate pairs.
    coverage : partial paths: what the computed set is known to contain (dict, see
        :func:`mbseig.eigen.solve_partial`); None for a dense path (everything).
    problem : (M, P, Q, γ) the pairs refer to (scaled copies where ``details["scaled"]``: s = γ μ),
        kept for :meth:`componentwise`; or the precomputed (η_c, κ_c), or a callable idx ↦
        (η_c, κ_c) of a partial path (formed on demand).
    """

    eigenvalues: np.ndarray
    vectors: np.ndarray
    backward_error: np.ndarray
    condition: np.ndarray
    solver: str
    reason: str
    n_infinite: int = 0
    norms: tuple = (0.0, 0.0, 0.0)
    details: dict = field(default_factory=dict)
    real_error: object = None
    left_vectors: object = None
    partial: bool = False
    n_dof: int = 0
    complex_problem: bool = False
    coverage: object = None
    problem: object = field(default=None, repr=False)

    def componentwise(self, idx=None):
        """(η_c, κ_c) of the pairs ``idx`` (default: all): componentwise backward errors and
        condition numbers (:func:`mbseig.eigen.measures.componentwise`), computed on demand."""
        idx = np.arange(self.eigenvalues.size) if idx is None else np.asarray(idx)
        if self.problem is None or idx.size == 0:
            return np.full(idx.size, np.inf), np.full(idx.size, np.inf)
        if callable(self.problem):  # a partial path's measures, formed on demand
            return self.problem(idx)
        if len(self.problem) == 2:  # precomputed by the path
            return self.problem[0][idx], self.problem[1][idx]
        M, P, Q, gamma = self.problem
        Yc = None if self.left_vectors is None else self.left_vectors[:, idx]
        s = self.eigenvalues[idx]
        mu = s.real / gamma + 1j * (s.imag / gamma)  # real divisions: a subnormal γ is exact
        eta_c, kappa_c = componentwise((M, P, Q), mu, self.vectors[:, idx], Yc)
        with np.errstate(over="ignore"):  # a bound beyond the double range is ∞: bounds nothing
            return eta_c, kappa_c * gamma
