"""The Cusick drape (issue 47, item 2): a circular specimen held between the two pedestal
discs of a drapemeter, hanging under its own weight — the physics of the scene kind ``drape``
(:mod:`fenics_garment.scene.drape`, ``fenics-garment run drape.toml``) and of
``benchmarks/validation.py``.

The Cusick drapemeter (BS 5058; ISO 9073-9) sandwiches the specimen (300 mm) between two discs
(180 mm) and lets the annulus outside them hang; a lamp above projects its shadow. Here the
annulus r ∈ [r_p, r_s] is the shell and the discs are its clamp (u = 0, θ = 0 on r = r_p) — a
first model; the frictional contact with a pedestal top and the fabric's contact with itself
are not modelled.

Folding is a bifurcation: the flat, axisymmetric state stays a solution. The path is made to
fold by a seeded, stress-free imperfection of the specimen's shape — a vertical waviness
a Σₖ cos(kφ + φₖ)·((r − r_p)/(r_s − r_p))², k = 2 … 12, random phases from ``seed`` — and
the self weight is applied in load steps (:func:`relax`). How DC and the node count depend on
that choice (amplitude, seed) and on the mesh is what :func:`drape` reports; it is not yet a
converged or validated value. Measured (P-m6, P2B-P2B, ``benchmarks/validation.py drape``): DC
0.512 / 0.464 / 0.426 on 12 / 9 / 6 mm meshes (10 nodes on each) — not converged: a fold's
radius is of the order of the bending length c ≈ 1–2 cm, which these meshes resolve with a few
cells only; seeds 0 / 1 / 2 at 12 mm: 0.512 / 0.529 / 0.520 (10 / 11 / 11 nodes); amplitude
0.3 / 1 / 3 mm: 0.527 / 0.512 / 0.511 (11 / 10 / 10 nodes).

Outputs as the instrument: the drape coefficient DC = (A_shadow − A_p)/(A_s − A_p) from the
area of the union of the deformed triangles projected on the horizontal plane
(:func:`drape_coefficient`, :func:`shadow_area`: a raster), and the node count (the lobes of
the projected hem, :func:`count_nodes`).
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass, field

import numpy as np

from fenics_garment import units
from fenics_garment._stack import MPI, dolfinx, ufl
from fenics_garment.geometry.gmsh_utils import gmsh_session, to_dolfinx
from fenics_garment.materials import Fabric
from fenics_garment.shell import bcs as B
from fenics_garment.shell.energy import commit_history
from fenics_garment.shell.kinematics import ShellGeometry
from fenics_garment.shell.model import EnergyTerm, ShellModel
from fenics_garment.solve import NonlinearSolver


def annulus_mesh(comm, r_in: float, r_out: float, size: float) -> dolfinx.mesh.Mesh:
    """An unstructured order-2 triangle mesh of the flat annulus r_in ≤ r ≤ r_out (z = 0)."""
    with gmsh_session(comm) as gmsh:
        if gmsh is not None:
            occ = gmsh.model.occ
            outer = occ.addDisk(0, 0, 0, r_out, r_out)
            inner = occ.addDisk(0, 0, 0, r_in, r_in)
            occ.cut([(2, outer)], [(2, inner)])
            occ.synchronize()
            surfaces = [s for _, s in gmsh.model.getEntities(2)]
            gmsh.model.addPhysicalGroup(2, surfaces, 1)
            gmsh.option.setNumber("Mesh.CharacteristicLengthMin", size)
            gmsh.option.setNumber("Mesh.CharacteristicLengthMax", size)
            gmsh.option.setNumber("Mesh.Algorithm", 6)
            gmsh.model.mesh.generate(2)
            gmsh.model.mesh.setOrder(2)
        data = to_dolfinx(comm, gmsh.model if gmsh is not None else None)
    return data.mesh if hasattr(data, "mesh") else data[0]


def imperfection(x: np.ndarray, r_in: float, r_out: float, amplitude: float, seed: int):
    """The vertical waviness a Σₖ cos(kφ + φₖ) ρ², ρ = (r − r_in)/(r_out − r_in), k = 2 … 12,
    each mode of amplitude a/√11 and a random phase (``numpy.random.default_rng(seed)``)."""
    rng = np.random.default_rng(seed)
    ks = np.arange(2, 13)
    phases = rng.uniform(0.0, 2 * math.pi, len(ks))
    r = np.hypot(x[:, 0], x[:, 1])
    phi = np.arctan2(x[:, 1], x[:, 0])
    rho = np.clip((r - r_in) / (r_out - r_in), 0.0, 1.0)
    wave = sum(np.cos(k * phi + p) for k, p in zip(ks, phases, strict=True)) / math.sqrt(len(ks))
    return amplitude * wave * rho**2


def shadow_area(xy: np.ndarray, triangles: np.ndarray, pixel: float, disc: float = 0.0) -> float:
    """Area [m²] of the union of the triangles (``xy`` (n, 2), ``triangles`` (m, 3)) and of the
    centred disc of radius ``disc`` (the pedestal) on a raster of square pixels of side
    ``pixel`` (a pixel counts when its centre is covered)."""
    lo = np.minimum(xy.min(axis=0), -disc) - pixel
    hi = np.maximum(xy.max(axis=0), disc) + pixel
    nx, ny = (np.ceil((hi - lo) / pixel)).astype(int)
    cx = lo[0] + (np.arange(nx) + 0.5) * pixel
    cy = lo[1] + (np.arange(ny) + 0.5) * pixel
    covered = np.hypot(cx[:, None], cy[None, :]) <= disc
    for t in triangles:
        p = xy[t]
        i0, j0 = np.floor((p.min(axis=0) - lo) / pixel).astype(int)
        i1, j1 = np.ceil((p.max(axis=0) - lo) / pixel).astype(int)
        cx = lo[0] + (np.arange(i0, i1) + 0.5) * pixel
        cy = lo[1] + (np.arange(j0, j1) + 0.5) * pixel
        X, Y = np.meshgrid(cx, cy, indexing="ij")
        (x0, y0), (x1, y1), (x2, y2) = p
        det = (x1 - x0) * (y2 - y0) - (x2 - x0) * (y1 - y0)
        if abs(det) < 1e-300:
            continue
        l1 = ((X - x0) * (y2 - y0) - (x2 - x0) * (Y - y0)) / det
        l2 = ((x1 - x0) * (Y - y0) - (X - x0) * (y1 - y0)) / det
        inside = (l1 >= 0) & (l2 >= 0) & (l1 + l2 <= 1)
        covered[i0:i1, j0:j1] |= inside
    return float(covered.sum()) * pixel**2


def count_nodes(phi: np.ndarray, radius: np.ndarray, prominence: float = 0.2) -> int:
    """The lobes of the projected hem: local maxima of its radius r(φ) around the circle that
    rise above both neighbouring minima by ``prominence`` × (max r − min r)."""
    order = np.argsort(phi)
    r = radius[order]
    span = r.max() - r.min()
    if span <= 0:
        return 0
    # resample on a regular angle grid and smooth over ±1° to remove mesh-scale ripples
    grid = np.linspace(-math.pi, math.pi, 720, endpoint=False)
    rr = np.interp(grid, phi[order], r, period=2 * math.pi)
    kernel = np.ones(5) / 5
    rr = np.convolve(np.concatenate([rr[-2:], rr, rr[:2]]), kernel, mode="valid")
    n = len(rr)
    peaks = [i for i in range(n) if rr[i] >= rr[i - 1] and rr[i] > rr[(i + 1) % n]]
    return sum(
        1
        for i in peaks
        if rr[i] - max(_side_min(rr, i, -1), _side_min(rr, i, 1)) >= prominence * span
    )


def _side_min(r: np.ndarray, i: int, step: int) -> float:
    """The minimum of r walking from peak i in direction ``step`` until r exceeds r[i]."""
    n = len(r)
    m = r[i]
    for j in range(1, n):
        v = r[(i + step * j) % n]
        if v > r[i]:
            break
        m = min(m, v)
    return m


@dataclass
class RelaxStep:
    load_factor: float
    damping: float
    iterations: int
    change: float  # max |Δu| of the step [m]


def relax(
    model: ShellModel,
    solver: NonlinearSolver,
    q_prev: dolfinx.fem.Function,
    k: dolfinx.fem.Constant,
    k0: float,
    *,
    steps: int = 20,
    shrink: float = 0.7,
    k_min_ratio: float = 1e-4,
    max_pseudo: int = 200,
) -> list[RelaxStep]:
    """Pseudo-transient continuation of the self weight: λ = 0 → 1 in ``steps`` equal steps,
    then pseudo-time steps at λ = 1 with the proximal stiffness k shrunk by ``shrink`` after
    each step that Newton solves in ≤ 5 iterations (and doubled, the step repeated, when it
    fails), down to ``k_min_ratio`` k₀; then k = 0 for the equilibrium itself. Each step
    starts from, and is damped towards, the last accepted state (``q_prev``); each accepted
    step is committed in the laws that have a history
    (:func:`~fenics_garment.shell.energy.commit_history`): the loading path of the drape."""
    q = model.q
    out: list[RelaxStep] = []
    comm = model.geometry.mesh.comm

    def step(lam: float, kv: float) -> tuple[bool, int]:
        q_prev.x.array[:] = q.x.array
        model.load_factor.value = lam
        k.value = kv
        its, reason = solver.solve()
        if reason <= 0:
            q.x.array[:] = q_prev.x.array
            q.x.scatter_forward()
            return False, its
        commit_history(model)  # a law with a history accepts the step (HystereticBending)
        d = q.x.array - q_prev.x.array
        change = comm.allreduce(float(np.abs(d).max()) if len(d) else 0.0, op=MPI.MAX)
        out.append(RelaxStep(lam, kv, its, change))
        return True, its

    kv = k0
    lam = 0.0
    dlam = 1.0 / steps
    while lam < 1.0 - 1e-12:
        ok, _ = step(min(1.0, lam + dlam), kv)
        if ok:
            lam = min(1.0, lam + dlam)
        else:
            kv *= 2.0
            if kv > 1e6 * k0:
                raise RuntimeError(f"pseudo-transient load step failed at λ = {lam + dlam:.4g}")
    for _ in range(max_pseudo):
        if kv < k_min_ratio * k0:
            break
        ok, its = step(1.0, kv)
        kv = kv * shrink if ok and its <= 5 else (kv if ok else 2.0 * kv)
    ok, _ = step(1.0, 0.0)
    if not ok:
        raise RuntimeError(f"no equilibrium at k = 0 after relaxing to k = {kv:.3g} Pa/m")
    return out


def drape_coefficient(
    xy: np.ndarray, triangles: np.ndarray, r_p: float, r_s: float, pixel: float
) -> tuple[float, float]:
    """(DC, shadow area [m²]) as the drapemeter computes them: the shadow of the triangles
    (``xy`` their nodes projected on the horizontal plane) united with the pedestal disc,
    DC = (A_shadow − π r_p²)/(π r_s² − π r_p²)."""
    area = shadow_area(xy, triangles, pixel, disc=r_p)
    a_p, a_s = math.pi * r_p**2, math.pi * r_s**2
    return (area - a_p) / (a_s - a_p), area


def polygon_area(xy: np.ndarray) -> float:
    """Area of the simple polygon with the vertices ``xy`` (n, 2) in order (shoelace)."""
    x, y = xy[:, 0], xy[:, 1]
    return 0.5 * abs(float(np.dot(x, np.roll(y, -1)) - np.dot(y, np.roll(x, -1))))


@dataclass
class DrapeResult:
    dc: float
    nodes: int
    shadow_area: float
    cells: int
    dofs: int
    load_steps: int
    newton_its: int
    wall_s: float
    #: the instrument on the undeformed specimen: its rasterised DC and the exact one of its
    #: mesh (the hem polygon's area against the pedestal's); they differ by the raster's error
    dc_flat: float = math.nan
    dc_flat_exact: float = math.nan
    #: largest |ℓ/L − 1| over the edges of the P1 sub-triangles: a drape is near inextensible
    edge_strain: float = math.nan
    hem: np.ndarray = field(default_factory=lambda: np.zeros((0, 3)), repr=False)
    positions: np.ndarray = field(default_factory=lambda: np.zeros((0, 3)), repr=False)
    reference: np.ndarray = field(default_factory=lambda: np.zeros((0, 3)), repr=False)
    triangles: np.ndarray = field(default_factory=lambda: np.zeros((0, 3), int), repr=False)
    model: ShellModel | None = field(default=None, repr=False)
    history: list[RelaxStep] = field(default_factory=list, repr=False)


def _sub_triangles(cells: np.ndarray) -> np.ndarray:
    """The four P1 sub-triangles of each P2 triangle (vertices 0-2, edge nodes 3-5 opposite)."""
    v0, v1, v2, e0, e1, e2 = cells.T
    return np.concatenate([np.stack(t, axis=1) for t in
                           ((v0, e2, e1), (v1, e0, e2), (v2, e1, e0), (e0, e1, e2))])  # fmt: skip


def edge_strain(reference: np.ndarray, deformed: np.ndarray, triangles: np.ndarray) -> float:
    """Largest |ℓ/L − 1| over the triangles' edges (L in ``reference``, ℓ in ``deformed``)."""
    e = np.concatenate([triangles[:, [0, 1]], triangles[:, [1, 2]], triangles[:, [2, 0]]])
    L = np.linalg.norm(reference[e[:, 1]] - reference[e[:, 0]], axis=1)
    ell = np.linalg.norm(deformed[e[:, 1]] - deformed[e[:, 0]], axis=1)
    return float(np.max(np.abs(ell / L - 1.0))) if len(L) else math.nan


def specimen_model(
    material: Fabric,
    *,
    specimen_diameter: float = 0.30,
    pedestal_diameter: float = 0.18,
    size: float = 0.008,
    amplitude: float = 1.0e-3,
    seed: int = 0,
    bending: EnergyTerm | None = None,
    comm=MPI.COMM_WORLD,
) -> ShellModel:
    """The shell of the hanging annulus (mesh, seeded imperfection, material, bending law
    ``bending`` — None: the elastic :func:`~fenics_garment.shell.energy.bending_energy`),
    with no load yet."""
    r_p, r_s = pedestal_diameter / 2, specimen_diameter / 2
    mesh = annulus_mesh(comm, r_p, r_s, size)
    x = mesh.geometry.x
    x[:, 2] = imperfection(x, r_p, r_s, amplitude, seed)
    model = ShellModel(ShellGeometry.from_mesh(mesh, warp=(1, 0, 0)), material)
    if bending is not None:
        model.bending = bending
    return model


def drape(
    material: Fabric,
    *,
    specimen_diameter: float = 0.30,
    pedestal_diameter: float = 0.18,
    size: float = 0.008,
    amplitude: float = 1.0e-3,
    seed: int = 0,
    steps: int = 20,
    damping: float | None = None,
    pixel: float = 5.0e-4,
    bending: EnergyTerm | None = None,
    petsc_options: dict | None = None,
    comm=MPI.COMM_WORLD,
) -> DrapeResult:
    """Hang the annulus of ``material`` under standard gravity (see the module docstring);
    mesh size ``size`` [m], imperfection ``amplitude`` [m] and ``seed``; ``damping`` k₀ [Pa/m]
    of the pseudo-transient continuation (:func:`relax`; default 10 W/(r_s − r_p));
    ``bending``: the bending law (None: elastic; e.g.
    :class:`~fenics_garment.shell.energy.HystereticBending`)."""
    t0 = time.perf_counter()
    r_p, r_s = pedestal_diameter / 2, specimen_diameter / 2
    model = specimen_model(material, specimen_diameter=specimen_diameter,
                           pedestal_diameter=pedestal_diameter, size=size, amplitude=amplitude,
                           seed=seed, bending=bending, comm=comm)  # fmt: skip
    mesh = model.geometry.mesh
    model.add_gravity((0.0, 0.0, -units.GRAVITY))
    # pseudo-transient continuation: a proximal term ½ k |u − u_prev|² regularises the Hessian
    # through the folding bifurcations; u_prev follows the last accepted state, k → 0 at the end
    q_prev = dolfinx.fem.Function(model.Q)
    k = model.constant(0.0)
    du = model.u - ufl.split(q_prev)[0]
    model.add_energy(0.5 * k * ufl.dot(du, du))
    bcs = B.clamped(model, lambda y: np.hypot(y[0], y[1]) < r_p + 1e-6)
    solver = NonlinearSolver(model, bcs, petsc_options=petsc_options)
    s = model.stiffness
    k0 = damping if damping is not None else 10.0 * s.mass_per_area * units.GRAVITY / (r_s - r_p)
    history = relax(model, solver, q_prev, k, k0, steps=steps)
    # deformed geometry nodes: the displacement (P2) at the P2 geometry nodes, gathered on
    # rank 0 by the nodes' input (gmsh) indices
    from scipy.spatial import cKDTree

    u = model.displacement()
    X = mesh.geometry.x
    idx = cKDTree(u.function_space.tabulate_dof_coordinates()).query(X)[1]
    pos = X + u.x.array.reshape(-1, 3)[idx]
    gid = np.asarray(mesh.geometry.input_global_indices, dtype=np.int64)
    cells = gid[mesh.geometry.dofmaps[0][: mesh.topology.index_map(2).size_local]]
    gathered = comm.gather((gid, pos, X.copy(), cells), root=0)
    out = DrapeResult(
        dc=math.nan, nodes=-1, shadow_area=math.nan,
        cells=mesh.topology.index_map(2).size_global,
        dofs=model.Q.dofmap.index_map.size_global * model.Q.dofmap.index_map_bs,
        load_steps=len(history), newton_its=solver.timings.newton_iterations, wall_s=0.0,
        model=model, history=history,
    )  # fmt: skip
    if comm.rank == 0:
        n_nodes = 1 + max(int(g.max()) for g, _, _, _ in gathered)
        allpos, X0 = np.zeros((n_nodes, 3)), np.zeros((n_nodes, 3))
        for g, p_, x_, _ in gathered:
            allpos[g], X0[g] = p_, x_
        tris = _sub_triangles(np.concatenate([c_ for _, _, _, c_ in gathered]))
        out.dc, out.shadow_area = drape_coefficient(allpos[:, :2], tris, r_p, r_s, pixel)
        on_hem = np.hypot(X0[:, 0], X0[:, 1]) > r_s - 1e-6
        out.hem = allpos[on_hem]
        out.nodes = count_nodes(np.arctan2(out.hem[:, 1], out.hem[:, 0]),
                                np.hypot(out.hem[:, 0], out.hem[:, 1]))  # fmt: skip
        out.dc_flat, out.dc_flat_exact = flat_coefficients(X0, tris, r_p, r_s, pixel)
        out.edge_strain = edge_strain(X0, allpos, tris)
        out.positions, out.reference, out.triangles = allpos, X0, tris
    out.dc, out.nodes, out.shadow_area, out.dc_flat, out.dc_flat_exact, out.edge_strain = (
        comm.bcast((out.dc, out.nodes, out.shadow_area, out.dc_flat, out.dc_flat_exact,
                    out.edge_strain), root=0))  # fmt: skip
    out.wall_s = time.perf_counter() - t0
    return out


def flat_coefficients(
    X0: np.ndarray, triangles: np.ndarray, r_p: float, r_s: float, pixel: float
) -> tuple[float, float]:
    """The instrument on the undeformed specimen ``X0`` (its triangles ``triangles``): (DC of
    its rasterised shadow, DC of its exact outline — the area of the hem polygon, the nodes at
    r = r_s in angular order, against the pedestal's)."""
    dc, _ = drape_coefficient(X0[:, :2], triangles, r_p, r_s, pixel)
    r = np.hypot(X0[:, 0], X0[:, 1])
    hem = X0[r > r_s * (1 - 1e-6)]
    hem = hem[np.argsort(np.arctan2(hem[:, 1], hem[:, 0]))]
    a_p, a_s = math.pi * r_p**2, math.pi * r_s**2
    return dc, (polygon_area(hem[:, :2]) - a_p) / (a_s - a_p)


def picture(result: DrapeResult, r_p: float, r_s: float, title: str, path) -> None:
    """Top view of the shadow (pedestal black, specimen outline dashed) beside the 3D shape
    (PNG, rank 0; needs matplotlib)."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from matplotlib.tri import Triangulation

    pos, tris = result.positions, result.triangles
    fig = plt.figure(figsize=(10, 4.6))
    ax = fig.add_subplot(1, 2, 1)
    tri = Triangulation(pos[:, 0], pos[:, 1], tris)
    ax.tripcolor(tri, facecolors=np.ones(len(tris)), cmap="gray_r", vmin=0, vmax=1.6)
    ax.add_patch(plt.Circle((0, 0), r_p, color="k"))
    ax.add_patch(plt.Circle((0, 0), r_s, fill=False, ls="--", lw=0.8))
    ax.set_aspect("equal")
    ax.set_xlim(-r_s * 1.05, r_s * 1.05)
    ax.set_ylim(-r_s * 1.05, r_s * 1.05)
    ax.set_xlabel("x [m]")
    ax.set_ylabel("y [m]")
    ax.set_title(title, fontsize=9)
    ax3 = fig.add_subplot(1, 2, 2, projection="3d")
    ax3.plot_trisurf(pos[:, 0], pos[:, 1], pos[:, 2], triangles=tris, cmap="viridis", lw=0)
    ax3.set_box_aspect((1, 1, 0.45))
    ax3.set_title("3D shape [m]", fontsize=9)
    fig.tight_layout()
    fig.savefig(path, dpi=80)
    plt.close(fig)
