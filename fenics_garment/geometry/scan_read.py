"""Reading a body-scan file into vertices and triangles: trimesh for what scanners export.

trimesh reads OBJ (texture coordinates, normals, quads and n-gons, groups, materials), PLY
(ascii and binary, with colours), STL (ascii and binary), OFF and GLB/glTF (node transforms
applied, all meshes concatenated), also gzip-compressed (``scan.obj.gz``). Quads and n-gons
come back triangulated. Other suffixes (``.msh``, ``.vtk``, ``.vtu`` …) go through meshio.
Every failure is a :class:`ScanError` that names the file.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import numpy.typing as npt

from . import surface as srf
from .errors import ScanError

Array = npt.NDArray[np.float64]
IArray = npt.NDArray[np.int64]

#: Suffixes read with trimesh; the rest with meshio.
TRIMESH_SUFFIXES = (".obj", ".ply", ".stl", ".off", ".glb", ".gltf")


def read_polygons(path: str | Path) -> tuple[Array, IArray]:
    """Vertices and triangles of a surface file (see the module docstring for the formats)."""
    p = Path(path)
    if not p.is_file():
        raise ScanError(f"{p}: no such file", "check the path (relative to the working directory)")
    if p.suffix.lower() == ".ply":
        with p.open("rb") as f:  # a PLY header cut short: say so instead of a parser message
            if b"end_header" not in f.read(1 << 16):
                raise ScanError(f"{p}: PLY header without end_header", "is the file truncated?")
    suffix = _format_suffix(p)
    if p.suffix.lower() == ".stl":
        _check_binary_stl_size(p)
    v, t = _read_trimesh(p, suffix) if suffix in TRIMESH_SUFFIXES else _read_meshio(p)
    if len(t) == 0 or len(v) == 0:
        raise ScanError(f"{p}: no surface faces", "expected triangles, quads or polygons")
    if not np.all(np.isfinite(v)):
        raise ScanError(f"{p}: {int((~np.isfinite(v)).any(axis=1).sum())} vertices are NaN/Inf")
    if t.min() < 0 or t.max() >= len(v):
        raise ScanError(f"{p}: faces refer to vertices that do not exist (file corrupted?)")
    return v, t


def _check_binary_stl_size(p: Path) -> None:
    """A binary STL is an 80-byte header, the triangle count n and 50 bytes per triangle: a file
    of another size that is not ASCII STL is cut short or not STL (trimesh 5.2 reads some such
    files as an empty mesh instead of failing)."""
    size = p.stat().st_size
    with p.open("rb") as f:
        start = f.read(4096)
    if start.lstrip()[:5].lower() == b"solid" and b"facet" in start:
        return  # ASCII STL
    n = int.from_bytes(start[80:84], "little") if len(start) >= 84 else -1
    if n < 0 or size != 84 + 50 * n:
        what = "shorter than its header" if size < 84 else f"{size} bytes, not 84 + 50 × {n}"
        raise ScanError(
            f"{p}: not a readable mesh (a binary STL {what})",
            "the file may be truncated or not an STL file",
        )


def _unreadable(p: Path, e: BaseException) -> ScanError:
    return ScanError(
        f"{p}: not a readable mesh ({type(e).__name__}: {e})",
        "expected OBJ, PLY, STL, OFF, GLB/glTF or a meshio format; the file may be truncated",
    )


def _format_suffix(p: Path) -> str:
    """``.obj`` for ``a.obj`` and ``a.OBJ.gz``."""
    s = p.suffixes
    if s and s[-1].lower() == ".gz":
        return s[-2].lower() if len(s) > 1 else ""
    return p.suffix.lower()


def _read_trimesh(p: Path, suffix: str) -> tuple[Array, IArray]:
    import gzip
    import io

    import trimesh

    try:
        src = io.BytesIO(gzip.decompress(p.read_bytes())) if p.suffix.lower() == ".gz" else p
        # merge_tex/merge_norm: one vertex per position even where texture seams split them;
        # process=False: no silent merging or dropping here, the cleaning step reports it
        m = trimesh.load(src, file_type=suffix[1:], force="mesh", process=False,
                         merge_tex=True, merge_norm=True, skip_materials=True)  # fmt: skip
    except (Exception, SystemExit) as e:  # parsers raise anything on a corrupted file
        raise _unreadable(p, e) from e
    faces = getattr(m, "faces", None)
    verts = getattr(m, "vertices", None)
    if faces is None or verts is None:
        raise ScanError(f"{p}: no surface faces", "expected triangles, quads or polygons")
    v = np.asarray(verts, dtype=np.float64).reshape(-1, 3)
    t = np.asarray(faces, dtype=np.int64).reshape(-1, 3)
    return v, t


def _read_meshio(p: Path) -> tuple[Array, IArray]:
    import meshio

    try:
        m = meshio.read(p)
    # meshio raises ReadError, ValueError, IndexError … on broken files; its STL reader even
    # calls sys.exit(1) on some (found by tests/test_fuzz.py)
    except (Exception, SystemExit) as e:
        raise _unreadable(p, e) from e
    blocks = [c.data for c in m.cells if c.dim == 2 and len(c.data)]
    if not blocks or len(m.points) == 0:
        raise ScanError(f"{p}: no surface cells", "expected triangles, quads or polygons")
    v = np.asarray(m.points[:, :3], dtype=np.float64)
    return v, srf.triangulate(blocks)
