"""Run a scene: build, dress, write outputs (seed paper §4.1, steps 1–12).

Three stages, :func:`build_stage` → :func:`solve_stage` → :func:`write_stage`. Between build and
solve the problem (:class:`~fenics_garment.scene.build.Built`: energy laws, contact and
friction laws, loads, constraints, as plain values) is handed to the scene's
``[physics] terms = "module:function"`` hook and to ``run(..., terms=hook)``, which may replace
laws or add terms (``demos/variants.py``); every output is then derived from the terms in use.

One output folder per run, ``<output.folder>/<name>/``:

* ``scene_used.toml`` — the scene with every default filled in;
* ``dressing.bp`` — VTX (ParaView) time series, one frame per converged dressing step:
  displacement, rotation vector, contact pressure, largest principal membrane strain and the
  membrane stress resultants N_warp, N_weft, N_shear on the garment (P2 fields);
* ``final_state.xdmf`` — final displacement, contact pressure [Pa] and largest principal
  membrane strain at the garment's nodes (one time step: ``meshio.xdmf.TimeSeriesReader``);
* ``body_pressure.vtu`` — the body surface with the pressure at its vertices [Pa] and regions;
  per-region statistics use the garment-side pressure at the contact points (``output``);
* ``summary.json`` and ``pressure_regions.csv`` — per-region pressure (kPa, mmHg, comfort band),
  contact area, penetration, strain, steps, Newton iterations, time split, dofs, ranks;
* ``pressure_garment.png``, ``pressure_body.png`` — front and back pressure maps;
  ``pressure_pattern.png`` — the pressure on the flat pattern pieces (a garment sewn from them),
  and the pieces themselves as ``pattern.toml`` (our format) and ``pattern.dxf`` (DXF-AAMA,
  seams in ``pattern_seams.toml``).
"""

from __future__ import annotations

import math
import os
import re
import shutil
import time
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from fenics_garment import interrupt, mpi_guard, output, sensors
from fenics_garment._stack import MPI, dolfinx, ufl
from fenics_garment.contact import pressure as cpressure
from fenics_garment.contact import uzawa
from fenics_garment.geometry import surface
from fenics_garment.geometry.gmsh_utils import time_limit
from fenics_garment.petsc_options import LINEAR_SOLVERS
from fenics_garment.progress import ProgressLine, expected_solves
from fenics_garment.progress import active as active_line
from fenics_garment.progress import current as current_line
from fenics_garment.scene import build as scene_build
from fenics_garment.scene import checkpoint, checks, config, error_bars, preflight, sequence
from fenics_garment.scene import folder as run_folder
from fenics_garment.scene.dressing import (
    C_ZERO,
    RELEASE_TOLERANCE,
    DressingFailed,
    DressReport,
    DressStep,
    Progress,
    dress,
)
from fenics_garment.shell.model import DEFAULT_ELEMENT
from fenics_garment.solve import NonlinearSolver

#: Newton settings of a scene unless its [solver.petsc] says otherwise. The relative tolerance
#: is loose enough for the round-off floor of a 20–100k-dof contact problem (the solver raises
#: the absolute tolerance to 10× the measured floor by itself). A dressing step that needs more
#: than 15 iterations is cut: on the gilet such steps ran into the 25-iteration limit anyway.
SCENE_SNES_OPTIONS = {"snes_rtol": 1e-8, "snes_max_it": 15}


@dataclass
class RunResult:
    folder: Path
    summary: dict
    regions: list[dict]
    report: DressReport | None  # None: a drape scene (no dressing)
    built: object = field(repr=False)
    completed: bool = True
    message: str = ""
    checks: list[checks.Check] = field(default_factory=list)
    fields: dict = field(default_factory=dict, repr=False)  # final arrays behind the files

    @property
    def checks_passed(self) -> bool:
        return all(c.ok for c in self.checks)


def _membrane_strain(model, V1: dolfinx.fem.FunctionSpace | None = None) -> dolfinx.fem.Function:
    """Largest principal Green–Lagrange membrane strain, interpolated into P1 (or ``V1``)."""
    eps = model.kinematics().membrane
    a, b, d = eps[0, 0], eps[0, 1], eps[1, 1]
    e_max = 0.5 * (a + d) + ufl.sqrt(0.25 * (a - d) ** 2 + b**2)
    V1 = V1 or dolfinx.fem.functionspace(model.geometry.mesh, ("Lagrange", 1))
    f = dolfinx.fem.Function(V1, name="membrane_strain_max")
    f.interpolate(dolfinx.fem.Expression(e_max, V1.element.interpolation_points))
    return f


def _membrane_fields(model) -> ufl.core.expr.Expr:
    """(largest principal membrane strain, N_warp, N_weft, N_shear [N/m]) as one UFL vector:
    one compiled Expression for the four output fields."""
    kin = model.kinematics()
    eps = kin.membrane
    a, b, d = eps[0, 0], eps[0, 1], eps[1, 1]
    e_max = 0.5 * (a + d) + ufl.sqrt(0.25 * (a - d) ** 2 + b**2)
    N = model.membrane_forces()  # of the membrane law in use
    return ufl.as_vector([e_max, N[0, 0], N[1, 1], N[0, 1]])


MEMBRANE_FIELDS = ("membrane_strain_max", "N_warp", "N_weft", "N_shear")


class _Frames:
    """The VTX time series at every converged step, all in P2: displacement, rotation vector,
    contact pressure [Pa], largest principal membrane strain and the membrane stress resultants
    N_warp, N_weft, N_shear [N/m] in the fabric's (warp, weft) frame."""

    def __init__(self, built, folder: Path, enabled: bool):
        self.built, self.enabled = built, enabled
        model = built.model
        mesh = model.geometry.mesh
        self.disp = model.displacement()
        V2v = self.disp.function_space
        self.rot = dolfinx.fem.Function(V2v, name="rotation")
        V2 = dolfinx.fem.functionspace(mesh, ("Lagrange", 2))
        self.p = dolfinx.fem.Function(V2, name="contact_pressure")
        self.scalars = [dolfinx.fem.Function(V2, name=n) for n in MEMBRANE_FIELDS]
        self.path = folder / "dressing.bp"
        self.tmp = folder / ".dressing.bp.part"
        self.writer = None
        if enabled:
            V4 = dolfinx.fem.functionspace(mesh, ("Lagrange", 2, (len(MEMBRANE_FIELDS),)))
            self.packed = dolfinx.fem.Function(V4)
            self.expr = dolfinx.fem.Expression(_membrane_fields(model),
                                               V4.element.interpolation_points)  # fmt: skip
            fields = [self.disp, self.rot, self.p, *self.scalars]
            self._guarded(lambda: setattr(self, "writer", dolfinx.io.VTXWriter(
                mesh.comm, self.tmp, fields, engine="BP4")))  # fmt: skip
        self.k = 0

    def write(self) -> None:
        if self.writer is None:
            return
        m = self.built.model
        self.disp.interpolate(m.q.sub(0).collapse())
        self.rot.interpolate(m.q.sub(1).collapse())
        self.p.interpolate(self.built.contact.pressure())
        self.packed.interpolate(self.expr)
        n = len(self.scalars)
        for k, f in enumerate(self.scalars):  # same P2 nodes: the blocked space's k-th component
            f.x.array[:] = self.packed.x.array[k::n]
        self._guarded(lambda: self.writer.write(float(self.k)))
        self.k += 1

    def _guarded(self, work: Callable[[], object]) -> None:
        """``work()`` on the ADIOS2 writer; a failure on any rank (a full disk: ADIOS2 raises a
        C++ exception, a RuntimeError here) is an OutputError on every rank, decided together
        (``output.agree``), with the partial series removed."""
        comm = self.built.model.geometry.mesh.comm
        message = None
        try:
            work()
        except Exception as err:  # whatever the C++ writer threw
            message = _adios_reason(str(err), self.tmp)
        message = output.agree(comm, message)
        if message is None:
            return
        self.discard(comm)
        raise output.OutputError(message)

    def discard(self, comm: MPI.Comm) -> None:
        """Remove the partial series (after a failure of this or another file, or an
        interruption). The writer is not closed: on a full disk its close, and then its
        destructor, would write again, and a C++ exception in a destructor aborts the process
        (and a collective close can leave one rank waiting for another that gave up). It is
        left alive until the process ends (:func:`_abandon`); its files are emptied and
        removed."""
        writer, self.writer = self.writer, None
        if writer is not None:
            _abandon(writer)
        if comm.rank == 0:
            _empty(self.tmp)  # frees the space at once: the writer keeps its files open
            shutil.rmtree(self.tmp, ignore_errors=True)

    def close(self, comm: MPI.Comm) -> None:
        if self.writer is None:
            return
        self._guarded(self.writer.close)
        comm.Barrier()
        output.guarded(comm, lambda: output.atomic_dir(self.path, lambda tmp: self.tmp.rename(tmp)))
        comm.Barrier()


#: VTX writers that failed (kept alive: see ``_Frames.discard``).
_ABANDONED: list = []


def _empty(folder: Path) -> None:
    for f in folder.glob("*"):
        try:
            os.truncate(f, 0)
        except OSError:
            pass


def _abandon(writer: object) -> None:
    """Keep ``writer`` alive until the process ends, its destructor never run: one more
    reference than any owner will release (the list alone is emptied at interpreter exit)."""
    import ctypes

    _ABANDONED.append(writer)
    ctypes.pythonapi.Py_IncRef(ctypes.py_object(writer))


def _adios_reason(text: str, path: Path) -> str:
    """One line from an ADIOS2 exception: the errno's reason when there is one."""
    plain = re.sub(r"\x1b\[[0-9;]*m", "", text)
    m = re.search(r"errno = (\d+)", plain)
    why = os.strerror(int(m.group(1))) if m else " ".join(plain.split())[:200]
    return f"cannot write {path}: {why}"


def _write_xdmf(folder: Path, garment, fields: dict[str, np.ndarray]) -> None:
    """The final state on the garment's reference mesh, one time step (rank 0).

    Written with meshio as XDMF with inline (XML) data: one grid holding every field, which
    ``meshio.xdmf.TimeSeriesReader`` reads without h5py (DOLFINx's XDMFFile puts each function
    in its own temporal collection, of which meshio reads only one).
    """
    import meshio

    def write(tmp: Path) -> None:
        with meshio.xdmf.TimeSeriesWriter(tmp, data_format="XML") as w:
            w.write_points_cells(garment.points, [("triangle", garment.triangles())])
            w.write_data(0.0, point_data=fields)

    output.atomic_write(folder / "final_state.xdmf", write)


def _write_body_vtu(folder: Path, body, point_data: dict[str, np.ndarray]) -> None:
    """The body with pressure fields [Pa]: ``contact_pressure`` (the garment's pressure at the
    closest point of the deformed garment, as in the pictures) and ``contact_pressure_lumped``
    (contact forces lumped on the body's vertices)."""
    import meshio

    mesh = meshio.Mesh(body.vertices, [("triangle", body.triangles)], point_data=point_data,
                       cell_data={"region": [body.region]})  # fmt: skip
    output.atomic_write(folder / "body_pressure.vtu", lambda p: meshio.write(p, mesh, "vtu"))


def _contact_measures(built) -> dict:
    st, c = built.contact.state, built.contact
    comm = built.model.geometry.mesh.comm
    f = cpressure.point_forces(st, c.traction)
    a = cpressure.point_areas(st, c.area_stretch())
    p = c.pressure_values()
    p_max = comm.allreduce(float(p.max()) if len(p) else 0.0, op=MPI.MAX)
    pen = max(uzawa.max_penetration(st), 0.0)
    return {
        "contact_area_garment_m2": comm.allreduce(float(a[p > 0].sum()), op=MPI.SUM),
        "contact_force_N": comm.allreduce(float(f.sum()), op=MPI.SUM),
        "max_pressure_kPa": p_max * 1e-3,
        "max_penetration_m": pen,
        "max_penetration_over_thickness": pen / built.model.stiffness.thickness,
    }


def contact_points_by_region(built) -> tuple[np.ndarray, ...]:
    """(body region, pressure [Pa], deformed area [m²], sensor reading [Pa]) of every contact
    point in contact, gathered on all ranks, and the sensors lying on the body
    (:func:`output.body_sensors`); the region is that of the closest body triangle, the sensor
    reading :func:`output.sensor_pressure` with the scene's sensor (:func:`sensors.pad`)."""
    st, c = built.contact.state, built.contact
    comm = built.model.geometry.mesh.comm
    p = c.pressure_values()
    a = cpressure.point_areas(st, c.area_stretch())
    x = cpressure.positions(st)
    on = p > 0
    faces = built.search_body.closest(x[on]).face
    parts = comm.allgather((built.body.region[faces], p, a, x, on))
    region, p, a, x, on = (np.concatenate([q[k] for q in parts]) for k in range(5))
    radius = 0.5 * sensors.pad(built.scene.output)[1]
    sensor = output.sensor_pressure(x[on], x, p * a, a, radius)
    b = built.body
    centres = b.vertices[b.triangles].mean(axis=1)
    weight = surface.areas(b.vertices, b.triangles)
    body = output.body_sensors(centres, b.region, weight, x, p * a, a, radius)
    return region, p[on], a[on], sensor, body


def gathered_points(built) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(pressure [Pa], deformed area [m²], position [m]) of every garment contact point,
    gathered on all ranks (collective)."""
    st, c = built.contact.state, built.contact
    parts = built.model.geometry.mesh.comm.allgather(
        (c.pressure_values(), cpressure.point_areas(st, c.area_stretch()), cpressure.positions(st))
    )
    p, a, x = (np.concatenate([q[k] for q in parts]) for k in range(3))
    return p, a, x


def sensor_table(built) -> tuple[list[dict], str | None]:
    """The sensors at anatomical points (:mod:`fenics_garment.sensors`, ``[output]
    sensor_instrument``) read from the garment's contact points gathered on all ranks
    (collective), and why there are none (a body without landmarks) or None."""
    p, a, x = gathered_points(built)
    try:
        placed = sensors.place(built.body)
    except sensors.NoLandmarks as e:
        return [], str(e)
    instrument, d = sensors.pad(built.scene.output)
    return sensors.read(placed.centres, x, p * a, a, d, instrument), None


def element_warning(variant) -> str | None:
    """The WARNING line for a shell element that has not passed the verification table."""
    if variant.verified:
        return None
    return (f"WARNING: element {variant.name} is a draft option, not verified: it locks in "
            f"bending on thin shells (docs/verification/shells.md); the verified element is "
            f"{DEFAULT_ELEMENT}")  # fmt: skip


#: A hook that edits the built problem between build and solve: ``hook(built) -> None``.
#: ``built`` (:class:`~fenics_garment.scene.build.Built`) is the scene's problem as plain values:
#: ``built.model`` (the shell's energy laws ``membrane``, ``bending``, ``shear``, ``drilling``,
#: plus ``add_energy`` / ``add_residual`` / loads), ``built.contact`` (``normal_law``,
#: ``friction`` with its ``law``, ``kappa``), ``built.bcs``, ``built.regularisation``;
#: ``built.terms()`` lists what is in use. Everything downstream — the residual, the stick/slip
#: and multiplier updates, the pressure and membrane-force outputs — is made from it.
TermsHook = Callable[[scene_build.Built], None]


def run(
    scene: config.Scene,
    out_root: str | Path | None = None,
    *,
    quiet: bool = False,
    comm: MPI.Comm = MPI.COMM_WORLD,
    first_step: float | None = None,
    resume: str | Path | None = None,
    checkpoints: bool = True,
    record: config.Scene | None = None,
    clear: bool = True,
    terms: TermsHook | None = None,
) -> RunResult:
    """Build, dress and write every output of ``scene`` (see the module doc).

    Three stages: :func:`build_stage` (body, garment, model, contact: the problem),
    :func:`solve_stage` (the dressing) and :func:`write_stage` (fields, checks, files). Between
    the first two the problem can be edited: by the scene's ``[physics] terms = "module:function"``
    (:func:`fenics_garment.scene.config.load_terms`), then by ``terms`` (a :data:`TermsHook`),
    e.g. ``run(scene, terms=lambda built: setattr(built.model, "membrane", my_law))``.

    ``first_step`` (a fraction of the initial shrink) overrides the first dressing step.
    A dressing that fails after its step cuts still writes the outputs of the last converged
    state; the result then has ``completed = False`` and the reason in ``message``. Every
    result carries its checks (``scene.checks``; ``checks_passed``).
    ``checkpoints``: write ``checkpoint/`` after every converged solve (``scene.checkpoint``);
    ``resume``: the folder of an interrupted run of ``scene``, continued from its checkpoint
    (:class:`~fenics_garment.scene.checkpoint.ResumeError` if it has none, another scene, or a
    damaged one). The folder is locked while the run writes it, a fresh run first removes an
    earlier run's outputs (``clear``), and ``run.json`` records its id and state
    (``scene.folder``). ``record``: the scene written to ``scene_used.toml`` and fingerprinted
    in the checkpoints (default ``scene``; the error bars' fine level records the whole run).
    Raises :class:`~fenics_garment.scene.preflight.PreflightError` before any solve when the
    output folder cannot be written or the scene cannot be dressed (``scene.preflight``), and
    :class:`~fenics_garment.output.OutputError` when a file cannot be written mid-run.
    """
    if scene.kind == "drape":  # a Cusick drape test: its own run (scene.drape)
        from fenics_garment.scene import drape

        if terms is not None or scene.physics.terms:
            raise preflight.PreflightError("a drape scene takes no terms hook")
        return drape.run(scene, out_root, quiet=quiet, comm=comm, resume=resume)
    if scene.output.error_bars and record is None:  # two mesh levels (scene.error_bars)
        return error_bars.run_with_error_bars(
            run, scene, out_root, quiet=quiet, comm=comm, resume=resume, first_step=first_step,
            checkpoints=checkpoints, terms=terms,
        )  # fmt: skip
    recorded = record or scene
    preflight.scene_limits(scene)
    meta = None
    if resume is not None:
        folder = Path(resume)
        meta = checkpoint.read(folder, recorded, comm)
    else:
        folder = run_folder.inside(Path(out_root if out_root is not None else
                                        scene.output.folder), scene.name)  # fmt: skip
    preflight.output_folder(folder, comm)
    state = run_folder.RunFolder(folder, comm)
    state.acquire()
    mpi_guard.ON_ABORT.append(state.mark_failed)
    interrupt.ON_STOP.append(state.mark_interrupted)
    try:
        state.start(fresh=meta is None, clear=clear)
        line = ProgressLine(enabled=comm.rank == 0 and not quiet)
        with active_line(line):
            result = _run_in(state, scene, recorded, meta, first_step=first_step,
                             checkpoints=checkpoints, terms=terms)  # fmt: skip
    except output.OutputError as err:
        state.finish("failed", collective=False, error=str(err), stage=interrupt.stage())
        err.folder = err.folder or folder
        err.checkpoint = checkpoint.exists(err.folder)
        raise
    except interrupt.Interrupted as err:
        err.folder = err.folder or folder
        err.checkpoint = checkpoint.exists(folder)
        state.finish("interrupted", collective=False, signal=interrupt.signal_name(err.signum),
                     stage=err.stage)  # fmt: skip
        raise
    except BaseException:
        state.finish("failed", collective=False)
        raise
    finally:
        mpi_guard.ON_ABORT.remove(state.mark_failed)
        interrupt.ON_STOP.remove(state.mark_interrupted)
        state.release()
    return result


#: Exit codes of a run (the CLI's): done; the dressing stopped (last converged state written);
#: done but a result check failed (a WARNING each; outputs written, ``summary.json`` checks).
EXIT_DONE, EXIT_STOPPED, EXIT_CHECKS = 0, 3, 4


def exit_code(result: RunResult) -> int:
    if not result.completed:
        return EXIT_STOPPED
    return EXIT_DONE if result.checks_passed else EXIT_CHECKS


def _status(result: RunResult) -> str:
    if not result.completed:
        return "stopped"
    return "completed" if result.checks_passed else "checks failed"


def _check_terms(built: scene_build.Built) -> None:
    """The edited problem's laws fit the scene's solver, or a one-line SceneError: the
    augmented Lagrangian needs a normal law that is a constraint (uzawa.require_constraint)."""
    scene = built.scene
    if scene.physics.contact != "augmented-lagrangian":
        return
    try:
        uzawa.require_constraint(built.contact.state)
    except uzawa.SoftLawError as err:
        raise config.SceneError(scene.source, "physics.contact", str(err)) from None


def _run_in(
    state: run_folder.RunFolder,
    scene: config.Scene,
    recorded: config.Scene,
    meta: dict | None,
    *,
    first_step: float | None,
    checkpoints: bool,
    terms: TermsHook | None = None,
) -> RunResult:
    """The run itself, in its locked folder: build, edit, solve, write. Its lines go through
    the progress line (:func:`fenics_garment.progress.current`: silent with ``quiet``)."""
    folder, comm = state.path, state.comm
    t_start = time.perf_counter()
    say = current_line().say
    text = config.dumps(recorded)
    output.guarded(comm, lambda: output.write_text(folder / "scene_used.toml", text))
    times: dict[str, float] = {}
    hooks = [h for h in (config.load_terms(scene.physics.terms, scene.source), terms) if h]
    depends = checkpoint.depends(scene, hooks)
    if meta is not None:
        checkpoint.check_depends(meta, depends, folder, later=("meshes",))
    interrupt.set_stage("while building the scene")
    built = build_stage(scene, comm, say, times, check=meta is None)
    depends["meshes"] = checkpoint.mesh_digest(built)
    if meta is not None:
        checkpoint.check_depends(meta, depends, folder)
    interrupt.poll(comm)

    def edit(b: scene_build.Built) -> None:
        for hook in hooks:
            hook(b)

    edit(built)
    _check_terms(built)
    tight = checks.tight_area(built)  # of the pattern, before the dressing moves it
    start, levels = None, []
    if meta is None:
        start, levels = sequence_stage(built, say, times, edit, first_step=first_step)
        first_step = None if start is not None else first_step
    solved = solve_stage(built, folder, recorded, meta, say, times, first_step=first_step,
                         checkpoints=checkpoints, start=start, depends=depends)  # fmt: skip
    if start is None and levels:  # a coarser level did not dress: this mesh was dressed directly
        solved.report.levels = levels
        solved.report.sequence_failed = levels[-1]["message"]
    current_line().stage("writing the outputs")
    interrupt.set_stage("while writing the outputs (the dressing is complete)")
    interrupt.poll(comm)
    result = write_stage(built, solved, tight, times, t_start)
    result.summary["run_id"] = state.run_id
    _write_outputs(folder, built, result)
    if scene.output.report:
        write_report(folder, comm, say, result.summary)
    state.finish(_status(result))
    _print_regions(say, result.regions)
    _print_sensors(say, result.summary)
    for c in result.checks:
        if not c.ok:
            say("  " + c.warning())
    current_line().close()
    say(f"outputs in {folder.resolve()} ({times['total']:.1f} s in all)")
    return result


def build_stage(
    scene: config.Scene,
    comm: MPI.Comm,
    say: Callable[..., object] = lambda *a: None,
    times: dict[str, float] | None = None,
    *,
    check: bool = True,
    body=None,
) -> scene_build.Built:
    """Stage 1: the problem of ``scene`` (:func:`fenics_garment.scene.build.build`), checked
    (``check``: ``scene.preflight``) but not yet compiled: edit it before :func:`solve_stage`.
    ``body``: the scene's body when it is made already (another garment level)."""
    t0 = time.perf_counter()
    if body is None:
        say(f"scene {scene.name!r}: {scene.garment.fabric} {scene.garment.kind} on a "
            f"{scene.body.kind} body, {comm.size} rank(s)")  # fmt: skip
    current_line().stage("meshing and building the model")
    built = scene_build.build(scene, comm, body)
    elapsed = time.perf_counter() - t0
    if times is not None:
        times["geometry_and_model"] = elapsed
    say(f"  garment: {len(built.garment.cells)} cells, element {scene.garment.element}, "
        f"{built.dofs} dofs ({elapsed:.1f} s)")  # fmt: skip
    if (warning := element_warning(built.model.variant)) is not None:
        say("  " + warning)
    if (notice := preflight.problem_size(scene, built.dofs, comm)) is not None:
        say("  " + notice)
    if check:
        preflight.check_built(built)
    return built


@dataclass
class Solved:
    """What :func:`solve_stage` leaves for :func:`write_stage`."""

    solver: NonlinearSolver
    report: DressReport
    completed: bool
    message: str


def solve_stage(
    built: scene_build.Built,
    folder: Path,
    recorded: config.Scene,
    meta: dict | None,
    say: Callable[..., object],
    times: dict[str, float],
    *,
    first_step: float | None = None,
    checkpoints: bool = True,
    start: Progress | None = None,
    depends: dict[str, str] | None = None,
) -> Solved:
    """Stage 2: compile the residual of the problem as it is now and dress (VTX frames and
    checkpoints on the way; ``meta``: the checkpoint to resume from; ``start``: where a fresh
    dressing starts, the state already in the model: :func:`sequence_stage`; ``depends``: what
    the checkpoints record besides the scene, :func:`.checkpoint.depends`)."""
    scene, comm = built.scene, built.model.geometry.mesh.comm
    t0 = time.perf_counter()
    say("  compiling the forms (FFCx JIT; cached for later runs) ...")
    current_line().stage("JIT: compiling the forms")
    interrupt.set_stage("while compiling the forms")
    hint = "see the dofs above; a coarser garment.mesh_size makes them fewer"
    what, why = "compiling the forms and allocating the Jacobian", "a hung C compiler or too large"
    with time_limit(JIT_TIME_LIMIT, what, by="the FFCx JIT", why=why, hint=hint):
        solver = scene_solver(built)
    solver.progress = _slow_iterations(say)
    frames = _Frames(built, folder, scene.output.vtx and scene.output.every_step)
    times["jit"] = time.perf_counter() - t0
    if times["jit"] >= SLOW_ITERATION_S:  # the JIT, or the Jacobian's sparsity of a large mesh
        say(f"  forms compiled and the Jacobian allocated ({times['jit']:.0f} s)")
    interrupt.poll(comm)
    t0 = time.perf_counter()
    progress = start
    if meta is not None:
        progress = checkpoint.restore(built, folder, meta)
        frames.k = len(progress.report.steps)
        say(f"  resuming from checkpoint {meta['checkpoint']} ({progress.stage}, shrink "
            f"{progress.shrink * 1e3:.2f} mm, {frames.k} solves done)")  # fmt: skip
    ckpt = checkpoint.Writer(folder, recorded, comm, meta["checkpoint"] if meta else 0,
                             depends)  # fmt: skip
    kappa0 = float(built.contact.kappa.value)
    try:
        report, completed, message = _dress(built, solver, frames, ckpt if checkpoints else None,
                                            progress, first_step, say)  # fmt: skip
        if start is not None and (not completed or report.final_regularisation > 0.0):
            # the carried state did not settle on this mesh (or only with the spring that
            # holds it there): dress it directly, as without a sequence (the coarser levels
            # stay in the report; the run says why)
            message = message or "the spring anchored at the carried state was not released"
            say(f"  the settling on the scene's mesh failed ({message}): dressing it from the "
                "start")  # fmt: skip
            sequence.reset(built, kappa0)
            levels, why = report.levels, message
            report, completed, message = _dress(built, solver, frames,
                                                ckpt if checkpoints else None, None, first_step,
                                                say)  # fmt: skip
            report.levels, report.sequence_failed = levels, why
    except output.OutputError:
        frames.discard(comm)  # e.g. a checkpoint hit a full disk: no partial series left
        raise
    except interrupt.Interrupted:  # (raised by a poll: on every rank at once)
        frames.discard(comm)
        raise
    times["dressing"] = time.perf_counter() - t0 - ckpt.seconds
    times["checkpoint"] = ckpt.seconds
    al = report.al_iterations
    passes = f" + {len(al)} multiplier passes ({sum(al)} its)" if al else ""
    say(f"  dressed: {len(report.steps)} solves, {report.newton_iterations} Newton iterations"
        f"{passes}, {len(report.failures)} cut(s) ({times['dressing']:.1f} s)")  # fmt: skip
    _say_release(say, built, report, completed)
    if report.answer_note:
        say(f"  note: {report.answer_note}")
    if report.al_message:
        say(f"  WARNING: {report.al_message}")
    if completed:
        frames.write()
    frames.close(comm)
    return Solved(solver, report, completed, message)


#: A Newton iteration longer than this [s] is reported when it ends (``NonlinearSolver.progress``):
#: a large problem (``preflight.problem_size``) would otherwise print nothing for minutes between
#: two dressing steps (the 10 m tube: 97 s an iteration on one rank).
SLOW_ITERATION_S = 10.0
#: Seconds the FFCx JIT and the Jacobian's allocation may take before the run stops with one
#: line (exit 2): the P1-P1 gilet's Jacobian takes 25–60 s of gcc, the 10 m tube's 1.28 M dofs
#: about 70 s of allocation; another process compiling the same form is waited for
#: (:mod:`fenics_garment.jit_wait`) within this limit too.
JIT_TIME_LIMIT = 1800.0


def _slow_iterations(say: Callable[..., object]) -> Callable[[int, float, float], None]:
    """The solver's progress hook: every Newton iteration on the progress line, and a line of
    its own for a slow one."""

    def on_iteration(its: int, fnorm: float, seconds: float) -> None:
        current_line().newton(its, fnorm)
        if seconds >= SLOW_ITERATION_S:
            say(f"    Newton iteration {its}: residual {fnorm:.3g} ({seconds:.0f} s)")

    return on_iteration


def _dressing_stage(built: scene_build.Built, progress_from: Progress | None) -> None:
    """The progress line's dressing stage, with the solves the fixed schedule foresees
    (:func:`fenics_garment.progress.expected_solves`; unknown on the adaptive schedule); a
    resumed dressing counts the solves done before."""
    d = built.scene.dressing
    total = None
    if d.schedule == "fixed":
        sew = d.sew_steps if built.garment.rest is not None else 0
        c0 = built.regularisation.c0
        total = expected_solves(d.steps, sew, c0, d.release_ratio, C_ZERO)
    h = built.scene.garment.mesh_size
    current_line().stage(f"dressing ({h * 1e3:.0f} mm garment mesh)", total)
    if progress_from is not None and progress_from.report is not None:
        current_line().state.step = len(progress_from.report.steps)


def scene_solver(built: scene_build.Built) -> NonlinearSolver:
    """Newton on the problem of ``built`` with the scene's solver settings and contact hooks."""
    scene = built.scene
    opts = {**SCENE_SNES_OPTIONS, **LINEAR_SOLVERS[scene.solver.linear], **scene.solver.petsc}
    return NonlinearSolver(built.model, built.bcs, **built.contact.solver_hooks(),
                           petsc_options=opts, prefix=f"scene{id(built)}_")  # fmt: skip


def sequence_stage(
    built: scene_build.Built,
    say: Callable[..., object],
    times: dict[str, float],
    edit: Callable[[scene_build.Built], None],
    *,
    first_step: float | None = None,
) -> tuple[Progress | None, list[dict]]:
    """Mesh sequencing (``[dressing] sequence``, :mod:`fenics_garment.scene.sequence`): dress on
    each coarser garment mesh in turn (``edit``: the scene's terms hooks, applied to every level
    as to ``built``), carry each dressed state to the next level and the last into ``built``.
    Returns where ``built``'s dressing starts — None: no sequence, or a coarser level did not
    dress (then ``built`` is dressed from the start, and the run says so) — and the coarser
    levels' records."""
    coarse = sequence.coarse_scenes(built.scene)
    if not coarse:
        return None, []
    comm = built.model.geometry.mesh.comm
    t0 = time.perf_counter()
    levels: list[dict] = []
    previous = None
    for level_scene in coarse:
        h = level_scene.garment.mesh_size
        t1 = time.perf_counter()
        level = build_stage(level_scene, comm, say, body=built.body)
        edit(level)
        solver = scene_solver(level)
        start = None
        if previous is not None:
            if (why := _carry(previous, level)) is not None:
                return _unsequenced(built, levels, why, say, times, t0)
            start = sequence.settling(level, levels, levels[-1]["stiffening"])
        kappa0 = float(level.contact.kappa.value)
        say(f"  level {h * 1e3:.1f} mm of the mesh sequence ({level.dofs} dofs):")
        report, completed, message = _dress(
            level, solver, None, None, start,
            first_step if previous is None else None, say,
        )  # fmt: skip
        levels.append({"mesh_size_m": h, "dofs": level.dofs, "completed": completed,
                       "solves": len(report.steps), "newton_iterations": report.newton_iterations,
                       "all_newton_iterations": report.all_newton_iterations,
                       "failed_attempts": len(report.failures),
                       "multiplier_passes": len(report.al_iterations),
                       "stiffening": float(level.contact.kappa.value) / kappa0,
                       "seconds": time.perf_counter() - t1})  # fmt: skip
        if not completed:
            why = f"level {h * 1e3:.1f} mm did not dress: {message}"
            return _unsequenced(built, levels, why, say, times, t0)
        previous = level
    if (why := _carry(previous, built)) is not None:
        return _unsequenced(built, levels, why, say, times, t0)
    times["sequence"] = time.perf_counter() - t0
    say(f"  carried over to the scene's mesh ({times['sequence']:.1f} s for the coarser levels)")
    return sequence.settling(built, levels, levels[-1]["stiffening"]), levels


def _carry(coarse: scene_build.Built, fine: scene_build.Built) -> str | None:
    """:func:`sequence.carry_over`; the reason when the levels do not fit together (the same on
    every rank), else None."""
    try:
        sequence.carry_over(coarse, fine)
    except sequence.SequenceError as err:
        return f"the state could not be carried over: {err}"
    return None


def _unsequenced(
    built: scene_build.Built, levels: list[dict], why: str, say, times: dict, t0: float
) -> tuple[None, list[dict]]:
    """The mesh sequence stops (``why``): ``built`` goes back to the undressed pattern, to be
    dressed from the start; the levels' records carry the reason."""
    sequence.reset(built, float(built.contact.kappa.value))
    levels[-1]["message"] = why
    say(f"  {why}; dressing on the scene's mesh from the start")
    times["sequence"] = time.perf_counter() - t0
    return None, levels


def write_stage(
    built: scene_build.Built, solved: Solved, tight: float, times: dict[str, float], t_start: float
) -> RunResult:
    """Stage 3: the fields, measures, checks and summary of the final state (collective), all
    from the problem's terms in use; the files are written by the caller."""
    t0 = time.perf_counter()
    result = _outputs(built, solved.solver, solved.report, (solved.completed, solved.message),
                      tight, times)  # fmt: skip
    times["outputs"] = time.perf_counter() - t0
    times["total"] = time.perf_counter() - t_start
    return result


def _dress(
    built: scene_build.Built,
    solver: NonlinearSolver,
    frames: _Frames | None,
    ckpt: checkpoint.Writer | None,
    progress: Progress | None,
    first_step: float | None,
    say: Callable[..., object],
) -> tuple[DressReport, bool, str]:
    """The dressing with its progress lines: (report, completed, message)."""
    scene = built.scene
    d, p = scene.dressing, scene.physics
    h = built.model.stiffness.thickness  # the tolerance is a fraction of it
    al = (p.tolerance * h, p.max_updates) if p.contact == "augmented-lagrangian" else None

    comm = built.model.geometry.mesh.comm
    solves = 0

    def on_step(rec: DressStep) -> None:
        nonlocal solves
        solves += 1
        if frames is not None:  # (None: a coarser level of a mesh sequence)
            frames.write()
        cut = f"  (after {rec.cuts} cut{'s' * (rec.cuts > 1)})" if rec.cuts else ""
        what = (f"shrink {rec.shrink * 1e3:6.2f} mm" if rec.stage == "dress"
                else f"sewn {rec.shrink:10.3f}   " if rec.stage == "sew"
                else f"spring c {rec.regularisation:8.2g} Pa/m")  # fmt: skip
        say(f"  {what}   Newton its {rec.iterations:2d}   {rec.seconds:5.1f} s{cut}")
        kind = {"dress": "shrink", "sew": "sewing"}.get(rec.stage, "spring release")
        current_line().step(kind, spring=rec.regularisation)
        level = "" if frames is not None else " of a coarser mesh level"
        interrupt.set_stage(f"while dressing{level} (after solve {solves}: "
                            f"{' '.join(what.split())})")  # fmt: skip

    def on_failure(target: float, its: int, reason: int, what: str = "shrink") -> None:
        to = f"{target * 1e3:6.2f} mm" if what == "shrink" else f"{target:.3f}"
        say(f"  {what} → {to} failed (SNES reason {reason}, {its} its): halving the step")
        interrupt.poll(comm)

    def on_checkpoint(pr: Progress) -> None:
        if ckpt is not None:
            ckpt.write(built, pr)
        interrupt.poll(comm)  # after the checkpoint: a resume loses no solve

    _dressing_stage(built, progress_from=progress)
    try:
        report = dress(built, solver, steps=d.steps, margin=d.margin, max_cuts=d.max_cuts,
                       grow=d.grow, first_step=first_step, on_step=on_step,
                       on_failure=on_failure, augmented_lagrangian=al,
                       on_checkpoint=on_checkpoint, resume=progress, schedule=d.schedule,
                       friction_while_growing=d.friction_while_growing,
                       release_ratio=d.release_ratio, predictor=d.predictor,
                       path_tolerance=d.path_tolerance,
                       release_multipliers=d.release_multipliers,
                       sew_steps=d.sew_steps)  # fmt: skip
    except DressingFailed as err:
        say("  " + str(err))
        return err.report, False, str(err)
    return report, True, ""


def _say_release(
    say: Callable[..., object], built: scene_build.Built, report: DressReport, completed: bool
) -> None:
    effect = report.regularisation_effect
    grew_only = not any(step.stage == "release" for step in report.steps)
    if not completed and grew_only and report.final_regularisation == 0.0:
        # stopped while the body grew: the release was never reached
        if built.regularisation.c0 > 0:
            say(f"  the stabilising spring (c = {built.regularisation.c0:.3g} Pa/m) was not "
                "released: the dressing stopped before the body reached its size")  # fmt: skip
    elif report.final_regularisation > 0 and not effect <= RELEASE_TOLERANCE:
        why = ("no release solve converged" if math.isnan(effect) else
               f"its last release changed the pressure by {effect:.2%}, more than "
               f"{RELEASE_TOLERANCE:.0%}")  # fmt: skip
        say(f"  WARNING: the stabilising spring is not fully released: c = "
            f"{report.final_regularisation:.3g} Pa/m remains ({why}); its traction is at most "
            f"{report.spring_traction:.3g} Pa, against contact pressures up to "
            f"{_contact_measures(built)['max_pressure_kPa'] * 1e3:.3g} Pa")  # fmt: skip
    elif report.final_regularisation > 0:
        say(f"  stabilising spring released to c = {report.final_regularisation:.3g} Pa/m "
            f"(from {built.regularisation.c0:.3g}); its last weakening changed the pressure by "
            f"{effect:.2%}, below the {RELEASE_TOLERANCE:.0%} tolerance")  # fmt: skip
    else:
        say(f"  stabilising spring fully released; its last stage changed the pressure by "
            f"{effect:.2%}")  # fmt: skip


def _outputs(
    built: scene_build.Built,
    solver: NonlinearSolver,
    report: DressReport,
    outcome: tuple[bool, str],
    tight: float,
    times: dict[str, float],
) -> RunResult:
    """Fields, measures, checks and the summary of the final state (collective)."""
    completed, message = outcome
    scene = built.scene
    comm = built.model.geometry.mesh.comm
    strain = _membrane_strain(built.model)
    st = built.contact.state
    p_lumped = cpressure.body_pressure(st, built.contact.traction, built.search_body)
    regions = output.region_table(built.body.regions, *contact_points_by_region(built))
    sensor_rows, sensors_skipped = sensor_table(built)
    x_g, p_g = garment_arrays(built)  # collective
    eps_g = output.garment_node_values(built.garment, strain)[:, 0]
    reach = 0.75 * scene.garment.mesh_size
    p_body = cpressure.body_pressure_map(built.contact.pressure(), built.model.displacement(),
                                         built.body.vertices, reach)  # fmt: skip
    measures = _contact_measures(built)
    applied, reaction = checks.forces(built)
    found = checks.result_checks(built, measures, report.spring_traction, tight,
                                 (applied, reaction), regions)  # fmt: skip
    max_strain = comm.allreduce(float(strain.x.array.max()), op=MPI.MAX)
    summary = {
        "scene": scene.name,
        "completed": completed,
        "message": message,
        "checks_passed": all(c.ok for c in found),
        "checks": {c.name: c.as_dict() for c in found},
        "garment": scene.garment.kind,
        "fabric": scene.garment.fabric,
        "element": scene.garment.element,
        "element_verified": built.model.variant.verified,
        "geometry_degree": built.model.geometry.mesh.geometry.cmaps[0].degree,
        "dofs": built.dofs,
        "garment_cells": len(built.garment.cells),
        "body_triangles": len(built.body.triangles),
        "body_triangles_dropped": built.search_body.dropped,  # outside the garment's reach
        "ranks": comm.size,
        **measures,
        "tight_area_m2": tight,  # of the pattern inside the body at the start
        "forces_N": {"applied": applied.tolist(), "reaction": reaction.tolist()},
        "max_membrane_strain": max_strain,
        "terms": built.terms(),  # the laws and terms of the problem solved
        "dressing": report.as_dict(),
        # the garment's stress-free state: its loft, or flat pattern pieces (a pattern file's,
        # or the loft's flattened: [garment] rest)
        "garment_rest": "pattern" if built.model.geometry.rest is not None else "loft",
        "dressing_schedule": scene.dressing.schedule,  # the path (scene.dressing module doc)
        "dressing_steps": scene.dressing.steps,
        "dressing_path": scene.dressing.path(),
        # ℓ of the penalty κ̂ E h / ℓ² (0: the garment's largest cell; config.PhysicsConfig)
        "penalty_length_m": scene.physics.penalty_length,
        "time_s": times,
        "solver_time_s": {
            k: v for k, v in solver.timings.as_dict().items() if k not in ("steps", "cuts")
        },  # LoadStepper's, unused here
        "contact_search_s": st.timings.search_s,
        "regions": regions,
        "sensors": sensor_rows,  # at anatomical points (fenics_garment.sensors)
    }
    if sensors_skipped:
        summary["sensors_skipped"] = sensors_skipped
    fields = {"x_g": x_g, "p_g": p_g, "eps_g": eps_g, "p_body": p_body, "p_lumped": p_lumped}
    return RunResult(Path(), summary, regions, report, built, completed, message, found, fields)


def _write_outputs(folder: Path, built: scene_build.Built, result: RunResult) -> None:
    """The files of rank 0 (a write failure is an OutputError on every rank)."""
    scene, f = built.scene, result.fields
    result.folder = folder

    def write() -> None:
        if scene.output.xdmf:
            _write_xdmf(folder, built.garment, {"displacement": f["x_g"] - built.garment.points,
                                                "contact_pressure": f["p_g"],
                                                "membrane_strain_max": f["eps_g"]})  # fmt: skip
        output.write_summary(folder, result.summary, result.regions)
        if result.summary.get("sensors"):
            output.write_text(folder / "pressure_sensors.csv",
                              output.csv_text(result.summary["sensors"]))  # fmt: skip
        _write_body_vtu(folder, built.body, {"contact_pressure": f["p_body"],
                                             "contact_pressure_lumped": f["p_lumped"]})  # fmt: skip
        if scene.output.pictures:
            _pictures(folder, built, (f["x_g"], f["p_g"]), f["p_body"])
        if built.garment.rest is not None:
            _write_pattern(folder, built)
        if scene.output.report:
            t0 = time.perf_counter()
            _write_surfaces(folder, built, f)
            result.summary["time_s"]["report"] = time.perf_counter() - t0

    output.guarded(built.model.geometry.mesh.comm, write)


def _write_surfaces(folder: Path, built: scene_build.Built, f: dict) -> None:
    """The surfaces of the report's 3D view (:mod:`fenics_garment.report.surfaces`): the body
    and the deformed garment with their pressure [Pa]."""
    from fenics_garment.report import Surface, write_surfaces

    b = built.body
    write_surfaces(folder, Surface.of(b.vertices, b.triangles, f["p_body"]),
                   Surface.of(f["x_g"], built.garment.triangles(), f["p_g"]))  # fmt: skip


def write_report(folder: Path, comm: MPI.Comm, say: Callable[..., object], summary: dict) -> None:
    """``report.html`` of the run in ``folder`` (rank 0; collective); its time is added to
    ``time_s.report`` of ``summary.json`` (with the surfaces'). A report that cannot be built is
    a WARNING (the run's own outputs are written); one that cannot be written (a full disk) is an
    :class:`~fenics_garment.output.OutputError`, as for every file."""
    from fenics_garment.report import write_report as write_html

    def write() -> None:
        try:
            path, seconds = write_html(folder)
        except OSError:
            raise
        except Exception as err:  # a bug of the report: the run's results stand
            print(f"  WARNING: the HTML report was not written: {type(err).__name__}: {err}",
                  flush=True)  # fmt: skip
            return
        summary["time_s"]["report"] = summary["time_s"].get("report", 0.0) + seconds
        output.write_summary(folder, summary, summary["regions"])
        say(f"  report: {path.name} ({path.stat().st_size / 1e6:.1f} MB, "
            f"{summary['time_s']['report']:.1f} s)")  # fmt: skip

    output.guarded(comm, write)


def _write_pattern(folder: Path, built: scene_build.Built) -> None:
    """The garment's flat pieces as a pattern: ``pattern.toml`` (our format) and
    ``pattern.dxf`` (DXF-AAMA) with its seams in ``pattern_seams.toml``."""
    from fenics_garment.pattern.dxf import write_dxf
    from fenics_garment.pattern.export import garment_pattern
    from fenics_garment.pattern.io import write_pattern

    try:
        pattern = garment_pattern(built.garment, built.scene.name)
    except ValueError as err:  # (on rank 0 only: never raised past here, the others wait)
        print(f"  WARNING: the flat pieces were not written as a pattern: {err}", flush=True)
        return
    write_pattern(pattern, folder / "pattern.toml")
    write_dxf(pattern, folder / "pattern.dxf", companion=folder / "pattern_seams.toml")


def garment_arrays(built) -> tuple[np.ndarray, np.ndarray]:
    """Deformed garment points and nodal pressure [Pa], in gmsh node order (every rank)."""
    mesh = built.model.geometry.mesh
    V1v = dolfinx.fem.functionspace(mesh, ("Lagrange", 1, (3,)))
    u1 = dolfinx.fem.Function(V1v)
    u1.interpolate(built.model.q.sub(0).collapse())
    u = output.garment_node_values(built.garment, u1)
    p = output.garment_node_values(built.garment, built.contact.pressure())[:, 0]
    return built.garment.points + u, p


def _pictures(folder: Path, built, garment_xp, p_body: np.ndarray) -> None:
    x, p = garment_xp
    # colour bar up to the 99th percentile: a single hot node at an armhole edge would
    # otherwise make the whole map one colour (the summary keeps the true maximum)
    touching = p[p > 0]
    top = float(np.percentile(touching, 99)) * 1e-3 if len(touching) else 1e-3
    tri = built.garment.triangles()
    b = built.body
    output.pressure_png(folder / "pressure_garment.png", x, tri, p,
                        f"{built.scene.garment.fabric} {built.scene.garment.kind}",
                        under=(b.vertices, b.triangles), vmax_kpa=top)  # fmt: skip
    output.pressure_png(folder / "pressure_body.png", b.vertices, b.triangles, p_body,
                        "body", vmax_kpa=top)  # fmt: skip
    if built.garment.rest is not None:  # sewn from flat pieces: the pressure on the pattern
        title = f"{built.scene.name} ({built.scene.garment.fabric})"
        output.pattern_png(folder / "pressure_pattern.png", built.garment.rest, p, title,
                           vmax_kpa=top)  # fmt: skip


def _print_sensors(say, summary: dict) -> None:
    """The sensors' readings at anatomical points, or why there are none."""
    rows = summary.get("sensors") or []
    if not rows:
        if summary.get("sensors_skipped"):
            say(f"  sensors: none ({summary['sensors_skipped']})")
        return
    d = rows[0]["diameter_m"] * 1e3
    under = [r for r in rows if r["points"] > 0]  # the others have no garment on their pad
    if under:
        say(f"  {'sensor':<16} {'kPa':>6} {'mmHg':>6}   ({rows[0]['instrument']}, {d:.0f} mm; "
            "* = pad covered in part)")  # fmt: skip
    for r in under:
        mark = "" if r["covered"] else " *"
        say(f"  {r['sensor']:<16} {r['reading_kPa']:6.2f} {r['reading_mmHg']:6.1f}{mark}")
    if len(under) < len(rows):
        off = ", ".join(r["sensor"] for r in rows if r["points"] == 0)
        say(
            f"  sensors with no garment within {d / 2:g} mm (not covered, or the garment stands "
            f"clear): {off}"
        )


def _print_regions(say, regions: list[dict]) -> None:
    say(
        f"  {'region':<12} {'contact':>9} {'mean':>6} {'p95':>6} {'max':>6} {'sensor':>6} "
        f"{'skin':>6}  kPa   comfort (p95)   (sensor / skin: p95 of the reading of a sensor "
        "of [output] sensor_instrument at the contact points / lying on the body)"
    )
    for r in regions:
        if r["contact_area_m2"] <= 0:
            continue
        say(f"  {r['region']:<12} {r['contact_area_m2'] * 1e4:7.0f}cm² {r['mean_kPa']:6.2f} "
            f"{r['p95_kPa']:6.2f} {r['max_kPa']:6.2f} {r.get('sensor_p95_kPa', 0.0):6.2f} "
            f"{r.get('body_sensor_p95_kPa', 0.0):6.2f}        {r['comfort']}")  # fmt: skip
