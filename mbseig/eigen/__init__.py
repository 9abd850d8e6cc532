"""Stage 3: eigensolvers for (M s² + P s + Q) x = 0 behind one registry (docs/design.md).

- :mod:`~mbseig.eigen.base`: the result type :class:`QEPSolution`, the :class:`SolverPath`
  contract and the registry :data:`SOLVERS` (dense and partial paths);
- :mod:`~mbseig.eigen.measures`: structure tests, backward errors η and condition numbers κ,
  computed in one place for every path;
- :mod:`~mbseig.eigen.dense`: eigh, proportional, companion, qz (all eigenvalues);
- :mod:`~mbseig.eigen.partial`: shift-invert Lanczos/Arnoldi for a few modes of large sparse
  models, with the constraints kept in a bordered pencil.

Classification (stable / critical / unstable) is not made here but in :mod:`mbseig.modal`.
"""

from .base import SOLVERS, QEPSolution, SingularPencilError, SolverPath, dense_solvers, partial_solvers
from .dense import choose_solver, solve_qep
from .measures import EPS
from .partial import solve_partial, sparse_structure

__all__ = ["SOLVERS", "QEPSolution", "SingularPencilError", "SolverPath", "dense_solvers", "partial_solvers",
           "choose_solver", "solve_qep", "solve_partial", "sparse_structure", "EPS"]
