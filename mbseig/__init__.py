"""mbseig: modal and stability analysis of constrained multibody systems.

Pipeline (each stage a function from one result object to the next; docs/design.md)::

    load_case(path) ─► equilibrium(model) ─► linearize(model, eq) ─► modes(M, P, Q) ─► check_modes
       Model              Equilibrium           LinearModel               Modes          CheckResult

and for any reference motion the case declares (rest, steady or periodic;
:mod:`mbseig.studies.reference`)::

    find_reference(case) ─► linearize(model, reference) ─► analyze(case).verdict

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
``report``          report blocks and rendering of computed data (it computes nothing)
``studies``         the reference motion, analyze, sweeps, refinement, report data, runners
``bench``           speed against accuracy
``cli``             one thin module per command
==================  ===========================================================================

Names are imported on first use (PEP 562): ``import mbseig`` loads none of the stages, and each
command loads only what it runs.
"""

from .lazy import lazy_names

__version__ = "0.1.0"

#: public name -> the module that defines it, imported on first use (PEP 562): ``import mbseig``
#: costs nothing beyond the package itself, so ``mbseig modes`` loads only what it runs
_LAZY = {
    "load_case": "casefile", "read_case": "casefile", "CaseSpec": "casefile",
    "CaseBuilder": "casefile.writer", "to_toml": "casefile.writer", "import_urdf": "casefile.urdf",
    "equilibrium": "statics", "Equilibrium": "statics",
    "linearize": "studies.reference", "LinearModel": "linear",
    "find_reference": "studies.reference", "reference_kind": "studies.reference",
    "modes": "modal", "Modes": "modal",
    "solve_qep": "eigen", "QEPSolution": "eigen",
    "check_modes": "check", "CheckResult": "check", "ModeCheck": "check",
    "analyze": "studies", "run_sweep": "studies", "SweepResult": "studies",
    "write_report": "studies.report_data", "report_data": "studies.report_data",
    "LinearCase": "model", "Model": "model",
    "MbseigError": "errors", "CaseError": "errors", "ExpressionError": "errors",
    "EquilibriumError": "errors", "SolverError": "errors", "SimulationError": "errors",
    "NumericalError": "errors", "ReportedWarning": "errors",
}

__all__ = list(_LAZY)


__getattr__, __dir__ = lazy_names(__name__, globals(), _LAZY)
