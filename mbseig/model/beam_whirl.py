"""The whirl stations of a spinning beam: what :mod:`mbseig.model.spatial_whirl` reads of a
beam with ``spin`` (its node frames, axis, speed and station points), like a rigid rotor."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .affine import Affine
from .spatial_body import vector_matrix


@dataclass(frozen=True, eq=False)
class SpinningShaft:
    """The whirl stations of a spinning beam (``spin``), read like a rigid ``rotor`` by
    :mod:`mbseig.model.spatial_whirl`: ``frame`` stacks the first node's frame [r; u; v; w] and
    the triads of the other nodes (a mode which only twists or tilts the nodes counts as body
    motion: ``motion_idx``, their coordinates), ``axis`` the beam axis in the first node's frame, ``speed`` Ω, ``stations``
    (label, Affine) of every node's point.  Not an element: it adds nothing to the equations."""

    name: str
    frame: Affine
    axis: np.ndarray
    speed: float
    stations: tuple = ()
    body: str = ""
    affine_field = "frame"

    def __post_init__(self):
        import scipy.sparse as sp

        from .affine import combine

        smap = combine([(1.0, aff) for _, aff in self.stations], stack=True)
        object.__setattr__(self, "station_map", (smap.idx, sp.csr_matrix(smap.C)))
        object.__setattr__(self, "motion_idx", self.frame.idx)

    def axis_map(self) -> Affine:
        V = vector_matrix(self.axis)
        return Affine(self.frame.idx, V @ self.frame.C[:12], V @ self.frame.d[:12])
