"""Run a drape scene (``kind = "drape"``, :class:`~fenics_garment.scene.config.DrapeConfig`):
the Cusick drape of one fabric (:mod:`fenics_garment.drape`), its outputs and checks.

One output folder per run, ``<output.folder>/<name>/`` (locked and marked as a garment run's,
:mod:`fenics_garment.scene.folder`):

* ``scene_used.toml`` — the scene with every default filled in;
* ``summary.json`` — DC (from the shadow's area, as the instrument computes it), the node
  count, the measured values and the error when known, the fabric in SI and where it came from,
  the bending law, cells, dofs, steps, Newton iterations, times and the checks;
* ``drape.png`` — the shadow seen from above (pedestal black, specimen outline dashed) beside
  the 3D shape;
* ``final_state.xdmf`` — the specimen's reference mesh (P1 sub-triangles of its order-2 cells)
  with the displacement and the height z [m] at its nodes (``meshio.xdmf.TimeSeriesReader``,
  ParaView); ``drape.bp`` — VTX (ParaView): displacement and rotation vector (P2 fields).

The checks (``summary.json`` → ``checks``; a failed one is a WARNING and exit code 4):

* ``instrument``: |DC of the undeformed specimen's rasterised shadow − DC of its exact outline
  (the hem polygon's area)| ≤ 0.005: the raster (``[drape] pixel``) resolves the specimen;
* ``membrane_strain``: the largest principal Green–Lagrange membrane strain of the shell ≤ 0.03:
  a drape folds a nearly inextensible fabric, so a larger stretch is a wrong equilibrium (the
  fabric's membrane stiffness is ~10⁵ its weight per metre). ``summary.json`` also gives
  ``max_chord_strain``, the largest |ℓ/L − 1| of the straight edges between the deformed P2
  nodes: folds tighter than the mesh shorten those chords (M-F at 12 mm: 0.076), a sign that
  the mesh does not resolve them;
* ``dc_range``: how far DC lies outside [0, 1] (0: inside): the shadow lies between the
  pedestal's and the flat specimen's.
"""

from __future__ import annotations

import json
import math
import time
from collections.abc import Callable
from pathlib import Path

import numpy as np

from fenics_garment import drape, measured, output
from fenics_garment._stack import MPI, dolfinx
from fenics_garment.materials import Fabric
from fenics_garment.petsc_options import LINEAR_SOLVERS
from fenics_garment.progress import ProgressLine
from fenics_garment.progress import active as active_line
from fenics_garment.progress import current as current_line
from fenics_garment.scene import checks, config
from fenics_garment.scene import folder as run_folder
from fenics_garment.scene.preflight import PreflightError
from fenics_garment.shell.energy import HystereticBending

#: The bound of each check (module doc).
LIMITS = {"instrument": 0.005, "membrane_strain": 0.03, "dc_range": 0.0}
#: The data file a drape scene's ``fabric`` names.
DATA_FILE = "fenics_garment/data/fabrics_measured.toml"


def fabric_of(scene: config.Scene) -> measured.MeasuredFabric:
    """The fabric of a drape scene in SI (:func:`fenics_garment.measured.material_si`): the data
    file's record of ``[drape] fabric``, or the scene's own KES / CLO3D-style values."""
    r = scene.drape
    if r.fabric:
        m = measured.by_id(r.fabric)
        return m
    values = r.kes or r.clo3d
    form = "KES" if r.kes else "CLO3D-style"
    return measured.MeasuredFabric(
        id=scene.name, name=f"{scene.name} ({form} values of the scene)",
        source=scene.source or "scene", dc_measured=r.dc_measured or math.nan, dc_clo3d=None,
        nodes_measured=r.nodes_measured or None, specimen_diameter=r.specimen_diameter,
        pedestal_diameter=r.pedestal_diameter, **measured.material_si(values),
    )  # fmt: skip


def bending_law(scene: config.Scene, m: measured.MeasuredFabric) -> HystereticBending | None:
    """The bending law of ``[drape] bending`` (None: elastic)."""
    if scene.drape.bending != "hysteresis":
        return None
    return HystereticBending(m.twoHB, m.twoHB_weft,
                             yield_curvature=scene.drape.yield_curvature)  # fmt: skip


def limits(scene: config.Scene) -> None:
    """Sizes that can run at all (before anything is built): the number of triangles, the
    raster's pixels."""
    r, src = scene.drape, scene.source or scene.name
    area = math.pi / 4 * (r.specimen_diameter**2 - r.pedestal_diameter**2)
    n = area / (math.sqrt(3) / 4 * r.mesh_size**2)
    if n > DRAPE_MAX_TRIANGLES:
        h = math.sqrt(area / (math.sqrt(3) / 4 * DRAPE_MAX_TRIANGLES))
        raise PreflightError(f"{src}: [drape.mesh_size] = {r.mesh_size:g} m would make about "
                             f"{n:.2g} triangles (at most {DRAPE_MAX_TRIANGLES:.0e}); use "
                             f"mesh_size >= {h:.2g} m")  # fmt: skip
    pixels = (1.1 * r.specimen_diameter / r.pixel) ** 2
    if pixels > MAX_PIXELS:
        raise PreflightError(f"{src}: [drape.pixel] = {r.pixel:g} m makes {pixels:.2g} pixels "
                             f"(at most {MAX_PIXELS:.0e}); use a larger pixel")  # fmt: skip
    if scene.output.error_bars:
        raise PreflightError(f"{src}: a drape has no error bars (run it on two meshes)")


#: At most this many triangles in a drape specimen (a 6 mm mesh of the standard specimen has
#: 3,000; 1e5 is ~1.8 M dofs, hours of Newton on one machine).
DRAPE_MAX_TRIANGLES = 1e5
#: At most this many raster pixels (a 300 mm specimen at 0.5 mm: 4·10⁵).
MAX_PIXELS = 1e8


def run(
    scene: config.Scene,
    out_root: str | Path | None = None,
    *,
    quiet: bool = False,
    comm: MPI.Comm = MPI.COMM_WORLD,
    resume: str | Path | None = None,
):
    """Drape the fabric of ``scene`` and write its folder (the module doc); returns a
    :class:`~fenics_garment.scene.run.RunResult` (``completed`` False when the path found no
    equilibrium, with the reason in ``message``)."""
    from fenics_garment.scene.checkpoint import ResumeError
    from fenics_garment.scene.preflight import output_folder

    if resume is not None:
        raise ResumeError(f"{resume}: a drape run keeps no checkpoint; start it again (without "
                          "--resume)")  # fmt: skip
    limits(scene)
    root = Path(out_root if out_root is not None else scene.output.folder)
    folder = run_folder.inside(root, scene.name)
    output_folder(folder, comm)
    state = run_folder.RunFolder(folder, comm)
    state.acquire()
    try:
        state.start(fresh=True)
        line = ProgressLine(enabled=comm.rank == 0 and not quiet)
        with active_line(line):
            result = _run_in(state, scene, comm)
    except BaseException:
        state.finish("failed", collective=False)
        raise
    finally:
        state.release()
    return result


def _run_in(state: run_folder.RunFolder, scene: config.Scene, comm: MPI.Comm):
    from fenics_garment.scene.run import RunResult

    folder = state.path
    say = current_line().say
    t0 = time.perf_counter()
    text = config.dumps(scene)
    output.guarded(comm, lambda: output.write_text(folder / "scene_used.toml", text))
    r = scene.drape
    m = fabric_of(scene)
    fabric = measured.to_fabric(m)
    law = bending_law(scene, m)
    say(f"drape {scene.name!r}: {m.id} ({m.name}), {r.bending} bending, specimen "
        f"{1e3 * r.specimen_diameter:g} mm on a {1e3 * r.pedestal_diameter:g} mm pedestal, "
        f"mesh {1e3 * r.mesh_size:g} mm, {comm.size} rank(s)")  # fmt: skip
    opts = {**LINEAR_SOLVERS[scene.solver.linear], **scene.solver.petsc}
    current_line().stage("draping (load steps, then pseudo-time relaxation)")
    completed, message = True, ""
    try:
        res = drape.drape(fabric, specimen_diameter=r.specimen_diameter,
                          pedestal_diameter=r.pedestal_diameter, size=r.mesh_size,
                          amplitude=r.imperfection, seed=r.seed, steps=r.load_steps,
                          pixel=r.pixel, bending=law, petsc_options=opts or None,
                          comm=comm)  # fmt: skip
    except RuntimeError as err:
        completed, message, res = False, str(err), None
    summary = _summary(scene, m, fabric, law, res, completed, message)
    strain = max_membrane_strain(res) if res is not None else math.nan
    summary["max_membrane_strain"] = strain
    found = _checks(res, strain) if res is not None else []
    summary["checks"] = {c.name: c.as_dict() for c in found}
    summary["checks_passed"] = all(c.ok for c in found)
    if res is not None:
        _write_fields(folder, scene, res, comm)
    summary["time_s"] = {"total": time.perf_counter() - t0}
    output.guarded(comm, lambda: output.write_text(
        folder / "summary.json", json.dumps(summary, indent=2, default=_plain)))  # fmt: skip
    if res is not None and scene.output.pictures and comm.rank == 0:
        title = (f"{scene.name} ({m.id}, {r.bending}): DC {res.dc:.3f}"
                 + (f" (measured {m.dc_measured:.3f})" if math.isfinite(m.dc_measured) else "")
                 + f", {res.nodes} nodes")  # fmt: skip
        _picture(folder, res, r, title)
    result = RunResult(folder, summary, [], None, res, completed, message, found)
    state.finish("stopped" if not completed else
                 "completed" if result.checks_passed else "checks failed")  # fmt: skip
    current_line().close()
    if res is not None:
        say(f"  DC {res.dc:.3f}" + (f" (measured {m.dc_measured:.3f}, error "
            f"{res.dc - m.dc_measured:+.3f})" if math.isfinite(m.dc_measured) else "")
            + f", {res.nodes} nodes" + (f" (measured {m.nodes_measured})"
            if m.nodes_measured else "") + f"; {res.cells} cells, {res.dofs} dofs, "
            f"{res.load_steps} steps, {res.newton_its} Newton iterations")  # fmt: skip
    for c in found:
        if not c.ok:
            say("  " + c.warning())
    say(f"outputs in {folder.resolve()} ({time.perf_counter() - t0:.1f} s in all)")
    return result


def _picture(folder: Path, res: drape.DrapeResult, r: config.DrapeConfig, title: str) -> None:
    def write(tmp: Path) -> None:
        drape.picture(res, r.pedestal_diameter / 2, r.specimen_diameter / 2, title, tmp)

    try:
        output.atomic_write(folder / "drape.png", write)
    except ImportError:  # no matplotlib: no picture (the numbers are in summary.json)
        print("  WARNING: no drape.png: matplotlib is not installed", flush=True)


def _plain(v):
    if isinstance(v, np.generic):
        return v.item()
    if isinstance(v, np.ndarray):
        return v.tolist()
    return str(v)


def max_membrane_strain(res: drape.DrapeResult) -> float:
    """The largest principal membrane strain of the final state at the reduced quadrature
    points, where the membrane energy holds it (collective). With a fabric's t_eff ≪ cell size
    the PSRI weight puts nearly all membrane energy there (``shell.model``): between them the
    strain is not constrained, and at the vertices it reads 0.25 on a 25 mm M-B drape."""
    import basix.ufl

    from fenics_garment.scene.run import _membrane_strain

    model = res.model
    mesh = model.geometry.mesh
    Qe = basix.ufl.quadrature_element(mesh.basix_cell(), value_shape=(),
                                      degree=model.variant.reduced_degree)  # fmt: skip
    f = _membrane_strain(model, dolfinx.fem.functionspace(mesh, Qe))
    n_cells = mesh.topology.index_map(2).size_local
    local = f.x.array.reshape(-1, len(f.x.array) // max(1, mesh.topology.index_map(2).size_local
                              + mesh.topology.index_map(2).num_ghosts))[:n_cells]  # fmt: skip
    return mesh.comm.allreduce(float(local.max(initial=-math.inf)), op=MPI.MAX)


def _checks(res: drape.DrapeResult, strain: float) -> list[checks.Check]:
    dc = res.dc
    outside = max(-dc, dc - 1.0, 0.0) if math.isfinite(dc) else math.nan
    return [
        checks.Check("instrument", abs(res.dc_flat - res.dc_flat_exact), LIMITS["instrument"],
                     "|DC of the flat specimen's raster − of its exact outline|"),
        checks.Check("membrane_strain", strain, LIMITS["membrane_strain"],
                     "largest principal membrane strain"),
        checks.Check("dc_range", outside, LIMITS["dc_range"], "distance of DC outside [0, 1]"),
    ]  # fmt: skip


def _summary(scene, m: measured.MeasuredFabric, fabric: Fabric, law, res, completed: bool,
             message: str) -> dict:  # fmt: skip
    r = scene.drape
    known = math.isfinite(m.dc_measured)
    s = {
        "scene": scene.name, "kind": "drape", "completed": completed, "message": message,
        "fabric": {
            "id": m.id, "name": m.name,
            "from": (f"{DATA_FILE} ({measured.sources()[m.source]['paper']})" if r.fabric
                     else f"[drape.{'kes' if r.kes else 'clo3d'}] of the scene"),
            "mass_per_area_kg_m2": m.mass_per_area, "thickness_m": m.thickness,
            "B_warp_Nm": m.B_warp, "B_weft_Nm": m.B_weft,
            "stretch_warp_N_m": fabric.E_warp * fabric.thickness,
            "stretch_weft_N_m": fabric.E_weft * fabric.thickness,
            "shear_N_m": fabric.G12 * fabric.thickness,
            "membrane_from": "measured" if m.stretch_warp is not None
                             else measured.MISSING_MEMBRANE_RULE,
            "twoHB_Nm_per_m": m.twoHB, "twoHB_weft_Nm_per_m": m.twoHB_weft,
        },
        "bending": r.bending,
        "bending_law": getattr(law, "__name__", "bending_energy"),
        "specimen_diameter_m": r.specimen_diameter, "pedestal_diameter_m": r.pedestal_diameter,
        "mesh_size_m": r.mesh_size, "imperfection_m": r.imperfection, "seed": r.seed,
        "bending_length_m": (m.B_warp / m.weight_per_area) ** (1 / 3),
        "dc_measured": m.dc_measured if known else None,
        "nodes_measured": m.nodes_measured,
        "dc_clo3d": m.dc_clo3d,
    }  # fmt: skip
    if res is not None:
        s |= {
            "dc": res.dc, "dc_error": res.dc - m.dc_measured if known else None,
            "nodes": res.nodes, "shadow_area_m2": res.shadow_area,
            "dc_flat_raster": res.dc_flat, "dc_flat_exact": res.dc_flat_exact,
            "max_chord_strain": res.edge_strain, "cells": res.cells, "dofs": res.dofs,
            "load_steps": res.load_steps, "newton_iterations": res.newton_its,
            "drape_s": res.wall_s,
        }  # fmt: skip
    return s


def _write_fields(folder: Path, scene: config.Scene, res: drape.DrapeResult, comm) -> None:
    """``final_state.xdmf`` (rank 0, meshio) and ``drape.bp`` (VTX, collective)."""
    if scene.output.xdmf:

        def write() -> None:
            import meshio

            def xdmf(tmp: Path) -> None:
                with meshio.xdmf.TimeSeriesWriter(tmp, data_format="XML") as w:
                    w.write_points_cells(res.reference, [("triangle", res.triangles)])
                    w.write_data(0.0, point_data={
                        "displacement": res.positions - res.reference,
                        "height": res.positions[:, 2].copy()})  # fmt: skip

            output.atomic_write(folder / "final_state.xdmf", xdmf)

        output.guarded(comm, write)
    if scene.output.vtx:
        model = res.model
        u = model.displacement()
        rot = dolfinx.fem.Function(u.function_space, name="rotation")
        rot.interpolate(model.q.sub(1).collapse())

        def vtx(tmp: Path) -> None:
            with dolfinx.io.VTXWriter(comm, tmp, [u, rot], engine="BP4") as w:
                w.write(0.0)

        _collective_dir(comm, folder / "drape.bp", vtx)


def _collective_dir(comm, path: Path, write: Callable[[Path], None]) -> None:
    """A directory written by every rank (ADIOS2), renamed into place by rank 0."""
    import shutil

    tmp = path.with_name(f".{path.name}.part")
    message = None
    try:
        write(tmp)
    except Exception as err:  # whatever the C++ writer threw
        message = f"cannot write {path}: {' '.join(str(err).split())[:200]}"
    message = output.agree(comm, message)
    comm.Barrier()

    def move() -> None:
        if path.exists():
            shutil.rmtree(path)
        tmp.rename(path)

    if message is None:
        output.guarded(comm, move)
    elif comm.rank == 0:
        shutil.rmtree(tmp, ignore_errors=True)
    if message is not None:
        raise output.OutputError(message)


def check(scene: config.Scene, comm: MPI.Comm = MPI.COMM_WORLD) -> str:
    """``fenics-garment check`` of a drape scene: the fabric, the limits and the specimen's mesh
    (no solve); the line printed."""
    limits(scene)
    r = scene.drape
    m = fabric_of(scene)
    bending_law(scene, m)
    model = drape.specimen_model(measured.to_fabric(m), specimen_diameter=r.specimen_diameter,
                                 pedestal_diameter=r.pedestal_diameter, size=r.mesh_size,
                                 amplitude=r.imperfection, seed=r.seed, comm=comm)  # fmt: skip
    cells = model.geometry.mesh.topology.index_map(2).size_global
    dofs = model.Q.dofmap.index_map.size_global * model.Q.dofmap.index_map_bs
    c = (m.B_warp / m.weight_per_area) ** (1 / 3)
    return (f"{scene.source or scene.name}: ok — drape of {m.id} ({m.name}), {r.bending} "
            f"bending; specimen {cells} cells, {dofs} dofs on {comm.size} rank(s); bending "
            f"length (B/W)^(1/3) = {1e3 * c:.1f} mm = {c / r.mesh_size:.2g} cells")  # fmt: skip
