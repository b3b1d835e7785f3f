"""The body as the rest of the package consumes it: plain arrays plus names.

``BodySurface`` is what the contact search reads (vertices and triangles, replicated on every
rank), what pressure is reported on (a region per triangle) and what garments are cut from
(horizontal sections at the landmark levels).
"""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
import numpy.typing as npt

from . import sections as sec
from . import surface as srf
from .errors import MissingRegion
from .measurements import Measurements

Array = npt.NDArray[np.float64]


@dataclass
class BodySurface:
    """A closed, outward-oriented triangle surface of a body (metres, +z up, facing −y).

    Attributes:
        vertices: (n, 3) float64 coordinates in metres.
        triangles: (m, 3) int64 vertex indices, counter-clockwise seen from outside.
        region: (m,) int32 region number of each triangle.
        regions: region name -> number, only regions that have triangles.
        landmarks: level name -> height (m) of the landmark levels that exist on this body.
        sections: level name -> (k, 2) closed section (x, y) at that level: the analytic
            curve the mannequin was lofted through, or the tape (convex-hull) section of a scan.
            Leg levels are keyed ``thigh_left``/``thigh_right`` etc. Garments are built from these.
        measurements: the requested measurements (mannequin only).
        part: (m,) body part per triangle (:data:`~.anatomy.PARTS`) where segmented (scans).
        points: named 3-D landmark points (``armpit_left``, ``shoulder_right`` …) of a scan.
        arm_cut: x of the vertical arm-root plane per side (``left`` > 0, ``right`` < 0).
        limbs: ``arm_left`` … ``leg_right`` -> :class:`~.limbs.Limb` (centreline, sections,
            joints) of a scan; ``limb_problems`` says why a limb is missing.
    """

    vertices: Array
    triangles: npt.NDArray[np.int64]
    region: npt.NDArray[np.int32]
    regions: dict[str, int]
    landmarks: dict[str, float]
    sections: dict[str, Array] = field(default_factory=dict)
    measurements: Measurements | None = None
    up: tuple[float, float, float] = (0.0, 0.0, 1.0)
    part: npt.NDArray[np.int32] | None = None
    points: dict[str, Array] = field(default_factory=dict)
    arm_cut: dict[str, float] = field(default_factory=dict)
    limbs: dict[str, Any] = field(default_factory=dict)
    limb_problems: dict[str, str] = field(default_factory=dict)

    def triangles_of(self, name: str) -> npt.NDArray[np.int64]:
        """Indices of the triangles of a named region; :class:`MissingRegion` if absent."""
        if name not in self.regions:
            raise MissingRegion(name, tuple(self.regions))
        return np.flatnonzero(self.region == self.regions[name])

    def section(self, level: str) -> tuple[float, Array]:
        """Height and closed (x, y) section of a landmark level (``waist``, ``thigh_left``…)."""
        base = level.removesuffix("_left").removesuffix("_right")
        if base not in self.landmarks:
            raise MissingRegion(level, tuple(self.landmarks))
        z = self.landmarks[base]
        if level in self.sections:
            return z, self.sections[level]
        loops = sec.slice_loops(self.vertices, self.triangles, z)
        if level.endswith(("_left", "_right")):
            sign = 1.0 if level.endswith("_left") else -1.0
            loops = [lp for lp in loops if sign * lp[:, 0].mean() > 0]
        loop = max(loops, key=lambda p: abs(sec.polygon_area(p)))
        return z, sec.convex_hull(loop)

    def girth(self, level: str) -> float:
        """Tape girth measured on the triangle surface at a landmark level (largest loop, or the
        left/right leg for ``*_left``/``*_right``)."""
        z = self.landmarks[level.removesuffix("_left").removesuffix("_right")]
        loops = sec.slice_loops(self.vertices, self.triangles, z)
        if level.endswith(("_left", "_right")):
            sign = 1.0 if level.endswith("_left") else -1.0
            loops = [lp for lp in loops if sign * lp[:, 0].mean() > 0]
        return sec.tape_girth(max(loops, key=lambda p: abs(sec.polygon_area(p))))

    def check(self) -> dict[str, Any]:
        """Closed/manifold, enclosed volume (> 0 means outward), area, counts."""
        return {
            "closed_manifold": srf.is_closed_manifold(self.triangles),
            "volume": srf.signed_volume(self.vertices, self.triangles),
            "area": float(srf.areas(self.vertices, self.triangles).sum()),
            "components": int(srf.components(self.triangles).max() + 1),
            "vertices": len(self.vertices),
            "triangles": len(self.triangles),
        }

    def _gmsh_model(self, g: Any) -> None:
        from .gmsh_utils import add_discrete_surface

        add_discrete_surface(g, self.vertices, self.triangles, self.region, self.regions)

    def write(self, path: str | Path) -> None:
        """Write a gmsh ``.msh`` (physical groups = regions) or any meshio format by suffix."""
        path = Path(path)
        if path.suffix == ".msh":
            from .gmsh_utils import gmsh_session

            with gmsh_session(name="body") as g:
                self._gmsh_model(g)
                g.option.setNumber("Mesh.MshFileVersion", 4.1)
                g.write(str(path))
        else:
            import meshio

            meshio.write(
                path,
                meshio.Mesh(
                    self.vertices,
                    [("triangle", self.triangles)],
                    cell_data={"region": [self.region]},
                ),
            )

    def to_dolfinx(self, comm: Any, rank: int = 0) -> Any:
        """The body as a distributed DOLFINx mesh (tdim 2, gdim 3) with region cell tags.

        Returns ``dolfinx.io.gmsh.MeshData``: ``.mesh``, ``.cell_tags`` (region numbers) and
        ``.physical_groups`` (name -> (dim, tag)). Collective on ``comm``.
        """
        from .gmsh_utils import gmsh_session, to_dolfinx

        with gmsh_session(comm, rank, name="body") as g:
            if g is not None:
                self._gmsh_model(g)
            return to_dolfinx(comm, g.model if g is not None else None, rank)


def finish_body(
    vertices: Array,
    triangles: npt.NDArray[np.int64],
    landmarks: dict[str, float],
    sections: dict[str, Array],
    measurements: Measurements | None = None,
    part: npt.NDArray[np.int32] | None = None,
) -> BodySurface:
    """Orient outward, tag regions (on the torso only where ``part`` is given), pack a
    :class:`BodySurface`."""
    from .regions import REGIONS, tag_regions

    tri = srf.orient_outward(vertices, triangles)
    centre_y = {k: float(sec.centroid(p)[1]) for k, p in sections.items() if k in landmarks}
    region = tag_regions(vertices, tri, landmarks, centre_y, part)
    present = {n: v for n, v in REGIONS.items() if np.any(region == v)}
    return BodySurface(
        vertices, tri, region, present, dict(landmarks), sections, measurements, part=part
    )
