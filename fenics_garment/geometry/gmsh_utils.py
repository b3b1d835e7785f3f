"""gmsh lives on one MPI rank: a context manager for its life cycle and the hand-over to DOLFINx.

gmsh keeps global state, so it is initialised once per ``with`` block and always finalised, even
when building the geometry raises. Only the ``rank`` process builds the model; the others get
``None`` and take part in the collective :func:`dolfinx.io.gmsh.model_to_mesh` afterwards.
"""

from __future__ import annotations

from collections.abc import Iterator
from contextlib import contextmanager
from typing import Any

import gmsh

from fenics_garment import interrupt


@contextmanager
def gmsh_session(
    comm: Any | None = None, rank: int = 0, verbose: bool = False, name: str = "model"
) -> Iterator[Any]:
    """Yield ``gmsh`` on ``rank`` of ``comm`` (always if ``comm`` is None), None elsewhere.

    If gmsh is already initialised by the caller it is left initialised, and a fresh model is
    added and removed instead, so sessions nest.
    """
    if comm is not None and comm.rank != rank:
        yield None
        return
    owner = not gmsh.isInitialized()
    if owner:
        gmsh.initialize(["-noenv"], readConfigFiles=False, interruptible=False)
    gmsh.option.setNumber("General.Terminal", 1 if verbose else 0)
    gmsh.option.setNumber("General.Verbosity", 5 if verbose else 1)
    gmsh.model.add(name)
    try:
        yield gmsh
    finally:
        try:
            gmsh.model.remove()
        finally:
            if owner:
                gmsh.finalize()
            interrupt.reinstall()  # gmsh's Python API resets SIGINT to its default action


def to_dolfinx(comm: Any, model: Any | None, rank: int = 0, gdim: int = 3) -> Any:
    """Distribute the gmsh model of ``rank`` as a DOLFINx mesh (``MeshData``); collective."""
    from dolfinx.io import gmsh as dgmsh

    from fenics_garment._stack import dolfinx  # noqa: F401  (import order: MPI first)

    return dgmsh.model_to_mesh(model, comm, rank, gdim=gdim)


def shared_result(comm: Any | None, data: Any, err: str | None) -> Any:
    """The gmsh rank's (data, error) on every rank of ``comm``; a GeometryError with the error
    (on every rank, so none is left waiting) if building failed."""
    from .errors import GeometryError

    if comm is not None and comm.size > 1:
        data, err = comm.bcast((data, err), root=0)
    if err:
        raise GeometryError(err)
    return data


def garment_mesh(comm: Any, model: Any | None, what: str) -> Any:
    """:func:`to_dolfinx` of a garment; DOLFINx's refusal (e.g. "Duplicate mesh entity
    detected") as a one-line GeometryError naming ``what``."""
    from .errors import GeometryError

    try:
        return to_dolfinx(comm, model, 0)
    except RuntimeError as e:
        first = str(e).strip().splitlines()[0] if str(e).strip() else type(e).__name__
        raise GeometryError(f"DOLFINx refused the {what} mesh: {first}") from e


def add_discrete_surface(
    g: Any,
    vertices: Any,
    triangles: Any,
    tags: Any,
    names: dict[str, int],
) -> None:
    """Put a triangle soup with one integer tag per triangle into the current model.

    One discrete surface (and one physical group named after the region) per tag, all sharing
    one node set, so that ``gmsh.write`` or ``model_to_mesh`` keep the region names.
    """
    import numpy as np

    vertices = np.asarray(vertices, dtype=np.float64)
    triangles = np.asarray(triangles, dtype=np.int64)
    tags = np.asarray(tags)
    base = g.model.addDiscreteEntity(2)  # holds the nodes, has no elements
    node_tags = np.arange(1, len(vertices) + 1, dtype=np.uint64)
    g.model.mesh.addNodes(2, base, node_tags, vertices.ravel())
    next_el = 1
    for name, value in sorted(names.items(), key=lambda kv: kv[1]):
        sel = np.flatnonzero(tags == value)
        if sel.size == 0:
            continue
        s = g.model.addDiscreteEntity(2)
        el = np.arange(next_el, next_el + sel.size, dtype=np.uint64)
        next_el += sel.size
        g.model.mesh.addElementsByType(s, 2, el, (triangles[sel] + 1).ravel().astype(np.uint64))
        g.model.addPhysicalGroup(2, [s], int(value), name=name)


#: seconds gmsh may spend building and meshing one garment or body before the run stops
GMSH_TIME_LIMIT = 600.0


@contextmanager
def time_limit(
    seconds: float | None,
    what: str,
    by: str = "gmsh",
    why: str = "a hung mesher",
    hint: str = "check the body's landmarks or use a coarser mesh_size",
) -> Iterator[None]:
    """Stop the process with a one-line error and exit code 2 if the block takes too long.

    gmsh's meshers run in C++ and cannot be interrupted from Python; the gmsh API is called
    through ctypes, which releases the GIL, so a watchdog thread can still act: it writes
    ``error: gmsh did not finish <what> within <seconds> s …`` to stderr and ends the process
    (``os._exit(2)``; under MPI, ``mpiexec`` then stops the other ranks). ``None``: no limit.
    ``by``, ``why``, ``hint``: who does the work, what a stop means, what to do (the C compiler
    of the FFCx JIT: ``scene.run``).
    """
    import os
    import sys
    import threading

    if not seconds:
        yield
        return

    def expire() -> None:
        sys.stderr.write(
            f"error: {by} did not finish {what} within {seconds:g} s ({why}); {hint}\n"
        )
        sys.stderr.flush()
        os._exit(2)

    timer = threading.Timer(seconds, expire)
    timer.daemon = True
    timer.start()
    try:
        yield
    finally:
        timer.cancel()
