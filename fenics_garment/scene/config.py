"""Scene files: a TOML description of body, garment, physics, dressing, solver and outputs.

A scene is loaded into frozen dataclasses and validated on load, so that a typo or a negative
thickness fails at once, naming the file and the key, instead of deep inside a Newton solve::

    name = "cotton-gilet"
    [body]
    kind = "mannequin"          # mannequin | scan | cylinder | arm
    size = "88"                 # EN 13402-3 size code; [body.measurements] overrides girths
    [garment]
    kind = "gilet"              # gilet | dress | tube | stocking | sleeve
    fabric = "cotton"           # built-in fabric; [garment.fabric_overrides] replaces fields
    ease = { waist = -0.04 }    # fraction of the body girth per level (or one number)
    [physics]
    friction = 0.4
    terms = "my_laws.py:terms"  # optional: edits the built problem before the solve
    [dressing]
    steps = 4

Every key has a default (the dataclass field); :func:`dump` writes the scene actually used.
"""

from __future__ import annotations

import difflib
import importlib
import importlib.util
import itertools
import json
import math
import re
import sys
import tomllib
import types
import typing
from collections.abc import Callable
from dataclasses import asdict, dataclass, field, fields, is_dataclass
from pathlib import Path
from typing import Any

from fenics_garment import bounded
from fenics_garment.bounded import shown
from fenics_garment.contact.terms import MU_SKIN_COTTON
from fenics_garment.petsc_options import LINEAR_SOLVERS


class SceneError(ValueError):
    """A scene file is invalid: names the file and the dotted key."""

    def __init__(self, source: str, key: str, message: str):
        self.source, self.key = source, key
        source, key = bounded.cut_path(source), bounded.cut(key)
        where = f"{source}: " if source else ""
        message = bounded.cut(message, 1000)
        super().__init__(f"{where}[{key}] {message}" if key else f"{where}{message}")


# ------------------------------------------------------------------------------------------------
# Sections. Field types drive the type check; ``_check_*`` functions the range checks.
# ------------------------------------------------------------------------------------------------


@dataclass(frozen=True)
class BodyConfig:
    """The body: a parametric mannequin, a scan file, an analytic cylinder (test rig), or an arm.

    ``kind = "arm"``: a straight arm lofted through the wrist, forearm, elbow and upper-arm
    sections (:func:`~fenics_garment.geometry.mannequin.make_arm`); ``measurements`` then takes
    ``wrist_girth``, ``forearm_girth``, ``elbow_girth``, ``upper_arm_girth`` [m], and
    ``z_range`` is not used (the arm has its own frame, wrist at z = 0).

    ``human = true`` (a mannequin only): the mannequin with two arms in an A-pose, a neck and a
    head, from the same measurements (:func:`~fenics_garment.geometry.human.make_human`;
    ``measurements`` also takes ``upper_arm_girth``, ``elbow_girth``, ``forearm_girth``,
    ``wrist_girth``, ``head_girth``, ``upper_arm_length``, ``forearm_length``, ``hand_length``),
    segmented as a scan is: a gilet's armholes go round its arm roots, a sleeve follows its left
    or right arm, a stocking its leg. The whole body is built (``legs`` is not used and
    ``z_range`` does not crop: the segmentation needs the legs, and the contact search crops
    the body anyway); ``landmarks`` replaces detected heights as for a scan.

    ``coarse_size`` (a mannequin): the body is meshed at ``mesh_size`` within ``z_range`` only
    and at ``coarse_size`` elsewhere, e.g. a human whose legs are fine under a stocking and
    whose torso, arms and head, which the stocking does not touch, are coarse; 0 (the default):
    ``mesh_size`` everywhere.
    """

    kind: str = "mannequin"
    size: str = "88"  # mannequin size code (bust girth in cm)
    measurements: dict[str, float] = field(default_factory=dict)  # overrides [m]
    legs: bool = False
    human: bool = False  # mannequin: arms (A-pose) and head, segmented like a scan (above)
    z_range: list[float] = field(default_factory=lambda: [0.75, 1.55])  # crop [m]; [] = none
    mesh_size: float = 0.02  # body triangle size [m]
    coarse_size: float = 0.0  # mannequin: triangle size outside z_range [m] (0: mesh_size)
    file: str = ""  # scan file (kind = "scan"), relative to the scene file
    units: str = ""  # scan units "mm" | "cm" | "dm" | "m" | "in" ("" = detect from the height)
    scale: float = 0.0  # scan: metres per file unit, instead of units (0 = use units)
    up: str = ""  # scan: the file's up axis "x" | "-x" | "y" | "-y" | "z" | "-z" ("" = detect)
    max_hole_edges: int = 40  # scan: holes up to this many boundary edges are filled
    remesh: bool = False  # scan: remesh with gmsh at mesh_size (false: keep its triangles)
    landmarks: dict[str, float] = field(default_factory=dict)  # scan, human: heights [m]
    # "rigid", or "soft": a Winkler layer of soft tissue of tissue_depth [m] over a rigid core,
    # with the seed paper's Table 1 body modulus and Poisson ratio (contact.terms.SoftTissue);
    # the contact stiffness is then the tissue's, not a numerical penalty
    tissue: str = "rigid"
    tissue_depth: float = 0.02  # [m] our assumption: the paper gives no depth
    radius: float = 0.1  # cylinder radius [m]
    length: float = 0.2  # cylinder length [m]


@dataclass(frozen=True)
class GarmentConfig:
    """The garment pattern: kind, ease per level (negative = tighter than the body), fabric."""

    kind: str = "gilet"
    ease: float | dict[str, float] = field(default_factory=dict)  # {} = the kind's default
    fabric: str = "cotton"
    fabric_overrides: dict[str, float] = field(default_factory=dict)  # e.g. thickness [m]
    mesh_size: float = 0.03  # target element size [m]
    element: str = "P2B-P2B"  # the verified element (shell.model.DEFAULT_ELEMENT)
    side: str = "left"  # the stocking's leg; on a scan also the sleeve's arm
    #: reference geometry: "curved" (order-2 mesh: geometry.garments, point 5), "straight"
    #: (order 1), or "auto" = curved for a P2 element, straight for P1
    geometry: str = "auto"
    #: sleeve and stocking: elements per turn of the limb's curvature (at most mesh_size)
    per_turn: int = 24
    #: smaller cells along these edges (names or name prefixes: "armhole", "neckline", "hem",
    #: "*" for all; geometry.garments.EdgeRefinement): edge_ratio × mesh_size on them, growing
    #: back to mesh_size over edge_band [m]
    refine_edges: list[str] = field(default_factory=list)
    edge_ratio: float = 0.25
    edge_band: float = 0.04
    #: the stress-free state: "pattern" (each panel flattened into its flat pattern piece,
    #: pattern.flatten; flat rest metric, zero rest curvature: the fabric strains where the
    #: body is doubly curved) or "loft" (the body-fitted 3D garment itself is stress free)
    rest: str = "loft"
    #: kind = "pattern": the sewing pattern (fenics_garment.pattern: our .toml/.json, a
    #: GarmentCode .json, a DXF-AAMA .dxf with a companion .toml of seams), relative to the
    #: scene file; its flat pieces are the stress-free state and its sizes the fit (no ease)
    pattern: str = ""


@dataclass(frozen=True)
class PhysicsConfig:
    """Loads and contact.

    ``friction`` default 0.4: skin against cotton, within the 0.3–0.6 of dry to normal skin in
    Derler & Gerhardt, "Tribology of skin: review and analysis of experimental results for the
    friction coefficient of human skin", Tribol. Lett. 45 (2012) 1–27 (see also
    :data:`fenics_garment.contact.terms.MU_SKIN_COTTON`).
    """

    gravity: bool = True
    friction: float = MU_SKIN_COTTON
    contact: str = "augmented-lagrangian"  # penalty | augmented-lagrangian
    tolerance: float = 0.01  # augmented Lagrangian: max penetration / garment thickness
    kappa_hat: float = 10.0  # penalty scale κ = κ̂ E h / ℓ² (contact.terms.default_penalty)
    #: ℓ [m] of the penalty κ = κ̂ E h / ℓ² on a rigid body: a fixed length, so κ is the same on
    #: every garment mesh (on a finer mesh a κ scaled by its cells made Newton converge only
    #: linearly while contact points switched: the nylon gilet at 8.8 mm took 4 failed tries and
    #: 206 Newton iterations, against none and 88 with ℓ = 4 cm, the same pressures to 0.7 %:
    #: records ``nylon_gilet:body-0.015+penalty-cells`` and ``nylon_gilet:body-0.015`` in
    #: ``benchmarks/results/convergence.json``); 0: the garment's largest cell (κ ∝ 1/cell²)
    penalty_length: float = 0.04
    #: the stick penalty κ_T [Pa/m] of the friction law; 0: the skin's tangential stiffness
    #: G / body.tissue_depth with the seed paper's Table 1 tissue (scene.build.stick_stiffness)
    stick_stiffness: float = 0.0
    max_updates: int = 16  # augmented-Lagrangian multiplier updates (the dress at 36.6 mm: 11)
    body_surface: str = "smooth"  # smooth (contact.smooth: C² IMLS distance) | faceted
    #: "module:function" or "file.py:function" (relative to the scene file): a hook called with
    #: the built problem before the solve, to replace laws or add terms (``scene.run``)
    terms: str = ""


@dataclass(frozen=True)
class DressingConfig:
    """Dressing by shrinking the body and growing it back in steps (:mod:`.dressing`).

    ``regularisation``: c₀ of the pseudo-time spring ½ c (u − u_prev)² relative to E h / L²
    (membrane stiffness over ``spring_length`` squared); on while the body grows, then released
    to c = 0. L is a fixed length, not the element size: the spring's pull when friction comes
    on is part of a frictional answer, so it must not change with the mesh.

    ``schedule``: ``"fixed"`` — the body grows in ``steps`` equal steps and the spring is
    released through a fixed sequence, the same path on every mesh (with friction the answer
    depends on the path) — or ``"adaptive"`` (steps grow by ``grow`` after an easy solve; fewer
    solves, a path per mesh).
    """

    steps: int = 4
    margin: float = 0.002  # shrink beyond the deepest initial penetration [m]
    max_cuts: int = 4  # halvings of a failed step before giving up
    #: a garment whose rest state is flat pattern pieces (``garment.rest = "pattern"``) is
    #: sewn once the body has grown: its rest state goes from the placed mesh to the pattern
    #: in this many equal steps of the sewing parameter w (``shell.rest.FlatRest.sewn``)
    sew_steps: int = 4
    regularisation: float = 1e-2
    spring_length: float = 0.03  # L [m] of the spring's scale E h / L²
    grow: float = 1.5  # step growth after an easy step (adaptive schedule)
    schedule: str = "fixed"
    #: Coulomb friction while the body grows too (else it comes on at s = 0, module
    #: :mod:`.dressing`; the Laplace-verified scenes, tube and limbs, switch it on at s = 0)
    friction_while_growing: bool = True
    #: where the spring pulls towards: "start" (the garment as placed around the shrunk body:
    #: a spring, so the path has a limit as the steps are refined) or "previous" (the last
    #: converged solve: a pseudo-time damper, so the garment drifts further with every solve)
    spring_anchor: str = "start"
    #: factor on the spring constant per release solve of the fixed schedule: c₀, c₀r, c₀r², …
    #: down to 1e-5 c₀, then 0 (0.25: 10 solves, as many as the adaptive release took on the
    #: gilets and the dress, 8–12)
    release_ratio: float = 0.25
    #: Newton's start of a grow step: "none" (the last converged state) or "secant" (that state
    #: plus the last grow step's change, scaled to the new step: ``dressing.secant_start``)
    predictor: str = "none"
    #: absolute Newton tolerance of the solves on the way to the answer — grow steps, release
    #: solves with a spring, multiplier passes — as a fraction of the scene's force scale ‖F‖
    #: of the undressed pattern; the answer's solves (c = 0, and one last pass at the final
    #: multipliers) stop at the solver's snes_rtol (1e-8) times that scale. Those path solves
    #: need not reach round-off: only the final state is the answer. Cotton gilet (137,460 /
    #: 36,948 dofs): 39 / 41 Newton iterations in all against 83 / 73 with every solve at 1e-8
    #: (with release_multipliers), key-region sensor p95 within 0.2 %
    #: (docs/verification/performance.md, "Fast scenes")
    path_tolerance: float = 1e-4
    #: update the augmented-Lagrangian multipliers after every release solve with a spring (not
    #: before the c = 0 one), so that they converge while the spring is released and fewer
    #: passes are left at c = 0. The loose dress releases worse with it (30 mm: a failed
    #: release solve), so its scene sets it off, and its path tolerance back to 1e-8
    release_multipliers: bool = True
    #: mesh sequencing (:mod:`.sequence`): garment mesh sizes [m], coarsest first, each larger
    #: than ``garment.mesh_size``; the whole dressing runs on the first, each level's dressed
    #: state is carried to the next and to the scene's mesh, where only the settling solves run
    #: (a release from ``sequence_spring`` × c₀, c = 0, the multiplier passes). [] = off
    sequence: list[float] = field(default_factory=list)
    #: the spring constant, as a fraction of c₀, of the first settling solve on a finer level
    sequence_spring: float = 1e-3

    def path(self) -> dict:
        """The settings that decide which solves stop at the path tolerance (recorded in
        ``summary.json`` as ``dressing_path``; the benchmarks reuse runs of the same path), and
        the mesh sequence when there is one."""
        path = {"path_tolerance": self.path_tolerance,
                "release_multipliers": self.release_multipliers}  # fmt: skip
        if self.sequence:
            path |= {"sequence": list(self.sequence), "sequence_spring": self.sequence_spring}
        return path


@dataclass(frozen=True)
class SolverConfig:
    """The linear solver by name and PETSc options passed through to SNES/KSP on top of it
    (e.g. snes_max_it = 30). ``linear``: "direct" (MUMPS, the default), "direct-blr" (MUMPS
    block low-rank) or "gamg" (CG/GMRES + algebraic multigrid with the shell's rigid-body
    near-nullspace, the path for meshes beyond one machine);
    :data:`fenics_garment.petsc_options.LINEAR_SOLVERS`."""

    linear: str = "direct"
    petsc: dict[str, Any] = field(default_factory=dict)


@dataclass(frozen=True)
class OutputConfig:
    folder: str = "output"  # relative to the current directory; the run makes <folder>/<name>
    vtx: bool = True
    xdmf: bool = True
    pictures: bool = True
    report: bool = True  # report.html: maps, tables, checks, history, 3D view (one file)
    every_step: bool = True  # VTX frame per dressing step (else only the final state)
    error_bars: bool = False  # also solve on a √2× coarser garment: Richardson error bars
    #: the pressure sensor, one for the regions' sensor p95 and the sensors at anatomical points:
    #: an instrument (fenics_garment.sensors.INSTRUMENTS: "ami", 20 mm air-pack; "picopress",
    #: 50 mm) and its pad's diameter [m] (0: the instrument's; another value: a pad of that size)
    sensor_instrument: str = "ami"
    sensor_diameter: float = 0.0


@dataclass(frozen=True)
class DrapeConfig:
    """A Cusick drape test (``kind = "drape"``, :mod:`fenics_garment.scene.drape`): a circular
    specimen held between the drapemeter's discs (the pedestal) hangs under its own weight; the
    run reports the drape coefficient DC from the shadow's area as the instrument computes it,
    and the node count.

    The fabric is one of three: ``fabric``, a fabric of the package's data file
    ``fenics_garment/data/fabrics_measured.toml`` by id (its measured DC and node count are then
    compared); ``[drape.kes]``, KES-FB values (``B_gf_cm2_per_cm``, ``W_mg_cm2``, ``T_mm``;
    optional ``twoHB_gf_cm_per_cm``, ``B_weft_gf_cm2_per_cm``, ``twoHB_weft_gf_cm_per_cm``); or
    ``[drape.clo3d]``, CLO3D-style converted values (``areal_mass_g_m2``, ``thickness_mm``,
    ``stretch_warp_g_s2``, ``stretch_weft_g_s2``, ``shear_g_s2``, ``bending_warp_g_mm2_s2``,
    ``bending_weft_g_mm2_s2``; optional ``twoHB_gf_cm_per_cm``) — the keys and units of the data
    file, converted to SI by one function (:func:`fenics_garment.measured.material_si`). KES
    values carry no tensile or shear data: the membrane gets the data file's stated rule
    (:data:`fenics_garment.measured.MISSING_MEMBRANE_RULE`).
    """

    #: id of a fabric of the data file (e.g. "P-m6", "M-B"); "" = the values of [drape.kes] or
    #: [drape.clo3d]
    fabric: str = ""
    kes: dict[str, float] = field(default_factory=dict)  # KES-FB values, units in the keys
    clo3d: dict[str, float] = field(default_factory=dict)  # CLO3D-style values, units in keys
    #: a measured DC to compare with (0: none; a data-file fabric brings its own)
    dc_measured: float = 0.0
    nodes_measured: int = 0  # a measured node count to compare with (0: none)
    specimen_diameter: float = 0.30  # [m] (BS 5058: 300 mm)
    pedestal_diameter: float = 0.18  # [m] (BS 5058: 180 mm)
    mesh_size: float = 0.012  # [m] triangle size of the specimen (order-2 mesh)
    #: amplitude [m] of the stress-free waviness that seeds the folds (drape.imperfection)
    imperfection: float = 0.001
    seed: int = 0  # the random phases of the waviness's modes 2–12
    #: "elastic", or "hysteresis": the KES 2HB friction moment (shell.energy.HystereticBending;
    #: needs 2HB)
    bending: str = "elastic"
    #: the hysteresis slider's elastic range κ_y [1/m] (shell.energy.YIELD_CURVATURE)
    yield_curvature: float = 5.0
    load_steps: int = 20  # equal steps of the self weight before the pseudo-time relaxation
    pixel: float = 0.0005  # [m] side of the shadow raster's pixels


@dataclass(frozen=True)
class Scene:
    #: "garment" (a garment dressed on a body: [body], [garment], [physics], [dressing]) or
    #: "drape" (a Cusick drape test: [drape])
    kind: str = "garment"
    name: str = "scene"
    body: BodyConfig = field(default_factory=BodyConfig)
    garment: GarmentConfig = field(default_factory=GarmentConfig)
    physics: PhysicsConfig = field(default_factory=PhysicsConfig)
    dressing: DressingConfig = field(default_factory=DressingConfig)
    solver: SolverConfig = field(default_factory=SolverConfig)
    output: OutputConfig = field(default_factory=OutputConfig)
    drape: DrapeConfig = field(default_factory=DrapeConfig)
    source: str = field(default="", compare=False)  # the file it came from (not a TOML key)


SCENE_KINDS = ("garment", "drape")
#: The sections of each scene kind (the others must not be given); solver and output are both's.
KIND_SECTIONS = {"garment": ("body", "garment", "physics", "dressing"), "drape": ("drape",)}
DRAPE_BENDING = ("elastic", "hysteresis")


BODY_KINDS = ("mannequin", "scan", "cylinder", "arm")
GARMENT_KINDS = ("gilet", "dress", "tube", "stocking", "sleeve", "pattern")
#: The body kind each garment kind needs (the rest need a mannequin or a scan).
GARMENT_BODY = {"tube": ("cylinder",), "sleeve": ("arm", "scan"), "pattern": BODY_KINDS}
#: Levels that a per-level ease may name, per garment kind (others are not checked).
_TORSO = ("hip", "abdomen", "waist", "underbust", "bust", "upper_chest", "shoulder", "neck_base",
          "neck")  # fmt: skip
EASE_LEVELS = {
    "sleeve": ("wrist", "forearm", "elbow", "upper_arm"),
    "stocking": ("ankle", "calf", "knee", "thigh"),
    "gilet": _TORSO,
    "dress": _TORSO,
    "tube": ("bottom", "mid", "top"),
}
SIDES = ("left", "right")
CONTACT_METHODS = ("penalty", "augmented-lagrangian")
GEOMETRIES = ("auto", "curved", "straight")
RESTS = ("loft", "pattern")  # scene.build: the garment's stress-free state
DRESSING_SCHEDULES = ("fixed", "adaptive")  # scene.dressing.dress
DRESSING_PREDICTORS = ("none", "secant")  # scene.dressing.dress
SPRING_ANCHORS = ("previous", "start")  # scene.build.Regularisation
BODY_SURFACES = ("faceted", "smooth")  # contact.search.SearchSurface | contact.smooth.SmoothBody
TISSUES = ("rigid", "soft")
ELEMENTS = ("P2B-P2B", "P2B-P2", "P2-P2", "P1-P1")

#: Accepted ranges (lo, hi, unit, why) of the lengths and stiffnesses that enter the arithmetic
#: squared or as a divisor — κ = κ̂ E h / ℓ², c = c₀ E h / L², k = E / depth — refused on load
#: outside them: far outside they overflow or divide by zero deep inside the build (1e300² = inf,
#: 1 / 1e-300² = inf: an OverflowError, not a message), and well before that the run means
#: nothing. Each range spans what a garment on a body can mean, with room to spare; the 0 of
#: ``penalty_length`` ("the garment's largest cell") is accepted besides.
#:
#: * ``physics.penalty_length``, ``dressing.spring_length``: a length of the garment over which
#:   its membrane stiffness E h is spread, from a fabric's thickness (0.1 mm) to 10 m (beyond
#:   any body). At 0.1 mm the stiffness is 1.6·10⁵ × the default ℓ = 4 cm's — the end of what
#:   preflight's κ̂ range (up to 10⁵ × its default) lets the linear solves resolve; at 10 m it is
#:   1.6·10⁻⁵ of it, a garment held by nothing.
#: * ``body.tissue_depth``: soft tissue over bone, from 1 mm (over the shin or the skull) to
#:   50 cm (no body part has more); the Winkler stiffness E / depth and the stick stiffness
#:   G / depth (the default of ``stick_stiffness``) divide by it.
#: * ``physics.stick_stiffness``: up to 10⁹ Pa/m, a shear modulus of 1 MPa (ten times the
#:   stiffest skin's ~0.1 MPa) over 1 mm of tissue; the seed paper's tissue over 2 cm gives
#:   3.4·10⁵ Pa/m. At 1e300 the friction law's tangent swamps every other term (exit 3 after
#:   the first solve).
#: * ``dressing.margin``: the extra shrink of the body below the garment, up to 1 m (it is a few
#:   millimetres; preflight checks it against the body's radius once the body is built).
#: * ``garment.edge_band``: the band over which refined edge cells grow back to the mesh size,
#:   from 0.1 mm to 10 m.
#:
#: And the other numbers that would make a run meaningless or endless far outside what can mean
#: something (each one at 1e300 and 1e-300 is refused, or equals its valid 0, in
#: ``tests/test_crash_paths.py``):
#:
#: * ``physics.tolerance``, ``dressing.path_tolerance``: relative tolerances below 10⁻⁴ of the
#:   thickness and 10⁻¹⁰ of the force scale cannot be reached in double precision after the
#:   contact's and the residual's round-off (the multiplier passes or Newton would run out).
#: * ``garment.edge_ratio``: edge cells of 1e-300 × the mesh size would make gmsh run out of
#:   memory: at most 100 times smaller than the mesh size.
#: * ``output.sensor_diameter``: a pressure sensor from 1 mm (none smaller is made) to 20 cm; 0:
#:   the instrument's.
#: * ``dressing.release_ratio``: 0.01 (a release of the spring in three solves) to 0.9 (110);
#:   0.999 would take 11,508 solves.
#: * ``dressing.grow``: the adaptive schedule's step growth, at most tenfold a step.
#: * ``body.scale``: metres per file unit of a scan, from a micrometre to a kilometre (mm:
#:   0.001, in: 0.0254); 0 means "use units".
#: * ``body.radius``, ``body.length``: a cylinder body's, from a finger to a barrel (also where
#:   the body is not a cylinder and they are not used, so that a scene changes kind safely).
LENGTH_RANGES: dict[str, tuple[float, float, str, str]] = {
    "physics.penalty_length": (1e-4, 10.0, "m", "a length of the garment (κ = κ̂ E h / ℓ²); 0: "
                               "the garment's largest cell"),
    "dressing.spring_length": (1e-4, 10.0, "m", "a length of the garment (c = c₀ E h / L²)"),
    "body.tissue_depth": (1e-3, 0.5, "m", "soft tissue over bone"),
    "physics.stick_stiffness": (1e2, 1e9, "Pa/m", "1 MPa of shear over 1 mm of tissue down to "
                                "100 Pa over 1 m; 0: the skin's G / body.tissue_depth"),
    "dressing.margin": (0.0, 1.0, "m", "an extra shrink of the body of a few millimetres"),
    "garment.edge_band": (1e-4, 10.0, "m", "the band of refined cells along an edge"),
    "physics.tolerance": (1e-4, 1.0, "", "a fraction of the garment thickness"),
    "dressing.path_tolerance": (1e-10, 1e-2, "", "a fraction of the scene's force scale"),
    "garment.edge_ratio": (1e-2, 1.0, "", "the edge cells' size / mesh_size"),
    "output.sensor_diameter": (1e-3, 0.2, "m", "a pressure sensor's diameter; 0: the "
                               "instrument's"),
    "dressing.release_ratio": (1e-2, 0.9, "", "the spring's factor per release solve"),
    "dressing.grow": (1.0, 10.0, "", "the adaptive schedule's step growth"),
    "body.scale": (1e-6, 1e3, "m per file unit", "0: use units"),
    "body.coarse_size": (1e-3, 0.1, "m", "a mannequin's triangles outside z_range; 0: "
                         "mesh_size everywhere"),
    "body.radius": (1e-3, 10.0, "m", "a cylinder body's radius"),
    "body.length": (1e-3, 10.0, "m", "a cylinder body's length"),
}  # fmt: skip
#: of the keys above, those where 0 selects a default rule (accepted besides the range)
ZERO_MEANS_DEFAULT = (
    "physics.penalty_length",
    "physics.stick_stiffness",
    "body.scale",
    "body.coarse_size",
    "output.sensor_diameter",
)
#: Lowest and highest landmark height [m] a scene may set (``body.landmarks``): an ankle is
#: some 7 cm above the floor, no body is 3 m tall
MIN_LANDMARK, MAX_LANDMARK = 0.01, 3.0


def scene_file(scene: Scene, name: str) -> Path:
    """A file named in ``scene`` (a scan, a pattern): relative to the scene file's folder
    (the folder of the file a linked scene file points to, if not found next to the link:
    ``demos/`` links the package's scenes)."""
    path = Path(name)
    if not path.is_absolute() and scene.source:
        here = Path(scene.source).parent / path
        there = Path(scene.source).resolve().parent / path
        path = here if here.exists() or not there.exists() else there
    return path


def load_terms(spec: str, source: str = "") -> Callable[[Any], None] | None:
    """The hook named by ``[physics] terms`` (None when empty), or a one-line SceneError.

    ``spec`` is ``"module:function"`` (an importable module, or one next to the scene file) or
    ``"file.py:function"`` (a path, relative to the scene file's folder).
    """
    if not spec:
        return None
    key = "physics.terms"
    where, sep, name = spec.rpartition(":")
    if not sep or not where or not name.isidentifier():
        raise SceneError(source, key, f"must be 'module:function' or 'file.py:function', "
                         f"got {shown(spec)}")  # fmt: skip
    folder = Path(source).parent if source else Path.cwd()
    try:
        module = _import_terms(where, folder)
    except Exception as err:  # an import error of the user's module, whatever it is
        raise SceneError(source, key, f"cannot import {shown(where)}: {type(err).__name__}: "
                         f"{str(err).splitlines()[0] if str(err) else ''}") from err  # fmt: skip
    hook = getattr(module, name, None)
    if not callable(hook):
        raise SceneError(source, key, f"{shown(where)} has no function {shown(name)}")
    return hook


def _import_terms(where: str, folder: Path) -> types.ModuleType:
    """The module ``where``: a ``.py`` path (relative to ``folder``) or a dotted module name,
    looked up next to the scene file first."""
    if where.endswith(".py"):
        path = Path(where) if Path(where).is_absolute() else folder / where
        if not path.is_file():
            raise FileNotFoundError(f"no file {path}")
        spec = importlib.util.spec_from_file_location(f"_scene_terms_{path.stem}", path)
        module = importlib.util.module_from_spec(spec)
        spec.loader.exec_module(module)
        return module
    sys.path.insert(0, str(folder))
    try:
        return importlib.import_module(where)
    finally:
        sys.path.remove(str(folder))


# ------------------------------------------------------------------------------------------------
# Generic conversion: TOML table -> dataclass, with the type of every field checked.
# ------------------------------------------------------------------------------------------------


def _type_name(tp: Any) -> str:
    if isinstance(tp, type):
        return {"float": "number", "int": "integer", "str": "string", "bool": "boolean"}.get(
            tp.__name__, tp.__name__
        )
    origin = typing.get_origin(tp)
    if origin in (typing.Union, types.UnionType):
        return " or ".join(_type_name(a) for a in typing.get_args(tp))
    if origin is dict:
        return f"table of {_type_name(typing.get_args(tp)[1])}s"
    if origin is list:
        return f"array of {_type_name(typing.get_args(tp)[0])}s"
    return str(tp)


def _convert(value: Any, tp: Any, key: str, src: str) -> Any:
    """``value`` as type ``tp`` (int accepted for float), or SceneError."""
    origin = typing.get_origin(tp)
    if tp is Any:
        return value
    if origin in (typing.Union, types.UnionType):
        for arg in typing.get_args(tp):
            try:
                return _convert(value, arg, key, src)
            except SceneError:
                continue
    elif origin is dict:
        if isinstance(value, dict):
            vt = typing.get_args(tp)[1]
            return {k: _convert(v, vt, f"{key}.{k}", src) for k, v in value.items()}
    elif origin is list:
        if isinstance(value, list):
            et = typing.get_args(tp)[0]
            return [_convert(v, et, f"{key}[{i}]", src) for i, v in enumerate(value)]
    elif tp is float:
        if isinstance(value, int | float) and not isinstance(value, bool):
            if not math.isfinite(value):
                raise SceneError(src, key, f"must be a finite number, got {value!r}")  # (a float)
            return float(value)
    elif tp is int:
        if isinstance(value, int) and not isinstance(value, bool):
            return value
    elif isinstance(tp, type) and isinstance(value, tp):
        return value
    name = _type_name(tp)
    article = "an" if name[0] in "aeiou" else "a"
    raise SceneError(src, key, f"must be {article} {name}, got {type(value).__name__} "
                     f"{shown(value)}")  # fmt: skip


def _unknown(key: str, known: list[str], where: str, src: str) -> SceneError:
    close = difflib.get_close_matches(key, known, n=1, cutoff=0.6)
    hint = f"; did you mean '{close[0]}'?" if close else f"; known keys: {', '.join(known)}"
    return SceneError(src, f"{where}.{key}" if where else key, f"unknown key{hint}")


def _from_table(cls: type, table: dict, where: str, src: str) -> Any:
    hints = typing.get_type_hints(cls)
    known = [f.name for f in fields(cls) if f.name != "source"]
    kwargs = {}
    for key, value in table.items():
        if key not in known:
            raise _unknown(key, known, where, src)
        tp = hints[key]
        dotted = f"{where}.{key}" if where else key
        if is_dataclass(tp):
            if not isinstance(value, dict):
                raise SceneError(src, dotted, f"must be a table, got {type(value).__name__}")
            kwargs[key] = _from_table(tp, value, key, src)
        else:
            kwargs[key] = _convert(value, tp, dotted, src)
    return cls(**kwargs)


# ------------------------------------------------------------------------------------------------
# Range checks
# ------------------------------------------------------------------------------------------------


def check_tissue_law(s: Scene) -> None:
    """A soft body's tissue is the contact law (its Winkler stiffness is the penalty): the
    augmented Lagrangian would remove the layer's compression and give the rigid pressure.
    Called by the loader and by ``scene.build`` (for scenes made in Python)."""
    ok = s.body.tissue != "soft" or s.physics.contact == "penalty"
    _require(ok, s.source, "physics.contact",
             "a soft body's tissue is the contact law: use contact = \"penalty\"")  # fmt: skip


def _require(ok: bool, src: str, key: str, message: str) -> None:
    if not ok:
        raise SceneError(src, key, message)


def _one_of(value: str, allowed: tuple[str, ...], src: str, key: str) -> None:
    if value not in allowed:
        close = difflib.get_close_matches(value, allowed, n=1)
        hint = f" (did you mean '{close[0]}'?)" if close else ""
        raise SceneError(src, key, f"must be one of {', '.join(allowed)}; got {shown(value)}{hint}")


def _check_ranges(s: Scene) -> None:
    """Every key of :data:`LENGTH_RANGES` within its range (one line: file, key, range, why)."""
    for key, (lo, hi, unit, why) in LENGTH_RANGES.items():
        section, name = key.split(".")
        v = getattr(getattr(s, section), name)
        if v == 0.0 and key in ZERO_MEANS_DEFAULT:
            continue
        u = f" {unit}" if unit else ""
        message = f"= {v:g}{u} is outside the accepted range [{lo:g}, {hi:g}]{u} ({why})"
        _require(lo <= v <= hi, s.source, key, message)


def _check(s: Scene) -> None:
    from fenics_garment.geometry.mannequin import ARM_LEVELS
    from fenics_garment.geometry.measurements import SIZE_CODES, Measurements
    from fenics_garment.materials import FABRICS

    src = s.source
    b, g, p, d = s.body, s.garment, s.physics, s.dressing
    _one_of(s.kind, SCENE_KINDS, src, "kind")
    for other in (k for k in KIND_SECTIONS if k != s.kind):
        for sec in KIND_SECTIONS[other]:
            _require(getattr(s, sec) == type(getattr(s, sec))(), src, sec,
                     f"is a section of a {other} scene, not of a {s.kind}")  # fmt: skip
    if s.kind == "drape":
        _check_drape(s)
    if b.kind == "mannequin":
        _one_of(b.size, SIZE_CODES, src, "body.size")
        known = [f.name for f in fields(Measurements)]
        for k, v in b.measurements.items():
            if k not in known:
                raise _unknown(k, known, "body.measurements", src)
            _require(v > 0, src, f"body.measurements.{k}", f"must be positive, got {v}")
    if b.kind == "arm":
        known = [f"{k}_girth" for k in ARM_LEVELS]
        for k, v in b.measurements.items():
            if k not in known:
                raise _unknown(k, known, "body.measurements", src)
            _require(v > 0, src, f"body.measurements.{k}", f"must be positive, got {v}")
    if b.kind == "scan":
        _require(bool(b.file), src, "body.file", "a scan body needs a file")
        from fenics_garment.geometry.orientation import ROTATIONS, UNITS

        _require(b.units in ("", *UNITS), src, "body.units", f"must be one of {', '.join(UNITS)}")
        _require(b.up in ("", *ROTATIONS), src, "body.up", f"must be one of {', '.join(ROTATIONS)}")
        _require(b.scale >= 0, src, "body.scale", f"must be positive (m per unit), got {b.scale}")
        _require(not (b.scale and b.units), src, "body.scale", "give units or scale, not both")
        _require(b.max_hole_edges >= 0, src, "body.max_hole_edges", "must be 0 or more")
    _require(not b.human or b.kind == "mannequin", src, "body.human",
             f"only a mannequin can have arms and a head (body.kind = {b.kind!r})")  # fmt: skip
    if b.kind == "scan" or b.human:
        from fenics_garment.geometry.anatomy import LANDMARKS

        for k, v in b.landmarks.items():
            if k not in LANDMARKS:
                raise _unknown(k, list(LANDMARKS), "body.landmarks", src)
            _require(MIN_LANDMARK <= v <= MAX_LANDMARK, src, f"body.landmarks.{k}",
                     f"must be a height above the floor in [{MIN_LANDMARK:g}, {MAX_LANDMARK:g}] "
                     f"m, got {v:g}")  # fmt: skip
    _one_of(b.tissue, TISSUES, src, "body.tissue")
    _require(b.tissue_depth > 0, src, "body.tissue_depth",
             f"must be positive, got {b.tissue_depth}")  # fmt: skip
    check_tissue_law(s)
    if b.z_range:
        _require(len(b.z_range) == 2 and b.z_range[0] < b.z_range[1], src, "body.z_range",
                 f"must be [z_min, z_max] with z_min < z_max, got {b.z_range}")  # fmt: skip
    for key in ("mesh_size", "radius", "length"):
        v = getattr(b, key)
        _require(v > 0, src, f"body.{key}", f"must be positive, got {v}")
    _one_of(g.kind, GARMENT_KINDS, src, "garment.kind")
    kinds = GARMENT_BODY.get(g.kind, ("mannequin", "scan"))
    ok = b.kind in kinds or (g.kind == "sleeve" and b.human)
    needs = " or ".join(kinds)
    an = "an" if needs[0] in "aeiou" else "a"
    msg = f"a {g.kind} needs {an} {needs} body (body.kind = {b.kind!r})"
    if g.kind == "sleeve":
        msg += ", or a mannequin with human = true"
    _require(ok, src, "garment.kind", msg)
    _one_of(g.side, SIDES, src, "garment.side")
    if g.kind == "stocking":
        _require(b.kind != "mannequin" or b.legs or b.human, src, "body.legs",
                 "a stocking on a mannequin needs legs = true")  # fmt: skip
    if g.kind == "pattern":
        _require(bool(g.pattern), src, "garment.pattern", "a pattern garment needs a pattern "
                 "file (our .toml/.json, GarmentCode .json or DXF-AAMA .dxf)")  # fmt: skip
        _require(g.ease == {}, src, "garment.ease", "a pattern garment's fit is in its "
                 "pattern's sizes: no ease")  # fmt: skip
    else:
        _require(not g.pattern, src, "garment.pattern",
                 f"is for kind = 'pattern' (this garment is a built-in {g.kind})")  # fmt: skip
    if isinstance(g.ease, dict) and g.kind in EASE_LEVELS:
        for k in g.ease:
            if k not in EASE_LEVELS[g.kind]:
                raise _unknown(k, list(EASE_LEVELS[g.kind]), "garment.ease", src)
    _one_of(g.fabric, tuple(FABRICS), src, "garment.fabric")
    _one_of(g.element, ELEMENTS, src, "garment.element")
    _one_of(g.geometry, GEOMETRIES, src, "garment.geometry")
    _one_of(g.rest, RESTS, src, "garment.rest")
    _require(g.per_turn >= 8, src, "garment.per_turn", f"must be at least 8, got {g.per_turn}")
    _require(g.mesh_size > 0, src, "garment.mesh_size", f"must be positive, got {g.mesh_size}")
    _require(0 < g.edge_ratio <= 1, src, "garment.edge_ratio",
             f"is the edge cells' size / mesh_size, in (0, 1]; got {g.edge_ratio}")  # fmt: skip
    _require(g.edge_band > 0, src, "garment.edge_band", f"must be positive [m], got {g.edge_band}")
    from fenics_garment.geometry.garments import EDGE_NAMES, EdgeRefinement

    names = EDGE_NAMES.get(g.kind, ())  # a pattern's edges are named in its file
    for e in g.refine_edges if names else ():
        ok = any(map(EdgeRefinement((e,)).selects, names))
        _require(ok, src, "garment.refine_edges",
                 f"a {g.kind} has no edge {shown(e)}; its edges: {', '.join(names)} (or a prefix, "
                 "e.g. 'armhole'; '*' for all)")  # fmt: skip
    eases = g.ease.values() if isinstance(g.ease, dict) else [g.ease]
    for e in eases:
        _require(-0.5 < e < 1.0, src, "garment.ease", f"must lie in (-0.5, 1), got {e}")
    fab_fields = ("E_warp", "E_weft", "G12", "B_warp", "B_weft", "thickness", "density", "nu12")
    for k, v in g.fabric_overrides.items():
        if k not in fab_fields:
            raise _unknown(k, list(fab_fields), "garment.fabric_overrides", src)
        zero_ok = k in ("density", "nu12")
        bound = ">= 0" if zero_ok else "positive"
        ok = v >= 0 if zero_ok else v > 0
        _require(ok, src, f"garment.fabric_overrides.{k}", f"must be {bound}, got {v}")
    _require(0 <= p.friction <= 2, src, "physics.friction", f"must lie in [0, 2], got {p.friction}")
    _one_of(p.contact, CONTACT_METHODS, src, "physics.contact")
    _one_of(p.body_surface, BODY_SURFACES, src, "physics.body_surface")
    load_terms(p.terms, src)
    _require(0 < p.tolerance <= 1, src, "physics.tolerance",
             f"is a fraction of the garment thickness in (0, 1], got {p.tolerance}")  # fmt: skip
    _require(p.kappa_hat > 0, src, "physics.kappa_hat", f"must be positive, got {p.kappa_hat}")
    _require(p.penalty_length >= 0, src, "physics.penalty_length",
             f"must be ≥ 0 (0: the garment's largest cell), got {p.penalty_length}")  # fmt: skip
    _require(p.stick_stiffness >= 0, src, "physics.stick_stiffness", "must be >= 0 (0: skin)")
    _require(p.max_updates >= 0, src, "physics.max_updates", "must be >= 0")
    _require(d.steps >= 1, src, "dressing.steps", f"must be >= 1, got {d.steps}")
    _require(d.margin >= 0, src, "dressing.margin", f"must be >= 0, got {d.margin}")
    _require(d.max_cuts >= 0, src, "dressing.max_cuts", f"must be >= 0, got {d.max_cuts}")
    _require(d.regularisation >= 0, src, "dressing.regularisation", "must be >= 0")
    _require(d.spring_length > 0, src, "dressing.spring_length", "must be positive")
    _require(d.grow >= 1, src, "dressing.grow", f"must be >= 1, got {d.grow}")
    _one_of(d.schedule, DRESSING_SCHEDULES, src, "dressing.schedule")
    _one_of(d.predictor, DRESSING_PREDICTORS, src, "dressing.predictor")
    _one_of(d.spring_anchor, SPRING_ANCHORS, src, "dressing.spring_anchor")
    _require(
        0 < d.path_tolerance <= 1e-2,
        src,
        "dressing.path_tolerance",
        f"is a fraction of the scene's force scale in (0, 0.01], got {d.path_tolerance}",
    )
    _require(0 < d.release_ratio < 1, src, "dressing.release_ratio",
             f"must be in (0, 1), got {d.release_ratio}")  # fmt: skip
    seq = [*d.sequence, s.garment.mesh_size]
    _require(all(a > b for a, b in itertools.pairwise(seq)), src, "dressing.sequence",
             "must be garment mesh sizes [m], coarsest first, each larger than "
             f"garment.mesh_size = {s.garment.mesh_size:g}; got {d.sequence}")  # fmt: skip
    _require(0 <= d.sequence_spring <= 1, src, "dressing.sequence_spring",
             f"is a fraction of c₀ in [0, 1], got {d.sequence_spring}")  # fmt: skip
    _one_of(s.solver.linear, tuple(LINEAR_SOLVERS), src, "solver.linear")
    o = s.output
    _require(0 <= o.sensor_diameter <= 0.2, src, "output.sensor_diameter",
             f"is a sensor's diameter in metres, in (0, 0.2] (0: the instrument's), got "
             f"{o.sensor_diameter}")  # fmt: skip
    from fenics_garment.sensors import INSTRUMENTS

    _one_of(o.sensor_instrument, tuple(INSTRUMENTS), src, "output.sensor_instrument")
    _no_control_characters(s)
    _require(_plain_name(s.name), src, "name",
             f"must be a plain folder name (no '/', '\\', control characters, '.' or '..'), "
             f"got {shown(s.name)}")  # fmt: skip
    _check_ranges(s)


def _check_drape(s: Scene) -> None:
    """The checks of ``[drape]`` (a fabric given once and valid, sizes in range)."""
    from fenics_garment import measured

    src, r = s.source, s.drape
    given = [k for k, v in (("fabric", r.fabric), ("kes", r.kes), ("clo3d", r.clo3d)) if v]
    _require(len(given) == 1, src, "drape.fabric",
             "give the fabric once: a fabric of the data file by id, or [drape.kes], or "
             f"[drape.clo3d] (got {' and '.join(given) or 'none'})")  # fmt: skip
    if r.fabric:
        _one_of(r.fabric, tuple(f.id for f in measured.fabrics()), src, "drape.fabric")
    for key, table, known in (("drape.kes", r.kes, measured.KES_KEYS + measured.KES_OPTIONAL),
                              ("drape.clo3d", r.clo3d,
                               measured.CLO3D_KEYS + measured.CLO3D_OPTIONAL)):  # fmt: skip
        for k in table:
            if k not in known:
                raise _unknown(k, list(known), key, src)
        if table:
            try:
                measured.material_si(table)
            except ValueError as err:
                raise SceneError(src, key, str(err)) from None
    _one_of(r.bending, DRAPE_BENDING, src, "drape.bending")
    if r.bending == "hysteresis":
        has_hb = (measured.by_id(r.fabric).twoHB is not None if r.fabric
                  else "twoHB_gf_cm_per_cm" in (r.kes or r.clo3d))  # fmt: skip
        _require(has_hb, src, "drape.bending",
                 "hysteresis needs the fabric's 2HB (twoHB_gf_cm_per_cm); this fabric has "
                 "none")  # fmt: skip
    _require(0.01 <= r.pedestal_diameter <= 0.5, src, "drape.pedestal_diameter",
             f"must be in [0.01, 0.5] m, got {r.pedestal_diameter:g}")  # fmt: skip
    _require(0 < r.pedestal_diameter < r.specimen_diameter <= 1.0, src,
             "drape.specimen_diameter", "must be larger than pedestal_diameter > 0, at most "
             f"1 m; got {r.specimen_diameter:g} and {r.pedestal_diameter:g} m")  # fmt: skip
    overhang = 0.5 * (r.specimen_diameter - r.pedestal_diameter)
    _require(1e-4 <= r.mesh_size <= 0.5 * overhang, src, "drape.mesh_size",
             f"must be at least 1e-4 m, at most half the overhang ({0.5 * overhang:g} m): "
             f"two cells across the hanging annulus; got {r.mesh_size:g}")  # fmt: skip
    _require(0 <= r.imperfection <= 0.1 * overhang, src, "drape.imperfection",
             f"is the seeding waviness's amplitude in [0, {0.1 * overhang:g}] m (a tenth of the "
             f"overhang), got {r.imperfection:g}")  # fmt: skip
    _require(r.seed >= 0, src, "drape.seed", f"must be >= 0, got {r.seed}")
    _require(0 <= r.dc_measured <= 1, src, "drape.dc_measured",
             f"is a drape coefficient in [0, 1] (0: none), got {r.dc_measured:g}")  # fmt: skip
    _require(r.nodes_measured >= 0, src, "drape.nodes_measured", "must be >= 0 (0: none)")
    _require(1e-3 <= r.yield_curvature <= 1e4, src, "drape.yield_curvature",
             f"must be in [1e-3, 1e4] 1/m, got {r.yield_curvature:g}")  # fmt: skip
    _require(1 <= r.load_steps <= 1000, src, "drape.load_steps",
             f"must be in [1, 1000], got {r.load_steps}")  # fmt: skip
    _require(1e-5 <= r.pixel <= 0.05 * r.pedestal_diameter, src, "drape.pixel",
             f"must be in [1e-05, {0.05 * r.pedestal_diameter:g}] m, got {r.pixel:g}")  # fmt: skip
    _require(not s.output.error_bars, src, "output.error_bars",
             "a drape has no error bars (run it on two meshes: drape.mesh_size)")  # fmt: skip


def _no_control_characters(s: Scene) -> None:
    """SceneError for a control character in any string of the scene (a folder, a file name, a
    fabric): it would end up in paths and in the run's own ``scene_used.toml``."""
    table = to_dict(s)
    table.pop("name")  # (checked as a folder name, which refuses control characters too)
    stack: list[tuple[str, Any]] = [("", table)]
    while stack:
        key, value = stack.pop()
        if isinstance(value, dict):
            stack += [(f"{key}.{k}" if key else str(k), v) for k, v in value.items()]
            stack += [(f"{key}.{k}", k) for k in value if isinstance(k, str)]
        elif isinstance(value, list):
            stack += [(f"{key}[{i}]", v) for i, v in enumerate(value)]
        elif isinstance(value, str) and bounded.has_control(value):
            raise SceneError(s.source, key, f"has a control character (a newline, a tab, an "
                             f"escape, …): {shown(value)}")  # fmt: skip


def _plain_name(name: str) -> bool:
    """A name that makes one folder directly in the output root."""
    bad = ("/", "\\")
    printable = name.isprintable() and not any(c in name for c in bad)
    return bool(name.strip()) and printable and name not in (".", "..") and len(name) <= 200


# ------------------------------------------------------------------------------------------------
# Public API
# ------------------------------------------------------------------------------------------------


def from_dict(data: dict, source: str = "") -> Scene:
    """Build and validate a :class:`Scene` from a parsed TOML table."""
    scene = _from_table(Scene, data, "", source)
    scene = _replace_source(scene, source)
    _check(scene)
    return scene


def _replace_source(scene: Scene, source: str) -> Scene:
    from dataclasses import replace

    return replace(scene, source=source)


def load(path: str | Path) -> Scene:
    """Read and validate a scene file; :class:`SceneError` names the file and the key.

    The file must be a regular file of at most :data:`~fenics_garment.bounded.MAX_SCENE_BYTES`,
    its tables nested at most :data:`~fenics_garment.bounded.MAX_DEPTH` deep, and it must set
    something (an empty file is refused: it would dress the default scene without a word)."""
    path = Path(path)
    where = bounded.cut_path(path)
    if bounded.has_control(str(path)):
        raise SceneError(bounded.cut_path(repr(str(path))), "", "the scene file's path has a "
                         "control character (a newline, a tab, …): rename it")  # fmt: skip
    data = _parse(path, where)
    if not data:
        raise SceneError(where, "", "empty scene file: nothing to dress (give at least its "
                         "name and [garment]; see demos/ for complete scenes)")  # fmt: skip
    return from_dict(data, str(path))


def _parse(path: Path, where: str) -> dict:
    """The TOML table of the scene file, bounded (:func:`load`)."""
    try:
        raw = bounded.read_bytes(path, bounded.MAX_SCENE_BYTES, "scene")
        data = tomllib.loads(raw.decode("utf-8"))
        bounded.check_depth(data, str(path))
    except FileNotFoundError:
        raise SceneError(where, "", "no such scene file") from None
    except UnicodeDecodeError as err:
        raise SceneError(where, "", f"not a UTF-8 text file (byte {err.start})") from None
    except OSError as err:
        raise SceneError(where, "", f"cannot read: {err.strerror or err}") from None
    except tomllib.TOMLDecodeError as err:
        raise SceneError(where, "", f"not valid TOML: {bounded.cut(str(err), 200)}") from None
    except RecursionError:
        raise SceneError(where, "", f"nested deeper than {bounded.MAX_DEPTH} levels") from None
    except bounded.BoundError as err:
        raise SceneError("", "", str(err)) from None
    return data


def to_dict(scene: Scene) -> dict:
    """The scene as a TOML-ready table (every key of its kind's sections, defaults included)."""
    d = asdict(scene)
    d.pop("source")
    for other in (k for k in KIND_SECTIONS if k != scene.kind):
        for sec in KIND_SECTIONS[other]:
            d.pop(sec)
    if scene.kind == "garment":  # the default kind is not written: the text of a garment scene
        d.pop("kind")  # (and its checkpoints' fingerprint) is as before drape scenes existed
    return d


def _toml_value(v: Any) -> str:
    if isinstance(v, bool):
        return "true" if v else "false"
    if isinstance(v, int | float):
        return repr(v)
    if isinstance(v, str):  # a TOML basic string: JSON's escapes are TOML's, DEL too
        return json.dumps(v, ensure_ascii=False).replace("\x7f", "\\u007f")
    if isinstance(v, list):
        return "[" + ", ".join(_toml_value(x) for x in v) + "]"
    if isinstance(v, dict):
        return "{ " + ", ".join(f"{_toml_key(k)} = {_toml_value(x)}" for k, x in v.items()) + " }"
    raise TypeError(f"cannot write {v!r} to TOML")


def _toml_key(k: str) -> str:
    return k if re.fullmatch(r"[A-Za-z0-9_-]+", k) else _toml_value(k)


def dumps(scene: Scene) -> str:
    """TOML text of the scene used (defaults filled in); :func:`load` reads it back equal."""
    d = to_dict(scene)
    source = bounded.cut(repr(scene.source)[1:-1], 300) if scene.source else "-"
    lines = [f"# scene used for this run (defaults filled in); from {source}",
             *([f"kind = {_toml_value(d.pop('kind'))}"] if "kind" in d else []),
             f"name = {_toml_value(d.pop('name'))}"]  # fmt: skip
    for section, table in d.items():
        lines += ["", f"[{section}]"]
        lines += [f"{_toml_key(k)} = {_toml_value(v)}" for k, v in table.items()]
    return "\n".join(lines) + "\n"
