"""fenics-garment: where, and how hard, does a garment press on a body?

A geometrically nonlinear Reissner–Mindlin (Naghdi) shell for the garment, written as a sum of
small UFL energy terms, in contact with a body surface mesh, solved with PETSc SNES in DOLFINx 0.11.

Importing the package is cheap: the DOLFINx stack is loaded by the submodules that need it
(through :mod:`fenics_garment.stack`, which gets the import order right: a script imports
``from fenics_garment.stack import MPI, dolfinx, ufl`` before anything else of the stack).
"""

from importlib.metadata import PackageNotFoundError, version

try:
    __version__ = version("fenics-garment")
except PackageNotFoundError:  # running from a source tree that is not installed
    __version__ = "0.1.0"

__all__ = ["__version__"]
