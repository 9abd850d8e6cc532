"""Spatial (3-D) case files: the reader of ``dimension = 3`` cases.

Points, point masses, springs and joints on points are read as in every dimension by
:class:`~mbseig.casefile.builder.Builder`; this subclass is where the spatial rigid bodies,
joints and forces of the 3-D case format are read.
"""

from __future__ import annotations

from .builder import Builder

__all__ = ["SpatialBuilder"]


class SpatialBuilder(Builder):
    """Reader of ``dimension = 3`` cases."""
