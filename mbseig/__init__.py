"""mbseig: modal and stability analysis of constrained multibody systems.

Pipeline (each stage a function from one result object to the next)::

    load_case(path) ─► equilibrium(model) ─► linearize(model, eq) ─► modes(M, P, Q)
       Model              Equilibrium           LinearModel               Modes

Modules: :mod:`~mbseig.case` (case files), :mod:`~mbseig.model` (elements and assembly),
:mod:`~mbseig.statics` (equilibrium), :mod:`~mbseig.linear` (linearization and projection),
:mod:`~mbseig.qep` (eigensolvers), :mod:`~mbseig.modal` (classification), :mod:`~mbseig.cli`.
"""

from .case import LinearCase, load_case
from .errors import (CaseError, EquilibriumError, ExpressionError, MbseigError, SimulationError,
                     SolverError)
from .linear import LinearModel, linearize
from .modal import Modes, modes
from .model import Model
from .qep import QEPSolution, solve_qep
from .statics import Equilibrium, equilibrium
from .timedomain import CheckResult, ModeCheck, check_modes

__version__ = "0.1.0"

__all__ = [
    "load_case",
    "equilibrium",
    "linearize",
    "modes",
    "solve_qep",
    "check_modes",
    "LinearCase",
    "Model",
    "Equilibrium",
    "LinearModel",
    "Modes",
    "QEPSolution",
    "CheckResult",
    "ModeCheck",
    "MbseigError",
    "CaseError",
    "ExpressionError",
    "EquilibriumError",
    "SolverError",
    "SimulationError",
]
