"""A C² body surface for contact: an implicit moving-least-squares (IMLS) signed distance.

A faceted body's distance has a gradient that jumps across concave edges (the closest face
switches) and turns with radius d over convex edges and vertices, so Newton cycles or converges
only linearly there. This module replaces it, in a band around the skin, by a smooth implicit
function built from the body's vertices ``p_i``, their angle-weighted normals ``n_i`` and a
per-vertex shape operator ``S_i`` (second fundamental form, fitted to the one-ring):

    a_i(x) = z + ½ yᵀ S_i y − ½ z |S_i y|²,  y = x − p_i, z = n_i·y   (signed distance to the
             osculating paraboloid at p_i, to third order: zero on it, |∇a_i| = 1 + O(|y|³))
    f(x)   = Σ w_i(x) a_i(x) / Σ w_i(x),   w_i(x) = φ(|x − p_i| / r)

with Wendland's compactly supported C² weight φ(t) = (1 − t)⁴₊ (4t + 1) (H. Wendland,
"Piecewise polynomial, positive definite and compactly supported radial functions of minimal
degree", Adv. Comput. Math. 4 (1995) 389–396). This is the point-set IMLS of Shen, O'Brien &
Shewchuk, "Interpolating and approximating implicit surfaces from polygon soup", SIGGRAPH 2004,
and Kolluri, "Provably good moving least squares", ACM TALG 4(2) 2008, with each sample's plane
replaced by its osculating paraboloid so that the surface does not shrink on curved parts
(a plane-only fit sits O(r²κ) inside a convex body), and the paraboloid's height corrected
(the −½ z|Sy|² term) so that |∇f| stays 1 to the same order: the contact traction t_N ∇f then
has the magnitude t_N reported as the pressure.

f is C² wherever Σ w_i > 0; its gradient and Hessian are analytic (``_imls``) and go into the
contact terms as the consistent linearisation (``ContactState``). It is exact on planes
(S = 0: every a_i is the plane's distance) and converges to the true distance of a smooth
body sampled by the mesh (tests/test_contact_smooth.py: sphere and cylinder, rate ≈ 2).

Away from the band (``|d_faceted| > band_factor · r``, or no vertex within reach) the exact
faceted signed distance of :class:`SearchSurface` is used: no contact is active there, and its
pseudonormal sign stays the robust inside/outside test.
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np
import numpy.typing as npt
from scipy.sparse import csr_matrix
from scipy.spatial import cKDTree

from fenics_garment.contact.search import ClosestPoints, SearchSurface

F64 = npt.NDArray[np.float64]

#: Support radius r of the weights, in units of the median over the vertices of their longest
#: one-ring edge (one r for the whole body: a ball of radius r then holds ≈ 20 vertices).
SUPPORT = 2.0
#: The smooth distance is used for |d_faceted| ≤ BAND_FACTOR · r.
BAND_FACTOR = 0.6
#: The Hessian is computed where d_faceted < hessian_below + HESSIAN_SLACK · r (|f − d_faceted|
#: stays well below it: tests), i.e. at every point that can carry traction.
HESSIAN_SLACK = 0.25
#: Neighbour lists are searched within (1 + BALL_SLACK) r and reused until a point has moved
#: by BALL_SLACK · r: the weights vanish beyond r, so the answer is the same.
BALL_SLACK = 0.1
#: Principal curvatures are capped at CURVATURE_CAP / r: a sharp rim (e.g. where a body is
#: cut off) is rounded over the support instead of extrapolating its osculating paraboloid.
CURVATURE_CAP = 2.0


def wendland(t: F64) -> F64:
    """φ(t) = (1 − t)⁴₊ (4t + 1): C², compact support [0, 1), φ(0) = 1."""
    s = np.clip(1.0 - t, 0.0, None)
    return s**4 * (4.0 * t + 1.0)


def _tangent_frames(n: F64) -> tuple[F64, F64]:
    """Two unit vectors completing each unit normal to a right-handed orthonormal frame."""
    helper = np.where(np.abs(n[:, :1]) < 0.9, [[1.0, 0.0, 0.0]], [[0.0, 1.0, 0.0]])
    t1 = np.cross(n, helper)
    t1 /= np.linalg.norm(t1, axis=1, keepdims=True)
    return t1, np.cross(n, t1)


def shape_operators(vertices: F64, normals: F64, edges: npt.NDArray[np.int64]) -> F64:
    """Per-vertex shape operator S_i (3×3, symmetric, S_i n_i = 0) fitted to the one-ring.

    For each neighbour j with tangential offset u = (t₁·e, t₂·e), e = p_j − p_i, two conditions
    in least squares: the neighbour lies on the paraboloid, n_i·e + ½ uᵀSu = 0, and its normal
    turns as the paraboloid's, (t₁·n_j, t₂·n_j) = S u (scaled by |u| to the same units).
    """
    t1, t2 = _tangent_frames(normals)
    rows_i = np.concatenate([edges[:, 0], edges[:, 1]])
    rows_j = np.concatenate([edges[:, 1], edges[:, 0]])
    e = vertices[rows_j] - vertices[rows_i]
    u1 = np.einsum("ij,ij->i", e, t1[rows_i])
    u2 = np.einsum("ij,ij->i", e, t2[rows_i])
    z = np.einsum("ij,ij->i", e, normals[rows_i])
    m1 = np.einsum("ij,ij->i", normals[rows_j], t1[rows_i])
    m2 = np.einsum("ij,ij->i", normals[rows_j], t2[rows_i])
    ul = np.hypot(u1, u2)
    zero = np.zeros_like(u1)
    # unknowns (S11, S12, S22); three equations per (i, j)
    a = np.stack(
        [
            np.stack([0.5 * u1**2, u1 * u2, 0.5 * u2**2], axis=1),
            np.stack([u1 * ul, u2 * ul, zero], axis=1),
            np.stack([zero, u1 * ul, u2 * ul], axis=1),
        ],
        axis=1,
    )  # (E, 3 equations, 3 unknowns)
    b = np.stack([-z, m1 * ul, m2 * ul], axis=1)
    nv = len(vertices)
    ata = np.zeros((nv, 3, 3))
    atb = np.zeros((nv, 3))
    np.add.at(ata, rows_i, np.einsum("eki,ekj->eij", a, a))
    np.add.at(atb, rows_i, np.einsum("eki,ek->ei", a, b))
    scale = np.trace(ata, axis1=1, axis2=2)[:, None, None]
    ata += 1e-12 * scale * np.eye(3)
    s11, s12, s22 = np.linalg.solve(ata, atb[..., None])[..., 0].T
    return (
        s11[:, None, None] * np.einsum("ni,nj->nij", t1, t1)
        + s12[:, None, None] * (np.einsum("ni,nj->nij", t1, t2) + np.einsum("ni,nj->nij", t2, t1))
        + s22[:, None, None] * np.einsum("ni,nj->nij", t2, t2)
    )


class _Rows:
    """Sums over the neighbours of each query point, stored contiguously (CSR order)."""

    def __init__(self, counts: npt.NDArray[np.int64]) -> None:
        self.m = len(counts)
        self.starts = np.concatenate([[0], np.cumsum(counts)[:-1]])
        self.full = counts > 0
        self.row = np.repeat(np.arange(self.m), counts)

    def sum(self, v: F64) -> F64:
        out = np.zeros((self.m, *v.shape[1:]))
        if len(v):
            out[self.full] = np.add.reduceat(v, self.starts[self.full], axis=0)
        return out


def _cap_curvature(s: F64, kmax: float) -> F64:
    """S with its eigenvalues (principal curvatures; 0 along the normal) clipped to ±kmax."""
    lam, vec = np.linalg.eigh(s)
    return np.einsum("nij,nj,nkj->nik", vec, np.clip(lam, -kmax, kmax), vec)


def _weights(y: F64, rho: F64, n: F64, s: F64, r: float, w: F64, z: F64) -> dict[str, F64]:
    """Per-neighbour quantities (flat, CSR order) shared by f, ∇f and ∇∇f (see :func:`_imls`),
    from the offsets y = x − p to the neighbours, ρ = |y|, w = φ(ρ/r) and z = n·y."""
    om = np.clip(1.0 - rho / r, 0.0, None)
    sig = np.einsum("kij,kj->ki", s, y)
    sig2 = np.einsum("ki,ki->k", sig, sig)
    q = dict(y=y, rho=rho, om=om, z=z, sig=sig, sig2=sig2, n=n)
    q["w"] = w
    q["a"] = z + 0.5 * np.einsum("ki,ki->k", y, sig) - 0.5 * z * sig2
    q["ssig"] = np.einsum("kij,kj->ki", s, sig)
    q["ga"] = n + sig - 0.5 * sig2[:, None] * n - z[:, None] * q["ssig"]
    q["gw"] = (-20.0 * om**3 / r**2)[:, None] * y
    return q


def _hessian(q: dict[str, F64], k: npt.NDArray[np.bool_] | None, c: F64, w: F64, sub: _Rows,
             r: float, grad: F64, sums: tuple[F64, F64]) -> F64:  # fmt: skip
    """W ∇∇f at the points of ``sub`` (their neighbours: the entries ``k``, None: all), see
    :func:`_imls`.

    The symmetric outer-product terms are written as M + Mᵀ with
    M = Σ y ⊗ (½ α y + β ∇a) − Σ n ⊗ w Sσ, α = 60 (1−t)² (a − f)/(r³ ρ), β = −20 (1−t)³/r²;
    ``sums`` = (Σ w S, Σ w z S²) per point.
    """

    def pick(a: F64) -> F64:
        return a if k is None else a[k]

    y, om, rho, ck = pick(q["y"]), pick(q["om"]), pick(q["rho"]), pick(c)
    alpha = 60.0 * om**2 / (r**3 * np.where(rho > 0.0, rho, 1.0)) * ck
    beta = -20.0 * om**3 / r**2
    v = 0.5 * alpha[:, None] * y + beta[:, None] * pick(q["ga"])
    u = -pick(w)[:, None] * pick(q["ssig"])
    outer = y[:, :, None] * v[:, None, :]
    outer += pick(q["n"])[:, :, None] * u[:, None, :]
    m = sub.sum(outer)
    h = m + m.transpose(0, 2, 1) + sums[0] - sums[1]
    h += sub.sum(beta * ck)[:, None, None] * np.eye(3)
    gW = sub.sum(beta[:, None] * y)
    return h - np.einsum("mi,mj->mij", grad, gW) - np.einsum("mi,mj->mij", gW, grad)


def _imls(y: F64, rho: F64, n: F64, s: F64, rows: _Rows, r: float, hessian: npt.NDArray[np.bool_],
          vertex_terms, w: F64, z: F64) -> tuple[F64, F64, Callable[..., F64], F64]:  # fmt: skip
    """f, ∇f, ∇∇f and W = Σw at the points of ``rows`` from the offsets y = x − p to their
    neighbours p, ρ = |y|, w = φ(ρ/r), z = n·y and the neighbours' normals n and shape
    operators S, given as flat (nnz, …) arrays in the order of ``rows``; ∇∇f only at the points
    where ``hessian`` (zero elsewhere). ``vertex_terms(k, need)`` gives (Σ w S, Σ w z S²) over
    the entries k (None: all) of the points ``need``. ∇∇f is returned as a function that
    computes it from the quantities f and ∇f were computed from (when called: the Newton
    residual needs f and ∇f only), at the points ``where`` if given (default ``hessian``).

    Per sample, with z = n·y and σ = S y:  a = z + ½ y·σ − ½ z |σ|²,
    ∇a = n + σ − ½ |σ|² n − z Sσ,  ∇∇a = S − n ⊗ Sσ − Sσ ⊗ n − z S²;
    the weight: ∇w = −20 (1−t)³ y / r², ∇∇w = −20/r² (1−t)² [(1−t) I − 3 y⊗y/(ρ r)];
    f = Σ w a / W:  ∇f = [Σ ∇w (a − f) + Σ w ∇a] / W,
    ∇∇f = [Σ ∇∇w (a − f) + Σ (∇w ⊗ ∇a + ∇a ⊗ ∇w) − ∇f ⊗ ∇W − ∇W ⊗ ∇f + Σ w ∇∇a] / W.
    """
    q = _weights(y, rho, n, s, r, w, z)
    gw = q["gw"]
    wsum = rows.sum(w)
    W = np.where(wsum > 0.0, wsum, 1.0)
    f = rows.sum(w * q["a"]) / W
    c = q["a"] - f[rows.row]
    grad = rows.sum(gw * c[:, None] + w[:, None] * q["ga"]) / W[:, None]

    def hess(where: npt.NDArray[np.bool_] | None = None) -> F64:
        need = hessian if where is None else where
        out = np.zeros((rows.m, 3, 3))
        if need.all():  # every point: no subsets to gather (the same sums)
            sums = vertex_terms(None, need)
            out[:] = _hessian(q, None, c, w, rows, r, grad, sums) / W[:, None, None]
        elif need.any():
            k = need[rows.row]
            sub = _Rows(np.bincount(rows.row[k], minlength=rows.m)[need])
            out[need] = (
                _hessian(q, k, c, w, sub, r, grad[need], vertex_terms(k, need))
                / W[need][:, None, None]
            )
        return out

    return f, grad, hess, wsum


class SmoothBody(SearchSurface):
    """A :class:`SearchSurface` whose distance and normal are the C² IMLS function (module doc).

    Args:
        vertices, triangles, keep: as for :class:`SearchSurface` (the crop keeps the vertices of
            the kept triangles in the smooth representation).
        support: support radius r / the median longest one-ring edge.
        band_factor: the smooth distance is used for |d_faceted| ≤ band_factor · r.
    """

    smooth = True

    def __init__(
        self,
        vertices: npt.ArrayLike,
        triangles: npt.ArrayLike,
        keep: npt.ArrayLike | None = None,
        *,
        support: float = SUPPORT,
        band_factor: float = BAND_FACTOR,
    ) -> None:
        super().__init__(vertices, triangles, keep)
        v, f = self.vertices, self.triangles
        edges = np.unique(np.sort(np.vstack([f[:, [0, 1]], f[:, [1, 2]], f[:, [2, 0]]]), 1), axis=0)
        length = np.linalg.norm(v[edges[:, 1]] - v[edges[:, 0]], axis=1)
        longest = np.zeros(len(v))
        np.maximum.at(longest, edges[:, 0], length)
        np.maximum.at(longest, edges[:, 1], length)
        self.shape = shape_operators(v, self.vertex_normals, edges)  # capped below
        used = np.unique(self._searched)
        self._ids = used
        self.support_radius = support * float(np.median(longest[used]))
        self.band = band_factor * self.support_radius
        self._kdtree = cKDTree(v[used])
        self.shape = _cap_curvature(self.shape, CURVATURE_CAP / self.support_radius)
        self._shape2 = np.einsum("nij,njk->nik", self.shape, self.shape)
        self._k = 64
        self._cache: tuple[F64, npt.NDArray[np.int64], npt.NDArray[np.int64]] | None = None

    def _balls(self, x: F64) -> tuple[npt.NDArray[np.int64], npt.NDArray[np.int64]]:
        """Vertex indices (flat, point by point) within (1 + BALL_SLACK) r, and their counts."""
        k, reach = self._k, (1.0 + BALL_SLACK) * self.support_radius
        while True:
            dist, idx = self._kdtree.query(x, k=k, distance_upper_bound=reach)
            if not np.isfinite(dist[:, -1]).any() or k >= len(self._ids):
                break
            k = min(2 * k, len(self._ids))  # a ball held more than k vertices
        self._k = k
        inside = np.isfinite(dist)
        ids = np.sort(np.where(inside, self._ids[np.minimum(idx, len(self._ids) - 1)], -1), axis=1)
        return ids[ids >= 0], inside.sum(axis=1)  # by vertex index: the sums' order is fixed

    def _cached_balls(self, x: F64) -> tuple[npt.NDArray[np.int64], npt.NDArray[np.int64]]:
        """:meth:`_balls`, reused while the same number of points has moved < BALL_SLACK · r."""
        c = self._cache
        if (
            c is None
            or len(c[0]) != len(x)
            or (
                np.linalg.norm(x - c[0], axis=1).max(initial=0.0) > BALL_SLACK * self.support_radius
            )
        ):
            self._cache = c = (x.copy(), *self._balls(x))
        return c[1], c[2]

    def smooth_distance(
        self, x: F64, hessian: npt.NDArray[np.bool_] | None = None
    ) -> tuple[F64, F64, F64, F64]:
        """f, ∇f, ∇∇f (where ``hessian``, default everywhere; zero elsewhere) and Σw of the
        IMLS function at x (m, 3)."""
        f, g, h, wsum = self._smooth_distance(x, hessian)
        return f, g, h(), wsum

    def _smooth_distance(
        self, x: F64, hessian: npt.NDArray[np.bool_] | None = None
    ) -> tuple[F64, F64, Callable[..., F64], F64]:
        """:meth:`smooth_distance` with ∇∇f as a function computing it on demand."""
        m = len(x)
        need = np.ones(m, dtype=bool) if hessian is None else hessian
        j, counts = self._cached_balls(x)
        r = self.support_radius
        y = x[np.repeat(np.arange(m), counts)] - self.vertices[j]
        rho = np.linalg.norm(y, axis=1)
        within = rho < r
        j, y, rho = j[within], y[within], rho[within]  # the vertices of nonzero weight, in
        rows = _Rows(np.bincount(np.repeat(np.arange(m), counts)[within], minlength=m))  # index
        n = self.vertex_normals[j]  # order: the same sums whether the balls were cached or not
        w = wendland(rho / r)
        z = np.einsum("ki,ki->k", n, y)

        def vertex_terms(
            k: npt.NDArray[np.bool_] | None, need: npt.NDArray[np.bool_]
        ) -> tuple[F64, F64]:
            """(Σ w S, Σ w z S²) of the points ``need`` over the entries k: sparse products,
            no 3×3 loops."""
            k = slice(None) if k is None else k
            sub_rows = (np.cumsum(need) - 1)[rows.row[k]]
            shape = (int(need.sum()), len(self.vertices))
            mw = csr_matrix((w[k], (sub_rows, j[k])), shape=shape)
            mz = csr_matrix((w[k] * z[k], (sub_rows, j[k])), shape=shape)
            return (
                (mw @ self.shape.reshape(-1, 9)).reshape(-1, 3, 3),
                (mz @ self._shape2.reshape(-1, 9)).reshape(-1, 3, 3),
            )

        return _imls(y, rho, n, self.shape[j], rows, r, need, vertex_terms, w, z)

    def closest(
        self,
        points: npt.ArrayLike,
        normal: str = "gradient",
        feature_tol: float = 1e-9,
        hessian_below: float = np.inf,
        defer_hessian: bool = False,
    ) -> ClosestPoints:
        """Faceted closest point, face and sign; IMLS distance, gradient and Hessian in the band.

        ``normal`` is ignored inside the band (the normal there is ∇f, consistent with f). The
        Hessian is computed only where f < ``hessian_below`` (the contact-active points: the
        contact terms need it nowhere else; computed with a slack) and is zero elsewhere.
        ``defer_hessian``: ``hessian`` is left None and ``hessian_later()`` computes it (the
        same values, from the quantities kept from this search); ``hessian_later(where)``
        computes it at the points ``where`` (a mask over ``points``) instead, e.g. where the
        contact law in use carries traction at the distance this search found
        (:meth:`fenics_garment.contact.state.ContactState.update_hessian`).
        """
        res = super().closest(points, normal, feature_tol)
        n_points = len(res.distance)
        near = np.flatnonzero(np.abs(res.distance) <= self.band)
        h: Callable[..., F64] | None = None
        ok = np.zeros(0, dtype=bool)
        if len(near):
            x = np.asarray(points, dtype=np.float64).reshape(-1, 3)[near]
            active = res.distance[near] < hessian_below + HESSIAN_SLACK * self.support_radius
            f, g, h, wsum = self._smooth_distance(x, active)
            ok = wsum > 0.0
            res.distance[near[ok]] = f[ok]
            res.normal[near[ok]] = g[ok]

        def hessian(where: npt.NDArray[np.bool_] | None = None) -> F64:
            hess = np.zeros((n_points, 3, 3))
            if h is not None:
                hess[near[ok]] = h(None if where is None else where[near])[ok]
            return hess

        if defer_hessian:
            res.hessian_later = hessian
        else:
            res.hessian = hessian()
        return res
