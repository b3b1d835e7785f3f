"""The one place that imports the MPI/PETSc/DOLFINx stack, in the order it needs.

Import the stack from here in a script, a demo or a terms hook, before anything else that
loads DOLFINx, petsc4py or mpi4py::

    from fenics_garment.stack import MPI, PETSc, dolfinx, ufl

(``fenics_garment._stack``, the name the package's own modules use, is the same module.)

Two stacks are supported and detected, never assumed:

* **PyPI wheels** (``dolfinx-solver-real``): DOLFINx, PETSc and MPICH live inside the wheel and
  ``import dolfinx_solver`` must run first — it loads the bundled ``libmpi`` — otherwise importing
  ``dolfinx`` or ``petsc4py`` fails with ``libmpi.so.12: cannot open shared object file``.
* **Debian packages** (``python3-dolfinx-real``, used by the Docker image): MPI is a system
  library and there is no ``dolfinx_solver``; ``mpi4py`` is imported first instead.

Every module of the package that needs DOLFINx imports it through here.
"""

from __future__ import annotations

import importlib.util

from fenics_garment.environment import ensure_home

ensure_home()  # ADIOS2 crashes (SIGSEGV) looking for its configuration when HOME is unset

STACK: str
if importlib.util.find_spec("dolfinx_solver") is not None:
    import dolfinx_solver  # noqa: F401  (side effect: loads the wheel's MPI before anything else)

    STACK = "pypi-wheels (dolfinx-solver-real)"
else:
    STACK = "system (e.g. Debian python3-dolfinx)"

try:
    from mpi4py import MPI
    from petsc4py import PETSc

    import dolfinx
    import dolfinx.fem.petsc
    import ufl
except ImportError as err:  # pragma: no cover - depends on the machine
    raise ImportError(
        "fenics-garment needs DOLFINx 0.11 with PETSc. Install it either from PyPI "
        "(`pip install dolfinx-solver-real`, Python >= 3.12) or from Debian unstable "
        "(`apt install python3-dolfinx-real`). Original error: " + str(err)
    ) from err

if not dolfinx.__version__.startswith("0.11"):  # pragma: no cover - depends on the machine
    raise ImportError(
        f"fenics-garment targets the DOLFINx 0.11 API; found DOLFINx {dolfinx.__version__} "
        f"({STACK}). Install dolfinx-solver-real 0.11.x or python3-dolfinx-real 0.11."
    )

# FFCx's JIT waits 10 s for another process compiling the same form, then fails; wait for a
# live compiler instead and take over a dead one's (fenics_garment.jit_wait)
from fenics_garment import jit_wait  # noqa: E402

jit_wait.install()

__all__ = ["MPI", "STACK", "PETSc", "dolfinx", "ufl"]
