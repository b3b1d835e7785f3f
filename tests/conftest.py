"""Shared test set-up: the stack is imported in the right order before any test module."""

import gc

import pytest

from fenics_garment._stack import MPI


@pytest.fixture(autouse=True)
def _collect_and_sync():
    # Like DOLFINx's own test suite: free PETSc objects collectively and keep ranks in step.
    yield
    gc.collect()
    MPI.COMM_WORLD.Barrier()
