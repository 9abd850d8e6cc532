"""Stage 3: eigensolvers for (M s² + P s + Q) x = 0 behind one contract (docs/design.md).

- :mod:`~mbseig.eigen.contract`: :class:`Problem`, :class:`Request`, the :class:`SolverPath`
  contract, the registry :data:`SOLVERS` and :func:`solve`, which every caller uses;
- :mod:`~mbseig.eigen.base`: the result type :class:`QEPSolution`;
- :mod:`~mbseig.eigen.measures`: structure tests, backward errors η and condition numbers κ,
  computed in one place for every path;
- :mod:`~mbseig.eigen.dense` (driver) and :mod:`~mbseig.eigen.dense_paths` (kernels): eigh,
  proportional, companion, qz (all eigenvalues);
- :mod:`~mbseig.eigen.small` and :mod:`~mbseig.eigen.small_measures`: the fused implementation
  of eigh and companion for small real dense problems (the same numbers; used by
  :func:`mbseig.modal.modes` through :mod:`mbseig.modal.small`);
- :mod:`~mbseig.eigen.partial` (driver), :mod:`~mbseig.eigen.searches`,
  :mod:`~mbseig.eigen.selection`, :mod:`~mbseig.eigen.shift_invert`,
  :mod:`~mbseig.eigen.projected`: shift-invert Lanczos/Arnoldi for a few modes of large sparse
  models, with the constraints kept in a bordered pencil.

Classification (stable / critical / unstable) is not made here but in :mod:`mbseig.modal`.
"""

from .base import QEPSolution, SingularPencilError
from .contract import (
    SOLVERS,
    Problem,
    Request,
    SolverPath,
    dense_solvers,
    partial_solvers,
    register,
    register_family,
    solve,
)
from .dense import choose_solver, solve_qep
from .descriptor import deflate_subspace as deflate_subspace
from .descriptor import descriptor_problem as descriptor_problem
from .measures import EPS
from .partial import solve_partial, sparse_structure

__all__ = ["SOLVERS", "Problem", "Request", "QEPSolution", "SingularPencilError", "SolverPath",
           "dense_solvers", "partial_solvers", "register", "register_family", "solve",
           "choose_solver", "solve_qep", "solve_partial", "sparse_structure", "EPS"]
