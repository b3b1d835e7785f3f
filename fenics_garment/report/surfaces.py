"""The surfaces of the report's 3D view: body and deformed garment with their pressure.

A run writes them to ``report_surfaces.npz`` (:func:`write_surfaces`), decimated to at most
:data:`MAX_TRIANGLES` triangles each, so that the report stays a few MB whatever the meshes. A
folder without that file (an older run) is read from ``body_pressure.vtu`` and
``final_state.xdmf`` instead (:func:`read_surfaces`).
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np
import numpy.typing as npt

from fenics_garment import output

#: The file a run writes for the report's 3D view.
SURFACES_FILE = "report_surfaces.npz"
#: Triangles of each surface at most (about 1 MB of the HTML each).
MAX_TRIANGLES = 40_000


@dataclass
class Surface:
    """A triangulated surface with one pressure [Pa] per vertex."""

    vertices: npt.NDArray[np.float32]  # (n, 3) [m]
    triangles: npt.NDArray[np.int32]  # (m, 3)
    pressure: npt.NDArray[np.float32]  # (n,) [Pa]

    @classmethod
    def of(cls, vertices, triangles, pressure) -> Surface:
        return cls(np.asarray(vertices, dtype=np.float32).reshape(-1, 3),
                   np.asarray(triangles, dtype=np.int32).reshape(-1, 3),
                   np.asarray(pressure, dtype=np.float32).reshape(-1))  # fmt: skip


def _area(vertices: np.ndarray, triangles: np.ndarray) -> float:
    v = vertices.astype(np.float64)[triangles]
    return 0.5 * float(np.linalg.norm(np.cross(v[:, 1] - v[:, 0], v[:, 2] - v[:, 0]), axis=1).sum())


def cluster(surface: Surface, cell: float) -> Surface:
    """Vertex clustering on a grid of ``cell`` [m]: the vertices of each grid cell merge into
    their mean (pressure averaged too); triangles that collapse, or repeat, are dropped."""
    v = surface.vertices.astype(np.float64)
    ijk = np.floor((v - v.min(axis=0)) / cell).astype(np.int64)
    dims = ijk.max(axis=0) + 1
    keys = ijk[:, 0] + dims[0] * (ijk[:, 1] + dims[1] * ijk[:, 2])  # one integer per grid cell
    _, label, counts = np.unique(keys, return_inverse=True, return_counts=True)
    label = label.reshape(-1)
    n = len(counts)
    merged = np.zeros((n, 3))
    np.add.at(merged, label, v)
    pressure = np.zeros(n)
    np.add.at(pressure, label, surface.pressure.astype(np.float64))
    tri = label[surface.triangles]
    ok = (tri[:, 0] != tri[:, 1]) & (tri[:, 1] != tri[:, 2]) & (tri[:, 0] != tri[:, 2])
    tri = tri[ok]
    st = np.sort(tri, axis=1).astype(np.int64)
    _, first = np.unique((st[:, 0] * n + st[:, 1]) * n + st[:, 2], return_index=True)
    tri = tri[np.sort(first)]
    used = np.unique(tri)  # drop the clusters no triangle uses
    renumber = np.full(n, -1, dtype=np.int64)
    renumber[used] = np.arange(len(used))
    return Surface.of(
        merged[used] / counts[used, None], renumber[tri], pressure[used] / counts[used]
    )


def decimate(surface: Surface, max_triangles: int = MAX_TRIANGLES) -> Surface:
    """``surface`` with at most ``max_triangles`` triangles (:func:`cluster` on a grid that
    coarsens until it fits); unchanged when it fits already."""
    if len(surface.triangles) <= max_triangles:
        return surface
    # n triangles of a surface of area A on a grid of cell c: about 2 A / c² of them
    cell = (2.0 * _area(surface.vertices, surface.triangles) / max_triangles) ** 0.5
    while True:
        out = cluster(surface, cell)
        if len(out.triangles) <= max_triangles:
            return out
        cell *= max(1.03, 1.02 * (len(out.triangles) / max_triangles) ** 0.5)


def write_surfaces(folder: Path, body: Surface, garment: Surface) -> Path:
    """``report_surfaces.npz`` in ``folder``: both surfaces, decimated (:func:`decimate`)."""
    arrays = {}
    for name, s in (("body", decimate(body)), ("garment", decimate(garment))):
        arrays |= {f"{name}_vertices": s.vertices, f"{name}_triangles": s.triangles,
                   f"{name}_pressure": s.pressure}  # fmt: skip

    def write(tmp: Path) -> None:
        with open(tmp, "wb") as f:
            np.savez_compressed(f, **arrays)

    return output.atomic_write(Path(folder) / SURFACES_FILE, write)


def read_surfaces(folder: Path) -> dict[str, Surface]:
    """The surfaces of the run in ``folder`` ({"body": …, "garment": …}, those found), from
    ``report_surfaces.npz``, else from ``body_pressure.vtu`` and ``final_state.xdmf``."""
    folder = Path(folder)
    path = folder / SURFACES_FILE
    if path.is_file():
        with np.load(path) as data:
            return {name: Surface.of(data[f"{name}_vertices"], data[f"{name}_triangles"],
                                     data[f"{name}_pressure"])
                    for name in ("body", "garment") if f"{name}_vertices" in data}  # fmt: skip
    found = {}
    if (folder / "body_pressure.vtu").is_file():
        found["body"] = decimate(_body_from_vtu(folder / "body_pressure.vtu"))
    if (folder / "final_state.xdmf").is_file():
        found["garment"] = decimate(_garment_from_xdmf(folder / "final_state.xdmf"))
    return found


def _body_from_vtu(path: Path) -> Surface:
    import meshio

    mesh = meshio.read(path)
    p = mesh.point_data.get("contact_pressure", np.zeros(len(mesh.points)))
    return Surface.of(mesh.points, mesh.get_cells_type("triangle"), p)


def _garment_from_xdmf(path: Path) -> Surface:
    import meshio

    with meshio.xdmf.TimeSeriesReader(path) as reader:
        points, cells = reader.read_points_cells()
        _, point_data, _ = reader.read_data(0)
    tri = next(c.data for c in cells if c.type == "triangle")
    x = points + point_data.get("displacement", 0.0)
    return Surface.of(x, tri, point_data.get("contact_pressure", np.zeros(len(points))))
