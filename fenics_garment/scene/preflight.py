"""Checks made before any solving, so that a hopeless run fails in seconds with a clear message.

* the output folder can be made and written (not under a file, not read-only);
* every MPI rank owns some garment cells;
* the body mesh resolves the body's curvature (facet size against the smallest body radius);
* the garment does not start deeper inside the body than the dressing can undo (the body would
  have to shrink past its own axis, where the closest-point normal is meaningless).

and, before anything is built, that the scene's sizes and counts are within what can run at all
(:func:`scene_limits`: a 1e-300 m mesh size would make gmsh run out of memory, 10¹⁸ dressing steps
would never end).

Each raises :class:`PreflightError` (a ``ValueError``) naming the numbers and what to do. The
checks are collective: every rank gets the same answer.
"""

from __future__ import annotations

import math
import os
from collections.abc import Callable
from pathlib import Path

import numpy as np

from fenics_garment._stack import MPI
from fenics_garment.petsc_options import PetscOptionError, check_options

#: Largest body facet size relative to the smallest body radius r: a chord h deviates from the
#: circle by r(1 − cos(h/2r)) ≈ h²/(8r), i.e. 3 % of r at h = r/2 — the size of a typical
#: contact penetration tolerance multiplied many times; finer is needed for accurate pressure.
MAX_BODY_H_OVER_R = 0.5
#: Largest garment element size relative to the smallest body radius (six elements around it).
MAX_GARMENT_H_OVER_R = 1.0
#: Largest shrink of the body (deepest initial penetration + margin) relative to its smallest
#: radius: beyond it the shrunk body has almost no cross-section left.
MAX_SHRINK_OVER_R = 0.8


#: Most triangles a body or garment mesh may have (about 1 GB of gmsh/DOLFINx memory).
MAX_TRIANGLES = 2_000_000
#: Area [m²] assumed for a mannequin or scan body before it is built (a whole adult ≈ 1.8 m²).
BODY_AREA = 2.0
#: Upper bounds of counts; beyond them a run would not end in a useful time.
MAX_COUNTS = {"dressing.steps": 10_000, "dressing.max_cuts": 40, "physics.max_updates": 1_000}
#: Lengths of a cylinder body [m] that a garment run makes sense for (a finger to a barrel).
LENGTH_RANGE = (1e-3, 10.0)
#: Penalty scale κ̂ (default 10, see contact.terms.default_penalty): beyond it the contact
#: stiffness swamps the fabric's by more than 10⁶ and Newton's linear solves lose all digits.
MAX_KAPPA_HAT = 1e6


class PreflightError(ValueError):
    """A run cannot start: names the value and what to change."""


def _collective(comm: MPI.Comm, message: str | None) -> None:
    message = comm.bcast(message, root=0)
    if message:
        raise PreflightError(message)


def output_folder(folder: Path, comm: MPI.Comm) -> None:
    """Make ``folder`` (rank 0) and check that a file can be written in it and in its
    ``checkpoint/`` if there is one (a resumed run writes there first)."""
    message = _path_too_long(folder) if comm.rank == 0 else None
    if comm.rank == 0 and message is None:
        try:
            folder.mkdir(parents=True, exist_ok=True)
            for where in (folder, folder / "checkpoint"):
                if where.is_dir():
                    probe = where / f".write-test-{os.getpid()}"
                    probe.write_bytes(b"")
                    probe.unlink()
        except OSError as err:
            why = err.strerror or type(err).__name__
            message = (f"cannot write the output folder {folder}: {why}"
                       f"{f' ({err.filename})' if err.filename else ''}; "
                       "choose another output root with -o/--output")  # fmt: skip
    _collective(comm, message)


#: Longest path the run writes below its folder (``checkpoint/.state-123.r1023.part4194304.npz``
#: and ADIOS2's files of ``.dressing.bp.part/``), with room to spare.
LONGEST_INSIDE = 64


def _path_too_long(folder: Path) -> str | None:
    """Why the run's files cannot have their paths below ``folder``, or None: the system's
    limits on a path (PATH_MAX) and on a name (NAME_MAX); ADIOS2 aborts the process on a path
    it cannot open."""
    from fenics_garment.bounded import cut

    full = os.path.abspath(folder)
    try:
        path_max = os.pathconf("/", "PC_PATH_MAX")
        name_max = os.pathconf("/", "PC_NAME_MAX")
    except (OSError, ValueError):
        path_max, name_max = 4096, 255
    if len(os.fsencode(full)) + LONGEST_INSIDE >= path_max:
        return (f"the output folder's path is {len(os.fsencode(full))} bytes long: the run's "
                f"files need at most {path_max - LONGEST_INSIDE} (PATH_MAX {path_max}); "
                f"choose a shorter output root with -o/--output ({cut(full)})")  # fmt: skip
    long_part = next((p for p in Path(full).parts if len(os.fsencode(p)) > name_max), None)
    if long_part is not None:
        return (f"a folder name in the output path is longer than {name_max} bytes "
                f"({cut(long_part)}); choose another output root with -o/--output")  # fmt: skip
    return None


def scene_limits(scene) -> None:
    """Sizes and counts of ``scene`` that can run at all (checked before anything is built)."""
    b, g, src = scene.body, scene.garment, scene.source or scene.name

    def fail(key: str, message: str) -> None:
        raise PreflightError(f"{src}: [{key}] {message}")

    for key in MAX_COUNTS:
        section, name = key.split(".")
        value = getattr(getattr(scene, section), name)
        if value > MAX_COUNTS[key]:
            fail(key, f"= {value} is more than {MAX_COUNTS[key]}; the run would not end")
    k = scene.physics.kappa_hat
    if k > MAX_KAPPA_HAT:
        why = "the linear solves would lose every digit (default 10)"
        fail("physics.kappa_hat", f"= {k:g} is more than {MAX_KAPPA_HAT:g}: {why}")
    if k < MIN_KAPPA_HAT:
        why = (f"the garment would sink into the body by about {1.3 / k:.2g}× its own hoop "
               "strain (default 10), too far for the multiplier updates to remove")  # fmt: skip
        fail("physics.kappa_hat", f"= {k:g} is less than {MIN_KAPPA_HAT:g}: {why}")
    reg_limits(scene, fail)
    fabric_limits(scene, fail)
    try:
        check_options(scene.solver.petsc)
    except PetscOptionError as err:
        raise PreflightError(f"{src}: {err}") from None
    if b.kind == "mannequin":
        mannequin_limits(scene)
    if b.kind == "arm":
        human_lengths(scene)
    if b.kind == "scan":
        scan_file(scene, fail)
    if g.kind == "pattern":
        pattern_file(scene, fail)
    area = BODY_AREA
    if b.kind == "cylinder":
        lo, hi = LENGTH_RANGE
        for key in ("radius", "length"):
            v = getattr(b, key)
            if not lo <= v <= hi:
                fail(f"body.{key}", f"= {v:g} m is outside [{lo:g}, {hi:g}] m")
        h_max = MAX_BODY_H_OVER_R * b.radius
        if b.mesh_size > h_max:
            fail("body.mesh_size", f"= {b.mesh_size:g} m is too coarse for a cylinder of radius "
                 f"{b.radius:g} m; use body.mesh_size <= {h_max:.3g} m")  # fmt: skip
        area = 2 * math.pi * b.radius * (b.length + 0.1 + b.radius)
    # the garment covers part of the body: a tube the cylinder's side, a sleeve or a stocking
    # a limb; the body's whole area bounds the rest
    garment_area = 2 * math.pi * b.radius * b.length if g.kind == "tube" else area
    for key, h, a in (("body.mesh_size", b.mesh_size, area),
                      ("garment.mesh_size", g.mesh_size, garment_area)):  # fmt: skip
        h_min = math.sqrt(a / (math.sqrt(3) / 4 * MAX_TRIANGLES))
        if h < h_min:
            n = MAX_TRIANGLES * (h_min / h) ** 2 if h > 1e-150 else math.inf
            fail(key, f"= {h:g} m would make about {n:.2g} triangles (at most "
                 f"{MAX_TRIANGLES:.0e}); use mesh_size >= {h_min:.2g} m")  # fmt: skip
        if h > 1.0:
            fail(key, f"= {h:g} m is larger than a body; use a few centimetres")


#: Smallest penalty scale κ̂ of the plain penalty (the augmented Lagrangian corrects a soft one):
#: the penetration grows like 1/κ̂ (0.17 h at 10 on the tight tube), so below this the garment
#: sinks into the body by many times its thickness.
MIN_KAPPA_HAT = 0.1
#: Range of dressing.regularisation (c₀ relative to A/ℓ², default 1e-2): 0 leaves the garment
#: with no support at all while the body grows (friction is off then, and a scene has no
#: boundary conditions), so Newton meets a singular Jacobian or the garment drifts off; above
#: 1 the spring is as stiff as the contact and is not released.
REG_RANGE = (1e-4, 1.0)
#: Largest fabric values (moduli in Pa, bending rigidity in N·m, thickness in m, density in
#: kg/m³): beyond them a "fabric" is steel-like or worse and the residual overflows.
FABRIC_MAX = {"E_warp": 1e12, "E_weft": 1e12, "G12": 1e12, "B_warp": 1e3, "B_weft": 1e3,
              "thickness": 0.05, "density": 1e5}  # fmt: skip


def reg_limits(scene, fail: Callable[[str, str], None]) -> None:
    lo, hi = REG_RANGE
    r = scene.dressing.regularisation
    if not lo <= r <= hi:
        why = (
            "nothing would hold the garment while the body grows (friction is off then)"
            if r < lo
            else "the spring would be as stiff as the contact and never released"
        )
        fail("dressing.regularisation", f"= {r:g} is outside [{lo:g}, {hi:g}]: {why} "
             "(default 0.01)")  # fmt: skip


def scan_file(scene, fail: Callable[[str, str], None]) -> None:
    """The scan file exists (checked on every rank: only rank 0 reads it)."""
    _file_exists(scene, "body.file", scene.body.file, fail)


def pattern_file(scene, fail: Callable[[str, str], None]) -> None:
    """The pattern file exists and reads as a valid pattern (a malformed one is refused here,
    before any meshing, with the reader's one line naming the panel and edge)."""
    from fenics_garment.pattern.io import read_pattern
    from fenics_garment.pattern.model import PatternError

    path = _file_exists(scene, "garment.pattern", scene.garment.pattern, fail)
    try:
        pattern = read_pattern(path)
    except PatternError as err:
        fail("garment.pattern", f"= {scene.garment.pattern!r}: {err}")
        return
    other = [(n, p.fabric) for n, p in pattern.panels.items()
             if p.fabric is not None and p.fabric != scene.garment.fabric]  # fmt: skip
    if other:
        fail("garment.pattern", f"= {scene.garment.pattern!r}: panel {other[0][0]!r} is of "
             f"{other[0][1]!r}, but a garment is of one fabric here ([garment] fabric = "
             f"{scene.garment.fabric!r}): per-panel fabrics are not modelled yet")  # fmt: skip
        return
    sewn = {r.panel for s in pattern.seams for r in (s.a, s.b) if s.a.panel != s.b.panel}
    loose = [n for n in pattern.panels if n not in sewn]
    if len(pattern.panels) > 1 and loose:
        why = (
            " (DXF-AAMA carries no seams: name them in a companion file of our format, "
            "fenics_garment/pattern/io.py)"
            if path.suffix.lower() == ".dxf"
            else ""
        )
        fail("garment.pattern", f"= {scene.garment.pattern!r}: panel {loose[0]!r} is sewn to no "
             f"other panel: it would fall off the body{why}")  # fmt: skip


def _file_exists(scene, key: str, name: str, fail: Callable[[str, str], None]) -> Path:
    from fenics_garment.scene.config import scene_file

    path = scene_file(scene, name)
    if not path.is_file():
        fail(key, f"= {name!r}: no such file {path} (a relative path is relative to the scene "
             "file's folder)")  # fmt: skip
    return path


#: Smallest fabric values (as FABRIC_MAX; the built-in cotton: E 1.1e6 Pa, G12 1.1e5 Pa, B
#: 1.5e-5 N·m, 0.46 mm): below them the shell has no stiffness to speak of — the contact
#: stiffness κ̂ E h / ℓ² and the thickness the checks divide by go to 0 (1e-300: a division by
#: zero), and Newton's linear solves meet a singular matrix
FABRIC_MIN = {"E_warp": 1e2, "E_weft": 1e2, "G12": 1e1, "B_warp": 1e-10, "B_weft": 1e-10,
              "thickness": 1e-5}  # fmt: skip


def fabric_limits(scene, fail: Callable[[str, str], None]) -> None:
    for k, v in scene.garment.fabric_overrides.items():
        top, low = FABRIC_MAX.get(k), FABRIC_MIN.get(k)
        if top is not None and v > top:
            fail(f"garment.fabric_overrides.{k}", f"= {v:g} is more than {top:g}: not a "
                 "fabric (the forces would overflow floating point)")  # fmt: skip
        if low is not None and v < low:
            fail(f"garment.fabric_overrides.{k}", f"= {v:g} is less than {low:g}: not a "
                 "fabric (no stiffness: the contact and the checks would divide by 0)")  # fmt: skip


#: Levels a garment kind needs inside the mannequin's crop (z_range) and on the body.
NEEDED_LEVELS = {"gilet": ("hip", "neck_base"), "dress": ("hip", "neck_base"),
                 "stocking": ("ankle", "thigh")}  # fmt: skip
#: Largest girth or stature [m] of a mannequin (the largest EN 13402-3 hip girth is 1.5 m).
MAX_HUMAN_LENGTH = 3.0
#: Smallest girth or height [m] of a mannequin or an arm (a baby's wrist is some 9 cm round)
MIN_HUMAN_LENGTH = 0.02


def human_lengths(scene) -> None:
    """The measurements of a mannequin or an arm are lengths of a human body."""
    src = scene.source or scene.name
    for k, v in scene.body.measurements.items():
        if not MIN_HUMAN_LENGTH <= v <= MAX_HUMAN_LENGTH:
            side = "more" if v > MAX_HUMAN_LENGTH else "less"
            limit = MAX_HUMAN_LENGTH if v > MAX_HUMAN_LENGTH else MIN_HUMAN_LENGTH
            raise PreflightError(f"{src}: [body.measurements.{k}] = {v:g} is {side} than "
                                 f"{limit:g} m: not a human body")  # fmt: skip


def mannequin_limits(scene) -> None:
    """The mannequin's measurements are a body's, and its crop keeps what the garment needs."""
    from fenics_garment.geometry.measurements import measurements

    b, src = scene.body, scene.source or scene.name
    human_lengths(scene)
    try:
        m = measurements(b.size, **b.measurements)
    except (ValueError, TypeError) as err:
        raise PreflightError(f"{src}: [body.measurements] {err}") from None
    if b.human:  # the whole body is built (no crop); the arms and head must fit
        from fenics_garment.geometry.errors import GeometryError
        from fenics_garment.geometry.human import Pose, check_human

        try:
            check_human(m, Pose())
        except GeometryError as err:
            raise PreflightError(f"{src}: [body.measurements] {err}") from None
        return
    needed = NEEDED_LEVELS.get(scene.garment.kind)
    if b.z_range and needed:
        lo, hi = (m.height(level) for level in needed)
        if not (b.z_range[0] < lo and b.z_range[1] > hi):
            raise PreflightError(
                f"{src}: [body.z_range] = {b.z_range} crops away part of the body a "
                f"{scene.garment.kind} needs: {needed[0]} at {lo:.2f} m to {needed[1]} at "
                f"{hi:.2f} m; use for example [{lo - 0.1:.2f}, {hi + 0.1:.2f}] or [] (no crop)"
            )


#: A garment level with more ease than this hangs clear of the body (the dress's neckline has
#: 25 %, the gilet's 15 %): the body's facets there are not what it presses on, and the facet
#: checks leave it out (the short woman's dress was refused for 23.2 mm facets at its neckline,
#: 0.2 mm over the limit, where it does not touch).
LOOSE_EASE = 0.10


def fitted_levels(garment) -> list:
    """The garment's levels with at most :data:`LOOSE_EASE` of ease (where it can press)."""
    return [lv for lv in garment.levels if lv.ease <= LOOSE_EASE]


def smallest_body_radius(built, pressed: bool = False) -> tuple[float, str]:
    """The smallest radius of the body where the garment is, and where (level name);
    ``pressed``: only where it is fitted (ease at most :data:`LOOSE_EASE`)."""
    sc = built.scene
    if sc.body.kind == "cylinder":
        return sc.body.radius, "cylinder"
    levels = fitted_levels(built.garment) if pressed else built.garment.levels
    if not levels:  # a pattern garment that goes round no landmark level
        return math.inf, "no level"
    level = min(levels, key=lambda lv: lv.body_girth)
    return level.body_girth / (2 * math.pi), f"level {level.name!r}"


def ranks_own_cells(n_owned: int, n_cells: int, comm: MPI.Comm) -> None:
    """Every rank owns at least one garment cell."""
    counts = comm.allgather(n_owned)
    empty = [r for r, n in enumerate(counts) if n == 0]
    if empty:
        raise PreflightError(
            f"the garment has {n_cells} cells for {comm.size} MPI ranks and rank(s) "
            f"{', '.join(map(str, empty))} own none; run with fewer ranks (about one per "
            "2000 cells is efficient) or a finer garment.mesh_size"
        )


#: Share of the body's edges near the garment's narrowest level that the facet size
#: (:func:`body_facet_size`) is above: a few long edges along a limb (slivers running down the
#: arm) do not cut into its round section.
FACET_QUANTILE = 0.9
#: How far [m] along the garment from its narrowest level, and out from it, the body's edges
#: are measured (:func:`body_facet_size`).
FACET_BAND = 0.02


def body_facet_size(built) -> float | None:
    """The size [m] of the body's own facets round the section where the fitted garment is
    narrowest (ease at most :data:`LOOSE_EASE`):
    on a scan kept as it is (``body.remesh = false``), the :data:`FACET_QUANTILE` quantile of
    the body's edges within :data:`FACET_BAND` of the garment's points within FACET_BAND (along
    the garment) of its narrowest level, each edge's length across the garment's axis (the
    warp there): the part that cuts a chord into the round section (MakeHuman's forearm has
    edges 14 mm long along it and 5 mm round it). None where the body was meshed at
    ``body.mesh_size`` (mannequin, arm, cylinder, remeshed scan) or nothing is near."""
    from scipy.spatial import cKDTree

    sc, body, garment = built.scene, built.body, built.garment
    fitted = fitted_levels(garment)
    if sc.body.kind != "scan" or sc.body.remesh or not fitted:
        return None
    level = min(fitted, key=lambda lv: lv.body_girth)
    sel = np.abs(garment.axial(garment.points) - level.z) <= FACET_BAND
    pts = garment.points[sel]
    if not len(pts):
        return None
    v, t = body.vertices, body.triangles
    d, _ = cKDTree(pts).query(v, distance_upper_bound=FACET_BAND + abs(level.clearance))
    near = np.isfinite(d)
    tri = t[near[t].all(axis=1)]
    if not len(tri):
        return None
    edges = np.concatenate([tri[:, [0, 1]], tri[:, [1, 2]], tri[:, [2, 0]]])
    e = v[edges[:, 0]] - v[edges[:, 1]]
    axis = garment.warp[sel].mean(axis=0)  # the warp runs along the garment's axis
    axis /= max(float(np.linalg.norm(axis)), 1e-300)
    across = e - np.outer(e @ axis, axis)  # the part of an edge round the section
    return float(np.quantile(np.linalg.norm(across, axis=1), FACET_QUANTILE))


def mesh_resolution(built) -> None:
    """The body's facets are small against its curvature radius: on a scan kept as it is, its
    own facets where the garment is narrowest (:func:`body_facet_size`: MakeHuman's arm has
    4–5 mm edges at the wrist, whatever ``body.mesh_size`` says), else ``body.mesh_size``, the
    size the body was meshed at."""
    sc = built.scene
    r, where = smallest_body_radius(built, pressed=True)
    h_limit = MAX_BODY_H_OVER_R * r
    measured = body_facet_size(built)
    if measured is not None:
        if measured > h_limit:
            raise PreflightError(
                f"{sc.source or sc.name}: [body.file] the scan's facets are too coarse for the "
                f"body's curvature where the garment is: {measured * 1e3:.1f} mm edges "
                f"({FACET_QUANTILE:.0%} quantile) against its smallest radius ({where}) of "
                f"{r * 1e3:.1f} mm, cutting up to {measured**2 / (8 * r) * 1e3:.1f} mm into the "
                f"surface; remesh it: body.remesh = true with body.mesh_size <= "
                f"{math.floor(h_limit * 1e4) / 1e4:g} m"
            )
        return
    h = sc.body.mesh_size
    if h > h_limit:
        raise PreflightError(
            f"{sc.source or sc.name}: [body.mesh_size] = {h:g} m is too coarse for the body's "
            f"curvature: its smallest radius ({where}) is {r:.3g} m, so facets would cut up to "
            f"{h * h / (8 * r) * 1e3:.1f} mm into the curved surface; use body.mesh_size <= "
            f"{math.floor(h_limit * 1e4) / 1e4:g} m (r/2, rounded down)"
        )


def garment_resolution(built) -> None:
    """The garment's elements are not larger than the smallest body radius."""
    sc = built.scene
    r, where = smallest_body_radius(built)
    h = sc.garment.mesh_size
    if h > MAX_GARMENT_H_OVER_R * r:
        raise PreflightError(
            f"{sc.source or sc.name}: [garment.mesh_size] = {h:g} m is too coarse to wrap the "
            f"body: its smallest radius ({where}) is {r:.3g} m; use garment.mesh_size <= "
            f"{MAX_GARMENT_H_OVER_R * r:.3g} m"
        )


def deepest_point(built) -> tuple[np.ndarray, str]:
    """Where the undeformed garment lies deepest inside the unshrunk body: the point (x, y, z)
    [m] and the garment's level nearest to it in height, "" without levels (collective)."""
    from fenics_garment.contact import pressure as cpressure
    from fenics_garment.scene.dressing import unshrunk

    with unshrunk(built.contact.state) as st:
        gap = st.local_values(st.gap)
        x = cpressure.positions(st)
    mine = (float(gap.min()), x[int(np.argmin(gap))]) if len(gap) else (np.inf, None)
    _, p = min(built.model.geometry.mesh.comm.allgather(mine), key=lambda a: a[0])
    levels = getattr(built.garment, "levels", None) or []
    near = min(levels, key=lambda lv: abs(lv.z - p[2]), default=None)
    return p, "" if near is None else near.name


def initial_depth(built, penetration0: float) -> None:
    """The dressing's shrink s₀ = penetration + margin leaves a body to dress."""
    sc = built.scene
    r, where = smallest_body_radius(built)
    s0 = max(penetration0, 0.0) + sc.dressing.margin
    if s0 >= MAX_SHRINK_OVER_R * r:
        p, level = deepest_point(built)
        where_in = f" at ({p[0]:.3f}, {p[1]:.3f}, {p[2]:.3f}) m" + (
            f", near its level '{level}'" if level else ""
        )
        raise PreflightError(
            f"{sc.source or sc.name}: the garment starts {penetration0 * 1e3:.3g} mm inside the "
            f"body{where_in}; with dressing.margin {sc.dressing.margin * 1e3:.3g} mm the body "
            f"would have to shrink by {s0 * 1e3:.3g} mm, more than {MAX_SHRINK_OVER_R:.0%} of "
            f"its smallest radius ({where}, {r * 1e3:.1f} mm), where the contact normal is "
            "meaningless; use a less negative garment.ease (or a smaller dressing.margin)"
        )


#: Peak memory of a direct (MUMPS) solve per degree of freedom [bytes]: the resident memory of
#: one Newton iteration over its dofs, measured on the P2B-P2B tube on a 10 m cylinder (one rank,
#: LU with friction): 1.91 GB at 333,516 dofs, 7.03 GB at 1,276,344 (5.7 and 5.5 kB a dof).
DIRECT_BYTES_PER_DOF = 6.0e3
#: Dofs per MPI rank from which a run is announced as large before its forms are compiled, and
#: its Newton iterations are then reported as they go (``scene.run``): one iteration took 10.6 s
#: at 333,516 dofs and 97 s at 1,276,344 on one rank of the 2-core development machine (the 10 m
#: tube that ran for minutes without a line after "compiling the forms").
LARGE_DOFS_PER_RANK = 250_000
#: Share of the machines' memory that a direct solve may be estimated to take.
MEMORY_SHARE = 0.8


def machine_memory(comm: MPI.Comm) -> float:
    """Physical memory [bytes] of the machines the ranks of ``comm`` run on (each host once)."""
    try:
        mine = float(os.sysconf("SC_PHYS_PAGES") * os.sysconf("SC_PAGE_SIZE"))
    except (ValueError, OSError, AttributeError):  # not a POSIX system: no limit known
        mine = math.inf
    hosts = dict(comm.allgather((MPI.Get_processor_name(), mine)))
    return float(sum(hosts.values()))


def problem_size(scene, dofs: int, comm: MPI.Comm) -> str | None:
    """Refuse a problem whose direct solve would not fit in the machines' memory (estimated at
    :data:`DIRECT_BYTES_PER_DOF`), naming the mesh size that would; a one-line notice for a
    large one (more than :data:`LARGE_DOFS_PER_RANK` dofs per rank), else None."""
    src = scene.source or scene.name
    h = scene.garment.mesh_size
    need = DIRECT_BYTES_PER_DOF * dofs
    per_rank = dofs / comm.size
    if scene.solver.linear == "direct":
        have = MEMORY_SHARE * machine_memory(comm)
        if need > have:
            h_fit = h * math.sqrt(need / have)
            raise PreflightError(
                f"{src}: [garment.mesh_size] = {h:g} m makes {dofs:,} dofs: a direct solve "
                f"needs about {need / 1e9:.3g} GB, more than the {have / 1e9:.3g} GB this "
                f"machine can give ({MEMORY_SHARE:.0%} of its memory); use garment.mesh_size >= "
                f'{h_fit:.2g} m, or solver.linear = "gamg" on more ranks'
            )
    if per_rank <= LARGE_DOFS_PER_RANK:
        return None
    h_ok = h * math.sqrt(per_rank / LARGE_DOFS_PER_RANK)
    memory = f", about {need / 1e9:.2g} GB for the direct solver" if "direct" in (
        scene.solver.linear) else ""  # fmt: skip
    return (
        f"a large problem: {dofs:,} dofs on {comm.size} rank(s){memory}; a Newton "
        f"iteration may take minutes (each one is reported); garment.mesh_size >= "
        f"{h_ok:.2g} m would keep to {LARGE_DOFS_PER_RANK:,} dofs a rank"
    )


def check_built(built) -> float:
    """The checks that need the built scene; returns the initial penetration [m]."""
    from fenics_garment.scene.dressing import initial_penetration

    mesh = built.model.geometry.mesh
    n_owned = mesh.topology.index_map(mesh.topology.dim).size_local
    ranks_own_cells(n_owned, len(built.garment.cells), mesh.comm)
    mesh_resolution(built)
    garment_resolution(built)
    pen = initial_penetration(built.contact)
    initial_depth(built, pen)
    return pen
