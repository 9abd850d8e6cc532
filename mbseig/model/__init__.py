"""Model layer: affine point maps, element kernels and the assembled system."""

from .affine import Affine, combine
from .system import Model

__all__ = ["Affine", "combine", "Model"]
