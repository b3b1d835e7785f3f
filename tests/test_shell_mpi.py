"""The shell gives the same answer on 1 and 2 ranks (run under ``mpiexec -n 2``)."""

import pytest

from fenics_garment._stack import MPI
from fenics_garment.verification import shells


@pytest.mark.mpi
def test_same_roof_deflection_on_all_ranks_and_serial():
    parallel = shells.scordelis_lo(8, comm=MPI.COMM_WORLD)
    serial = shells.scordelis_lo(8, comm=MPI.COMM_SELF)
    # Identical to the solver tolerance (Newton stops at a relative residual of 1e-9).
    assert parallel.value == pytest.approx(serial.value, rel=1e-7)
    assert abs(parallel.rel_error) < 0.01
