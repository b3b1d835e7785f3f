"""The package's own name for :mod:`fenics_garment.stack` (the same objects): scripts, demos
and terms hooks import ``fenics_garment.stack``."""

from fenics_garment.stack import MPI, STACK, PETSc, dolfinx, ufl

__all__ = ["MPI", "STACK", "PETSc", "dolfinx", "ufl"]
