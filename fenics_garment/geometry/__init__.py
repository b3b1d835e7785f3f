"""Bodies and garments as meshes: parametric mannequin, scan import, garments, regions.

Conventions: metres, +z up, the body faces −y (its left side is +x). Import the submodules
directly; nothing here needs DOLFINx until ``to_dolfinx`` is called.
"""

from .body import BodySurface
from .errors import GeometryError, MissingRegion, ScanError
from .mannequin import MeshSizes, make_mannequin
from .measurements import Measurements, measurements

__all__ = [
    "BodySurface",
    "GeometryError",
    "Measurements",
    "MeshSizes",
    "MissingRegion",
    "ScanError",
    "make_mannequin",
    "measurements",
]
