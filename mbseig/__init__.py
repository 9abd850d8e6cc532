"""mbseig: modal and stability analysis of constrained multibody systems.

Pipeline (each stage a function from one result object to the next; docs/design.md)::

    load_case(path) ─► equilibrium(model) ─► linearize(model, eq) ─► modes(M, P, Q) ─► check_modes
       Model              Equilibrium           LinearModel               Modes          CheckResult

Packages, in the order of the pipeline (a stage imports only those before it; the layers
contract in pyproject.toml is checked by the test suite):

==================  ===========================================================================
``errors``          exception hierarchy
``numerics``        sparse assembly, constraint rank and null space, column norms, JSON values
``plots``           figures (matplotlib, no global state)
``model``           elements behind base classes, the assembled Model, LinearCase
``statics``         equilibrium, inverse statics (actuator commands), reactions
``linear``          LinearModel (M, P, Q, N) about an equilibrium
``eigen``           one registry of dense and partial eigensolvers; η and κ in one place
``modal``           classification: the only place a verdict is made
``check``           time-domain verification against the nonlinear model
``casefile``        the reader: TOML → Model; called only by the entry points below
``studies``         analyze, sweeps, refinement, runners
``report``          report blocks and rendering
``bench``           speed against accuracy
``cli``             one thin module per command
==================  ===========================================================================
"""

from .casefile import CaseSpec, load_case, read_case
from .check import CheckResult, ModeCheck, check_modes
from .eigen import QEPSolution, solve_qep
from .errors import (CaseError, EquilibriumError, ExpressionError, MbseigError, NumericalError,
                     ReportedWarning, SimulationError, SolverError)
from .linear import LinearModel, linearize
from .modal import Modes, modes
from .model import LinearCase, Model
from .statics import Equilibrium, equilibrium
from .studies import analyze, run_sweep

__version__ = "0.1.0"

__all__ = [
    "load_case",
    "read_case",
    "equilibrium",
    "linearize",
    "modes",
    "solve_qep",
    "check_modes",
    "analyze",
    "run_sweep",
    "CaseSpec",
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
    "NumericalError",
    "ReportedWarning",
]
