"""Checks made before any solving, so that a hopeless run fails in seconds with a clear message.

* the output folder can be made and written (not under a file, not read-only);
* every MPI rank owns some garment cells;
* the body mesh resolves the body's curvature (facet size against the smallest body radius);
* the garment does not start deeper inside the body than the dressing can undo (the body would
  have to shrink past its own axis, where the closest-point normal is meaningless).

Each raises :class:`PreflightError` (a ``ValueError``) naming the numbers and what to do. The
checks are collective: every rank gets the same answer.
"""

from __future__ import annotations

import math
import os
from pathlib import Path

from fenics_garment._stack import MPI

#: Largest body facet size relative to the smallest body radius r: a chord h deviates from the
#: circle by r(1 − cos(h/2r)) ≈ h²/(8r), i.e. 3 % of r at h = r/2 — the size of a typical
#: contact penetration tolerance multiplied many times; finer is needed for accurate pressure.
MAX_BODY_H_OVER_R = 0.5
#: Largest shrink of the body (deepest initial penetration + margin) relative to its smallest
#: radius: beyond it the shrunk body has almost no cross-section left.
MAX_SHRINK_OVER_R = 0.8


class PreflightError(ValueError):
    """A run cannot start: names the value and what to change."""


def _collective(comm: MPI.Comm, message: str | None) -> None:
    message = comm.bcast(message, root=0)
    if message:
        raise PreflightError(message)


def output_folder(folder: Path, comm: MPI.Comm) -> None:
    """Make ``folder`` (rank 0) and check that a file can be written in it."""
    message = None
    if comm.rank == 0:
        try:
            folder.mkdir(parents=True, exist_ok=True)
            probe = folder / f".write-test-{os.getpid()}"
            probe.write_bytes(b"")
            probe.unlink()
        except OSError as err:
            why = err.strerror or type(err).__name__
            message = (f"cannot write the output folder {folder}: {why}"
                       f"{f' ({err.filename})' if err.filename else ''}; "
                       "choose another output root with -o/--output")  # fmt: skip
    _collective(comm, message)


def smallest_body_radius(built) -> tuple[float, str]:
    """The smallest radius of the body where the garment is, and where (level name)."""
    sc = built.scene
    if sc.body.kind == "cylinder":
        return sc.body.radius, "cylinder"
    level = min(built.garment.levels, key=lambda lv: lv.body_girth)
    return level.body_girth / (2 * math.pi), f"level {level.name!r}"


def ranks_own_cells(n_owned: int, n_cells: int, comm: MPI.Comm) -> None:
    """Every rank owns at least one garment cell."""
    counts = comm.allgather(n_owned)
    empty = [r for r, n in enumerate(counts) if n == 0]
    if empty:
        raise PreflightError(
            f"the garment has {n_cells} cells for {comm.size} MPI ranks and rank(s) "
            f"{', '.join(map(str, empty))} own none; run with fewer ranks (about one per "
            "2000 cells is efficient) or a finer garment.mesh_size"
        )


def mesh_resolution(built) -> None:
    """The body's facets are small against its curvature radius."""
    sc = built.scene
    r, where = smallest_body_radius(built)
    h = sc.body.mesh_size
    if h > MAX_BODY_H_OVER_R * r:
        raise PreflightError(
            f"{sc.source or sc.name}: [body.mesh_size] = {h:g} m is too coarse for the body's "
            f"curvature: its smallest radius ({where}) is {r:.3g} m, so facets would cut up to "
            f"{h * h / (8 * r) * 1e3:.1f} mm into the curved surface; use body.mesh_size <= "
            f"{MAX_BODY_H_OVER_R * r:.3g} m (r/2)"
        )


def initial_depth(built, penetration0: float) -> None:
    """The dressing's shrink s₀ = penetration + margin leaves a body to dress."""
    sc = built.scene
    r, where = smallest_body_radius(built)
    s0 = max(penetration0, 0.0) + sc.dressing.margin
    if s0 >= MAX_SHRINK_OVER_R * r:
        raise PreflightError(
            f"{sc.source or sc.name}: the garment starts {penetration0 * 1e3:.1f} mm inside the "
            f"body; with dressing.margin {sc.dressing.margin * 1e3:.1f} mm the body would have to "
            f"shrink by {s0 * 1e3:.1f} mm, more than {MAX_SHRINK_OVER_R:.0%} of its smallest "
            f"radius ({where}, {r * 1e3:.1f} mm), where the contact normal is meaningless; use "
            "a less negative garment.ease (or a smaller dressing.margin)"
        )


def check_built(built) -> float:
    """The checks that need the built scene; returns the initial penetration [m]."""
    from fenics_garment.scene.dressing import initial_penetration

    mesh = built.model.geometry.mesh
    n_owned = mesh.topology.index_map(mesh.topology.dim).size_local
    ranks_own_cells(n_owned, len(built.garment.cells), mesh.comm)
    mesh_resolution(built)
    pen = initial_penetration(built.contact)
    initial_depth(built, pen)
    return pen
