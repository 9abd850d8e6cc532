"""A linear case: the matrices of (M s² + P s + Q) x = 0 given directly, no multibody model."""

from __future__ import annotations

from dataclasses import dataclass, field
from types import MappingProxyType

import numpy as np

__all__ = ["LinearCase"]


@dataclass(frozen=True, eq=False)
class LinearCase:
    """A linear case: (M s² + P s + Q) x = 0 given directly, M, P, Q possibly parameter sums."""

    name: str
    source: str
    parameters: dict
    M: np.ndarray
    P: np.ndarray
    Q: np.ndarray
    description: str = ""
    expected: dict = field(default_factory=dict)

    # what the stages read of every model (mbseig.model.Model), empty here: no elements, no
    # commands, no inputs or outputs, no report tables, no beams
    forces = ()
    constraints = ()
    velocity_constraints = ()
    commands = ()
    inputs = ()
    outputs = ()
    report = MappingProxyType({})
    flexible = MappingProxyType({})
    bodies = MappingProxyType({})

    @property
    def n(self) -> int:
        return self.M.shape[0]

    @property
    def coordinate_names(self):
        return tuple(f"x{k + 1}" for k in range(self.n))

    @property
    def n_constraints(self) -> int:
        """Always 0: the matrices are already in independent coordinates."""
        return 0
