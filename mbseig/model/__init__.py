"""The model layer: elements behind base classes, the assembled Model, and LinearCase.

- :mod:`~mbseig.model.base`: the element contract (Constraint, Force), docs/design.md "Elements";
- :mod:`~mbseig.model.affine`: affine point maps r = C q[idx] + d (natural coordinates);
- :mod:`~mbseig.model.elements`: planar bodies' mass, springs, dampers, torsional springs,
  follower forces, distance and linear constraints;
- :mod:`~mbseig.model.driver`: the angle driver (prescribed relative angle);
- :mod:`~mbseig.model.batched`: many identical spring-dampers as one vectorized element;
- :mod:`~mbseig.model.beams`, :mod:`~mbseig.model.fe_body`: flexible bodies;
- :mod:`~mbseig.model.system`: the assembled :class:`Model`;
- :mod:`~mbseig.model.linear_case`: :class:`LinearCase`, matrices given directly.
"""

from .affine import Affine, combine
from .base import Constraint, Force
from .linear_case import LinearCase
from .system import Model

__all__ = ["Affine", "combine", "Constraint", "Force", "LinearCase", "Model"]
