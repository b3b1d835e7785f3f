"""From a :class:`~fenics_garment.scene.config.Scene` to body, garment, shell model and contact.

Pipeline (seed paper §4.1, steps 1–3): the body surface (mannequin from measurements, a scan, or
a cylinder) → the garment cut from it with its pattern ease → the Naghdi shell of the fabric on
the garment mesh → contact (normal penalty or augmented Lagrangian, Coulomb friction) with the
body, gravity, and a pseudo-time regularisation that the dressing drives to zero.
"""

from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np

from fenics_garment._stack import MPI, dolfinx, ufl
from fenics_garment.contact import search
from fenics_garment.contact import shell as shell_contact
from fenics_garment.contact.smooth import SmoothBody
from fenics_garment.geometry import garments as gm
from fenics_garment.geometry import gmsh_utils
from fenics_garment.geometry.body import BodySurface
from fenics_garment.materials import Fabric, fabric
from fenics_garment.scene.config import DressingConfig, Scene, scene_file
from fenics_garment.shell.kinematics import ShellGeometry
from fenics_garment.shell.model import ELEMENTS, ShellModel


def make_body(scene: Scene, comm: MPI.Comm) -> BodySurface:
    """The body of the scene, built on rank 0 and broadcast (gmsh is deterministic but serial),
    within :data:`~fenics_garment.geometry.gmsh_utils.GMSH_TIME_LIMIT` seconds (else one line
    and exit 2: no scene sits in meshing for good)."""
    b = scene.body
    body = None
    if comm.rank == 0:
        why = "a hung mesher or section search"
        limit = gmsh_utils.GMSH_TIME_LIMIT
        with gmsh_utils.time_limit(limit, f"the {b.kind} body", by="the build", why=why):
            body = _make_body(scene)
    return comm.bcast(body, root=0)


def _make_body(scene: Scene) -> BodySurface:
    """The body of the scene, on this process (:func:`make_body`)."""
    b = scene.body
    if b.kind == "cylinder":
        return gm.cylinder_body(b.radius, b.length, h=b.mesh_size)
    if b.kind == "arm":
        from fenics_garment.geometry.mannequin import make_arm

        girths = {k.removesuffix("_girth"): v for k, v in b.measurements.items()}
        return make_arm(girths, h=b.mesh_size)
    if b.kind == "scan":
        from fenics_garment.geometry.scan import load_scan

        body, _ = load_scan(scene_file(scene, b.file), units=b.units or None, up=b.up or None,
                            max_hole_edges=b.max_hole_edges, scale=b.scale or None,
                            remesh=b.mesh_size if b.remesh else None,
                            landmarks=dict(b.landmarks) or None)  # fmt: skip
        return body
    from fenics_garment.geometry.mannequin import MeshSizes, make_mannequin
    from fenics_garment.geometry.measurements import measurements

    m = measurements(b.size, **b.measurements)
    band = tuple(b.z_range) if b.coarse_size > 0 and b.z_range else None
    sizes = MeshSizes(coarse=b.coarse_size if band else b.mesh_size, fine=b.mesh_size, band=band)
    if b.human:  # the whole body, segmented as a scan (z_range and legs not used)
        from fenics_garment.geometry.human import make_human

        return make_human(m, sizes, landmarks=dict(b.landmarks) or None)
    z = tuple(b.z_range) if b.z_range else None
    return make_mannequin(m, sizes, z_range=z, legs=b.legs)


def make_garment(scene: Scene, body: BodySurface, comm: MPI.Comm) -> gm.GarmentSurface:
    """The garment pattern (stress-free reference) cut from ``body`` with the scene's ease."""
    g = scene.garment
    kw: dict = {"h": g.mesh_size, "comm": comm, "order": geometry_order(scene)}
    if g.ease != {}:
        kw["ease"] = g.ease
    if g.refine_edges:
        kw["refine"] = gm.EdgeRefinement(tuple(g.refine_edges), g.edge_ratio, g.edge_band)
    if g.kind == "pattern":
        from fenics_garment.pattern.io import read_pattern
        from fenics_garment.pattern.sew import fit_levels, pattern_garment

        pattern = read_pattern(scene_file(scene, g.pattern))
        with gmsh_utils.time_limit(gmsh_utils.GMSH_TIME_LIMIT, "the sewn pattern"):
            garment = pattern_garment(pattern, body, kw["h"], comm, kw["order"],
                                      kw.get("refine"))[0]  # fmt: skip
        garment.levels = fit_levels(garment, body)
        return garment
    if g.kind in ("gilet", "dress") and g.rest == "pattern":
        kw["princess"] = princess_offset(body)
    if g.kind == "gilet":
        return gm.make_gilet(body, **kw)
    if g.kind == "dress":
        return gm.make_dress(body, **kw)
    if g.kind == "stocking":
        return gm.make_stocking(body, side=g.side, per_turn=g.per_turn, **kw)
    if g.kind == "sleeve":
        return gm.make_sleeve(body, per_turn=g.per_turn, side=g.side, **kw)
    return gm.make_tube(body, **kw)


#: princess seams of a fitted pattern at x = ±PRINCESS_FRACTION × bust girth: over the bust
#: point (bust-point separation ≈ 2 × 0.1 × bust girth, 17.6 cm at bust 88 cm). Measured on the
#: cotton gilet (25 mm, ARAP flattening): without them the flat front and back pieces are
#: 2.3–3.4 % (RMS) and up to 24 % from the body-fitted shape; with seams at ±6 cm 0.4–1.4 %
#: and ≤ 10 %.
PRINCESS_FRACTION = 0.1


def princess_offset(body: BodySurface) -> float:
    """x [m] of the princess seams of a pattern garment on ``body``."""
    return PRINCESS_FRACTION * body.girth("bust")


def geometry_order(scene: Scene) -> int:
    """Degree of the garment's reference geometry: ``[garment] geometry``, where "auto" is the
    displacement's degree (a P2 displacement on straight-sided cells adds the chord-to-arc
    stretch of :mod:`fenics_garment.geometry.garments`, point 5)."""
    g = scene.garment
    if g.geometry == "auto":
        return min(ELEMENTS[g.element].u_degree, 2)
    return 2 if g.geometry == "curved" else 1


def make_fabric(scene: Scene) -> Fabric:
    """The built-in fabric with the scene's overrides (Fabric re-checks its ranges)."""
    base = fabric(scene.garment.fabric)
    overrides = scene.garment.fabric_overrides
    return replace(base, **overrides) if overrides else base


@dataclass
class Regularisation:
    """Dressing spring Π_reg = ½ c |u − u_a|² dA, anchored at u_a: the garment as placed at the
    start of the dressing (``anchor = "start"``) or the last converged step (``"previous"``).

    A garment held only by contact and friction has zero-stiffness modes while it is out of
    contact (the body is shrunk at the start of dressing). The spring removes them, and the
    dressing drives c to 0 on the final solve, so the answer is an equilibrium without it. With
    friction the answer depends on the path, and the anchor decides whether the path has a limit
    as its steps are refined: anchored at the start, each state of the dressing is an
    equilibrium of one problem with parameters (s, c); anchored at the previous step, the spring
    is a damper and each solve lets the garment drift further (:mod:`.dressing`). Where the
    release fails, c · :meth:`stretch` bounds the traction the spring still carries.
    """

    c: dolfinx.fem.Constant  # [Pa/m]
    c0: float
    q_prev: dolfinx.fem.Function
    u_dofs: np.ndarray  # the displacement's dofs in q (collapsed once, not per step)
    #: "previous": u_prev follows every converged step; "start": u_prev stays where
    #: :meth:`place` put it (``DressingConfig.spring_anchor``)
    anchor: str = DressingConfig.spring_anchor

    def place(self, q: dolfinx.fem.Function) -> None:
        """Anchor the spring at the state ``q``."""
        self.q_prev.x.array[:] = q.x.array

    def accept_step(self, q: dolfinx.fem.Function) -> None:
        """A step converged at ``q``: the anchor follows it (``anchor = "previous"``) or stays."""
        if self.anchor == "previous":
            self.place(q)

    def stretch(self, q: dolfinx.fem.Function) -> float:
        """max |u − u_a| over all ranks [m]."""
        moved = np.abs(q.x.array[self.u_dofs] - self.q_prev.x.array[self.u_dofs])
        comm = q.function_space.mesh.comm
        return comm.allreduce(float(moved.max()) if len(moved) else 0.0, op=MPI.MAX)


def add_regularisation(
    model: ShellModel, c0: float, anchor: str = DressingConfig.spring_anchor
) -> Regularisation:
    """Add the residual c (u − u_prev)·δu of :class:`Regularisation` to ``model``."""
    q_prev = dolfinx.fem.Function(model.Q, name="q_prev")
    c = dolfinx.fem.Constant(model.geometry.mesh, dolfinx.default_scalar_type(c0))
    v_u = ufl.split(ufl.TestFunction(model.Q))[0]
    u_prev = ufl.split(q_prev)[0]
    model.add_residual(c * ufl.dot(model.u - u_prev, v_u) * model.dx_full)
    return Regularisation(c, c0, q_prev, model.Q.sub(0).collapse()[1], anchor)


@dataclass
class Built:
    """The scene's problem, as plain values: everything a dressing run needs.

    Edit it between :func:`build` and the solve (``scene.run``'s ``terms`` hook): the shell's
    energy laws are ``model.membrane`` etc., further terms go through ``model.add_energy`` /
    ``model.add_residual``, the contact laws are ``contact.normal_law`` and
    ``contact.friction.law``; :meth:`terms` lists what is in use.
    """

    scene: Scene
    body: BodySurface
    garment: gm.GarmentSurface
    model: ShellModel
    contact: shell_contact.ShellContact
    search_body: search.SearchSurface
    regularisation: Regularisation
    bcs: list
    mu: dolfinx.fem.Constant | None
    gravity: dolfinx.fem.Constant | None

    @property
    def dofs(self) -> int:
        im = self.model.Q.dofmap.index_map
        return im.size_global * self.model.Q.dofmap.index_map_bs

    def terms(self) -> dict:
        """The laws and terms in use, by name (recorded in ``summary.json``)."""
        m, c = self.model, self.contact
        return {
            **{k: _name(getattr(m, k)) for k in ("membrane", "bending", "shear", "drilling")},
            "added_energies": [_name(d) for d, _ in m.added_energies],
            "added_residuals": len(m.added_residuals),  # contact, regularisation, user terms
            "loads": {k: len(v) for k, v in m.loads.items()},
            "normal_law": _name(c.normal_law),
            "friction_law": _name(c.friction.law) if c.friction is not None else None,
            "constraints": len(self.bcs),
        }


def _name(term) -> str:
    """``module.function`` of a law (``expression`` for a UFL density)."""
    if isinstance(term, ufl.core.expr.Expr):  # (UFL expressions are callable too)
        return "expression"
    return f"{getattr(term, '__module__', '?')}.{getattr(term, '__qualname__', repr(term))}"


def outward_from_axis(body: BodySurface):
    """Outward direction for the garment cells: horizontally away from the body's axis."""
    c = body.vertices.mean(axis=0)

    def outward(x: np.ndarray) -> np.ndarray:
        d = np.asarray(x, dtype=np.float64) - c
        d[:, 2] = 0.0
        return d

    return outward


def build(scene: Scene, comm: MPI.Comm, body: BodySurface | None = None) -> Built:
    """Body, garment, shell model, contact, friction, gravity and regularisation of ``scene``
    (``body``: the scene's body, made already, e.g. by another garment level of the scene)."""
    body = make_body(scene, comm) if body is None else body
    garment = make_garment(scene, body, comm)
    mesh = garment.mesh
    W = dolfinx.fem.functionspace(mesh, ("Lagrange", 2, (3,)))
    geo = ShellGeometry.from_mesh(
        mesh, warp=garment.warp_function(W), outward=outward_from_axis(body),
        rest=rest_map(scene, garment),
    )  # fmt: skip
    model = ShellModel(geo, make_fabric(scene), element=scene.garment.element)
    p = scene.physics
    gravity = model.add_gravity() if p.gravity else None
    keep = search.reach_mask(body.vertices, body.triangles, garment.points, search.REACH_MARGIN)
    surface = SmoothBody if p.body_surface == "smooth" else search.SearchSurface
    sbody = surface(body.vertices, body.triangles, keep=keep)  # cropped search body
    contact = shell_contact.attach(model, sbody, kappa=contact_penalty(scene, model),
                                   kappa_hat=p.kappa_hat, rule=_rule(model),
                                   mu=p.friction if p.friction > 0 else None,
                                   kappa_t=stick_stiffness(scene))  # fmt: skip
    mu = contact.friction.mu if contact.friction else None
    d = scene.dressing
    c0 = d.regularisation * model.stiffness.membrane_scale / d.spring_length**2
    reg = add_regularisation(model, c0, anchor=d.spring_anchor)
    return Built(scene, body, garment, model, contact, sbody, reg, [], mu, gravity)


def rest_map(scene: Scene, garment: gm.GarmentSurface) -> dolfinx.fem.Function | None:
    """The flat map of the garment's pattern pieces: those it was sewn from (``[garment]
    pattern``), or those of the built-in loft flattened (``rest = "pattern"``,
    :mod:`fenics_garment.pattern.flatten`); None: the garment mesh itself is the stress-free
    state (``"loft"``)."""
    if garment.rest is not None:  # sewn from a pattern file: its pieces' coordinates
        return garment.rest.flat_map(garment.mesh)
    if scene.garment.rest != "pattern":
        return None
    from fenics_garment.geometry.errors import GeometryError
    from fenics_garment.pattern.flatten import garment_flat_map

    Y, flat = garment_flat_map(garment)
    bad = {k: f.flipped for k, f in flat.panels.items() if f.flipped}
    if bad:
        raise GeometryError(f"the {garment.kind}'s pattern pieces fold over when flattened "
                            f"(flipped triangles per panel: {bad})")  # fmt: skip
    garment.info["pattern"] = {k: (f.rms_strain, f.max_strain) for k, f in flat.panels.items()}
    garment.rest = flat.cells  # the garment is now made of these flat pieces
    return Y


def tissue_stiffness(scene: Scene) -> float | None:
    """Contact stiffness [Pa/m] of a soft body (``body.tissue = "soft"``): the Winkler layer of
    :class:`~fenics_garment.contact.terms.SoftTissue` with the seed paper's Table 1 modulus and
    Poisson ratio over ``body.tissue_depth``; None for a rigid body (the numerical penalty)."""
    from fenics_garment.contact.terms import SoftTissue
    from fenics_garment.scene.config import check_tissue_law

    check_tissue_law(scene)  # also for a Scene made in Python (the loader checks files)
    b = scene.body
    return SoftTissue(depth=b.tissue_depth).stiffness if b.tissue == "soft" else None


def contact_penalty(scene: Scene, model: ShellModel) -> float | None:
    """The normal contact stiffness κ [Pa/m]: a soft body's tissue (:func:`tissue_stiffness`),
    else the penalty κ̂ E h / ℓ² (:func:`fenics_garment.contact.terms.default_penalty`) with
    ℓ = ``physics.penalty_length``; None (``penalty_length = 0``): ℓ is the garment's largest
    cell (``contact.shell.attach``)."""
    from fenics_garment.contact.terms import default_penalty

    p = scene.physics
    soft = tissue_stiffness(scene)
    if soft is not None or p.penalty_length == 0.0:
        return soft
    return default_penalty(model.stiffness.membrane_scale, p.penalty_length, p.kappa_hat)


def stick_stiffness(scene: Scene) -> float:
    """The stick penalty κ_T [Pa/m] of the friction law: ``physics.stick_stiffness`` or, if 0,
    the tangential stiffness G / depth of the skin's tissue layer (seed paper Table 1 modulus
    and Poisson ratio, ``body.tissue_depth``; :attr:`SoftTissue.shear_stiffness`), for rigid
    and soft bodies alike. A physical value, not the normal penalty: κ = κ̂ E h / ℓ² grows as
    the garment mesh is refined, and with it how firmly a sticking point holds — measured on
    the cotton gilet, the frictional p95 drifted by 10–50 % from 35 to 12.4 mm garment cells
    while the frictionless one converged to 1 %."""
    from fenics_garment.contact.terms import SoftTissue

    p = scene.physics
    return p.stick_stiffness or SoftTissue(depth=scene.body.tissue_depth).shear_stiffness


def _rule(model: ShellModel) -> str:
    """Contact points: nodal for P1 (measured best, contact.state), lumped P2⊕bubble otherwise."""
    return "vertex" if model.variant.u_degree == 1 else "lumped"
