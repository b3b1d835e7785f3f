"""Closest point on the body surface, robust sign, smoothed normal, and a broad phase.

The body surface is a triangle mesh replicated on every rank. Its search structure (libigl's
AABB tree) is built once per scene; each rank queries only its own garment points.

* **Distance**: exact Euclidean distance to the closest point ``c`` on the triangles (libigl).
* **Sign** (inside/outside): the angle-weighted pseudonormal of the feature (face, edge or vertex)
  that holds ``c`` — Bærentzen & Aanæs, "Signed distance computation using the angle weighted
  pseudonormal", IEEE TVCG 11(3), 2005. It is exact for a closed, consistently oriented mesh, so
  a point that has slipped inside is seen as inside however close it is to the surface. A point
  it puts more than ``WINDING_DEPTH`` inside is confirmed by the generalised winding number,
  which stays right where a scan's surface crosses itself.
* **Normal**: a faceted body's face normal jumps from facet to facet, which makes Newton chatter.
  ``normal="phong"`` blends the angle-weighted vertex normals with the barycentric coordinates of
  ``c`` (continuous over the surface); ``normal="gradient"`` uses the distance gradient
  ``(x − c)/|x − c|`` off the surface (continuous outside, falls back to Phong within
  ``1e-12`` m of the surface). The distance itself is always the exact one.
* **Crop to the garment's reach** (:func:`reach_mask`): body triangles outside the garment's
  bounding box grown by a margin are left out of the AABB tree (``SearchSurface(..., keep=)``).
  Face indices, normals and pseudonormals stay those of the whole body, so for every point whose
  distance to the body is below ``margin − (its travel out of the box)`` the answer is exactly the
  uncropped one: the triangle holding its closest point meets the grown box.
* **Broad phase**: the distance is 1-Lipschitz, ``|d(x) − d(x₀)| ≤ |x − x₀|``, so a point whose
  last exact distance minus its travel since then exceeds the contact band cannot be in contact
  and is not searched (no approximation involved).
"""

from __future__ import annotations

import time
from collections.abc import Callable
from dataclasses import dataclass, field

import numpy as np
import numpy.typing as npt

try:
    import igl
except ImportError as err:  # pragma: no cover - depends on the environment
    raise ImportError("fenics_garment.contact needs libigl: `pip install libigl`") from err

#: Default crop margin [m]: the contact band (0.02 m, ContactState) plus 3 cm of garment travel.
REACH_MARGIN = 0.05
#: A point the pseudonormal puts deeper than this [m] inside the body is confirmed by the
#: generalised winding number (:meth:`SearchSurface.winding_number`): the pseudonormal's sign is
#: exact only on a surface that does not cross itself. On MakeHuman's short, heavy, flabby old
#: man (thigh and calf overlapping behind the knee) a point 10 cm behind his leg was taken as
#: 110 mm inside it. Near the surface the pseudonormal is exact and the winding number ≈ 1/2.
WINDING_DEPTH = 0.002

F64 = npt.NDArray[np.float64]
I64 = npt.NDArray[np.int64]


def _unit(v: F64) -> F64:
    n = np.linalg.norm(v, axis=-1, keepdims=True)
    return v / np.where(n > 0.0, n, 1.0)


@dataclass
class ClosestPoints:
    """Result of a closest-point query for ``n`` points.

    Attributes:
        distance: signed distance to the surface (> 0 outside), shape (n,).
        point: closest point on the surface, shape (n, 3).
        face: index of the triangle holding it, shape (n,).
        normal: unit contact normal (outward, smoothed as chosen), shape (n, 3).
        hessian: the distance's Hessian, shape (n, 3, 3), for a smooth body
            (:class:`fenics_garment.contact.smooth.SmoothBody`); None for the faceted one.
        hessian_later: a smooth body's Hessian on demand (``closest(defer_hessian=True)``),
            at every point of the search's ``hessian_below`` or at those of a mask passed to it.
    """

    distance: F64
    point: F64
    face: I64
    normal: F64
    hessian: F64 | None = None
    hessian_later: Callable[..., F64] | None = None


class SearchSurface:
    """A closed (or open, consistently oriented) triangulated body surface with an AABB tree.

    Args:
        vertices: (n, 3) vertex coordinates [m].
        triangles: (m, 3) vertex indices, oriented so that face normals point out of the body.
            A closed mesh with negative enclosed volume is flipped automatically.
        keep: optional (m,) boolean mask of the triangles searched (see :func:`reach_mask`);
            the others stay in the normals but not in the tree. ``dropped`` counts them.
    """

    #: the distance is the faceted one (its Hessian is not passed on to the contact terms)
    smooth = False

    def __init__(
        self, vertices: npt.ArrayLike, triangles: npt.ArrayLike, keep: npt.ArrayLike | None = None
    ) -> None:
        self.vertices = np.ascontiguousarray(vertices, dtype=np.float64)
        self.triangles = np.ascontiguousarray(triangles, dtype=np.int64)
        v, f = self.vertices, self.triangles
        e1 = v[f[:, 1]] - v[f[:, 0]]
        e2 = v[f[:, 2]] - v[f[:, 0]]
        cross = np.cross(e1, e2)
        if np.einsum("ij,ij->", v[f[:, 0]], cross) < 0.0:  # 6 × enclosed volume
            self.triangles = f = np.ascontiguousarray(f[:, ::-1])
            cross = -cross
        self.face_normals = _unit(cross)
        self.vertex_normals = self._angle_weighted_vertex_normals()
        self._edge_of, self.edge_normals = self._edge_pseudonormals()
        if keep is None:
            self._face_ids = np.arange(len(f), dtype=np.int64)
        else:
            self._face_ids = np.flatnonzero(np.asarray(keep, dtype=bool)).astype(np.int64)
            if len(self._face_ids) == 0:
                raise ValueError("SearchSurface: the crop keeps no triangle of the body")
        self._searched = np.ascontiguousarray(f[self._face_ids])
        self._winding = None  # the fast winding number's tree, built on first use
        self.dropped = len(f) - len(self._face_ids)
        self._tree = igl.AABB()
        t0 = time.perf_counter()
        self._tree.init(self.vertices, self._searched)
        self.build_time = time.perf_counter() - t0
        lengths = np.linalg.norm(
            v[f[:, [1, 2, 0]]] - v[f[:, [0, 1, 2]]], axis=-1
        )  # (m, 3) edge lengths
        self.max_edge = float(lengths.max())

    def _angle_weighted_vertex_normals(self) -> F64:
        v, f = self.vertices, self.triangles
        acc = np.zeros_like(v)
        for k in range(3):
            a = v[f[:, (k + 1) % 3]] - v[f[:, k]]
            b = v[f[:, (k + 2) % 3]] - v[f[:, k]]
            cosang = np.einsum("ij,ij->i", _unit(a), _unit(b))
            angle = np.arccos(np.clip(cosang, -1.0, 1.0))
            np.add.at(acc, f[:, k], angle[:, None] * self.face_normals)
        return _unit(acc)

    def _edge_pseudonormals(self) -> tuple[I64, F64]:
        """Edge index of each (face, local edge k = opposite vertex k) and the edge normals."""
        f = self.triangles
        # local edge k is opposite vertex k: (k+1, k+2)
        pairs = np.stack([f[:, [1, 2]], f[:, [2, 0]], f[:, [0, 1]]], axis=1).reshape(-1, 2)
        uniq, inv = np.unique(np.sort(pairs, axis=1), axis=0, return_inverse=True)
        acc = np.zeros((len(uniq), 3))
        np.add.at(acc, inv.ravel(), np.repeat(self.face_normals, 3, axis=0))
        return inv.reshape(-1, 3), _unit(acc)

    def closest(
        self,
        points: npt.ArrayLike,
        normal: str = "phong",
        feature_tol: float = 1e-9,
        hessian_below: float = np.inf,
        defer_hessian: bool = False,
    ) -> ClosestPoints:
        """Exact closest points, signed distances and contact normals.

        Args:
            points: (n, 3) query points [m].
            normal: ``"phong"`` (blended vertex normals), ``"gradient"`` (distance gradient)
                or ``"face"`` (raw facet normal, for comparison only).
            feature_tol: barycentric tolerance below which the closest point is taken to lie
                on an edge or vertex (for the choice of pseudonormal).
            hessian_below, defer_hessian: unused here (a smooth body's Hessian, :mod:`.smooth`).
        """
        x = np.ascontiguousarray(np.asarray(points, dtype=np.float64).reshape(-1, 3))
        if len(x) == 0:
            e = np.zeros((0, 3))
            return ClosestPoints(np.zeros(0), e, np.zeros(0, np.int64), e.copy())
        sq, face, c = self._tree.squared_distance(self.vertices, self._searched, x)
        face = self._face_ids[np.asarray(face, dtype=np.int64)]
        bary = self._barycentric(c, face)
        pseudo = self._pseudonormal(face, bary, feature_tol)
        diff = x - c
        dist = np.sqrt(np.maximum(sq, 0.0))
        sign = np.where(np.einsum("ij,ij->i", diff, pseudo) < 0.0, -1.0, 1.0)
        deep = np.flatnonzero((sign < 0.0) & (dist > WINDING_DEPTH))
        if len(deep):  # a surface that crosses itself: the winding number decides
            sign[deep[np.abs(self.winding_number(x[deep])) < 0.5]] = 1.0
        signed = sign * dist
        phong = _unit(np.einsum("ik,ikj->ij", bary, self.vertex_normals[self.triangles[face]]))
        if normal == "phong":
            n = phong
        elif normal == "gradient":
            off = dist > 1e-12
            n = phong.copy()
            n[off] = sign[off, None] * diff[off] / dist[off, None]
        elif normal == "face":
            n = self.face_normals[face]
        else:
            raise ValueError(f"normal must be 'phong', 'gradient' or 'face', not {normal!r}")
        return ClosestPoints(signed, c, face, n)

    def winding_number(self, points: F64) -> F64:
        """The generalised winding number of the whole body surface at ``points`` (libigl's
        fast winding number, Barill et al., SIGGRAPH 2018): ≈ 1 inside, ≈ 0 outside, also
        where the surface crosses itself."""
        if self._winding is None:
            self._winding = igl.FastWindingNumberBVH()
            self._winding.init(self.vertices, self.triangles)
        return np.asarray(self._winding.winding_number(np.ascontiguousarray(points)))

    def barycentric(self, c: F64, face: I64) -> F64:
        """Barycentric coordinates (n, 3) of the points ``c`` in their triangles ``face``."""
        return self._barycentric(c, face)

    def _barycentric(self, c: F64, face: I64) -> F64:
        v = self.vertices[self.triangles[face]]  # (n, 3, 3)
        e1, e2, r = v[:, 1] - v[:, 0], v[:, 2] - v[:, 0], c - v[:, 0]
        d11 = np.einsum("ij,ij->i", e1, e1)
        d12 = np.einsum("ij,ij->i", e1, e2)
        d22 = np.einsum("ij,ij->i", e2, e2)
        r1 = np.einsum("ij,ij->i", r, e1)
        r2 = np.einsum("ij,ij->i", r, e2)
        det = d11 * d22 - d12 * d12
        b1 = (d22 * r1 - d12 * r2) / det
        b2 = (d11 * r2 - d12 * r1) / det
        b = np.column_stack([1.0 - b1 - b2, b1, b2])
        b = np.clip(b, 0.0, 1.0)
        return b / b.sum(axis=1, keepdims=True)

    def _pseudonormal(self, face: I64, bary: F64, tol: float) -> F64:
        """Angle-weighted pseudonormal of the face, edge or vertex that holds the closest point."""
        pn = self.face_normals[face].copy()
        small = bary < tol
        nsmall = small.sum(axis=1)
        on_edge = nsmall == 1
        if on_edge.any():
            k = np.argmax(small[on_edge], axis=1)  # the edge opposite the vanishing coordinate
            pn[on_edge] = self.edge_normals[self._edge_of[face[on_edge], k]]
        on_vertex = nsmall >= 2
        if on_vertex.any():
            k = np.argmax(bary[on_vertex], axis=1)
            pn[on_vertex] = self.vertex_normals[self.triangles[face[on_vertex], k]]
        return pn


def reach_mask(vertices: npt.ArrayLike, triangles: npt.ArrayLike, points: npt.ArrayLike,
               margin: float) -> npt.NDArray[np.bool_]:  # fmt: skip
    """Triangles that meet the bounding box of ``points`` grown by ``margin`` on every side.

    The garment's reference points and a margin ≥ (largest displacement + contact band) keep
    every triangle a contact search can need (module doc); the rest can be dropped.
    """
    x = np.asarray(points, dtype=np.float64).reshape(-1, 3)
    lo, hi = x.min(axis=0) - margin, x.max(axis=0) + margin
    tri = np.asarray(vertices, dtype=np.float64)[np.asarray(triangles)]  # (m, 3, 3)
    return np.all((tri.max(axis=1) >= lo) & (tri.min(axis=1) <= hi), axis=1)


@dataclass
class BroadPhase:
    """Skip the exact search for points that provably stay out of the contact band.

    Since the signed distance is 1-Lipschitz, a point with last exact distance ``d₀`` taken at
    ``x₀`` satisfies ``d(x) ≥ d₀ − |x − x₀|``; if that bound exceeds ``band`` it is skipped and
    its distance replaced by the bound (any value above the band switches contact off).

    Attributes:
        band: contact band [m]; points closer than this to the surface are always searched.
        skipped_fraction: fraction of points skipped in the last query.
    """

    band: float
    skipped_fraction: float = 0.0
    _x0: F64 | None = field(default=None, repr=False)
    _d0: F64 | None = field(default=None, repr=False)
    _n0: F64 | None = field(default=None, repr=False)

    def query(
        self,
        body: SearchSurface,
        x: F64,
        normal: str = "phong",
        hessian_below: float = np.inf,
        defer_hessian: bool = False,
    ) -> tuple[F64, F64, F64 | Callable[..., F64] | None]:
        """Signed distance, normal and (smooth body) Hessian of every point of ``x``, searching
        only the candidates; a skipped point keeps its last normal and gets a zero Hessian.
        With ``defer_hessian`` the Hessian is returned as a function that computes it (at the
        points of an optional mask ``where`` over ``x``: :meth:`SmoothBody.closest`)."""
        n = len(x)
        if self._x0 is None or self._x0.shape != x.shape:
            res = body.closest(x, normal, hessian_below=hessian_below, defer_hessian=defer_hessian)
            self._x0, self._d0, self._n0 = x.copy(), res.distance.copy(), res.normal.copy()
            self.skipped_fraction = 0.0
            return res.distance, res.normal, res.hessian_later or res.hessian
        assert self._d0 is not None and self._n0 is not None
        bound = self._d0 - np.linalg.norm(x - self._x0, axis=1)
        near = bound <= self.band
        d = bound.copy()
        nrm = self._n0.copy()
        res = None
        if near.any():
            res = body.closest(x[near], normal, hessian_below=hessian_below,
                               defer_hessian=defer_hessian)  # fmt: skip
            d[near] = res.distance
            nrm[near] = res.normal
            self._x0[near] = x[near]
            self._d0[near] = res.distance
            self._n0[near] = res.normal
        self.skipped_fraction = float(1.0 - near.sum() / n) if n else 0.0
        if not body.smooth:
            return d, nrm, None

        def hessian(where: npt.NDArray[np.bool_] | None = None) -> F64:
            hess = np.zeros((n, 3, 3))
            if res is not None and res.hessian_later is None:
                hess[near] = res.hessian
            elif res is not None:
                hess[near] = res.hessian_later(None if where is None else where[near])
            return hess

        return d, nrm, hessian if defer_hessian else hessian()

    def memory(self) -> dict[str, F64]:
        """The last exact search: points ``x0``, distances ``d0`` and normals ``n0`` (empty
        before the first query)."""
        if self._x0 is None:
            return {}
        return {"x0": self._x0, "d0": self._d0, "n0": self._n0}

    def restore(self, memory: dict[str, F64]) -> None:
        """Put back a :meth:`memory` (copies)."""
        if memory:
            self._x0, self._d0, self._n0 = (memory[k].copy() for k in ("x0", "d0", "n0"))
