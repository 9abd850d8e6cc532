"""Stage 5: time-domain verification of predicted modes against the nonlinear model.

- :mod:`~mbseig.check.dynamics`: index-1 constrained dynamics with projection, integrators;
- :mod:`~mbseig.check.modes`: :func:`check_modes` starts on each mode, fits δ and ω of the
  modal coordinate and compares them with the prediction (docs/design.md, "Time-domain check").
"""

from .dynamics import INTEGRATORS, ForwardDynamics, Simulation, simulate
from .modes import CheckResult, ModeCheck, check_modes, parse_mode_list

__all__ = ["INTEGRATORS", "ForwardDynamics", "Simulation", "simulate", "CheckResult",
           "ModeCheck", "check_modes", "parse_mode_list"]
