"""What a model is built from, recorded where it is made (the readers build through this).

A reader (the TOML case reader, the URDF reader, the Python case builder) allocates the
coordinates here with their *kind*, and names, for each element it makes, the points the
element acts between:

    asm = Assembly()
    ix = asm.coordinates(["B.x", "B.y"], [0.3, 0.0], "length")      # → array([0, 1])
    asm.ends("spring 1", "A", "B")                                   # drawn from A to B

Coordinate kinds (:data:`KINDS`):

``length``     a point's position component (m): scaled by the model's length in the statics,
               printed in metres;
``direction``  a component of a spatial body's unit vector (dimensionless);
``angle``      a beam node's cross-section angle (rad);
``modal``      a modal coordinate of an FE body (dimensionless amplitude).

The recorded kinds reach the :class:`~mbseig.model.system.Model` as ``coordinate_kinds`` and
the ends as ``element_ends`` (element name → the named points it acts between, in the order
of its difference map r_b − r_a; or ``("bodies", b1, b2)`` for an element acting between two
bodies, ``None`` for the ground), so that no stage guesses either from names or by evaluating
maps.
"""

from __future__ import annotations

import numpy as np

__all__ = ["Assembly", "KINDS", "UNITS"]

KINDS = ("length", "direction", "angle", "modal")
#: the unit each kind of coordinate is printed in
UNITS = {"length": "m", "direction": "1", "angle": "rad", "modal": "1"}


class Assembly:
    """The coordinates (names, initial values, kinds) and element ends of a model being built."""

    def __init__(self):
        self.names: list[str] = []
        self.values: list[float] = []
        self.kinds: list[str] = []
        self.element_ends: dict[str, tuple] = {}

    def __len__(self) -> int:
        return len(self.names)

    def coordinates(self, names, values, kind) -> np.ndarray:
        """Append coordinates of one ``kind``; their indices."""
        if kind not in KINDS:
            raise ValueError(f"unknown coordinate kind {kind!r} ({', '.join(KINDS)})")
        names = list(names)
        values = [float(v) for v in values]
        if len(names) != len(values):
            raise ValueError("one initial value per coordinate name")
        k = len(self.names)
        self.names += names
        self.values += values
        self.kinds += [kind] * len(names)
        return np.arange(k, k + len(names), dtype=np.intp)

    def block(self, names, values, kinds) -> np.ndarray:
        """Append coordinates of several kinds at once (one per name, value and kind, already
        floats and known kinds: a batch reader's bodies); their indices."""
        k = len(self.names)
        if not (len(names) == len(values) == len(kinds)) or set(kinds) - set(KINDS):
            raise ValueError("one initial value and one known kind per coordinate name")
        self.names += names
        self.values += values
        self.kinds += kinds
        return np.arange(k, k + len(names), dtype=np.intp)

    def coordinate(self, name, value, kind) -> int:
        """Append one coordinate; its index."""
        return int(self.coordinates([name], [value], kind)[0])

    def ends(self, element, *points):
        """Record the named points (or ``"bodies", b1, b2``) element ``element`` acts between."""
        self.element_ends[element] = tuple(points)
