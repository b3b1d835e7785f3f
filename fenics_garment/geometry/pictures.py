"""PNG pictures with matplotlib (no OpenGL needed): the body by region, garments on the body.

Triangles are drawn back to front with flat Lambert shading, as a painter's algorithm over a
2-D orthographic projection; matplotlib's 3-D axes do not sort mixed collections reliably.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import numpy.typing as npt

Array = npt.NDArray[np.float64]


def _view_basis(azimuth_deg: float) -> tuple[Array, Array, Array]:
    """Screen right, screen up and the direction towards the viewer (azimuth 0 = from the front,
    i.e. looking along +y at a body that faces −y)."""
    a = np.radians(azimuth_deg)
    toward = np.array([np.sin(a), -np.cos(a), 0.0])
    up = np.array([0.0, 0.0, 1.0])
    right = np.cross(up, toward)
    return right, up, toward


def draw_mesh(
    ax,
    vertices: Array,
    cells: npt.NDArray[np.int64],
    colors: Array,
    azimuth: float = 0.0,
    two_sided: bool = True,
    alpha: float = 1.0,
    edge: str | None = None,
) -> list:
    """Add shaded polygons of a surface to a 2-D axes; returns (depth, polygon, colour) items."""
    from matplotlib.colors import to_rgba

    right, up, toward = _view_basis(azimuth)
    p = vertices[cells]
    n = np.cross(p[:, 1] - p[:, 0], p[:, 2] - p[:, 0])
    n /= np.linalg.norm(n, axis=1)[:, None] + 1e-300
    facing = n @ toward
    keep = np.ones(len(cells), bool) if two_sided else facing > 0
    light = np.array([0.3, -0.8, 0.5])
    light /= np.linalg.norm(light)
    shade = 0.35 + 0.65 * np.abs(n @ light)
    rgba = np.array([to_rgba(c) for c in colors]) if np.ndim(colors) == 1 else np.asarray(colors)
    rgba = rgba.copy()
    rgba[:, :3] *= shade[:, None]
    rgba[:, 3] = alpha
    depth = p.mean(axis=1) @ toward
    xy = np.stack([p @ right, p @ up], axis=-1)
    # layer 1 for faces turned to the viewer when two-sided: a garment's outside is drawn
    # over the body, whose coarse triangles would otherwise win the centroid-depth sort
    layer = (facing > 0).astype(int) if two_sided else np.zeros(len(cells), int)
    return [((layer[i], depth[i]), xy[i], rgba[i], edge) for i in np.flatnonzero(keep)]


def render(items: list, ax) -> None:
    """Draw collected polygons back to front."""
    from matplotlib.collections import PolyCollection

    items.sort(key=lambda t: t[0])
    polys = [t[1] for t in items]
    cols = [t[2] for t in items]
    ec = [t[3] if t[3] else t[2] for t in items]
    ax.add_collection(PolyCollection(polys, facecolors=cols, edgecolors=ec, linewidths=0.15))
    allp = np.concatenate(polys)
    ax.set_xlim(allp[:, 0].min() - 0.02, allp[:, 0].max() + 0.02)
    ax.set_ylim(allp[:, 1].min() - 0.02, allp[:, 1].max() + 0.02)
    ax.set_aspect("equal")
    ax.axis("off")


def body_regions_png(body, path: str | Path, azimuths=(0.0, 90.0, 180.0)) -> Path:
    """The body coloured by region, from the front, the left side and the back, with a legend."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from matplotlib.patches import Patch

    cmap = plt.get_cmap("tab20")
    names = sorted(body.regions, key=body.regions.get)
    colour_of = {body.regions[n]: cmap(i % 20) for i, n in enumerate(names)}
    colors = np.array([colour_of[r] for r in body.region])
    fig, axes = plt.subplots(1, len(azimuths), figsize=(4 * len(azimuths), 6))
    for ax, az in zip(np.atleast_1d(axes), azimuths, strict=True):
        render(draw_mesh(ax, body.vertices, body.triangles, colors, az, two_sided=False), ax)
        ax.set_title({0.0: "front", 90.0: "left side", 180.0: "back"}.get(az, f"{az:g}°"))
    handles = [Patch(color=colour_of[body.regions[n]], label=n) for n in names]
    fig.legend(handles=handles, loc="center right", fontsize=8)
    fig.subplots_adjust(right=0.85)
    path = Path(path)
    fig.savefig(path, dpi=110)
    plt.close(fig)
    return path


def garment_on_body_png(body, garment, path: str | Path, azimuths=(0.0, 180.0)) -> Path:
    """A garment (coloured by panel, mesh edges drawn) on the grey body, front and back."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    cmap = plt.get_cmap("Set2")
    panel_names = sorted(garment.panels, key=garment.panels.get)
    colour_of = {garment.panels[n]: cmap(i % 8) for i, n in enumerate(panel_names)}
    gcols = np.array([colour_of[t] for t in garment.cell_panel])
    bcols = np.tile(np.array([0.78, 0.78, 0.80, 1.0]), (len(body.triangles), 1))
    fig, axes = plt.subplots(1, len(azimuths), figsize=(4.5 * len(azimuths), 6))
    for ax, az in zip(np.atleast_1d(axes), azimuths, strict=True):
        items = draw_mesh(ax, body.vertices, body.triangles, bcols, az, two_sided=False)
        tri = garment.triangles()
        items += draw_mesh(ax, garment.points, tri, gcols[garment.triangle_cell], az, edge="k")
        render(items, ax)
        ax.set_title(f"{garment.kind}: " + ("front" if az == 0 else "back"))
    path = Path(path)
    fig.savefig(path, dpi=110)
    plt.close(fig)
    return path
