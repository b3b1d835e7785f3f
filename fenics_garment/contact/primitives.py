"""Closed triangulated bodies with exact analytic distance, for tests and benchmarks.

They are plain numpy arrays (no gmsh, no DOLFINx): ``(vertices (n, 3) float64, triangles (m, 3)
int64)``, outward oriented (counter-clockwise seen from outside).
"""

from __future__ import annotations

import numpy as np
import numpy.typing as npt

Mesh = tuple[npt.NDArray[np.float64], npt.NDArray[np.int64]]


def cylinder(radius: float, z0: float, z1: float, n_theta: int, n_z: int) -> Mesh:
    """Closed circular cylinder about the z axis, side vertices exactly on r = radius.

    The caps are fans around their centre points. The side triangles are alternated
    (criss-cross free) so that the faceting is symmetric.
    """
    θ = np.linspace(0.0, 2.0 * np.pi, n_theta, endpoint=False)
    z = np.linspace(z0, z1, n_z + 1)
    ring = np.column_stack([radius * np.cos(θ), radius * np.sin(θ)])
    side = np.array([[x, y, zk] for zk in z for x, y in ring])
    i, k = np.meshgrid(np.arange(n_theta), np.arange(n_z), indexing="ij")
    i, k = i.ravel(), k.ravel()
    a = k * n_theta + i
    b = k * n_theta + (i + 1) % n_theta
    c = a + n_theta
    d = b + n_theta
    tris = np.vstack([np.column_stack([a, b, d]), np.column_stack([a, d, c])])
    bottom, top = len(side), len(side) + 1
    ring0 = np.arange(n_theta)
    ring1 = n_z * n_theta + np.arange(n_theta)
    cap0 = np.column_stack([np.full(n_theta, bottom), np.roll(ring0, -1), ring0])
    cap1 = np.column_stack([np.full(n_theta, top), ring1, np.roll(ring1, -1)])
    verts = np.vstack([side, [[0.0, 0.0, z0], [0.0, 0.0, z1]]])
    return verts.astype(np.float64), np.vstack([tris, cap0, cap1]).astype(np.int64)


def icosphere(radius: float, subdivisions: int) -> Mesh:
    """Sphere about the origin: a subdivided icosahedron with vertices projected onto it."""
    t = (1.0 + np.sqrt(5.0)) / 2.0
    v = np.array(
        [[-1, t, 0], [1, t, 0], [-1, -t, 0], [1, -t, 0], [0, -1, t], [0, 1, t],
         [0, -1, -t], [0, 1, -t], [t, 0, -1], [t, 0, 1], [-t, 0, -1], [-t, 0, 1]],
        dtype=np.float64,
    )  # fmt: skip
    f = np.array(
        [[0, 11, 5], [0, 5, 1], [0, 1, 7], [0, 7, 10], [0, 10, 11], [1, 5, 9], [5, 11, 4],
         [11, 10, 2], [10, 7, 6], [7, 1, 8], [3, 9, 4], [3, 4, 2], [3, 2, 6], [3, 6, 8],
         [3, 8, 9], [4, 9, 5], [2, 4, 11], [6, 2, 10], [8, 6, 7], [9, 8, 1]],
        dtype=np.int64,
    )  # fmt: skip
    v /= np.linalg.norm(v, axis=1)[:, None]
    for _ in range(subdivisions):
        edges = np.sort(np.vstack([f[:, [0, 1]], f[:, [1, 2]], f[:, [2, 0]]]), axis=1)
        uniq, inv = np.unique(edges, axis=0, return_inverse=True)
        mid = v[uniq[:, 0]] + v[uniq[:, 1]]
        mid /= np.linalg.norm(mid, axis=1)[:, None]
        m = len(v) + inv.reshape(3, -1)
        a, b, c = f.T
        f = np.vstack(
            [np.column_stack([a, m[0], m[2]]), np.column_stack([m[0], b, m[1]]),
             np.column_stack([m[2], m[1], c]), np.column_stack([m[0], m[1], m[2]])]
        )  # fmt: skip
        v = np.vstack([v, mid])
    return radius * v, f


def sphere_patch(radius: float, half_angle: float, n: int) -> Mesh:
    """Open cube-sphere patch of a sphere about the origin around +z: the points
    r (a, b, 1)/|(a, b, 1)| with |a|, |b| ≤ tan(half_angle), n × n quads split in two,
    outward oriented. Its vertices lie exactly on the sphere."""
    t = np.tan(half_angle)
    a, b = np.meshgrid(np.linspace(-t, t, n + 1), np.linspace(-t, t, n + 1), indexing="ij")
    v = np.column_stack([a.ravel(), b.ravel(), np.ones(a.size)])
    v = radius * v / np.linalg.norm(v, axis=1)[:, None]
    i, j = np.meshgrid(np.arange(n), np.arange(n), indexing="ij")
    i, j = i.ravel(), j.ravel()
    p00 = i * (n + 1) + j
    p10, p01, p11 = p00 + n + 1, p00 + 1, p00 + n + 2
    tris = np.vstack([np.column_stack([p00, p10, p11]), np.column_stack([p00, p11, p01])])
    return v.astype(np.float64), tris.astype(np.int64)
