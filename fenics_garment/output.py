"""Outputs of a run: pressure statistics per body region, comfort bands, files and pictures.

Every file is written to a temporary name and renamed, so a reader (or a crashed run) never sees
half a file. Only rank 0 writes the small files; the DOLFINx writers are collective.
"""

from __future__ import annotations

import csv
import io
import json
import os
from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np
import numpy.typing as npt

from fenics_garment import units

Array = npt.NDArray[np.float64]

#: Comfort bands of garment pressure [kPa], upper bounds: Anthropometry, Apparel Sizing and
#: Design, 2nd ed. (Gupta & Zakaria eds., Woodhead/Elsevier 2020), ch. 13, Table 13.5.
COMFORT_BANDS: tuple[tuple[float, str], ...] = (
    (0.4, "negligible"),
    (1.3, "comfortable"),
    (2.0, "critical for casual wear"),
    (3.3, "medical/shapewear"),
    (float("inf"), "critical"),
)


def comfort_band(p_kpa: float) -> str:
    """The comfort band of a pressure in kPa (:data:`COMFORT_BANDS`)."""
    for upper, name in COMFORT_BANDS:
        if p_kpa < upper:
            return name
    return COMFORT_BANDS[-1][1]


# ------------------------------------------------------------------------------------------------
# Atomic files
# ------------------------------------------------------------------------------------------------


class OutputError(RuntimeError):
    """A file of the run could not be written (full disk, read-only folder, …): nothing
    half-written is left under the file's own name. ``folder``: the run folder (set by the
    run), to resume from when it has a checkpoint (``checkpoint``)."""

    folder: Path | None = None
    checkpoint: bool = False  # whether the run folder has a checkpoint to resume from


def describe_os_error(err: OSError) -> str:
    """``cannot write PATH: No space left on device`` (one line)."""
    where = f" {err.filename}" if err.filename else ""
    return f"cannot write{where}: {err.strerror or type(err).__name__}"


#: Seconds a rank with an output error waits for every other rank to reach the decision
#: (:func:`agree`) before it stops the job: another rank may be stuck in a collective call of a
#: writer that the failed rank left (ADIOS2 aggregates the ranks' data).
AGREE_GRACE = 30.0
#: Exit code of an output fault (the command line's).
EXIT_OUTPUT = 5


def agree(comm, message: str | None, *, grace: float = AGREE_GRACE) -> str | None:
    """One decision of every rank on an output error (collective): the first rank's message,
    or None when no rank failed. A rank with an error waits at most ``grace`` seconds for the
    others, then prints its message and ends the job with :data:`EXIT_OUTPUT`; so no rank
    waits for ever in its next collective call for a rank that gave up."""
    if comm.size == 1:
        return message
    from fenics_garment import mpi_guard
    from fenics_garment._stack import MPI

    flag, anyone = np.array([int(message is not None)], np.int32), np.zeros(1, np.int32)
    req = comm.Iallreduce(flag, anyone, op=MPI.MAX)
    if message is None:
        req.Wait()
    elif not mpi_guard.wait(req, grace):
        mpi_guard.abort(EXIT_OUTPUT, f"{message}; another rank did not answer within "
                        f"{grace:.0f} s")  # fmt: skip
    if not anyone[0]:
        return None
    return next(m for m in comm.allgather(message) if m)


def guarded(comm, work: Callable[[], object], *, root_only: bool = True) -> None:
    """Run ``work()`` on rank 0 (``root_only``) or on every rank; an ``OSError`` on any rank
    becomes an :class:`OutputError` on every rank (collective: :func:`agree`)."""
    message = None
    if comm.rank == 0 or not root_only:
        try:
            work()
        except OSError as err:
            message = describe_os_error(err)
    if root_only:
        message = comm.bcast(message, root=0)
    else:
        message = agree(comm, message)
    if message:
        raise OutputError(message)


def atomic_write(path: Path, write: Callable[[Path], None]) -> Path:
    """Call ``write(tmp)`` for a temporary name next to ``path``, then rename it to ``path``."""
    path = Path(path)
    tmp = path.with_name(f".{path.stem}.part{os.getpid()}{path.suffix}")
    try:
        write(tmp)
        os.replace(tmp, path)
    except OSError as err:
        err.filename = err.filename or str(path)  # (a writer's error may not name its file)
        raise
    finally:
        if tmp.exists():
            tmp.unlink()
    return path


def write_text(path: Path, text: str) -> Path:
    return atomic_write(path, lambda p: p.write_text(text))


def atomic_dir(path: Path, write: Callable[[Path], None]) -> Path:
    """Like :func:`atomic_write` for writers that make a directory (ADIOS2 ``.bp``)."""
    import shutil

    path = Path(path)
    tmp = path.with_name(f".{path.name}.part")
    try:
        write(tmp)
        if path.exists():
            shutil.rmtree(path)
        os.replace(tmp, path)
    finally:
        if tmp.exists():
            shutil.rmtree(tmp, ignore_errors=True)
    return path


# ------------------------------------------------------------------------------------------------
# Pressure on the body, per region
# ------------------------------------------------------------------------------------------------


def weighted_percentile(values: Array, weights: Array, q: float) -> float:
    """The q-th percentile (0–100) of ``values`` with ``weights`` (area), interpolated.

    Each value stands for its share of the weight, centred at the middle of its interval of
    the cumulative weight; the percentile is the piecewise-linear interpolation through those
    midpoints (the weighted form of definition 5 of Hyndman & Fan, "Sample quantiles in
    statistical packages", Am. Stat. 50 (1996) 361–365), clamped to the smallest and largest
    value. Unlike the step definition (the value at which the cumulative weight first reaches
    q %), it changes continuously with the values and weights, so a region's p95 does not jump
    from one point's pressure to the next as the garment mesh is refined.
    """
    if len(values) == 0:
        return 0.0
    order = np.argsort(values)
    v, w = np.asarray(values)[order], np.asarray(weights)[order]
    cum = np.cumsum(w)
    mid = cum - 0.5 * w
    return float(np.interp(q / 100.0 * cum[-1], mid, v))


def sensor_pressure(centres: Array, x: Array, force: Array, area: Array, radius: float) -> Array:
    """The reading of a round pressure sensor of ``radius`` [m] centred at each of ``centres``
    (m, 3): the contact force over the garment area within ``radius`` of the centre,
    Σ f_j / Σ a_j over the garment points j (positions ``x``, forces ``force`` [N], areas
    ``area`` [m²], all points, pressed or not) [Pa].

    Clothing pressure is measured with sensors a couple of centimetres across (the air-pack
    sensors of AMI Techno's AMI3037 series are 20 mm in diameter; Kikuhime's probe is 30 mm),
    which average the pressure over their pad. Unlike the pressure at a point, the reading of a
    sensor of fixed size converges as the garment mesh is refined: it does not see the
    cell-to-cell scatter of a discrete contact traction (±11–15 % about its local mean on the
    cotton gilet at every mesh) nor the sharpening of a narrow peak.
    """
    if len(centres) == 0:
        return np.zeros(0)
    f, a = _pad_sums(centres, x, force, area, radius)
    return f / a


def _pad_sums(centres: Array, x: Array, force: Array, area: Array, radius: float):
    """(Σ f_j, Σ a_j) over the garment points j within ``radius`` of each centre: the force on a
    round sensor pad and the garment area over it."""
    from scipy.spatial import cKDTree

    balls = cKDTree(x).query_ball_point(centres, radius)
    return (np.array([force[j].sum() for j in balls]), np.array([area[j].sum() for j in balls]))


#: Share of a body sensor's pad the garment must cover for the sensor to count (body_sensors).
SENSOR_COVER = 0.5


def body_sensors(
    centres: Array, region: npt.NDArray[np.int32], weight: Array, x: Array, force: Array,
    area: Array, radius: float,
) -> tuple[npt.NDArray[np.int32], Array, Array]:  # fmt: skip
    """Sensors lying on the body: one centred at each body triangle's centre (``centres``, of
    ``region`` and area ``weight``) whose pad the garment covers (garment points of area
    ≥ :data:`SENSOR_COVER` × π ``radius``² within ``radius``); its reading is
    :func:`sensor_pressure`. Returns (region, reading [Pa], area [m²]) of the covered sensors
    that read a pressure (> 0).

    A sensor is placed on the skin, under the garment: the places it is read at do not move when
    the garment mesh changes, so a percentile of the readings over a region samples the same
    places on every garment mesh (the readings at the garment's contact points, ``sensor`` of
    :func:`region_table`, sample wherever that mesh put its points). One that the garment covers
    only in part — beside a hem or an armhole — would read the mean over the covered part alone,
    as if its pad were that part, and is left out, as one would not place a sensor there.
    """
    if len(x) == 0:
        return region[:0], np.zeros(0), np.zeros(0)
    near = np.all((centres >= x.min(axis=0) - radius) & (centres <= x.max(axis=0) + radius), 1)
    near = np.flatnonzero(near)
    f, cover = _pad_sums(centres[near], x, force, area, radius)
    reading = f / np.where(cover > 0, cover, 1.0)
    keep = (cover >= SENSOR_COVER * np.pi * radius**2) & (reading > 0)
    return region[near[keep]], reading[keep], weight[near[keep]]


def region_table(
    regions: dict[str, int],
    region: npt.NDArray[np.int32],
    p: Array,
    area: Array,
    sensor: Array | None = None,
    body: tuple[npt.NDArray[np.int32], Array, Array] | None = None,
) -> list[dict]:
    """Per body region: contact area, normal force and mean / max / 95th-percentile pressure
    (kPa and mmHg).

    Args:
        regions: region name -> number (``BodySurface.regions``).
        region: the body region under each garment contact point (its closest body triangle's).
        p: pressure at each contact point [Pa] (contact force over deformed area).
        area: deformed area carried by each contact point [m²].
        sensor: the reading of a pressure sensor centred at each contact point [Pa]
            (:func:`sensor_pressure`); gives the rows' ``sensor_p95`` (its area-weighted
            95th percentile over the region).
        body: (region, reading [Pa], area [m²]) of sensors lying on the body
            (:func:`body_sensors`); gives the rows' ``body_sensor_p95``, the area-weighted 95th
            percentile of the readings of the region's sensors.

    Only points in contact (p > 0) count. Statistics are area weighted, so a region half covered
    reports the pressure where it is pressed, and its contact area separately. The garment-side
    pressure is used rather than the force lumped onto the body's vertices, which aliases when the
    body mesh is finer than the garment's. The comfort band is judged on the 95th percentile,
    which single-node spikes at hems and armholes do not move.
    """
    rows = []
    for name, tag in sorted(regions.items(), key=lambda kv: kv[1]):
        sel = (region == tag) & (p > 0)
        a, pr = area[sel], p[sel]
        mean = float(np.sum(pr * a) / np.sum(a)) if len(a) else 0.0
        stats = [("mean", mean), ("p95", weighted_percentile(pr, a, 95.0)),
                 ("max", float(pr.max()) if len(pr) else 0.0)]  # fmt: skip
        if sensor is not None:
            stats.append(("sensor_p95", weighted_percentile(sensor[sel], a, 95.0)))
        if body is not None:
            on = body[0] == tag
            stats.append(("body_sensor_p95", weighted_percentile(body[1][on], body[2][on], 95.0)))
        row: dict = {"region": name, "contact_area_m2": float(a.sum()),
                     "force_N": float(np.sum(pr * a))}  # fmt: skip
        for key, val in stats:
            row[f"{key}_kPa"] = units.pa_to_kpa(val)
            row[f"{key}_mmHg"] = units.pa_to_mmhg(val)
        row["comfort"] = comfort_band(row["p95_kPa"])
        rows.append(row)
    return rows


def csv_text(rows: list[dict]) -> str:
    buf = io.StringIO()
    if rows:
        w = csv.DictWriter(buf, fieldnames=list(rows[0]), lineterminator="\n")
        w.writeheader()
        for r in rows:
            w.writerow({k: (f"{v:.6g}" if isinstance(v, float) else v) for k, v in r.items()})
    return buf.getvalue()


def write_summary(folder: Path, summary: dict, rows: list[dict]) -> tuple[Path, Path]:
    """``summary.json`` (everything) and ``pressure_regions.csv`` (the region table)."""
    folder = Path(folder)
    j = write_text(folder / "summary.json", json.dumps(summary, indent=2, default=_jsonable))
    c = write_text(folder / "pressure_regions.csv", csv_text(rows))
    return j, c


def _jsonable(v):
    if isinstance(v, np.generic):
        return v.item()
    if isinstance(v, np.ndarray):
        return v.tolist()
    return str(v)


# ------------------------------------------------------------------------------------------------
# Pictures
# ------------------------------------------------------------------------------------------------


def pressure_png(
    path: Path,
    vertices: Array,
    triangles: npt.NDArray[np.int64],
    p_vertex: Array,
    title: str,
    *,
    under: tuple[Array, npt.NDArray[np.int64]] | None = None,
    vmax_kpa: float | None = None,
) -> Path:
    """Front and back views of a surface coloured by pressure, colour bar in kPa.

    ``under`` (vertices, triangles) is drawn in grey first (the body under a garment).
    """
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from matplotlib.cm import ScalarMappable
    from matplotlib.colors import Normalize

    from fenics_garment.geometry.pictures import draw_mesh, render

    p_kpa = units.pa_to_kpa(np.asarray(p_vertex, dtype=float))
    top = vmax_kpa or max(float(p_kpa.max()), 1e-6)
    norm = Normalize(0.0, top)
    cmap = plt.get_cmap("viridis")
    colours = cmap(norm(p_kpa[triangles].mean(axis=1)))
    fig, axes = plt.subplots(1, 2, figsize=(9, 6))
    for ax, az, label in zip(axes, (0.0, 180.0), ("front", "back"), strict=True):
        items = []
        if under is not None:
            grey = np.tile([0.8, 0.8, 0.82, 1.0], (len(under[1]), 1))
            items += draw_mesh(ax, under[0], under[1], grey, az, two_sided=False)
        items += draw_mesh(ax, vertices, triangles, colours, az, two_sided=under is not None)
        render(items, ax)
        ax.set_title(f"{title}: {label}")
    clipped = float(p_kpa.max()) > top * (1 + 1e-9)
    label = "contact pressure [kPa]" + (f" (max {p_kpa.max():.2f})" if clipped else "")
    fig.colorbar(ScalarMappable(norm, cmap), ax=axes, shrink=0.7, label=label,
                 extend="max" if clipped else "neither")  # fmt: skip
    return atomic_write(Path(path), lambda p: fig.savefig(p, dpi=110, format="png"))


# ------------------------------------------------------------------------------------------------
# DOLFINx fields as arrays on the garment's gmsh nodes (for pictures and tables, on every rank)
# ------------------------------------------------------------------------------------------------


def garment_node_values(garment, f) -> Array:
    """Values of a P1 Function ``f`` (scalar or vector) at the garment's gmsh nodes, (n, bs).

    The cell's P1 dofs and its first geometry nodes (the vertices, also on a curved order-2
    mesh) follow the same reference-vertex order, so each vertex node takes the value of the
    dof in the same cell slot; the owners' values are gathered by original (gmsh) node number
    and shared with every rank.
    """
    from fenics_garment._stack import MPI

    mesh = f.function_space.mesh
    bs = f.function_space.dofmap.index_map_bs
    vdm = f.function_space.dofmap.list
    gdm = mesh.geometry.dofmaps[0][:, : vdm.shape[1]]
    nodes = np.unique(gdm.ravel())
    node_dof = np.empty(len(mesh.geometry.x), dtype=np.int64)
    node_dof[gdm.ravel()] = vdm.ravel()
    vals = f.x.array.reshape(-1, bs)[node_dof[nodes]]
    gidx = np.asarray(mesh.geometry.input_global_indices, dtype=np.int64)[nodes]
    out = np.zeros((len(garment.points), bs))
    seen = np.zeros(len(garment.points))
    out[gidx] = vals
    seen[gidx] = 1.0
    comm = mesh.comm
    out = comm.allreduce(out * seen[:, None], op=MPI.SUM)
    seen = comm.allreduce(seen, op=MPI.SUM)
    return out / np.maximum(seen, 1.0)[:, None]


def pattern_pieces(cell_nodes: npt.NDArray[np.int64], cell_flat: Array) -> npt.NDArray[np.int64]:
    """The pattern piece of each cell: cells joined where they share an edge with the same
    flat coordinates on both sides (a seam or a dart separates pieces: its two sides have
    their own flat coordinates). Numbered 0… in order of first cell."""
    from scipy.sparse import coo_matrix
    from scipy.sparse.csgraph import connected_components

    tri = np.asarray(cell_nodes)[:, :3]
    uv = np.asarray(cell_flat)[:, :3]
    m = len(tri)
    rows, cols = [], []
    keys: dict[tuple[int, int], list[tuple[int, int, int]]] = {}
    for c in range(m):
        for a, b in ((0, 1), (1, 2), (2, 0)):
            i, j = int(tri[c, a]), int(tri[c, b])
            la, lb = (a, b) if i < j else (b, a)
            keys.setdefault((min(i, j), max(i, j)), []).append((c, la, lb))
    for sides in keys.values():
        if len(sides) != 2:
            continue
        (c1, a1, b1), (c2, a2, b2) = sides
        if np.allclose(uv[c1, a1], uv[c2, a2], atol=1e-9) and np.allclose(
            uv[c1, b1], uv[c2, b2], atol=1e-9
        ):
            rows.append(c1)
            cols.append(c2)
    graph = coo_matrix((np.ones(len(rows)), (rows, cols)), shape=(m, m))
    return connected_components(graph, directed=False)[1]


def pattern_png(
    path: Path, rest: Any, p_vertex: Array, title: str, *, vmax_kpa: float | None = None
) -> Path:
    """The flat pattern pieces side by side, coloured by the contact pressure where each piece
    presses on the body (``rest``: the garment's :class:`~fenics_garment.shell.rest.FlatCells`;
    ``p_vertex``: pressure [Pa] per garment vertex, gmsh order)."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from matplotlib.cm import ScalarMappable
    from matplotlib.collections import PolyCollection
    from matplotlib.colors import Normalize

    tri = np.asarray(rest.cell_nodes)[:, :3]
    flat = np.asarray(rest.cell_flat)[:, :3]
    uv = np.stack([-flat[..., 1], flat[..., 0]], axis=-1)  # the grain (warp, flat x) upright
    piece = pattern_pieces(rest.cell_nodes, rest.cell_flat)
    gap, x0 = 0.05, 0.0
    for k in range(piece.max() + 1):  # lay the pieces out left to right, bottoms aligned
        sel = piece == k
        lo = uv[sel].reshape(-1, 2).min(axis=0)
        hi = uv[sel].reshape(-1, 2).max(axis=0)
        uv[sel] += np.array([x0 - lo[0], -lo[1]])
        x0 += hi[0] - lo[0] + gap
    p_kpa = units.pa_to_kpa(np.asarray(p_vertex, dtype=float))
    top = vmax_kpa or max(float(p_kpa.max()), 1e-6)
    norm = Normalize(0.0, top)
    cmap = plt.get_cmap("viridis")
    height = float(np.ptp(uv[..., 1]))
    fig, ax = plt.subplots(figsize=(min(16.0, max(6.0, 5.0 * x0 / height)), 5.0))
    ax.add_collection(PolyCollection(uv, facecolors=cmap(norm(p_kpa[tri].mean(axis=1))),
                                     edgecolors="none"))  # fmt: skip
    ax.autoscale()
    ax.set_aspect("equal")
    ax.set_xlabel("flat pattern pieces, grain (warp) upright [m]")
    ax.set_title(f"{title}: pressure on the pattern")
    fig.colorbar(ScalarMappable(norm, cmap), ax=ax, shrink=0.8, label="contact pressure [kPa]")
    fig.savefig(path, dpi=110, bbox_inches="tight")
    plt.close(fig)
    return Path(path)
