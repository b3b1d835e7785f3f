r"""A cantilever bending under its own weight: the heavy elastica and the shell strip.

**The heavy elastica** (Peirce 1930; Bisshopp & Drucker, Q. Appl. Math. 3 (1945) 272–275 for
the tip load, the distributed-weight case in Frisch-Fay, *Flexible Bars*, 1962, §2): an
inextensible strip of length L, bending rigidity B per unit width and weight W per unit area,
clamped horizontally at one end. With s ∈ [0, 1] the arc length over L and θ(s) the angle of
the tangent below the horizontal, the moment balance reads

.. math::
    \theta'' = -\Gamma\,(1 - s)\cos\theta, \qquad \theta(0) = 0,\quad \theta'(1) = 0, \qquad
    \Gamma = \frac{W L^3}{B},

and the tip sits at x/L = ∫cos θ ds, δ/L = ∫sin θ ds below the clamp. Everything depends on Γ
alone (the master curve). For small Γ, δ/L = Γ/8 and θ(1) = Γ/6 (Euler–Bernoulli).

**ASTM D1388** (option A, cantilever): the overhang L is pushed out until the line from the
clamp edge to the tip makes 41.5° with the horizontal; the bending length is c = L/2. Peirce's
approximate solution of the elastica gives c = (B/W)^{1/3} at that angle — the reason for
41.5°: c³ = L³ cos(θ/2)/(8 tan θ) = L³/8 there. The exact elastica reaches 41.5° at a Γ of its
own (:func:`chord_gamma`), so the exact c/(B/W)^{1/3} = Γ*^{1/3}/2 differs slightly from 1.

**The shell strip**: a flat strip L × b of the package's Naghdi shell, clamped along x = 0 (u =
0, θ = 0), loaded by its self weight ρh g along −z in load steps. Its bending stiffness per unit
width is D11 of the material (plate: E h³/12(1−ν²) for an isotropic one). A beam of the same
section has E h³/12 per unit width: with ν ≠ 0 a plate strip in cylindrical bending is stiffer
by 1/(1 − ν²), while a narrow strip is free to curl anticlastically and bends with
D11 − D12²/D22 (= E h³/12 for isotropic); which of the two a strip shows depends on Searle's
parameter b²/(R t) (Searle, *Experimental Elasticity*, 1908; Ashwell, J. R. Aeronaut. Soc. 54
(1950) 708). The master curve is therefore compared at ν = 0, where all of these agree.
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass, field, replace

import numpy as np
from scipy.integrate import solve_bvp
from scipy.optimize import brentq

from fenics_garment import units
from fenics_garment._stack import MPI
from fenics_garment.materials import Fabric, Isotropic
from fenics_garment.path import DofProbe
from fenics_garment.shell import bcs as B
from fenics_garment.shell.geometry import parametric_surface_mesh
from fenics_garment.shell.kinematics import ShellGeometry
from fenics_garment.shell.model import ShellModel
from fenics_garment.solve import LoadStepper, NonlinearSolver

#: ASTM D1388 (stiffness of fabrics), option A (cantilever): the tip-to-clamp line at 41.5°
#: below the horizontal.
ASTM_D1388_ANGLE_DEG = 41.5
#: ASTM D1388 specimen width, 25 mm (its length, 200 mm, only bounds the overhang).
ASTM_D1388_WIDTH = 0.025


# ---------------------------------------------------------------------------------------------
# The heavy elastica (reference)
# ---------------------------------------------------------------------------------------------
@dataclass(frozen=True)
class Elastica:
    """The heavy elastica at Γ: tip drop δ/L, tip horizontal position x/L, tip angle θ(1) [rad],
    clamp curvature θ'(0) (= M(0) L/B) and the tip-to-clamp (chord) angle [rad]."""

    gamma: float
    tip_drop: float
    tip_x: float
    tip_angle: float
    root_curvature: float

    @property
    def chord_angle(self) -> float:
        return math.atan2(self.tip_drop, self.tip_x)


def _elastica_bvp(gamma: float, guess=None):
    def rhs(s, y):
        th, k = y[0], y[1]
        return np.vstack([k, -gamma * (1 - s) * np.cos(th), np.cos(th), np.sin(th)])

    def bc(y0, y1):
        return np.array([y0[0], y1[1], y0[2], y0[3]])

    s = np.linspace(0.0, 1.0, 201)
    if guess is None:  # the linear (Euler–Bernoulli) solution
        th = gamma / 6 * (1 - (1 - s) ** 3)
        y = np.vstack([th, gamma / 2 * (1 - s) ** 2, s, np.zeros_like(s)])
    else:
        y = guess.sol(s)
    sol = solve_bvp(rhs, bc, s, y, tol=1e-10, max_nodes=100000)
    if not sol.success:
        raise RuntimeError(f"heavy elastica Γ = {gamma:g}: solve_bvp failed ({sol.message})")
    return sol


def heavy_elastica(gamma: float) -> Elastica:
    """The heavy elastica at Γ = W L³/B, by SciPy's ``solve_bvp`` (collocation, tolerance 1e-10)
    on θ'' = −Γ(1 − s) cos θ with x' = cos θ, z' = sin θ; continued in Γ from the linear
    solution at Γ ≤ 1 (large Γ needs a guess near the bent shape)."""
    if not (gamma > 0 and math.isfinite(gamma)):
        raise ValueError(f"Γ must be a positive finite number, got {gamma!r}")
    sol = None
    g = min(gamma, 1.0)
    while True:
        sol = _elastica_bvp(g, sol)
        if g >= gamma:
            break
        g = min(gamma, 2.0 * g)
    th, k, x, z = sol.sol(np.array([0.0, 1.0]))
    return Elastica(gamma, float(z[1]), float(x[1]), float(th[1]), float(k[0]))


def chord_gamma(angle_deg: float = ASTM_D1388_ANGLE_DEG) -> float:
    """The Γ at which the elastica's tip-to-clamp line makes ``angle_deg`` with the horizontal."""
    t = math.tan(math.radians(angle_deg))
    if not (0 < t < 1e3):
        raise ValueError(f"angle must lie in (0°, 90°), got {angle_deg}")

    def rhs(s, y, p):
        th = y[0]
        return np.vstack([y[1], -p[0] * (1 - s) * np.cos(th), np.cos(th), np.sin(th)])

    def bc(y0, y1, p):  # Γ is the unknown parameter; the fifth condition is the chord angle
        return np.array([y0[0], y1[1], y0[2], y0[3], y1[3] - t * y1[2]])

    g0 = 8.0  # Peirce's value at 41.5°: a guess, refined by the collocation
    guess = _elastica_bvp(g0, _elastica_bvp(4.0, _elastica_bvp(2.0, _elastica_bvp(1.0))))
    s = np.linspace(0.0, 1.0, 201)
    sol = solve_bvp(rhs, bc, s, guess.sol(s), p=[g0], tol=1e-10, max_nodes=100000)
    if not sol.success:
        raise RuntimeError(f"chord angle {angle_deg}°: solve_bvp failed ({sol.message})")
    return float(sol.p[0])


def peirce_bending_length(B: float, W: float) -> float:
    """Peirce's bending length c = (B/W)^(1/3) [m], B per unit width [N·m], W weight per area
    [N/m²] (F. T. Peirce, J. Text. Inst. 21 (1930) T377–T416)."""
    return (B / W) ** (1.0 / 3.0)


# ---------------------------------------------------------------------------------------------
# The shell strip
# ---------------------------------------------------------------------------------------------
@dataclass
class Strip:
    """A clamped shell strip under self weight, with probes at the tip's mid-point."""

    model: ShellModel
    solver: NonlinearSolver
    stepper: LoadStepper
    length: float
    width: float
    #: the gravity vector's Constant (its value at load factor 1)
    gravity: object
    probes: dict[str, DofProbe] = field(default_factory=dict)

    def gamma(self, load_factor: float | None = None) -> float:
        """Γ = W L³/D11 at ``load_factor`` (default: the current one)."""
        lam = float(self.model.load_factor.value) if load_factor is None else load_factor
        s = self.model.stiffness
        W = s.mass_per_area * float(np.linalg.norm(self.gravity.value)) * lam
        return W * self.length**3 / s.D11

    def load_factor_for(self, gamma: float) -> float:
        return gamma / self.gamma(1.0)

    def tip(self) -> Elastica:
        """The tip of the current state as an :class:`Elastica` record (curvature NaN)."""
        L = self.length
        ux, uz, ty = (self.probes[k]() for k in ("ux", "uz", "ty"))
        return Elastica(self.gamma(), -uz / L, (L + ux) / L, ty, math.nan)


def strip(
    material: Isotropic | Fabric,
    length: float,
    width: float,
    *,
    gamma_max: float | None = None,
    gravity: float = units.GRAVITY,
    n: int = 32,
    n_width: int = 1,
    element: str | None = None,
    steps: int = 10,
    comm=MPI.COMM_WORLD,
) -> Strip:
    """A strip [0, L] × [0, b] in the plane z = 0, warp along x, clamped at x = 0, self weight
    along −z: ``gravity`` m/s² at load factor 1, or the gravity that gives Γ = ``gamma_max``
    there. ``n`` cells along, ``n_width`` across (each a pair of triangles), order-2 geometry."""
    L, b = length, width
    mesh = parametric_surface_mesh(comm, lambda x, y: np.array([x, y, 0.0 * x]),
                                   (0.0, L), (0.0, b), (n, n_width))  # fmt: skip
    model = ShellModel(ShellGeometry.from_mesh(mesh, warp=(1, 0, 0)), material, element=element)
    s = model.stiffness
    if s.mass_per_area <= 0:
        raise ValueError("the strip's material needs a density > 0 (its self weight)")
    if gamma_max is not None:
        gravity = gamma_max * s.D11 / (s.mass_per_area * L**3)
    g = model.add_gravity((0.0, 0.0, -gravity))
    bcs = B.clamped(model, lambda x: np.isclose(x[0], 0.0))
    solver = NonlinearSolver(model, bcs)
    tip = (L, b / 2, 0.0)
    probes = {"ux": DofProbe.at_point(model, tip, 0), "uz": DofProbe.at_point(model, tip, 2),
              "ty": DofProbe.at_point(model, tip, 1, field=1)}  # fmt: skip
    model.load_factor.value = 0.0
    stepper = LoadStepper(solver, steps=steps, max_cuts=8)
    return Strip(model, solver, stepper, L, b, g, probes)


@dataclass
class CurvePoint:
    gamma: float
    model: Elastica
    reference: Elastica
    wall_s: float

    @property
    def drop_error(self) -> float:
        return self.model.tip_drop / self.reference.tip_drop - 1

    @property
    def angle_error(self) -> float:
        return self.model.tip_angle / self.reference.tip_angle - 1


#: The master curve's Γ values (10⁻² … 10²).
MASTER_GAMMAS = (0.01, 0.1, 1.0, 3.0, 10.0, 30.0, 100.0)

#: The master-curve strip: L = 1 m, b = 0.1 m, h = 0.01 m, E = 1.2e6 Pa, ν = 0, ρ = 100 kg/m³;
#: the gravity is set per Γ. h/L = 0.01 keeps the membrane and transverse-shear strains
#: ≈ Γ (h/L)²/12 ≤ 1e-3 at Γ = 100: the strip is inextensible to that order.
MASTER_MATERIAL = Isotropic(E=1.2e6, nu=0.0, thickness=0.01, density=100.0, name="strip")


def master_curve(
    gammas=MASTER_GAMMAS,
    *,
    n: int = 32,
    material: Isotropic | Fabric = MASTER_MATERIAL,
    length: float = 1.0,
    width: float = 0.1,
    comm=MPI.COMM_WORLD,
) -> tuple[list[CurvePoint], Strip]:
    """Tip drop and angle of the shell strip along one load path through ``gammas`` (ascending;
    the load stepper continues from each to the next), each beside :func:`heavy_elastica`."""
    gammas = sorted(gammas)
    st = strip(material, length, width, gamma_max=gammas[-1], n=n, comm=comm)
    out = []
    for g in gammas:
        t0 = time.perf_counter()
        st.stepper.run(st.load_factor_for(g))
        out.append(CurvePoint(g, st.tip(), heavy_elastica(g), time.perf_counter() - t0))
    return out, st


def effective_rigidity(
    width: float,
    *,
    nu: float = 0.3,
    gamma: float = 3.0,
    n: int = 16,
    n_width: int = 4,
    comm=MPI.COMM_WORLD,
) -> tuple[float, float]:
    """The plate-vs-beam (anticlastic) effect: an isotropic strip L = 1 m, h = 0.01 m of width
    ``width`` and Poisson ratio ``nu`` under the self weight of Γ = W L³/D = ``gamma`` (D the
    plate rigidity E h³/12(1 − ν²)). Returns (tip drop δ/L, B_eff/D) with B_eff the rigidity of
    the elastica that drops as far (1 for cylindrical bending, 1 − ν² for a beam)."""
    mat = Isotropic(E=1.2e6, nu=nu, thickness=0.01, density=100.0, name="strip")
    st = strip(mat, 1.0, width, gamma_max=gamma, n=n, n_width=n_width, comm=comm)
    st.stepper.run(1.0)
    drop = st.tip().tip_drop
    g_eff = brentq(lambda g: heavy_elastica(g).tip_drop - drop, 0.3 * gamma, 3.0 * gamma,
                   xtol=1e-10)  # fmt: skip
    return drop, gamma / g_eff


# ---------------------------------------------------------------------------------------------
# ASTM D1388 bending length of the model
# ---------------------------------------------------------------------------------------------
@dataclass
class BendingLength:
    """The model's ASTM D1388 bending length c = L*/2 (L* the overhang at 41.5°), the strip's Γ
    there, and the overhang iterations."""

    c: float
    overhang: float
    gamma: float
    iterations: list[tuple[float, float]]  # (overhang L, Γ at 41.5° on that strip)
    wall_s: float


def _chord_crossing(st: Strip, target: float, *, max_gamma: float = 40.0) -> float:
    """Γ at which the strip's chord angle passes ``target`` [rad]: load steps up to the first
    state beyond it, then secant iterations on Newton solves between the bracketing states."""
    lo_g, lo_a, lo_q = 0.0, 0.0, st.model.q.x.array.copy()
    g = 2.0
    while True:
        st.stepper.run(st.load_factor_for(g))
        a = st.tip().chord_angle
        if a >= target:
            break
        lo_g, lo_a, lo_q = g, a, st.model.q.x.array.copy()
        g *= 1.5
        if g > max_gamma:
            raise RuntimeError(f"chord angle {math.degrees(a):.1f}° < target up to Γ = {g:.3g}")
    hi_g, hi_a = g, a
    q = st.model.q
    for _ in range(30):
        g = lo_g + (target - lo_a) * (hi_g - lo_g) / (hi_a - lo_a)
        q.x.array[:] = lo_q
        q.x.scatter_forward()
        st.model.load_factor.value = st.load_factor_for(g)
        _, reason = st.solver.solve()
        if reason <= 0:
            raise RuntimeError(f"Newton failed at Γ = {g:.6g} (reason {reason})")
        a = st.tip().chord_angle
        if abs(a - target) < 1e-9:
            return g
        if a < target:
            lo_g, lo_a, lo_q = g, a, q.x.array.copy()
        else:
            hi_g, hi_a = g, a
    return g


def across(material: Fabric) -> Fabric:
    """The same fabric turned by 90° in its plane (weft along e₁): for a weft-direction strip.
    ν21 = ν12 E_weft/E_warp keeps the membrane compliance symmetric."""
    return replace(material, E_warp=material.E_weft, E_weft=material.E_warp,
                   B_warp=material.B_weft, B_weft=material.B_warp,
                   nu12=material.nu12 * material.E_weft / material.E_warp,
                   name=f"{material.name} (weft)")  # fmt: skip


def bending_length(
    material: Fabric | Isotropic,
    *,
    width: float = ASTM_D1388_WIDTH,
    angle_deg: float = ASTM_D1388_ANGLE_DEG,
    n: int = 24,
    n_width: int = 6,
    rtol: float = 1e-3,
    comm=MPI.COMM_WORLD,
) -> BendingLength:
    """The ASTM D1388 bending length the shell model gives for ``material`` (warp along the
    strip): the overhang L* at which the tip-to-clamp line makes ``angle_deg`` under standard
    gravity, c = L*/2.

    For a given strip length the load factor (the gravity) is raised until the chord angle
    reaches the target, which gives that strip's Γ*; the overhang that has Γ* under standard
    gravity is L' = (Γ* D11/W)^(1/3). The strip is rebuilt at L' until L changes by < ``rtol``
    (Γ* depends on L only through b/L and the thickness ratio: one or two rebuilds).

    Mesh: ``n`` × ``n_width`` cell pairs. A strip about as wide as long needs cells across
    it: the anticlastic boundary layers at its free edges (measured, polyester P-m1, b = 25 mm:
    Γ* ≈ 5.3 with one cell across — a spurious softening, Newton cutting back — against
    7.941 / 7.952 with 4 / 8 across at n = 16, and 7.956 at n = 32 with 4 across).
    """
    t0 = time.perf_counter()
    s = material.stiffness()
    W = s.mass_per_area * units.GRAVITY
    L = 2.0 * peirce_bending_length(s.D11, W)
    target = math.radians(angle_deg)
    its: list[tuple[float, float]] = []
    for _ in range(6):
        st = strip(material, L, width, gravity=units.GRAVITY, n=n, n_width=n_width, comm=comm)
        g = _chord_crossing(st, target)
        its.append((L, g))
        L_new = (g * s.D11 / W) ** (1.0 / 3.0)
        done = abs(L_new / L - 1) < rtol
        L = L_new
        if done:
            break
    return BendingLength(L / 2, L, its[-1][1], its, time.perf_counter() - t0)
