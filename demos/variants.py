# # Research variants of the weak form: five laws replaced, one line each
#
# Every physical law of a scene is a value — a short UFL function of documented inputs — and a
# scene's problem is a plain object between build and solve (``scene.build.Built``). A variant
# is a *hook* that edits it, given to ``run(scene, terms=hook)`` (or, from the command line, as
# ``[physics] terms = "module:function"`` in the scene file). Everything downstream is made from
# the terms in use: the residual and its Jacobian (``ufl.derivative``), the contact's active set
# (where the smooth body's curvature enters the Jacobian: where the law in use pushes), the
# stick/slip anchor and multiplier updates (the same UFL law evaluated at the contact points),
# the pressure and membrane-force outputs. A contact law is a function of one argument ``c``,
# its documented inputs (``contact.laws.Inputs``: the gap and its rate, the multiplier, the
# slip, the scene's μ, the warp and weft directions, the position, …).
#
# Five variants on the tight tube (``demos/tube_on_cylinder.toml``: cotton, ease −7 %, a rigid
# cylinder R = 0.1 m, P2B-P2B), each checked against an independent estimate:
#
# 1. a strain-stiffening membrane law, against Laplace's law with the law's hoop tension;
# 2. a smooth (tanh) regularisation of Coulomb friction, with gravity along the tube, against
#    the conservation of force (the body carries the tube's weight ρ h g A) and Laplace;
# 3. an elastic foundation added as an energy, against Laplace plus the foundation's force;
# 4. an exponential pressure–overclosure contact law, against Laplace's law at the radius where
#    the law holds the tube;
# 5. an anisotropic friction law (the weft's coefficient half the warp's), against the weight it
#    holds and Coulomb's sliding force along each yarn.
#
# Each run also reports Newton's constant C of ρ_{k+1} ≤ C ρ_k² (:func:`quadratic_constants`).
#
# ```
# python demos/variants.py   # six tube runs, ~25 s each with a warm JIT cache (cold: minutes)
# ```

# +
from fenics_garment.stack import MPI  # noqa: I001  (MPI before DOLFINx)

import math
import os
from dataclasses import replace
from pathlib import Path

import numpy as np

from fenics_garment.stack import dolfinx, ufl
from fenics_garment.contact import laws, terms
from fenics_garment.contact import pressure as cpressure
from fenics_garment.scene import config
from fenics_garment.scene.run import run
from fenics_garment.shell.energy import membrane_energy
from fenics_garment.verification.contact import tube_pressure

HERE = Path(__file__).resolve().parent
OUT = Path(os.environ.get("VARIANTS_OUTPUT", "output")) / "variants"
comm = MPI.COMM_WORLD
base = config.load(HERE / "tube_on_cylinder.toml")
base = replace(base, output=replace(base.output, pictures=False, vtx=False, xdmf=False))
# -

# ## The reference: Laplace's law of a tube with free ends
#
# The tube (rest radius $r_0$, warp along the axis) is stretched onto the cylinder: its
# mid-surface sits at $R_c = R + h/2$, so the hoop stretch is $\lambda = R_c/r_0$ and the hoop
# Green–Lagrange strain $E = (\lambda^2 - 1)/2$. With free ends the axial force vanishes,
# $S_{zz} = A_{11} E_{zz} + A_{12} E = 0$, so $E_{zz} = -(A_{12}/A_{11}) E$ and
# $\lambda_z = \sqrt{1 + 2E_{zz}}$. The hoop (Cauchy) force is $n = (\lambda/\lambda_z) S$ with
# $S$ the hoop second Piola–Kirchhoff resultant, and the contact pressure $p = n / R_c$ (plus the
# small bending part): ``tube_pressure``. The pressure measured is the contact force over the
# deformed area of the contact points in the middle half of the tube (away from the free ends).


# +
def strains(result) -> tuple[float, float, float, float]:
    """(R_c, r0, λ, λ_z) of the tube of ``result`` (the exact free-end kinematics)."""
    b = result.built
    s = b.model.stiffness
    R_c = b.scene.body.radius + s.thickness / 2
    r0 = b.scene.body.radius + b.garment.level("mid").clearance
    lam = R_c / r0
    e_zz = -s.A12 / s.A11 * (lam**2 - 1) / 2
    return R_c, r0, lam, math.sqrt(1 + 2 * e_zz)


def laplace(result) -> float:
    """Laplace's pressure of the quadratic membrane law with free ends (``tube_pressure``)."""
    R_c, r0, _, _ = strains(result)
    return tube_pressure(R_c, r0, result.built.model.stiffness, warp="axial")


def mid_region(result) -> np.ndarray:
    """The contact points in the middle half of the tube (z within L/4 of the middle)."""
    st = result.built.contact.state
    z = cpressure.positions(st)[:, 2]
    L = result.built.scene.body.length
    return np.abs(z - L / 2) < L / 4


def mid_pressure(result) -> float:
    """Contact force / deformed area over the middle half [Pa] (all ranks)."""
    b = result.built
    st, c = b.contact.state, b.contact
    f = cpressure.point_forces(st, c.traction)
    a = cpressure.point_areas(st, c.area_stretch())
    sel = mid_region(result)
    return comm.allreduce(f[sel].sum(), op=MPI.SUM) / comm.allreduce(a[sel].sum(), op=MPI.SUM)


def quadratic_constants(result) -> list[float]:
    """Per dressing step, the largest C_k = ρ_{k+1}/ρ_k² of its Newton iterations after the
    first, ρ_k = ‖F_k‖/‖F_0‖. Newton's quadratic rate keeps C bounded, ρ_{k+1} ≤ C ρ_k²
    (measured ≤ 13 here); a linear rate ρ_{k+1} = c ρ_k (an inconsistent Jacobian, e.g. the
    Phong normal's c ≈ 0.2) gives C = c/ρ_k, 10⁴ and more once ρ_k < 10⁻⁵. Iterations that end
    below ρ = 10⁻⁸ are left out: there the residual is at the round-off floor of the penalised
    system (the baseline's first step ends 54.7 → 0.35 → 2.0e-4 → 1.1e-7 N, ρ = 2e-9: C = 150
    from that last step alone)."""
    constants = []
    for step in result.report.steps:
        rho = np.asarray(step.residuals) / step.residuals[0] if step.residuals else []
        if step.stage == "dress" and len(rho) >= 3:
            c = rho[2:] / rho[1:-1] ** 2
            above = rho[2:] >= 1e-8
            if above.any():
                constants.append(float(np.max(c[above])))
    return constants


def check(result, p_expected: float, label: str, tol: float) -> float:
    """Assert completion, the pressure within ``tol`` of ``p_expected`` and quadratic Newton
    steps (:func:`quadratic_constants`); print the residual histories; return the pressure."""
    assert result.completed, result.message
    p = mid_pressure(result)
    constants = quadratic_constants(result)
    if comm.rank == 0:
        print(f"{label:<28} p = {p:8.1f} Pa   Laplace {p_expected:8.1f} Pa "
              f"({p / p_expected - 1:+.2%})   Newton C {np.round(constants, 2)}")  # fmt: skip
        for step in (st for st in result.report.steps if st.stage == "dress"):
            history = np.array2string(np.asarray(step.residuals), precision=2)
            print(f"{'':<28} {step.stage:<8} ‖F‖: {history}")
    assert abs(p / p_expected - 1) < tol, (label, p, p_expected)
    assert constants and max(constants) < 100.0, (label, constants)
    return p


def say(text: str) -> None:
    if comm.rank == 0:
        print(text)


# -

# ## The baseline, and what it shares with every variant
#
# The baseline run keeps the default laws. Its residual discretisation error (the garment's
# curved P2 reference mesh at 2 cm on the smooth body: about −0.2 % in pressure,
# docs/verification/shells.md) is shared by every variant, so each variant is checked twice: against
# its analytic pressure directly, and by its *change* from the baseline — a ratio for a law
# that scales the hoop tension, a difference for an added pressure — against the change the
# analytic solution predicts.

# +
baseline = run(replace(base, name="variant-baseline"), OUT, quiet=True)
p_base = check(baseline, laplace(baseline), "baseline (default laws)", tol=0.015)
# -

# ## 1. A strain-stiffening membrane
#
# Knitted and woven fabrics stiffen as their yarns straighten. Add to the quadratic membrane
# energy a quartic term in the hoop (weft) strain,
#
# $$ \psi_m = \tfrac12\,\varepsilon : \mathsf A : \varepsilon
#    + \frac{A_{22}}{4\,\varepsilon_*^2}\,\varepsilon_{22}^4 , $$
#
# which doubles the tangent stiffness at $\varepsilon_{22} = \varepsilon_*/\sqrt3$. The variant
# is one assignment in the hook; the membrane-force output $N = \partial\psi_m/\partial\varepsilon$
# is derived from the law in use.

# +
EPS_STAR = 0.1


def stiffening_membrane(kin, C):
    """ψ_m = ½ ε:A:ε + A22 ε₂₂⁴ / (4 ε*²)."""
    return membrane_energy(kin, C) + C.A22 * kin.membrane[1, 1] ** 4 / (4 * EPS_STAR**2)


def use_stiffening(built) -> None:
    built.model.membrane = stiffening_membrane  # the whole variant


stiff = run(replace(base, name="variant-stiffening"), OUT, quiet=True, terms=use_stiffening)
# -

# The quartic term adds only to the hoop resultant, $S = (A_{22} - A_{12}^2/A_{11})E
# + A_{22}E^3/\varepsilon_*^2$; the axial condition $S_{zz} = 0$, hence $\lambda_z$, is
# unchanged. So the stiffened law's Laplace pressure is the quadratic one plus
# $(\lambda/\lambda_z)\,A_{22}E^3/(\varepsilon_*^2 R_c)$: at $E = 0.081$ the pressure rises
# by about 70 %. The measured rise over the baseline must match the predicted one to 1.5 %,
# and so must the rise of the membrane-force output $N_{22}$ — derived from the law in use (it
# once showed the old law's 39.9 N/m against the true 67.1 N/m).


# +
def hoop_force_mid(result) -> float:
    """Mean output N₂₂ [N/m] over the contact points of the middle half (all ranks)."""
    st = result.built.contact.state
    n22 = st.evaluate(result.built.model.membrane_forces()[1, 1]).ravel()[mid_region(result)]
    return comm.allreduce(n22.sum(), op=MPI.SUM) / comm.allreduce(len(n22), op=MPI.SUM)


s = stiff.built.model.stiffness
R_c, r0, lam, lz = strains(stiff)
E = (lam**2 - 1) / 2
extra = s.A22 * E**3 / EPS_STAR**2
p_quad = tube_pressure(R_c, r0, s, warp="axial")
p_stiff = check(stiff, p_quad + (lam / lz) * extra / R_c, "stiffening membrane", tol=0.015)
rise, predicted = p_stiff / p_base, 1 + (lam / lz) * extra / R_c / p_quad
S_quad = (s.A22 - s.A12**2 / s.A11) * E
n_rise, n_predicted = hoop_force_mid(stiff) / hoop_force_mid(baseline), 1 + extra / S_quad
say(f"{'':<28} pressure ×{rise:.4f} (predicted ×{predicted:.4f}), "
    f"N22 ×{n_rise:.4f} (predicted ×{n_predicted:.4f})")  # fmt: skip
assert abs(rise / predicted - 1) < 0.015, (rise, predicted)
assert abs(n_rise / n_predicted - 1) < 0.015, (n_rise, n_predicted)
assert stiff.summary["terms"]["membrane"].endswith("stiffening_membrane")
# -

# ## 2. Another regularisation of Coulomb friction
#
# The default law is the return map: elastic stick $t_T = -\kappa_T\Delta u_T$ up to the cone
# $|t_T| = \mu t_N$. A smooth alternative saturates instead of switching,
#
# $$ t_T = -\mu t_N \tanh\!\Big(\frac{\kappa_T |\Delta u_T|}{\mu t_N}\Big)
#          \frac{\Delta u_T}{|\Delta u_T|} , $$
#
# with the same initial stiffness $\kappa_T$ and the same limit $\mu t_N$. One assignment
# replaces it in the residual, in the stick/slip anchor update ($u_{\rm anchor} \leftarrow u +
# t_T/\kappa_T$, evaluated from this expression) and in the reaction output. With gravity along
# the tube (the cylinder's axis is $z$) the friction must hold the tube up: the body's reaction
# balances the weight $\rho h g A$ (a conservation check; the stabilising spring is released).

# +
TINY = 1e-9  # [Pa]: keeps the law finite where μ t_N = 0 (friction off while dressing)
#: tanh(20) = 1 in double precision; capping the argument there keeps its derivative finite
#: (UFL differentiates tanh as sech², 2 cosh y / (cosh 2y + 1): inf/inf = NaN for y ≳ 355)
SATURATED = 20.0


def tanh_friction(c, eps=1e-30):
    """t_T = −μ t_N tanh(κ_T |Δu_T| / (μ t_N)) Δu_T / |Δu_T|."""
    norm = ufl.sqrt(ufl.dot(c.slip, c.slip) + eps)
    limit = c.mu * c.normal_traction
    z = ufl.min_value(c.kappa_t * norm / (limit + TINY), SATURATED)
    return -limit * ufl.tanh(z) * c.slip / norm


def use_tanh_friction(built) -> None:
    built.contact.friction = replace(built.contact.friction, law=tanh_friction)


heavy = replace(base, name="variant-tanh-friction", physics=replace(base.physics, gravity=True))
fric = run(heavy, OUT, quiet=True, terms=use_tanh_friction)
p_fric = check(fric, laplace(fric), "tanh friction, gravity", tol=0.015)
assert abs(p_fric / p_base - 1) < 0.005, (p_fric, p_base)  # friction changes no normal force
forces = fric.summary["forces_N"]
applied, reaction = np.array(forces["applied"]), np.array(forces["reaction"])
model = fric.built.model
garment_area = comm.allreduce(
    float(cpressure.point_areas(fric.built.contact.state, ufl.as_ufl(1.0)).sum()), op=MPI.SUM
)  # the reference area ∫ dA at the contact points
weight = model.stiffness.mass_per_area * 9.80665 * garment_area
assert abs(applied[2] / -weight - 1) < 1e-6, (applied, weight)
assert abs(reaction[2] / weight - 1) < 1e-4, (reaction, weight)  # measured 4e-7
assert fric.summary["terms"]["friction_law"].endswith("tanh_friction")
say(f"{'':<28} weight {weight:.4f} N, body reaction {reaction[2]:.4f} N")
# -

# ## 3. An elastic foundation, added as an energy
#
# Tie the tube to its pattern radius with a Winkler foundation of stiffness $k_f$ [Pa/m]:
#
# $$ \Pi_f = \tfrac12 \int k_f\,(\rho - r_0)^2\,dA, \qquad
#    \rho = |(\mathbf X + \mathbf u)_\perp| , $$
#
# $\rho$ the distance of the current point from the axis. ``model.add_energy`` adds it to
# $\Pi$, so it is varied with the rest (and the Jacobian stays consistent). On the body the
# tube now presses with its hoop force and the foundation's pull, $k_f (R_c - r_0)$ per
# reference area, i.e. $k_f (R_c - r_0)/(\lambda \lambda_z)$ per deformed area.

# +
K_F = 0.5 * p_quad / (R_c - r0)  # [Pa/m]: the foundation adds about half the pressure


def use_foundation(built) -> None:
    m = built.model
    x = ufl.SpatialCoordinate(m.geometry.mesh) + m.u
    rho = ufl.sqrt(x[0] ** 2 + x[1] ** 2)
    r_pattern = built.scene.body.radius + built.garment.level("mid").clearance
    m.add_energy(0.5 * m.constant(K_F) * (rho - r_pattern) ** 2)


found = run(replace(base, name="variant-foundation"), OUT, quiet=True, terms=use_foundation)
R_c, r0, lam, lz = strains(found)
p_extra = K_F * (R_c - r0) / (lam * lz)
p_found = check(found, p_quad + p_extra, "elastic foundation", tol=0.015)
say(f"{'':<28} added {p_found - p_base:.1f} Pa (predicted {p_extra:.1f} Pa)")
assert abs((p_found - p_base) / p_extra - 1) < 0.015, (p_found - p_base, p_extra)
assert found.summary["terms"]["added_energies"] == ["expression"]
# -

# ## 4. An exponential pressure–overclosure contact law
#
# Between garment and skin, a compressible layer (a quilted lining, say) pushes before they touch
# and stiffens as it is squeezed. The exponential pressure–overclosure law gives the pressure
# $p_0$ at zero gap, nothing beyond the layer's reach $c_0$, and a zero slope there:
#
# $$ t_N = \frac{p_0}{e - 1}\, x\,(e^x - 1), \qquad x = \langle 1 - g/c_0 \rangle_+ . $$
#
# It is a *soft* law, not a constraint: it does not use the multiplier, and the tube settles at
# the gap where the law's pressure balances the hoop tension. The augmented Lagrangian, which
# would drive that gap to zero, refuses it in one line before solving, so the scene runs with the
# penalty's solver (``[physics] contact = "penalty"``; the penalty κ itself is unused by the law).
# The tube floats off the body, where the default law carries nothing: the smooth body's
# curvature enters the Jacobian wherever the law in use pushes, so Newton stays quadratic
# (``tests/test_contact_law_newton.py``: with the curvature only where the *default* law
# pushes, a cap held 2 mm off the body ended its steps with C = 2078).
#
# The reference is Laplace's law at the radius the law holds the tube at, $R_m = R_c + g$ with
# $g$ the mean gap over the middle half, weighted by the contact points' areas: $\lambda =
# R_m/r_0$ in ``tube_pressure``. (The gap is not uniform: the lumped rule's vertex, edge and
# centre points carry −20 %, +26 % and −3 % of the mean traction at equilibrium, with the
# penalty too; a soft law turns that into ±0.15 mm of gap.) The reported pressure must equal
# it, and the law evaluated by hand (NumPy) at the measured gaps.

# +
P0, C0 = 1.0e3, 2.0e-3  # [Pa], [m]


def exponential_contact(c):
    """t_N = p₀ x (eˣ − 1)/(e − 1), x = ⟨1 − g/c₀⟩₊."""
    x = laws.macaulay(1.0 - c.gap / C0)
    return P0 / (math.e - 1.0) * x * (ufl.exp(x) - 1.0)


def use_exponential_contact(built) -> None:
    built.contact.normal_law = exponential_contact


soft = replace(base, name="variant-exponential-contact",
               physics=replace(base.physics, contact="penalty"))  # fmt: skip
expo = run(soft, OUT, quiet=True, terms=use_exponential_contact)
st = expo.built.contact.state
sel = mid_region(expo)
gaps = st.local_values(st.gap)[sel]
areas = cpressure.point_areas(st, ufl.as_ufl(1.0))[sel]  # reference areas of the points
g_mid = comm.allreduce(float((gaps * areas).sum()), op=MPI.SUM) / comm.allreduce(
    float(areas.sum()), op=MPI.SUM
)
R_c, r0, _, _ = strains(expo)
p_expo = check(expo, tube_pressure(R_c + g_mid, r0, expo.built.model.stiffness, warp="axial"),
               "exponential contact law", tol=0.015)  # fmt: skip
x = np.maximum(1.0 - gaps / C0, 0.0)
by_hand = P0 / (math.e - 1.0) * x * np.expm1(x)  # per reference area, at the measured gaps
deformed = cpressure.point_areas(st, expo.built.contact.area_stretch())[sel]
p_hand = comm.allreduce(float((by_hand * areas).sum()), op=MPI.SUM) / comm.allreduce(
    float(deformed.sum()), op=MPI.SUM
)
say(f"{'':<28} mean gap {g_mid * 1e3:.3f} mm; the law at the measured gaps {p_hand:.2f} Pa")
assert abs(p_expo / p_hand - 1) < 1e-9, (p_expo, p_hand)
assert g_mid > 0.0  # off the body: only a law that pushes before contact holds it there
assert expo.summary["terms"]["normal_law"].endswith("exponential_contact")
# -

# ## 5. Anisotropic friction
#
# A woven fabric slides more easily along one yarn than along the other. Coulomb friction along
# each yarn, with the scene's μ along the warp and half of it along the weft, smoothed like the
# tanh law of variant 2, is a few lines: the law gets the warp and weft directions on the
# deformed garment (``c.warp``, ``c.weft``) and the scene's coefficient ``c.mu``. The dressing
# switches friction off while the body grows and on at s = 0 by a factor on the law's traction,
# so the law is switched however it is written.
#
# Two references. With gravity along the tube (the warp), the body must carry the weight, as in
# variant 2. And on the dressed tube, sliding far along the warp (the anchors moved by 5 cm
# along the axis) the friction force must be Coulomb's $\mu \sum t_N\,dA$ along the axis;
# sliding along the weft (round the hoop) the friction torque about the axis
# $\tfrac12\mu \sum t_N\, r\, dA$.

# +
WEFT_RATIO = 0.5


def yarn_friction(c):
    """t_T = −Σ μ_i t_N tanh(κ_T s_i / (μ_i t_N)) a_i over the warp and weft a_i (made tangent
    to the body), s_i = Δu_T·a_i, μ_warp = μ, μ_weft = μ/2."""
    t = 0
    for mu, yarn in ((c.mu, c.warp), (WEFT_RATIO * c.mu, c.weft)):
        a = yarn - ufl.dot(yarn, c.normal) * c.normal
        a = a / ufl.sqrt(ufl.dot(a, a))
        limit = mu * c.normal_traction
        z = c.kappa_t * ufl.dot(c.slip, a) / (limit + TINY)
        t += -limit * ufl.tanh(ufl.max_value(ufl.min_value(z, SATURATED), -SATURATED)) * a
    return t


def use_yarn_friction(built) -> None:
    built.contact.friction = replace(built.contact.friction, law=yarn_friction)


yarn = run(replace(heavy, name="variant-yarn-friction"), OUT, quiet=True, terms=use_yarn_friction)
p_yarn = check(yarn, laplace(yarn), "yarn friction, gravity", tol=0.015)
reaction = np.array(yarn.summary["forces_N"]["reaction"])
assert abs(reaction[2] / weight - 1) < 1e-4, (reaction, weight)
say(f"{'':<28} weight {weight:.4f} N, body reaction {reaction[2]:.4f} N")
assert yarn.summary["terms"]["friction_law"].endswith("yarn_friction")


def friction_torque(contact) -> float:
    """∫ (x × t_T)·e_z dA of the friction traction in use [N m] (all ranks)."""
    st = contact.state
    x = ufl.SpatialCoordinate(st.mesh) + st.u
    t_t = terms.tractions(st, contact.kappa)[1]
    form = dolfinx.fem.form((x[0] * t_t[1] - x[1] * t_t[0]) * st.dx)
    return comm.allreduce(dolfinx.fem.assemble_scalar(form), op=MPI.SUM)


contact = yarn.built.contact
st = contact.state
mu = float(contact.friction.mu.value)
forces = cpressure.point_forces(st, contact.traction)  # t_N dA per point
xq = cpressure.positions(st)
radius = np.hypot(xq[:, 0], xq[:, 1])
normal_force = comm.allreduce(float(forces.sum()), op=MPI.SUM)
moment = comm.allreduce(float((forces * radius).sum()), op=MPI.SUM)
u_k, anchors = st.local_values(st.u_k), st.local_values(st.u_old)
try:
    st.set_local_values(st.u_old, u_k - 0.05 * np.array([0.0, 0.0, 1.0]))  # along the warp
    warp_force = contact.reaction((0.0, 0.0, 1.0))
    hoop = np.column_stack([-xq[:, 1], xq[:, 0], 0.0 * radius]) / radius[:, None]
    st.set_local_values(st.u_old, u_k - 0.05 * hoop)  # along the weft
    weft_torque = friction_torque(contact)
finally:
    st.set_local_values(st.u_old, anchors)  # the converged state's anchors back
coulomb_warp, coulomb_weft = -mu * normal_force, -WEFT_RATIO * mu * moment
say(f"{'':<28} sliding along the warp {warp_force:.4f} N (Coulomb {coulomb_warp:.4f} N), "
    f"along the weft {weft_torque:.5f} N m (Coulomb {coulomb_weft:.5f} N m)")  # fmt: skip
assert abs(warp_force / coulomb_warp - 1) < 2e-3, (warp_force, coulomb_warp)
assert abs(weft_torque / coulomb_weft - 1) < 2e-3, (weft_torque, coulomb_weft)
# -
