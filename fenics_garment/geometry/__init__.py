"""Bodies and garments as meshes: parametric mannequin and human, scan import, garments, regions.

Conventions: metres, +z up, the body faces −y (its left side is +x). Import the submodules
directly; nothing here needs DOLFINx until ``to_dolfinx`` is called.
"""

from .body import BodySurface
from .errors import GeometryError, MissingRegion, ScanError
from .human import Pose, make_human
from .mannequin import MeshSizes, make_mannequin
from .measurements import Measurements, measurements

__all__ = [
    "BodySurface",
    "GeometryError",
    "Measurements",
    "MeshSizes",
    "MissingRegion",
    "Pose",
    "ScanError",
    "make_human",
    "make_mannequin",
    "measurements",
]
