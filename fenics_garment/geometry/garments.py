"""Garments cut from a body: gilet, one-piece dress, tube, arm sleeve and compression stocking.

Construction (the garment mesh is the shell's **stress-free reference configuration**):

1. At each garment level (landmark heights of the body, plus hem/top levels) take the body's
   tape section ``S`` (convex, counter-clockwise; :meth:`BodySurface.section`) with girth ``G``.
2. The garment section is the **normal offset** of ``S`` by the signed clearance ``d`` chosen so
   that its perimeter is ``(1 + ease) G``. For a convex curve Steiner's formula gives
   ``d = ease · G / (2π)`` (a few Newton steps remove the discretisation error). Positive ease:
   the garment is outside the body at distance ``d``; negative ease (tight): ``d < 0``, the
   stress-free garment lies inside the body by ``|d|``, and the dressing step later grows the
   body from inside it. ``min_clearance`` (optional) raises ``d`` to at least that value; the
   level's effective ease then follows from the new perimeter and is what the table reports.
3. OpenCASCADE lofts (``ThruSections``) one smooth open surface through the sections; each
   section is a back half and a front half meeting at the lateral points, so the loft comes out
   as a **back** and a **front** panel sharing the side seam lines. Armholes, necklines and a
   front opening are boolean cuts with ellipsoids/boxes.
4. gmsh meshes it (triangles, or quadrilaterals by recombination), every panel's mesh is
   oriented so that its cell normals point **away from the body** (outward), and physical
   groups name panels (``front``, ``back`` or ``front_left``/``front_right``) and edges
   (``hem``, ``neckline``, ``armhole_left``/``_right``, ``side_seam_left``/``_right``,
   ``shoulder_seam_left``/``_right``, ``opening_left``/``_right``, ``welt``, ``top``).
5. With ``order=2`` (the default) the DOLFINx mesh is **curved**: gmsh adds a node at each edge
   midpoint, on the lofted surface (``setOrder(2)``), and the mesh's coordinate element is P2.
   A straight-sided (P1) reference is a polygon: a P2 displacement that makes it round again
   stretches each edge from its chord to its arc, an extra strain ≈ (h/R)²/24 for edges of
   length h on a curvature radius R — measured +11.8 / +1.9 % in the tube's Laplace pressure
   at h = 4 / 2 cm, +0.05 / −0.20 % on the curved mesh. The plain arrays (``points``,
   ``cells``) stay the vertex nodes and 3-node triangles (pictures, tables), numbered as the
   DOLFINx mesh's first geometry nodes.

Between levels the loft interpolates, so ``d`` is exact at the levels and smooth in between.
Directions: +z up, the body faces −y, its left is +x; the warp (fabric length direction) is the
vertical projected on the tangent plane (``warp_direction``).
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import numpy as np
import numpy.typing as npt

from . import sections as sec
from .body import BodySurface
from .errors import GeometryError, MissingRegion
from .garment_checks import check_garment
from .gmsh_utils import GMSH_TIME_LIMIT, garment_mesh, gmsh_session, shared_result, time_limit
from .limbs import Limb
from .mannequin import add_loft

Array = npt.NDArray[np.float64]


@dataclass(frozen=True)
class GarmentLevel:
    """One row of a garment's construction table (all lengths in metres).

    ``garment_girth = (1 + ease) · body_girth`` and ``clearance`` is the signed normal distance
    from the body section to the garment section at height ``z`` (negative: inside the body).
    Skirt levels below the hip have no body section: their ``body_girth`` is the hip's.
    """

    name: str
    z: float
    body_girth: float
    ease: float
    garment_girth: float
    clearance: float


@dataclass(frozen=True)
class EdgeRefinement:
    """Smaller cells along some of the garment's edges (a gmsh distance/threshold size field).

    Cells of ``ratio`` × h on the curves whose name starts with one of ``edges`` (``"armhole"``
    matches ``armhole_left`` and ``armhole_right``; ``"*"`` every named edge), growing linearly
    to h at the distance ``band`` [m] from them. With ``ratio`` fixed, a mesh sequence in h
    refines the edges and the rest alike (the convergence study's size ratio holds everywhere).
    Where an armhole passes over the body's side below the shoulder the pressure concentrates in
    a patch of a few centimetres that uniform meshes do not resolve
    (docs/verification/convergence.md, "Armhole-graded meshes": the dress's upper chest +7.2 %
    at its last uniform level, +1.7 % graded).
    """

    edges: tuple[str, ...] = ("armhole",)
    ratio: float = 0.25
    band: float = 0.04

    def __post_init__(self) -> None:
        if not 0 < self.ratio <= 1:
            raise ValueError(f"edge refinement ratio must be in (0, 1], got {self.ratio}")
        if not self.band > 0:
            raise ValueError(f"edge refinement band must be > 0 m, got {self.band}")

    def selects(self, name: str) -> bool:
        """Whether the edge called ``name`` is refined (a name, its prefix or ``"*"``)."""
        return any(e == "*" or (e and name.startswith(e)) for e in self.edges)

    def curves(self, named: dict[str, list[int]]) -> list[int]:
        """The gmsh curve tags of the refined edges among the ``named`` curves."""
        return sorted({c for name, cs in named.items() for c in cs if self.selects(name)})

    def apply(self, g: Any, named: dict[str, list[int]]) -> None:
        """Set the size field of the model in the gmsh session ``g`` (before meshing; h is its
        ``Mesh.MeshSizeMax``, :func:`_mesh_options`)."""
        h = g.option.getNumber("Mesh.MeshSizeMax")
        curves = self.curves(named)
        if not curves:
            raise GeometryError(f"edge refinement: no edge named {', '.join(self.edges)} "
                                f"(the garment has {', '.join(sorted(named))})")  # fmt: skip
        f = g.model.mesh.field
        dist = f.add("Distance")
        f.setNumbers(dist, "CurvesList", curves)
        f.setNumber(dist, "Sampling", 200)
        th = f.add("Threshold")
        f.setNumber(th, "InField", dist)
        f.setNumber(th, "SizeMin", self.ratio * h)
        f.setNumber(th, "SizeMax", h)
        f.setNumber(th, "DistMin", 0.0)
        f.setNumber(th, "DistMax", self.band)
        f.setAsBackgroundMesh(th)


@dataclass
class GarmentSurface:
    """A meshed garment: arrays on every rank and, if built with a communicator, a DOLFINx mesh.

    Arrays are in gmsh node order (``points[i]`` is gmsh node ``i + 1``), replicated on all ranks:
    ``cells`` (m, 3) triangles or (m, 4) quadrilaterals oriented with normals pointing away
    from the body; ``cell_panel`` the panel tag per cell; ``warp`` and ``normal`` unit vectors
    per node. ``edge_nodes[name]`` holds the (k, 2) node pairs of each tagged edge.
    """

    kind: str
    points: Array
    cells: npt.NDArray[np.int64]
    cell_panel: npt.NDArray[np.int32]
    panels: dict[str, int]
    edges: dict[str, int]
    edge_nodes: dict[str, npt.NDArray[np.int64]]
    warp: Array
    normal: Array
    levels: list[GarmentLevel]
    meshdata: Any = None
    info: dict[str, float] = field(default_factory=dict)
    #: the limb a sleeve or stocking follows on a scan (:class:`~.limbs.Limb`), or None
    frame: Any = None
    #: a garment sewn from flat pattern pieces: the flat coordinates of every cell's nodes
    #: (:class:`fenics_garment.shell.rest.FlatCells`), or None
    rest: Any = None

    def axial(self, points: Array) -> Array:
        """The garment's level coordinate of points: their height, or on a limb of a scan the
        distance z' along its centreline (:meth:`~.limbs.Limb.axial`), as ``levels[i].z``."""
        if self.frame is None:
            return np.asarray(points)[:, 2]
        return self.frame.axial(points)

    # -- DOLFINx side -------------------------------------------------------------------------
    @property
    def mesh(self) -> Any:
        """The DOLFINx mesh (tdim 2, gdim 3); only when built with ``comm``."""
        if self.meshdata is None:
            raise RuntimeError("built without a communicator: pass comm=MPI.COMM_WORLD")
        return self.meshdata.mesh

    @property
    def cell_tags(self) -> Any:
        """Panel tags of the DOLFINx cells (values: :attr:`panels`)."""
        return self.meshdata.cell_tags

    @property
    def facet_tags(self) -> Any:
        """Edge tags (hems, seams…) of the DOLFINx facets (values: :attr:`edges`)."""
        return self.meshdata.facet_tags

    def panel(self, name: str) -> int:
        """Tag of a named panel; :class:`MissingRegion` if absent."""
        if name not in self.panels:
            raise MissingRegion(name, tuple(self.panels))
        return self.panels[name]

    def edge(self, name: str) -> int:
        """Tag of a named edge (hem, seam…); :class:`MissingRegion` if absent."""
        if name not in self.edges:
            raise MissingRegion(name, tuple(self.edges))
        return self.edges[name]

    def node_values(self, values: Array) -> Array:
        """Per-gmsh-node ``values`` reordered to this rank's DOLFINx geometry nodes.

        On a curved (order-2) mesh the edge nodes are not in the arrays: they get NaN.
        """
        idx = np.asarray(self.mesh.geometry.input_global_indices, dtype=np.int64)
        vertex = idx < len(self.points)
        out = np.full((len(idx), *np.shape(values)[1:]), np.nan)
        out[vertex] = np.asarray(values)[idx[vertex]]
        return out

    def warp_function(self, V: Any) -> Any:
        """The warp direction as a DOLFINx Function on the vector space ``V``.

        Each dof takes the inverse-distance mean of the three nearest geometry nodes' warp,
        re-projected on the tangent plane and normalised (exact at P1 dofs).
        """
        return self._vector_function(V, self.warp)

    def normal_function(self, V: Any) -> Any:
        """The outward (away-from-body) unit normal as a Function on the vector space ``V``."""
        return self._vector_function(V, self.normal)

    def _vector_function(self, V: Any, nodal: Array) -> Any:
        from scipy.spatial import cKDTree

        from fenics_garment._stack import dolfinx

        # the replicated gmsh-order arrays, not this rank's nodes: the same neighbours (and tie
        # breaks) on every number of ranks, so the answer does not depend on the partition
        x, vals, nrm = self.points, np.asarray(nodal), self.normal
        tree = cKDTree(x)
        f = dolfinx.fem.Function(V)

        def evaluate(p: Array) -> Array:
            d, i = tree.query(p.T, k=min(3, len(x)))
            w = 1.0 / np.maximum(d, 1e-12) ** 2
            w[d < 1e-12] = 1e12
            v = np.einsum("pk,pki->pi", w, vals[i])
            n = np.einsum("pk,pki->pi", w, nrm[i])
            n /= np.linalg.norm(n, axis=1)[:, None]
            if nodal is not self.normal:
                v -= np.einsum("pi,pi->p", v, n)[:, None] * n
            return (v / np.linalg.norm(v, axis=1)[:, None]).T

        f.interpolate(evaluate)
        return f

    def cell_orientation(self) -> npt.NDArray[np.int8]:
        """+1/−1 per local DOLFINx cell: does its vertex order give the outward normal?

        DOLFINx may reorder cell vertices, so the shell should multiply ``CellNormal`` (or any
        normal built from the cell's own vertex order) by this sign.
        """
        mesh = self.mesh
        dm = mesh.geometry.dofmaps[0]
        x = mesh.geometry.x
        n_out = self.node_values(self.normal)
        p0, p1, p2 = x[dm[:, 0]], x[dm[:, 1]], x[dm[:, 2]]
        if dm.shape[1] == 4 and mesh.topology.cell_name() == "quadrilateral":
            p1, p2 = x[dm[:, 1]], x[dm[:, 2]]  # DOLFINx quad order: 0-1 / 2-3 tensor layout
        nc = np.cross(p1 - p0, p2 - p0)
        out = n_out[dm[:, :3]].sum(axis=1)  # vertex nodes come first on a curved mesh too
        return np.where(np.einsum("ij,ij->i", nc, out) >= 0, 1, -1).astype(np.int8)

    # -- plain-array helpers ------------------------------------------------------------------
    def triangles(self) -> npt.NDArray[np.int64]:
        """Cells as triangles (quads split along 0–2), orientation kept."""
        if self.cells.shape[1] == 3:
            return self.cells
        c = self.cells
        return np.concatenate([c[:, [0, 1, 2]], c[:, [0, 2, 3]]])

    @property
    def triangle_cell(self) -> npt.NDArray[np.int64]:
        """For each row of :meth:`triangles`, the cell it came from."""
        m = len(self.cells)
        return np.arange(m) if self.cells.shape[1] == 3 else np.concatenate([np.arange(m)] * 2)

    def girth(self, z: float) -> float:
        """Length of the garment's section at height ``z`` (all pieces summed)."""
        return sec.section_length(self.points, self.triangles(), z)

    def level(self, name: str) -> GarmentLevel:
        """The construction row of a level by name."""
        for lv in self.levels:
            if lv.name == name:
                return lv
        raise MissingRegion(name, tuple(lv.name for lv in self.levels))


def intended_clearance(garment: GarmentSurface) -> list[GarmentLevel]:
    """The construction table: per level the body girth, ease, garment girth and clearance."""
    return list(garment.levels)


# ---------------------------------------------------------------------------------------------
# Building blocks
# ---------------------------------------------------------------------------------------------


@dataclass(frozen=True)
class _Cut:
    kind: str  # "ellipsoid" or "box"
    centre: tuple[float, float, float]
    size: tuple[float, float, float]  # semi-axes (ellipsoid) or full extents (box)


def _garment_section(
    body_pts: Array, ease: float, min_clearance: float | None
) -> tuple[Array, float, float, float]:
    """Offset the tape section: returns (points, body girth, effective ease, clearance)."""
    hull = sec.convex_hull(body_pts)
    dense = sec.resample_by_angle(hull, 720)
    g = sec.perimeter(dense)
    pts, d = sec.offset_to_perimeter(dense, (1.0 + ease) * g)
    if min_clearance is not None and d < min_clearance:
        pts, d = sec.offset_by(dense, min_clearance), min_clearance
    return pts, g, sec.perimeter(pts) / g - 1.0, d


def _levels_from(
    body: BodySurface | Limb,
    names: list[str],
    ease: dict[str, float],
    min_clearance: float | None,
    extra: dict[str, tuple[float, str, float]] | None = None,
) -> tuple[dict[str, tuple[float, Array]], list[GarmentLevel]]:
    """Garment sections for body levels ``names`` (bottom to top); ``extra`` adds levels
    ``name -> (z, copy_of_level, extra_clearance)`` that reuse another level's body section.
    ``body`` is anything with ``section(level) -> (z, points)``: a body, or a scan's limb in
    its straightened coordinates."""
    out: dict[str, tuple[float, Array]] = {}
    table: list[GarmentLevel] = []
    for name in names:
        if extra and name in extra:
            z, src, add = extra[name]
            _, body_pts = body.section(src)
            e = ease.get(name, ease.get(src, 0.0))
            pts, g, e_eff, d = _garment_section(body_pts, e, min_clearance)
            if add:
                pts = sec.offset_by(pts, add)
                d += add
                e_eff = sec.perimeter(pts) / g - 1.0
        else:
            z, body_pts = _under_the_overhang(body, name)
            pts, g, e_eff, d = _garment_section(body_pts, ease.get(name, 0.0), min_clearance)
        out[name] = (z, pts)
        table.append(GarmentLevel(name, z, g, e_eff, (1.0 + e_eff) * g, d))
    return out, table


#: levels of a bodice that hang from the bust: between them the body may overhang (a breast)
OVERHANG_LEVELS = ("underbust", "bust")
#: height step [m] of the sections between the under-bust and the bust (:func:`_under_the_overhang`)
OVERHANG_STEP = 0.003
#: the sections between them must reach this far [m] beyond a level's own section to count
OVERHANG_MIN = 0.005


def _under_the_overhang(body: BodySurface | Limb, name: str) -> tuple[float, Array]:
    """A level's body section, but for the under-bust and bust levels of a segmented scan the
    convex hull of every torso section from the under-bust up to the bust when they reach more
    than :data:`OVERHANG_MIN` beyond the level's own section: fabric hanging from the bust
    bridges the breast's lower part; it does not follow it in to the chest wall. (MakeHuman's
    heavy woman with its largest, softest breasts: the loft through the two sections, 1.025 and
    1.056 m, lay 41.8 mm inside the breast at 1.044 m, and the dress was refused.)"""
    z, pts = body.section(name)
    marks = getattr(body, "landmarks", {})
    if (name not in OVERHANG_LEVELS or getattr(body, "part", None) is None
            or not all(k in marks for k in OVERHANG_LEVELS)):  # fmt: skip
        return z, pts
    from .anatomy import torso_section

    z_lo, z_hi = marks["underbust"], marks["bust"]
    stack = [pts] + [
        torso_section(body.vertices, body.triangles, float(zz), body.arm_cut, marks.get("armpit"))
        for zz in np.arange(z_lo, z_hi + 1e-9, OVERHANG_STEP)
    ]
    hull = sec.convex_hull(np.vstack(stack))
    centre = sec.centroid(pts)
    reach = np.linalg.norm(sec.resample_by_angle(hull, 360, centre) - centre, axis=1)
    own = np.linalg.norm(sec.resample_by_angle(pts, 360, centre) - centre, axis=1)
    return (z, hull) if float((reach - own).max()) > OVERHANG_MIN else (z, pts)


def _mesh_options(g: Any, h: float, quads: bool, per_circle: int = 0) -> None:
    """Target size ``h``: gmsh's sizes from the loft's points and from the surface curvature are
    switched off (with them the gilet's median edge stayed ≈ 13 mm for any h from 0.015 to 0.08:
    24 elements per circle on the ≈ 5 cm flank curvature of the torso section). The sleeve keeps
    ``per_circle`` = 24 elements per turn of curvature (at most ``h``): with uniform 6–10 mm
    triangles its dressing stalled 0.4–0.5 mm short of the arm, with 24 per turn it dresses."""
    g.option.setNumber("Mesh.MeshSizeMax", h)
    g.option.setNumber("Mesh.MeshSizeMin", h / 4)
    g.option.setNumber("Mesh.MeshSizeFromPoints", 0)
    g.option.setNumber("Mesh.MeshSizeFromCurvature", per_circle)
    g.option.setNumber("Mesh.MeshSizeExtendFromBoundary", 1)
    g.option.setNumber("Mesh.Algorithm", 8 if quads else 6)
    if quads:
        g.option.setNumber("Mesh.RecombineAll", 1)
        g.option.setNumber("Mesh.RecombinationAlgorithm", 1)
        g.option.setNumber("Mesh.SubdivisionAlgorithm", 1)  # split leftovers: all quads
        g.option.setNumber("Mesh.MeshSizeMax", 2 * h)  # subdivision halves the size


def _centre_of(levels: dict[str, tuple[float, Array]]) -> tuple[Array, Array]:
    zs = np.array([z for z, _ in levels.values()])
    cs = np.array([p.mean(axis=0) for _, p in levels.values()])
    order = np.argsort(zs)
    return zs[order], cs[order]


#: Largest height [m] between the rings a gilet on a segmented body (a scan, the human
#: mannequin: levels found on the body, unevenly spaced) is lofted through: its landmark
#: sections are joined by monotone interpolated rings (``mannequin.guide_rings``), so that the
#: loft cannot overshoot between them into the body or away from it (MakeHuman's short, heavy,
#: old woman: 6.7 cm into the belly without). Not on the parametric mannequin, whose levels are
#: its own proportions and whose recorded runs stand: there the rings move the strap's front
#: between shoulder and neck base by up to 1.1 cm (median 1 mm over the gilet). Not on the
#: dress: with its degree-3 loft, gmsh did not finish the cotton dress's rings in 300 s.
TORSO_GUIDE = 0.02


def _build(
    g: Any,
    kind: str,
    levels: dict[str, tuple[float, Array]],
    cuts: list[_Cut],
    classify: Any,
    h: float,
    quads: bool,
    max_degree: int = -1,
    per_circle: int = 0,
    order: int = 2,
    refine: EdgeRefinement | None = None,
    guide: float = 0.0,
    guide_top: float = np.inf,
) -> dict[str, Any]:
    """Loft, cut, mesh, orient, name; returns the plain arrays (on the gmsh rank).

    ``guide`` > 0: the loft runs through monotone guide rings at most ``guide`` apart between
    the levels (:func:`~.mannequin.guide_rings`; the gilet on a segmented body: TORSO_GUIDE),
    at or below ``guide_top`` [m] only (the dress: SKIRT_GUIDE, in its skirt).

    ``order``: geometry degree of the mesh handed to DOLFINx (1 straight, 2 curved: module doc).
    ``refine``: smaller cells along some edges (:class:`EdgeRefinement`), or None.

    ``max_degree``: the loft's degree cap (see :func:`add_loft`); the dress without guide rings
    needs 3 (measured at h = 3 cm: OCC's default folds the skirt across the axis, 423
    triangles, min angle 3.3°; degree 3: no fold, min angle 8.7°; degree 2: no fold but 0.6°).
    """
    if order not in (1, 2):
        raise ValueError(f"garment geometry order must be 1 or 2, got {order}")
    occ = g.model.occ
    loft = add_loft(g, levels, solid=False, max_degree=max_degree, guide=guide, guide_top=guide_top)
    faces = [dt for dt in loft if dt[0] == 2]
    if cuts:
        tools = []
        for c in cuts:
            if c.kind == "ellipsoid":
                t = occ.addSphere(*c.centre, 1.0)
                occ.dilate([(3, t)], *c.centre, *c.size)
            else:
                t = occ.addBox(*(np.array(c.centre) - np.array(c.size) / 2), *c.size)
            tools.append((3, t))
        faces, _ = occ.cut(faces, tools)
        faces = [dt for dt in faces if dt[0] == 2]
        if not faces:
            raise GeometryError(f"{kind}: the cuts removed the whole garment")
    princess = getattr(classify, "princess", None)
    if princess:  # vertical seams x = ±princess: the loft's faces split by two planes
        big = 4.0
        planes = []
        for x in (princess, -princess):
            r = occ.addRectangle(-big / 2, -big / 2, 0.0, big, big)
            occ.rotate([(2, r)], 0, 0, 0, 0, 1, 0, np.pi / 2)  # into the plane x = 0
            occ.translate([(2, r)], x, 0.0, 0.0)
            planes.append((2, r))
        _, pieces = occ.fragment(faces, planes)
        faces = [dt for m in pieces[: len(faces)] for dt in m if dt[0] == 2]
    occ.synchronize()
    _remove_all_but(g, faces)
    zc, cc = _centre_of(levels)

    def centre(z: float) -> Array:
        return np.array([np.interp(z, zc, cc[:, 0]), np.interp(z, zc, cc[:, 1])])

    # panels
    panel_faces: dict[str, list[int]] = {}
    for _, f in faces:
        x, y, z = g.model.occ.getCenterOfMass(2, f)
        panel_faces.setdefault(classify.panel(x, y - centre(z)[1]), []).append(f)
    panels = {name: i + 1 for i, name in enumerate(sorted(panel_faces))}
    # edges
    curves: dict[str, list[int]] = {}
    face_set = {f for _, f in faces}
    all_curves = {
        abs(c) for _, f in faces for _, c in g.model.getBoundary([(2, f)], oriented=False)
    }
    for c in sorted(all_curves):
        up, _ = g.model.getAdjacencies(1, c)
        n_faces = len([f for f in up if f in face_set])
        bb = g.model.getBoundingBox(1, c)
        name = classify.edge(bb, n_faces)
        if name:
            curves.setdefault(name, []).append(c)
    edges = {name: 100 + i for i, name in enumerate(sorted(curves))}
    for name, tag in panels.items():
        g.model.addPhysicalGroup(2, panel_faces[name], tag, name=name)
    for name, tag in edges.items():
        g.model.addPhysicalGroup(1, curves[name], tag, name=name)
    _mesh_options(g, h, quads, per_circle)
    if refine is not None:
        g.option.setNumber("Mesh.MeshSizeMin", refine.ratio * h / 4)
        refine.apply(g, curves)
    g.model.mesh.generate(2)
    g.model.mesh.renumberNodes()
    g.model.mesh.renumberElements()
    # orient each face's mesh outward (away from the garment axis)
    for _, f in faces:
        etypes, _, enodes = g.model.mesh.getElements(2, f)
        x = _node_coords(g)
        s = 0.0
        for et, en in zip(etypes, enodes, strict=True):
            k = 3 if et == 2 else 4
            c = en.astype(np.int64).reshape(-1, k) - 1
            p = x[c]
            nrm = np.cross(p[:, 1] - p[:, 0], p[:, 2] - p[:, 0])
            mid = p.mean(axis=1)
            rad = mid[:, :2] - np.array([centre(z) for z in mid[:, 2]])
            s += float(np.sum(nrm[:, 0] * rad[:, 0] + nrm[:, 1] * rad[:, 1]))
        if s < 0:
            g.model.mesh.reverse([(2, f)])
    data = _extract(g, kind, panels, edges, panel_faces, curves)
    if order == 2:
        _curve(g, data["points"])
    return data


def _curve(g: Any, vertices: Array) -> None:
    """Raise the mesh to order 2 (edge nodes on the CAD surface), keeping the vertex numbering.

    gmsh's ``setOrder`` renumbers every node; the vertices are put back to tags 1…n (matched by
    their coordinates, which it does not move) and the new edge nodes follow, so that
    ``points[i]`` is still gmsh node i + 1 and DOLFINx's ``input_global_indices`` < n are the
    vertices.
    """
    from scipy.spatial import cKDTree

    g.model.mesh.setOrder(2)
    tags, coords, _ = g.model.mesh.getNodes()
    dist, idx = cKDTree(vertices).query(coords.reshape(-1, 3))
    vertex = dist <= 1e-12 * max(1.0, float(np.abs(vertices).max()))
    if vertex.sum() != len(vertices):
        raise GeometryError(f"order-2 mesh: {vertex.sum()} of {len(vertices)} vertices found")
    new = np.empty(len(tags), dtype=np.int64)
    new[vertex] = idx[vertex] + 1
    new[~vertex] = len(vertices) + 1 + np.arange(int((~vertex).sum()))
    g.model.mesh.renumberNodes(tags.astype(np.int64), new)


def _remove_all_but(g: Any, faces: list[tuple[int, int]]) -> None:
    """Delete construction entities (section points, wires, tools) so that no orphan node is
    meshed: only ``faces`` and their boundary curves and points stay in the model."""
    keep = set(faces)
    keep |= set(g.model.getBoundary(faces, combined=False, oriented=False, recursive=False))
    keep |= set(g.model.getBoundary(faces, combined=False, oriented=False, recursive=True))
    keep = {(d, abs(t)) for d, t in keep}
    for dim in (3, 2, 1, 0):
        drop = [dt for dt in g.model.getEntities(dim) if dt not in keep]
        if drop:
            g.model.occ.remove(drop)
    g.model.occ.synchronize()


def _node_coords(g: Any) -> Array:
    tags, coords, _ = g.model.mesh.getNodes()
    x = np.empty((int(tags.max()), 3))
    x[tags.astype(np.int64) - 1] = coords.reshape(-1, 3)
    return x


def _extract(g, kind, panels, edges, panel_faces, curves) -> dict[str, Any]:
    x = _node_coords(g)
    cells, cell_panel = [], []
    for name, fs in panel_faces.items():
        for f in fs:
            etypes, _, enodes = g.model.mesh.getElements(2, f)
            for et, en in zip(etypes, enodes, strict=True):
                k = 3 if et == 2 else 4
                c = en.astype(np.int64).reshape(-1, k) - 1
                cells.append(c)
                cell_panel.append(np.full(len(c), panels[name], dtype=np.int32))
    ks = {c.shape[1] for c in cells}
    if len(ks) != 1:
        raise GeometryError(f"{kind}: mixed triangles and quadrilaterals after recombination")
    cells_a = np.concatenate(cells)
    edge_nodes = {}
    for name, cs in curves.items():
        pairs = []
        for c in cs:
            _, _, en = g.model.mesh.getElements(1, c)
            pairs.append(en[0].astype(np.int64).reshape(-1, 2) - 1)
        edge_nodes[name] = np.concatenate(pairs)
    normal = nodal_normals(x, cells_a)
    return {
        "kind": kind,
        "points": x,
        "cells": cells_a,
        "cell_panel": np.concatenate(cell_panel),
        "panels": panels,
        "edges": edges,
        "edge_nodes": edge_nodes,
        "normal": normal,
        "warp": warp_direction(normal),
    }


def nodal_normals(x: Array, cells: npt.NDArray[np.int64]) -> Array:
    """Area-weighted unit vertex normals of a triangle or quadrilateral mesh (cell order)."""
    p = x[cells]
    nc = np.cross(p[:, 1] - p[:, 0], p[:, 2] - p[:, 0])
    if cells.shape[1] == 4:
        nc = 0.5 * np.cross(p[:, 2] - p[:, 0], p[:, 3] - p[:, 1])
    normal = np.zeros_like(x)
    for j in range(cells.shape[1]):
        np.add.at(normal, cells[:, j], nc)
    return normal / (np.linalg.norm(normal, axis=1)[:, None] + 1e-300)


def warp_direction(normal: Array, along: Any = (0.0, 0.0, 1.0)) -> Array:
    """Unit tangent closest to ``along`` (vertical by default; one vector, or one per node) at
    each node.

    Where the surface is nearly horizontal (the tangential part of ``along`` shorter than 0.2)
    the fabric's warp is taken front-to-back (the y axis projected) instead.
    """
    a = np.broadcast_to(np.asarray(along, dtype=float), normal.shape)
    w = a - np.einsum("ij,ij->i", normal, a)[:, None] * normal
    flat = np.linalg.norm(w, axis=1) < 0.2
    ey = np.array([0.0, 1.0, 0.0])
    w[flat] = ey - (normal[flat] @ ey)[:, None] * normal[flat]
    return w / np.linalg.norm(w, axis=1)[:, None]


def _finish(
    kind: str,
    comm: Any | None,
    build: Any,
    table: list[GarmentLevel],
    frame: Any = None,
) -> GarmentSurface:
    """Run ``build(g)`` on rank 0 in a gmsh session, share the arrays, make the DOLFINx mesh.

    With a ``frame`` (a :class:`~.limbs.Limb`) the garment is built and checked in the limb's
    straightened coordinates and then mapped onto the limb (:func:`_onto_limb`).
    """
    import time

    t0 = time.perf_counter()
    with gmsh_session(comm, 0, name=kind) as g:
        data, err = None, None
        if g is not None:
            try:
                with time_limit(GMSH_TIME_LIMIT, f"the {kind}"):
                    data = build(g)
                check_garment(kind, data["points"], data["cells"], [lv.z for lv in table],
                              max(lv.garment_girth for lv in table))  # fmt: skip
                if frame is not None:
                    data = _onto_limb(kind, data, frame)
            except GeometryError as e:
                err = str(e)
            except Exception as e:  # gmsh raises a bare Exception with its last error
                err = f"gmsh could not build the {kind}: {_first_line(e)}"
        data = shared_result(comm, data, err)
        meshdata = None
        if comm is not None:
            meshdata = garment_mesh(comm, g.model if g is not None else None, kind)
            if frame is not None:  # every node (edge nodes of a curved mesh too) onto the limb
                x = meshdata.mesh.geometry.x
                x[:] = frame.to_world(x)
    data["info"] = {"seconds": time.perf_counter() - t0, "cells": len(data["cells"])}
    return GarmentSurface(levels=table, meshdata=meshdata, frame=frame, **data)


def _onto_limb(kind: str, data: dict[str, Any], limb: Any) -> dict[str, Any]:
    """Map a garment built in a limb's straightened coordinates onto the limb: the points by
    :meth:`~.limbs.Limb.to_world`, the normals recomputed, the warp along the limb's axis.

    Each section plane is moved rigidly, so girths are kept; lengths along the limb change by
    1 − κ r cos φ on a centreline of curvature κ (the inside of a bent elbow is shorter), so a
    curvature radius below the section's radius would fold the garment: refused here.
    """
    from .garment_checks import MAX_TURN, largest_turn

    straight = data["points"]
    x = limb.to_world(straight)
    turn = largest_turn(x, data["cells"])
    if turn > MAX_TURN:
        raise GeometryError(
            f"the {kind} folds where it follows the {limb.name.replace('_', ' ')} "
            f"(cells turn by {turn:.0f}°): the limb bends too sharply for it"
        )
    normal = nodal_normals(x, data["cells"])
    return {**data, "points": x, "normal": normal,
            "warp": warp_direction(normal, limb.axis_at(straight))}  # fmt: skip


def _limb_source(body: Any, kind: str, side: str) -> tuple[Any, Any]:
    """What a sleeve (``kind = "arm"``) or stocking (``"leg"``) is cut from, and its frame: on
    a scan the limb followed along its centreline (:mod:`.limbs`), else the body itself."""
    if side not in ("left", "right"):
        raise GeometryError(f"side must be 'left' or 'right', got {side!r}")
    limbs = getattr(body, "limbs", None) or {}
    if not limbs:
        return body, None
    name = f"{kind}_{side}"
    if name not in limbs:
        why = getattr(body, "limb_problems", {}).get(name, f"no {kind} found on the {side}")
        raise GeometryError(f"no {side} {kind} to build on: {why}")
    return limbs[name], limbs[name]


def _first_line(e: BaseException) -> str:
    lines = str(e).strip().splitlines()
    return lines[0] if lines else type(e).__name__


class _TorsoClassifier:
    """Panels by the side of the face's centre of mass; edges by position and valence.

    ``princess``: the x (m) of vertical princess seams either side of the centre, front and
    back (None: none); the pieces outside them are ``front_side_left``/``_right`` and
    ``back_side_left``/``_right``, their seams ``princess_front_left``… . ``y_mid``: the
    body's centre depth, which tells a front seam from a back one.
    """

    def __init__(self, z_hem, z_top, z_arm, x_neck, gap, princess=None, y_mid=0.0):
        self.z_hem, self.z_top, self.z_arm, self.x_neck, self.gap = z_hem, z_top, z_arm, x_neck, gap
        self.princess, self.y_mid = princess, y_mid

    def panel(self, x: float, dy: float) -> str:
        side = "left" if x > 0 else "right"
        if dy > 0:
            return f"back_side_{side}" if self.princess and abs(x) > self.princess else "back"
        if self.princess and abs(x) > self.princess:
            return f"front_side_{side}"
        if self.gap:
            return "front_left" if x > 0 else "front_right"
        return "front"

    def edge(self, bb, n_faces: int) -> str | None:
        x0, y0, z0, x1, y1, z1 = bb
        xc, zc = 0.5 * (x0 + x1), 0.5 * (z0 + z1)
        side = "left" if xc > 0 else "right"
        if (
            n_faces == 2
            and self.princess
            and x1 - x0 < 1e-3
            and (abs(abs(xc) - self.princess) < 1e-3)
        ):
            part = "back" if 0.5 * (y0 + y1) > self.y_mid else "front"
            return f"princess_{part}_{side}"
        if n_faces == 2:
            return f"side_seam_{side}" if zc < self.z_arm else f"shoulder_seam_{side}"
        if self.gap and x1 - x0 < 1e-3 and abs(abs(xc) - self.gap / 2) < 1e-3:
            return f"opening_{side}"
        if z1 < self.z_hem + 1e-4:
            return "hem"
        if z0 > self.z_top - 1e-4 or abs(xc) < self.x_neck:
            return "neckline"
        return f"armhole_{side}"


class _TubeClassifier:
    def __init__(self, z_hem, z_top, top_name="top", x_mid=0.0):
        self.z_hem, self.z_top, self.top_name, self.x_mid = z_hem, z_top, top_name, x_mid

    def panel(self, x: float, dy: float) -> str:
        return "back" if dy > 0 else "front"

    def edge(self, bb, n_faces: int) -> str | None:
        x0, _, z0, x1, _, z1 = bb
        if n_faces == 2:
            return "seam_left" if 0.5 * (x0 + x1) > self.x_mid else "seam_right"
        if z1 < self.z_hem + 1e-4:
            return "hem"
        if z0 > self.z_top - 1e-4:
            return self.top_name
        return None


_TORSO_EDGES = ("hem", "neckline", "armhole_left", "armhole_right", "side_seam_left",
                "side_seam_right", "shoulder_seam_left", "shoulder_seam_right", "opening_left",
                "opening_right", "princess_front_left", "princess_front_right",
                "princess_back_left", "princess_back_right")  # fmt: skip
#: the edges each garment kind names (its classifier above: _TorsoClassifier, _TubeClassifier)
EDGE_NAMES = {
    "gilet": _TORSO_EDGES,
    "dress": _TORSO_EDGES,
    "tube": ("hem", "top", "seam_left", "seam_right"),
    "sleeve": ("hem", "top", "seam_left", "seam_right"),
    "stocking": ("hem", "welt", "seam_left", "seam_right"),
}


def _ease_dict(ease: float | dict[str, float], default: dict[str, float]) -> dict[str, float]:
    if isinstance(ease, dict):
        return {**default, **ease}
    return dict.fromkeys(default, float(ease))


# ---------------------------------------------------------------------------------------------
# The garments
# ---------------------------------------------------------------------------------------------

GILET_EASE = {
    "hip": 0.04, "abdomen": 0.04, "waist": 0.03, "underbust": 0.03, "bust": 0.03,
    "upper_chest": 0.03, "shoulder": 0.02, "neck_base": 0.15,
}  # fmt: skip


def _y_mid(levels: dict[str, tuple[float, Array]]) -> float:
    """The mean depth (y) of the garment's level sections: the plane between front and back."""
    return float(np.mean([sec[:, 1].mean() for _, sec in levels.values()]))


#: How far inside the arm root (the vertical plane through the armpit) a segmented body's
#: armhole begins [m], so that a torso garment clears the arm. Measured on MakeHuman's bodies
#: (the scan gilet's pattern, ``tests/test_body_sweep_fixes.py``): the nearest point of the
#: garment to an arm 1.9 mm away on the female body and 1.5 mm on the short, heavy, old woman
#: with the armholes cut up to the arm roots (3.1 % of the dressed female gilet's contact force
#: on the arms), 4.5 and 3.7 mm with 1.5 cm (no contact on the arms: exit 0). 1.5 cm was not
#: enough on MakeHuman's old and teenage men (the dress: 0.37 % and 0.15 % of the contact force
#: on the arm roots, limit 0.1 %) nor, after the landmarks moved (the ISO hip, the fold's
#: under-bust), on the female body (the gilet: 0.12 %): 2.5 cm.
ARMHOLE_CLEARANCE = 0.025
#: The least clearance, to which ARMHOLE_CLEARANCE gives way where it leaves no shoulder strap
MIN_ARMHOLE_CLEARANCE = 0.015
#: The narrowest shoulder strap left between the neck and the armhole [m]
MIN_STRAP = 0.02


def _top_cuts(
    body: BodySurface,
    levels: dict[str, tuple[float, Array]],
    strap: float,
    arm_drop: float,
    scoop_front: float,
    scoop_back: float,
    gap: float | None,
    z_lo: float,
    z_hi: float,
    clearance: float = ARMHOLE_CLEARANCE,
) -> tuple[list[_Cut], float, float]:
    """Armhole ellipsoids at the shoulder tips, neckline scoops, an optional front opening;
    on a segmented body the armholes clear the arm roots by ``clearance``."""
    z_sh, sh = levels["shoulder"]
    z_nb, nb = levels["neck_base"]
    z_uc = body.landmarks["upper_chest"]
    x_tip = sh[:, 0].max()
    x_neck = nb[:, 0].max()
    z_bottom = z_uc - arm_drop
    if "armpit" in body.landmarks:  # a segmented body: the armhole reaches below the real armpit
        drop = max(arm_drop, 2 * clearance)
        z_bottom = min(z_bottom, body.landmarks["armpit"] - drop)
    zc = z_sh + 0.03
    cuts = []
    x_in = x_neck + strap
    roots = [body.points.get(f"armpit_{side}") for side in ("left", "right")]
    if all(r is not None and np.all(np.isfinite(r)) for r in roots):
        # a segmented body: the armhole's inner edge ARMHOLE_CLEARANCE inside the arm roots
        # (the planes through the armpits), the strap narrowed to what is left between it
        # and the neck, so that the garment clears the arms
        x_root = min(abs(float(r[0])) for r in roots)
        x_in = min(x_in, x_root - clearance)
        if x_in - x_neck < MIN_STRAP:
            # the neckline's ease gives way first: it narrows towards the neck itself (the
            # heavy, muscular man's neck base is 41 cm wide, 4 cm from each arm root: with the
            # dress's 25 % neckline ease there was no strap left), down to the neck's own
            # section at mid-neck (on a heavy body the neck base's section takes in the
            # trapezius slope: the short, heavy, flabby old man's was 2.6 cm from his arm roots);
            # a clearance beyond MIN_ARMHOLE_CLEARANCE gives way too
            level = "neck" if "neck" in body.landmarks else "neck_base"
            x_body = float(body.section(level)[1][:, 0].max())
            x_in = max(x_in, min(x_root - MIN_ARMHOLE_CLEARANCE, x_body + MIN_STRAP))
            if x_in - x_body < MIN_STRAP - 1e-9:
                raise GeometryError(
                    f"no room for a shoulder strap: {(x_root - x_body) * 100:.1f} cm from the "
                    f"neck to the arm root, at least "
                    f"{(MIN_STRAP + MIN_ARMHOLE_CLEARANCE) * 100:.1f} cm needed; check the body's "
                    f"{level} and armpit landmarks"
                )
            x_neck = min(x_neck, x_in - MIN_STRAP)
    ax = x_tip + 0.03 - x_in
    for s in (1.0, -1.0):
        root = body.points.get("arm_root_left" if s > 0 else "arm_root_right")
        if root is None or not np.all(np.isfinite(root)):
            cuts.append(
                _Cut("ellipsoid", (s * (x_tip + 0.03), 0.0, zc), (ax, 0.085, zc - z_bottom))
            )
            continue
        # a segmented body (scan): the opening in the garment's plane (0.03 m inside the
        # ellipsoid's centre, where its cross-section is shrunk by k) reaches down to z_bottom
        # and, from the armpit up, spans the arm root's depth with ARMHOLE_CLEARANCE to spare
        # either side: the half-width w at the armpit height, Δ below the centre, needs the
        # half-axis w / √(1 − (Δ / c)²) for a vertical half-axis c
        k = np.sqrt(max(1.0 - (0.03 / ax) ** 2, 0.1))
        y_c, w = 0.5 * (root[0] + root[1]), 0.5 * (root[1] - root[0]) + clearance
        c, dz = zc - z_bottom, zc - root[2]
        half = max(w / np.sqrt(1.0 - min(dz / c, 0.9) ** 2), 0.5 * (root[1] - root[0]) + 0.02)
        cuts.append(_Cut("ellipsoid", (s * (x_tip + 0.03), y_c, zc),
                         (ax, half / k, c / k)))  # fmt: skip
    y_front = nb[:, 1].min()
    y_back = nb[:, 1].max()
    if scoop_front > 0:
        cuts.append(_Cut("ellipsoid", (0.0, y_front, z_nb), (x_neck + 0.01, 0.09, scoop_front)))
    if scoop_back > 0:
        cuts.append(_Cut("ellipsoid", (0.0, y_back, z_nb), (x_neck + 0.01, 0.09, scoop_back)))
    if gap:
        cuts.append(_Cut("box", (0.0, -0.5, 0.5 * (z_lo + z_hi)), (gap, 1.0, z_hi - z_lo + 0.2)))
    cuts.append(
        _Cut("box", (0.0, 0.0, z_nb + 0.5), (2.0, 2.0, 1.0))
    )  # everything above the neck base
    return cuts, x_neck * 0.999, z_bottom


def make_gilet(
    body: BodySurface,
    ease: float | dict[str, float] = GILET_EASE,
    h: float = 0.015,
    min_clearance: float | None = None,
    hem: str = "hip",
    strap: float = 0.07,
    armhole_drop: float = 0.02,
    neck_scoop: float = 0.06,
    front_opening: float | None = None,
    quads: bool = False,
    order: int = 2,
    comm: Any | None = None,
    refine: EdgeRefinement | None = None,
    princess: float | None = None,
) -> GarmentSurface:
    """A sleeveless gilet from ``hem`` level (2.5 cm below it) to the base of the neck.

    Args:
        body: the body (mannequin or scan) with torso landmarks.
        ease: one value for all levels or a dict per level (fraction: 0.03 = +3 % girth).
        h: target element size (m).
        min_clearance: raise the normal offset to at least this (m), see module doc.
        hem: landmark level of the hem (``hip``, ``abdomen`` or ``waist``).
        strap: width (m) of fabric left between the neck and the armhole over the shoulder.
        armhole_drop: how far (m) the armhole reaches below the upper-chest level (or below
            the armpit, if lower, on a body whose arms were found: a scan).
        neck_scoop: depth (m) of the front neckline below the neck base.
        front_opening: width (m) of a centre-front opening (None: closed front).
        quads: quadrilateral cells (gmsh recombination) instead of triangles.
        order: geometry degree of the DOLFINx mesh, 2 (curved, default) or 1 (module doc, 5).
        comm: MPI communicator: build on its rank 0 and distribute as a DOLFINx mesh.
        princess: princess seams at x = ±princess (m), front and back (None: none), which
            split the front and back into a centre and two side pieces each: the seams that
            let flat pattern pieces follow the bust and the shoulder blades.
    """
    torso = ["hip", "abdomen", "waist", "underbust", "bust", "upper_chest", "shoulder"]
    names = ["hem", *torso[torso.index(hem) :], "neck_base", "neck"]
    e = _ease_dict(ease, GILET_EASE)
    e.setdefault("neck", e["neck_base"])
    z_hem = body.landmarks[hem] - 0.025
    levels, table = _levels_from(body, names, e, min_clearance, {"hem": (z_hem, hem, 0.0)})
    table = table[:-1]  # the neck section only guides the loft; it is cut away
    z_top = levels["neck_base"][0]
    cuts, x_neck, z_arm = _top_cuts(
        body, levels, strap, armhole_drop, neck_scoop, 0.0, front_opening, z_hem, z_top
    )
    cls = _TorsoClassifier(z_hem, z_top, z_arm, x_neck, front_opening, princess,
                           _y_mid(levels))  # fmt: skip
    return _finish(
        "gilet",
        comm,
        lambda g: _build(
            g,
            "gilet",
            levels,
            cuts,
            cls,
            h,
            quads,
            order=order,
            refine=refine,
            guide=TORSO_GUIDE if getattr(body, "part", None) is not None else 0.0,
        ),
        table,
    )


DRESS_EASE = {
    "hip": 0.06, "abdomen": 0.05, "waist": 0.03, "underbust": 0.03, "bust": 0.03,
    "upper_chest": 0.03, "shoulder": 0.02, "neck_base": 0.25,
}  # fmt: skip


def make_dress(
    body: BodySurface,
    ease: float | dict[str, float] = DRESS_EASE,
    h: float = 0.015,
    min_clearance: float | None = None,
    length: float = 0.45,
    flare: float = 0.25,
    strap: float = 0.045,
    armhole_drop: float = 0.03,
    neck_scoop: float = 0.12,
    back_scoop: float = 0.10,
    quads: bool = False,
    order: int = 2,
    comm: Any | None = None,
    refine: EdgeRefinement | None = None,
    princess: float | None = None,
    guide: float | None = None,
) -> GarmentSurface:
    """A one-piece dress: fitted bodice with shoulder straps (cut by wide armholes and front and
    back scoops) and a flared skirt hanging ``length`` (m) below the hip level.

    The skirt sections are the hip section offset further, linearly in height, so that the hem
    girth is ``(1 + ease_hip + flare) ×`` the hip girth; rows ``skirt_k`` of the table report
    that against the hip girth. ``princess``: princess seams as in :func:`make_gilet`.

    ``guide`` [m] (None: :data:`SKIRT_GUIDE`): the skirt, hem to hip, is lofted through monotone
    guide rings this far apart (:func:`~.mannequin.guide_rings`) with OCC's default degree;
    0 gives the former loft of degree ≤ 3 through the levels only, which bulges the skirt
    3.6–5.4 cm between its levels (:func:`~.garment_checks.skirt_bulge`, measured on the human
    and five MakeHuman bodies at h = 3 cm; tests/test_skirt_fairness.py). Guide rings above
    the hip folded the bodice where its levels are close (under-bust and bust).
    """
    guide = SKIRT_GUIDE if guide is None else guide
    e = _ease_dict(ease, DRESS_EASE)
    z_hip = body.landmarks["hip"]
    g_hip = sec.perimeter(sec.resample_by_angle(sec.convex_hull(body.section("hip")[1]), 720))
    n_sk = 3
    extra = {}
    for k in range(n_sk, 0, -1):
        frac = k / n_sk
        extra[f"skirt_{n_sk - k}"] = (
            z_hip - frac * length,
            "hip",
            frac * flare * g_hip / (2 * np.pi),
        )
    names = [*extra, "hip", "abdomen", "waist", "underbust", "bust", "upper_chest", "shoulder"]
    names += ["neck_base", "neck"]
    e.setdefault("neck", e["neck_base"])
    levels, table = _levels_from(body, names, e, min_clearance, extra)
    table = table[:-1]  # the neck section only guides the loft; it is cut away
    if getattr(body, "part", None) is not None:  # a segmented body: legs apart, arms beside
        _skirt_around_the_legs(body, levels, table, [f"skirt_{k}" for k in range(n_sk)])
    z_hem = levels["skirt_0"][0]
    z_top = levels["neck_base"][0]
    cuts, x_neck, z_arm = _top_cuts(
        body,
        levels,
        strap,
        armhole_drop,
        neck_scoop,
        back_scoop,
        None,
        z_hem,
        z_top,
    )
    cls = _TorsoClassifier(z_hem, z_top, z_arm, x_neck, None, princess, _y_mid(levels))
    return _finish(
        "dress",
        comm,
        lambda g: _build(
            g,
            "dress",
            levels,
            cuts,
            cls,
            h,
            quads,
            -1 if guide else 3,
            order=order,
            refine=refine,
            guide=guide,
            guide_top=levels["hip"][0] + 1e-9,
        ),
        table,
    )


#: the dress's guide ring spacing [m] in the skirt, hem to hip (:func:`make_dress`)
SKIRT_GUIDE = 0.05

#: the skirt's least clearance [m] around the legs of a segmented body (:func:`make_dress`)
SKIRT_CLEARANCE = 0.01


def _skirt_around_the_legs(
    body: BodySurface,
    levels: dict[str, tuple[float, Array]],
    table: list[GarmentLevel],
    skirt: list[str],
) -> None:
    """Widen the skirt sections (bottom to top in ``skirt``) of a segmented body so that the
    skirt hangs clear of its legs and arms, in place.

    A flared cone from the hip section assumes legs that stay inside the hip's outline; a real
    body stands with its knees apart (MakeHuman: the cone cut 21 mm into the knees). Each skirt
    section is widened to the convex hull of the hip section and of every leg point from the
    next skirt level down (one level spacing below it) up to the hip, offset by
    :data:`SKIRT_CLEARANCE` (a convex curve around both): consecutive sections then both enclose
    the legs between them, and so does the loft interpolating them. The flare stays where it is
    wider. Arms and hands must not reach inside the skirt: refused with the heights."""
    from .anatomy import PARTS

    z_hip, hip = levels["hip"]
    tri = body.triangles
    leg = np.isin(body.part, [PARTS["leg_left"], PARTS["leg_right"]])
    pts = body.vertices[np.unique(tri[leg])]
    zs = [levels[k][0] for k in skirt]
    rows = {r.name: i for i, r in enumerate(table)}
    g_hip = table[rows["hip"]].body_girth
    for k, name in enumerate(skirt):
        z, cur = levels[name]
        lo = z - (zs[1] - zs[0] if len(zs) > 1 else 0.0) if k == 0 else zs[k - 1]
        near = pts[(pts[:, 2] >= lo) & (pts[:, 2] <= z_hip), :2]
        if not len(near) or np.all(sec.signed_distance_2d(near, cur) <= -SKIRT_CLEARANCE):
            continue
        env = sec.resample_by_angle(sec.convex_hull(np.vstack([hip, near])), 720)
        around = sec.offset_by(env, SKIRT_CLEARANCE)
        target = max(sec.perimeter(cur), sec.perimeter(around))
        new, d = sec.offset_to_perimeter(env, target)
        levels[name] = (z, new)
        girth = sec.perimeter(new)
        table[rows[name]] = GarmentLevel(name, z, g_hip, girth / g_hip - 1.0, girth, d)
    # each section encloses the one above it (the hip's for the top one): the skirt flares
    # monotonically, without a bulge at a level widened around the legs more than the level
    # below it (MakeHuman's short, heavy, old woman: 14.8 mm at 'skirt_1', measured by
    # garment_checks.skirt_bulge)
    above = hip
    for name in reversed(skirt):
        z, cur = levels[name]
        if np.any(sec.signed_distance_2d(above, cur) > 0.0):
            new = sec.resample_by_angle(sec.convex_hull(np.vstack([cur, above])), len(cur))
            levels[name] = (z, new)
            girth = sec.perimeter(new)
            old = table[rows[name]]
            table[rows[name]] = GarmentLevel(
                name, z, g_hip, girth / g_hip - 1.0, girth, old.clearance
            )
        above = levels[name][1]
    arm = np.isin(body.part, [PARTS["arm_left"], PARTS["arm_right"]])
    hands = body.vertices[np.unique(tri[arm])]
    for name in ["hip", *skirt]:
        z, cur = levels[name]
        band = hands[np.abs(hands[:, 2] - z) < 0.05]
        if len(band) and np.any(sec.signed_distance_2d(band[:, :2], cur) < SKIRT_CLEARANCE):
            raise GeometryError(
                f"dress: an arm or hand hangs inside the skirt at z = {z:.2f} m; "
                "shorten the skirt (length) or pose the arms away from the hips"
            )


STOCKING_EASE = {"ankle": -0.20, "calf": -0.16, "knee": -0.13, "thigh": -0.10}


def make_stocking(
    body: BodySurface,
    side: str = "left",
    ease: float | dict[str, float] = STOCKING_EASE,
    h: float = 0.012,
    min_clearance: float | None = None,
    per_turn: int = 24,
    quads: bool = False,
    order: int = 2,
    comm: Any | None = None,
    refine: EdgeRefinement | None = None,
) -> GarmentSurface:
    """A compression stocking on one leg, ankle to thigh, graduated ease (tightest at the ankle).

    Default ease (−20 % ankle … −10 % thigh) is our illustrative graduation, not a class of a
    compression standard. ``per_turn``: elements per turn of curvature (at most ``h``), the
    resolution of the leg's round sections (:func:`_mesh_options`).

    On a mannequin the levels are horizontal sections of the leg; on a scan the leg's own
    (:mod:`.limbs`): the stocking is built around the ``side`` leg's centreline from its
    perpendicular sections and mapped onto it (:func:`_onto_limb`).
    """
    src, frame = _limb_source(body, "leg", side)
    e = _ease_dict(ease, STOCKING_EASE)
    lv = ["ankle", "calf", "knee", "thigh"]
    e = {f"{k}_{side}": v for k, v in e.items()}
    z_a, z_t = src.landmarks["ankle"], src.landmarks["thigh"]
    extra = {
        "hem": (z_a - 0.015, f"ankle_{side}", 0.0),
        "welt": (z_t + 0.02, f"thigh_{side}", 0.0),
    }
    e["hem"], e["welt"] = e[f"ankle_{side}"], e[f"thigh_{side}"]
    names = ["hem", *[f"{k}_{side}" for k in lv], "welt"]
    levels, table = _levels_from(src, names, e, min_clearance, extra)
    levels = _follow_the_limb(frame, levels, table, min_clearance)
    x_mid = float(np.mean([p[:, 0].mean() for _, p in levels.values()]))
    cls = _TubeClassifier(levels["hem"][0], levels["welt"][0], "welt", x_mid)
    return _finish(
        "stocking",
        comm,
        lambda g: _build(
            g,
            "stocking",
            levels,
            [],
            cls,
            h,
            quads,
            per_circle=per_turn,
            order=order,
            refine=refine,
        ),
        table,
        frame,
    )


#: spacing [m] along a scan's limb of the sections a sleeve or stocking is lofted through
LIMB_LOFT_STEP = 0.02


def _follow_the_limb(
    limb: Limb | None,
    levels: dict[str, tuple[float, Array]],
    table: list[GarmentLevel],
    min_clearance: float | None,
) -> dict[str, tuple[float, Array]]:
    """On a scan's limb, the garment sections at every ``LIMB_LOFT_STEP`` between its levels
    (and its end sections, which copy the nearest level's section) are the limb's own sections
    there, offset to the ease interpolated linearly in z' between the levels, so that the
    garment's ease follows the graduation all along the limb.

    With the levels alone the loft interpolates the garment's girth between sections up to
    21 cm apart while the leg's girth does not change linearly (the ankle-to-calf stretch of
    the MakeHuman leg): the stocking's ease went from −8 % at the ankle to −0.6 % half-way to the
    calf and back to −8 % (its pressure 3.7 → 0.27 → 1.9 kPa), and the ankle band, between
    the loft's dip towards the hem (whose section copied the ankle's while the heel widens
    under it) and the slow rise above, was at −9 % (measured; docs/guide/scan.md).
    The end sections are the limb's own there too, where the plane meets the limb alone."""
    if limb is None:
        return levels
    rows = sorted(table, key=lambda r: r.z)
    zs = np.array([r.z for r in rows])
    eases = np.array([r.ease for r in rows])
    out: dict[str, tuple[float, Array]] = {}
    ends = {rows[0].name, rows[-1].name}
    n_extra = 0
    for k, row in enumerate(rows):
        z0 = row.z
        if row.name in ends and (own := limb.section_at(z0)) is not None:
            pts, g, e_eff, d = _garment_section(own, row.ease, min_clearance)
            out[row.name] = (z0, pts)
            i = table.index(row)
            table[i] = GarmentLevel(row.name, z0, g, e_eff, (1.0 + e_eff) * g, d)
        else:
            out[row.name] = levels[row.name]
        if k + 1 == len(rows):
            break
        z1 = rows[k + 1].z
        n = int(np.floor((z1 - z0) / LIMB_LOFT_STEP - 0.5))
        for z in np.linspace(z0, z1, n + 2)[1:-1]:
            own = limb.section_at(float(z))
            if own is None:
                continue
            pts, _, _, _ = _garment_section(own, float(np.interp(z, zs, eases)), min_clearance)
            out[f"_limb_{n_extra}"] = (float(z), pts)
            n_extra += 1
    return dict(sorted(out.items(), key=lambda kv: kv[1][0]))


#: a scan's sleeve hem lies this far [m] below the wrist: the hand widens right after the
#: narrowest section (MakeHuman: +14 % girth 2 cm beyond it, tests/test_scan_makehuman.py)
HAND_CLEARANCE = 0.005
SLEEVE_EASE = {"wrist": -0.07, "forearm": -0.065, "elbow": -0.06, "upper_arm": -0.055}


def make_sleeve(
    body: BodySurface,
    ease: float | dict[str, float] = SLEEVE_EASE,
    h: float = 0.01,
    min_clearance: float | None = None,
    end: float = 0.025,
    per_turn: int = 24,
    quads: bool = False,
    order: int = 2,
    comm: Any | None = None,
    side: str = "left",
    hem_end: float | None = None,
    refine: EdgeRefinement | None = None,
) -> GarmentSurface:
    """A compression sleeve on an arm, from ``hem_end`` below the wrist (edge ``hem``) to
    ``end`` above the upper-arm level (edge ``top``), ease per level.

    The arm is the body from :func:`~.mannequin.make_arm` (its levels are horizontal sections;
    ``side`` is not used), or the ``side`` arm of a scan, followed along its own centreline
    (:mod:`.limbs`: the sleeve is built from the arm's perpendicular sections and mapped onto
    it, :func:`_onto_limb`). The end sections repeat the wrist's and the upper arm's (the
    parametric arm's stubs are prismatic), so the levels lie ``end`` away from the free edges.
    ``hem_end`` defaults to ``end`` on the parametric arm and to ``HAND_CLEARANCE`` on a scan,
    whose hand widens right after the wrist (the narrowest section). Default ease (−7 % wrist
    … −5.5 % upper arm) is our illustrative graduation, not a compression class.
    ``per_turn``: elements per turn of curvature (at most ``h``; :func:`_mesh_options`).
    """
    src, frame = _limb_source(body, "arm", side)
    if hem_end is None:
        hem_end = end if frame is None else HAND_CLEARANCE
    e = _ease_dict(ease, SLEEVE_EASE)
    z_w, z_u = src.landmarks["wrist"], src.landmarks["upper_arm"]
    extra = {"hem": (z_w - hem_end, "wrist", 0.0), "top": (z_u + end, "upper_arm", 0.0)}
    names = ["hem", "wrist", "forearm", "elbow", "upper_arm", "top"]
    levels, table = _levels_from(src, names, e, min_clearance, extra)
    levels = _follow_the_limb(frame, levels, table, min_clearance)
    cls = _TubeClassifier(levels["hem"][0], levels["top"][0])
    return _finish(
        "sleeve",
        comm,
        lambda g: _build(
            g, "sleeve", levels, [], cls, h, quads, per_circle=per_turn, order=order, refine=refine
        ),
        table,
        frame,
    )


def make_tube(
    body: BodySurface,
    ease: float | dict[str, float] = -0.07,
    h: float = 0.01,
    min_clearance: float | None = None,
    quads: bool = False,
    order: int = 2,
    comm: Any | None = None,
    refine: EdgeRefinement | None = None,
) -> GarmentSurface:
    """A sleeve/tube over a cylinder body from :func:`cylinder_body` (levels bottom, mid, top)."""
    e = _ease_dict(ease, {"bottom": 0.0, "mid": 0.0, "top": 0.0})
    levels, table = _levels_from(body, ["bottom", "mid", "top"], e, min_clearance)
    cls = _TubeClassifier(levels["bottom"][0], levels["top"][0])
    return _finish(
        "tube",
        comm,
        lambda g: _build(g, "tube", levels, [], cls, h, quads, order=order, refine=refine),
        table,
    )


def cylinder_body(radius: float = 0.1, length: float = 0.2, margin: float = 0.05,
                  h: float = 0.01) -> BodySurface:  # fmt: skip
    """A closed circular cylinder (an arm, or a test rig) as a body, axis z, z ∈ [−margin,
    length + margin]; its levels ``bottom``/``mid``/``top`` are at 0, length/2 and length."""
    from .mannequin import _surface_arrays
    from .surface import orient_outward

    with gmsh_session(name="cylinder") as g:
        g.model.occ.addCylinder(0, 0, -margin, 0, 0, length + 2 * margin, radius)
        g.model.occ.synchronize()
        g.option.setNumber("Mesh.MeshSizeMax", h)
        g.option.setNumber("Mesh.MeshSizeFromCurvature", 24)
        g.model.mesh.generate(2)
        v, t = _surface_arrays(g, 1)
    t = orient_outward(v, t)
    th = np.linspace(0, 2 * np.pi, 720, endpoint=False)
    circle = radius * np.column_stack([np.cos(th), np.sin(th)])
    marks = {"bottom": 0.0, "mid": length / 2, "top": length}
    return BodySurface(
        v, t, np.ones(len(t), np.int32), {"cylinder": 1}, marks, dict.fromkeys(marks, circle)
    )
