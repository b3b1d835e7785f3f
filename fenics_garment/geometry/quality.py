"""Mesh quality report: minimum angle and aspect ratio, for triangles or quadrilaterals.

Aspect ratio here is longest edge over shortest altitude-like length: for a triangle
``L_max · perimeter / (4 √3 · area)`` (1 for an equilateral triangle), for a quadrilateral
longest over shortest edge (1 for a square).
"""

from __future__ import annotations

import numpy as np
import numpy.typing as npt


def cell_angles(points: npt.NDArray[np.float64], cells: npt.NDArray[np.int64]) -> np.ndarray:
    """Interior angles (degrees), one column per corner."""
    p = points[cells]
    k = cells.shape[1]
    out = np.empty((len(cells), k))
    for j in range(k):
        a = p[:, (j - 1) % k] - p[:, j]
        b = p[:, (j + 1) % k] - p[:, j]
        c = np.einsum("ij,ij->i", a, b) / (np.linalg.norm(a, axis=1) * np.linalg.norm(b, axis=1))
        out[:, j] = np.degrees(np.arccos(np.clip(c, -1.0, 1.0)))
    return out


def aspect_ratio(points: npt.NDArray[np.float64], cells: npt.NDArray[np.int64]) -> np.ndarray:
    """Aspect ratio per cell (1 is ideal), see the module docstring."""
    p = points[cells]
    k = cells.shape[1]
    lengths = np.stack(
        [np.linalg.norm(p[:, (j + 1) % k] - p[:, j], axis=1) for j in range(k)], axis=1
    )
    if k == 4:
        return lengths.max(axis=1) / lengths.min(axis=1)
    area = 0.5 * np.linalg.norm(np.cross(p[:, 1] - p[:, 0], p[:, 2] - p[:, 0]), axis=1)
    return lengths.max(axis=1) * lengths.sum(axis=1) / (4.0 * np.sqrt(3.0) * area)


def quality_report(points: npt.NDArray[np.float64], cells: npt.NDArray[np.int64]) -> dict:
    """Cell count, min/mean of the minimum angle, max/mean aspect ratio, mean edge length (m)."""
    ang = cell_angles(points, cells).min(axis=1)
    ar = aspect_ratio(points, cells)
    p = points[cells]
    k = cells.shape[1]
    edges = np.concatenate([np.linalg.norm(p[:, (j + 1) % k] - p[:, j], axis=1) for j in range(k)])
    return {
        "cells": len(cells),
        "min_angle_deg": float(ang.min()),
        "mean_min_angle_deg": float(ang.mean()),
        "max_aspect_ratio": float(ar.max()),
        "mean_aspect_ratio": float(ar.mean()),
        "mean_edge_m": float(edges.mean()),
    }
