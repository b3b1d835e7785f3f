"""Path following (``fenics_garment.path``) against analytic equilibrium paths, and the Sze et al.
hinged roof against its published limit loads.

The analytic model: a shallow two-bar (von Mises) truss whose apex (deflection u₁) is pushed
through a linear spring k by the load P at the far end of the spring (deflection u₂). With
EA/L³ = 1 and rise h = 1 the truss resists r(u₁) = (u₁² − 2u₁)(u₁ − 1) and equilibrium is

    P = r(u₁),   u₂ = u₁ + P/k.

P(u₁) has its limit points where r'(u₁) = 3u₁² − 6u₁ + 2 = 0, u₁ = 1 ∓ 1/√3, P = ±2/(3√3)
(snap-through); u₂(u₁) turns back where du₂/du₁ = 1 + r'(u₁)/k = 0, u₁ = 1 ∓ √((1 − k)/3),
which exists for k < −min r' = 1 (snap-back); for k = 1/2, u₁ = 1 ∓ 1/√6 and
r = ±5/(6√6). Load control stops at the first limit point; displacement control of u₁ passes
the snap-through but not the snap-back of u₂; the arc length passes both.
"""

import math

import numpy as np
import pytest

from fenics_garment._stack import MPI, dolfinx, ufl
from fenics_garment.path import (
    ArcLength,
    DisplacementControl,
    DofProbe,
    LimitPointWarning,
    newtonal_path,
)
from fenics_garment.solve import LoadStepper, NonlinearSolver, SolveFailed

K = 0.5
P_LIMIT = 2 / (3 * math.sqrt(3))  # ±, at u₁ = 1 ∓ 1/√3
U1_TURN = (1 - 1 / math.sqrt(6), 1 + 1 / math.sqrt(6))  # where u₂(u₁) turns back


def r(u1):
    return (u1**2 - 2 * u1) * (u1 - 1)


def u2_of(u1):
    return u1 + r(u1) / K


class TrussSpring:
    """The two-dof model above on a one-cell mesh (DG0, two components): q = (u₁, u₂)."""

    def __init__(self):
        mesh = dolfinx.mesh.create_unit_interval(MPI.COMM_SELF, 1)
        self.Q = dolfinx.fem.functionspace(mesh, ("DG", 0, (2,)))
        self.q = dolfinx.fem.Function(self.Q)
        self.load_factor = dolfinx.fem.Constant(mesh, 0.0)

    def residual(self):
        u1, u2 = self.q[0], self.q[1]
        v = ufl.TestFunction(self.Q)
        spring = K * (u2 - u1)
        return (r(u1) - spring) * v[0] * ufl.dx + (spring - self.load_factor) * v[1] * ufl.dx

    def jacobian(self, F):
        return ufl.derivative(F, self.q, ufl.TrialFunction(self.Q))

    def tangent_load(self):  # −∂F/∂λ
        return ufl.TestFunction(self.Q)[1] * ufl.dx


def first_maximum(lam):
    return lam[: int(np.argmax(np.diff(lam) < 0)) + 1].max()


def _probe(model, index):
    e = dolfinx.fem.petsc.create_vector(model.Q)
    e.zeroEntries()
    e.setValue(index, 1.0)
    e.assemble()
    return DofProbe(model, e)


@pytest.fixture
def truss():
    model = TrussSpring()
    return model, NonlinearSolver(model, [])


def test_arc_length_passes_snap_through_and_snap_back(truss):
    model, solver = truss
    u1, u2 = _probe(model, 0), _probe(model, 1)
    path = ArcLength(solver, monitor=u2)
    states = []
    path.on_step = lambda p: states.append((p.load_factor, u1(), u2()))
    path.run(0.02, max_step_ratio=1.0, lambda_max=1.0, max_steps=400)
    lam, a, b = np.array(states).T
    # every point is on the analytic path (residual converged) ...
    assert np.allclose(lam, r(a), atol=1e-8) and np.allclose(b, u2_of(a), atol=1e-7)
    # ... and the path is followed continuously, through both limit loads and both turns of u₂
    assert np.max(np.abs(np.diff(a))) < 0.1
    assert first_maximum(lam) == pytest.approx(P_LIMIT, rel=2e-3)
    assert lam.min() == pytest.approx(-P_LIMIT, rel=2e-3)
    assert b[: np.argmax(lam < 0)].max() == pytest.approx(u2_of(U1_TURN[0]), abs=1e-2)
    assert b[np.argmax(lam < 0) :].min() == pytest.approx(u2_of(U1_TURN[1]), abs=1e-2)
    assert np.any(np.diff(b) < 0)  # u₂ went back: the snap-back was traced, not jumped
    assert lam[-1] >= 1.0 and a[-1] > 2.0  # the stiffening branch beyond the inverted apex
    assert path.stats.cuts == 0


def test_displacement_control_lands_on_the_analytic_load(truss):
    """u₁ prescribed from 0 to 2.5: λ = r(u₁) at every point, through both limit loads."""
    model, solver = truss
    u1 = _probe(model, 0)
    path = DisplacementControl(solver, u1)
    history = path.run(0.05, 2.5, max_increment=0.1)
    w = np.array([p.value for p in history])
    lam = np.array([p.load_factor for p in history])
    assert w[-1] == pytest.approx(2.5, abs=1e-12)
    assert np.allclose(lam, r(w), atol=1e-8)
    assert first_maximum(lam) == pytest.approx(P_LIMIT, rel=2e-2)
    assert lam.min() == pytest.approx(-P_LIMIT, rel=2e-2)
    assert lam[-1] == pytest.approx(r(2.5), rel=1e-8)


def test_snes_newtonal_traces_the_same_path(truss):
    """PETSc's SNESNEWTONAL (fixed arc length, every dof weighted) on the same model."""
    model, solver = truss
    u1, u2 = _probe(model, 0), _probe(model, 1)
    result = newtonal_path(solver, 0.05, lambda_max=1.0, max_steps=400, monitor=u2)
    assert result.reason > 0
    lam = np.array([p.load_factor for p in result.history])
    b = np.array([p.value for p in result.history])
    assert lam[-1] == pytest.approx(1.0)
    assert first_maximum(lam) == pytest.approx(P_LIMIT, rel=1e-2)
    assert lam.min() == pytest.approx(-P_LIMIT, rel=1e-2)
    assert np.any(np.diff(b) < 0)
    assert u2_of(u1()) == pytest.approx(u2(), abs=1e-8)


def test_load_stepping_continues_after_path_following(truss):
    """Arc length to λ ≈ 0.1, then load control to 0.3 from there (``from_current``): the
    steps start at the path's λ, and the end state is the analytic one on the first branch,
    r(u₁) = 0.3 with u₁ < 1 − 1/√3 (before the snap-through)."""
    model, solver = truss
    u1 = _probe(model, 0)
    path = ArcLength(solver)
    path.run(0.02, lambda_max=0.1)
    lam0 = float(model.load_factor.value)
    assert 0.1 <= lam0 < 0.15 and r(u1()) == pytest.approx(lam0, abs=1e-8)
    stepper = LoadStepper(solver, steps=4, predictor="none")
    history = stepper.run(0.3, from_current=True)
    assert history[0].load_factor == pytest.approx(lam0 + (0.3 - lam0) / 4, rel=1e-12)
    roots = np.roots([1.0, -3.0, 2.0, -0.3])  # r(u₁) = u₁³ − 3u₁² + 2u₁ = 0.3
    first = min(x.real for x in roots if abs(x.imag) < 1e-12 and x.real > 0)
    assert first < 1 - 1 / math.sqrt(3)
    assert u1() == pytest.approx(first, abs=1e-8) and history[-1].load_factor == 0.3
    with pytest.raises(ValueError, match="beyond the target") as err:
        LoadStepper(solver).run(0.2, from_current=True, back=False)
    assert "\n" not in str(err.value)
    # back (the default): down the same branch to λ = 0.2 exactly, the first root of r = 0.2
    LoadStepper(solver).run(0.2, from_current=True)
    assert float(model.load_factor.value) == 0.2
    assert u1() == pytest.approx(_real_roots([1.0, -3.0, 2.0, -0.2])[0], abs=1e-8)


def _real_roots(coefficients) -> list[float]:
    return sorted(x.real for x in np.roots(coefficients) if abs(x.imag) < 1e-12)


def test_arc_length_stops_exactly_at_a_load_on_every_branch(truss):
    """``stop_at_load = 0.2`` three times in a row: the path meets λ = 0.2 rising (before the
    snap-through), falling (after the limit point) and rising again (the inverted truss), each
    time exactly, at the three roots of r(u₁) = u₁³ − 3u₁² + 2u₁ = 0.2."""
    model, solver = truss
    u1, u2 = _probe(model, 0), _probe(model, 1)
    path = ArcLength(solver, monitor=u2)
    roots = _real_roots([1.0, -3.0, 2.0, -0.2])
    assert roots[0] < 1 - 1 / math.sqrt(3) < roots[1] < 1 + 1 / math.sqrt(3) < roots[2]
    for root in roots:
        history = path.run(0.02, stop_at_load=0.2)
        last = history[-1]
        assert last.landed and last.load_factor == 0.2  # exactly, not within a tolerance
        assert float(model.load_factor.value) == 0.2
        assert u1() == pytest.approx(root, abs=1e-8)
        assert u2() == pytest.approx(u2_of(root), abs=1e-8)
    assert path.stats.cuts == 0 and path.stats.landing_solves <= 6


def test_arc_length_stops_exactly_at_a_displacement(truss):
    """``stop_at = (u₂, 1)``: u₂ = 1 is met three times, rising, on the snap-back (u₂ going
    back) and rising again; u₁ + r(u₁)/k = 1 is 2u₁³ − 6u₁² + 5u₁ − 1 = 0, whose roots are
    u₁ = 1 − 1/√2, 1, 1 + 1/√2 with the loads λ = r(u₁) = 1/(2√2), 0, −1/(2√2)."""
    model, solver = truss
    u1, u2 = _probe(model, 0), _probe(model, 1)
    path = ArcLength(solver, monitor=u2)
    a = 1 / math.sqrt(2)
    for root, load in ((1 - a, a / 2), (1.0, 0.0), (1 + a, -a / 2)):
        last = path.run(0.02, stop_at=(u2, 1.0))[-1]
        assert last.landed and abs(u2() - 1.0) <= 1e-14 and last.value == u2()
        assert u1() == pytest.approx(root, abs=1e-8)
        assert last.load_factor == pytest.approx(load, abs=1e-8)


def test_going_back_to_a_load_the_path_has_passed(truss):
    """Arc length with ``lambda_max = 1`` ends beyond λ = 1 (issue 40: λ = 2.27);
    ``LoadStepper.run(1, from_current=True)`` takes it back along the path and stops exactly at
    λ = 1 on the same (inverted) branch: u₁ the largest root of r(u₁) = 1; so does
    ``ArcLength.run(..., stop_at_load=1, reverse=True)``."""
    model, solver = truss
    u1, u2 = _probe(model, 0), _probe(model, 1)
    root = _real_roots([1.0, -3.0, 2.0, -1.0])[-1]
    with pytest.warns(LimitPointWarning):
        ArcLength(solver).run(0.02, lambda_max=1.0)
    beyond = float(model.load_factor.value)
    assert beyond > 1.0
    stepper = LoadStepper(solver)
    history = stepper.run(1.0, from_current=True)
    assert history[-1].load_factor == 1.0 and float(model.load_factor.value) == 1.0
    assert all(1.0 <= h.load_factor < beyond for h in history)  # down, not up
    assert u1() == pytest.approx(root, abs=1e-8) and u2() == pytest.approx(u2_of(root), abs=1e-8)
    ArcLength(solver).run(0.02, lambda_max=1.5)  # beyond again, then back by arc length
    beyond = float(model.load_factor.value)
    back = ArcLength(solver)
    last = back.run(0.02, stop_at_load=1.0, reverse=True)[-1]
    assert last.landed and last.load_factor == 1.0
    assert u1() == pytest.approx(root, abs=1e-8)
    assert all(p.load_factor < beyond for p in back.history)


def test_going_back_stops_at_a_limit_point(truss):
    """From λ = 0.3 on the inverted branch (u₁ > 1 + 1/√3), λ = −0.5 lies beyond its minimum
    −2/(3√3): going back refuses in one line naming the limit, not a NaN or a wrong branch."""
    model, solver = truss
    path = ArcLength(solver)
    with pytest.warns(LimitPointWarning):
        path.run(0.02, stop_at_load=-0.2)  # over the maximum, down the branch
    with pytest.warns(LimitPointWarning):
        path.run(0.02, stop_at_load=0.3)  # on: through the minimum, up the inverted branch
    assert _probe(model, 0)() > 1 + 1 / math.sqrt(3)
    with pytest.raises(SolveFailed, match=r"turns at a minimum λ ≈ -0\.3849") as err:
        with pytest.warns(LimitPointWarning):
            LoadStepper(solver).run(-0.5, from_current=True)
    assert "\n" not in str(err.value)


@pytest.mark.parametrize("first_step", [0.02, 0.1, 0.5])
def test_limit_points_found_and_resolved(truss, first_step):
    """Issue 44 item 3: whatever the first step, the snap-through's maximum and minimum of λ are
    detected (the tangent's λ component turns), the arc is refined there until the fold's load
    (the extremum of the cubic through the increment's ends) is within ``limit_rtol``, and a
    warning names each. Without the refinement, a first step of 0.5 jumps from λ = 0.385 to
    −0.365 in one increment."""
    model, solver = truss
    u1 = _probe(model, 0)
    path = ArcLength(solver, monitor=u1)
    with pytest.warns(LimitPointWarning) as caught:
        path.run(first_step, lambda_max=1.0)
    folds = path.stats.limit_points
    assert [p.kind for p in folds] == ["maximum", "minimum"] and all(p.resolved for p in folds)
    assert folds[0].load_factor == pytest.approx(P_LIMIT, rel=1e-4)
    assert folds[1].load_factor == pytest.approx(-P_LIMIT, rel=1e-4)
    assert len([w for w in caught if "limit point" in str(w.message)]) == 2
    lam = np.array([p.load_factor for p in path.history])
    a = np.array([p.value for p in path.history])
    assert first_maximum(lam) == pytest.approx(P_LIMIT, rel=2e-3)  # traced, not jumped
    assert lam.min() == pytest.approx(-P_LIMIT, rel=2e-3)
    assert np.max(np.abs(np.diff(a))) < 0.25
    # Bergan's stiffness parameter: 1 at the start, through 0 to negative after the maximum
    sp = np.array([p.stiffness for p in path.history])
    i = folds[0].increment
    assert 1.0 >= sp[0] > sp[i - 1] > 0 > sp[i]  # the truss softens up to its maximum
    assert path.stats.refinements > 0 or first_step == 0.02


# Sze et al. 2004 §3.6, hinged roof, P2B-P2B quarter model n×n, against the first limit point of
# Sze's Tables 9 (shells.HINGED_ROOF_LIMIT). Measured (constant arc from Δλ₀ = 0.02, limit load
# by the parabola through the three highest samples), n = 4 / 8 / 12 / 16:
#   12.7 mm: P_lim −0.27 / −0.22 / −0.23 / −0.24 %, w_C there 10.98 / 10.92 / 10.91 / 10.91 mm
#            (Sze 11.29: −3.4 %, on a flat peak);
#   6.35 mm: P_lim −0.63 / −0.27 / −0.31 / −0.34 %, w_C 13.38 / 13.28 / 13.25 / 13.25 mm
#            (Sze 12.89: +2.7 %).
# The limit load is converged in the mesh to 0.05 % from n = 8 and sits 0.2–0.3 % below Sze's
# ABAQUS S4R value: tolerance 1 %; the deflection at the limit, 5 %. The default case (arc up to
# 2× the first, n = 8): 160 / 62 increments, 319 / 139 Newton iterations, 32 / 14 s (JIT warm).
@pytest.mark.slow
@pytest.mark.parametrize("thickness", [12.7, 6.35])
def test_sze_hinged_roof_limit_load(thickness):
    from fenics_garment.verification import shells

    with pytest.warns(LimitPointWarning):
        r = shells.hinged_roof(thickness, 8)
    P, w = np.array(r.extra["P"]), np.array(r.extra["w"])
    print(
        f"t = {thickness}: P_lim {r.value:.1f} N vs {r.reference:.1f} ({100 * r.rel_error:+.2f} %),"
        f" w_lim {r.extra['w_limit']:.2f} vs {r.extra['w_limit_reference']:.2f} mm,"
        f" {r.extra['increments']} increments, {r.newton_its} Newton its, {r.wall_s:.1f} s;"
        f" limit points {r.extra['limit_points']}, {r.extra['refinements']} refinements"
    )
    assert abs(r.rel_error) < 0.01
    assert r.extra["w_limit"] == pytest.approx(r.extra["w_limit_reference"], rel=0.05)
    assert w[-1] >= 30.0 and r.extra["cuts"] == 0
    # the first limit point found on the path (refined to limit_rtol) is Sze's limit load
    P_fold, kind = r.extra["limit_points"][0]
    assert kind == "maximum" and P_fold == pytest.approx(r.reference, rel=0.01)
    i = int(np.argmax(P >= r.value * 0.999))
    assert P[i:].min() < 0.5 * r.value  # past the limit point: the descending branch was traced
    if thickness == 6.35:  # the centre deflection turns back (snap-back) and the load reverses
        assert np.any(np.diff(w[i:]) < -0.1) and P.min() < 0
    assert [k for _, k in r.extra["limit_points"]] == ["maximum", "minimum"]


@pytest.mark.slow
def test_sze_hinged_roof_displacement_control():
    """The 12.7 mm roof by displacement control of w_C (its snap-through has no snap-back at
    the centre). Measured 8×8: 31 increments, P_lim −0.20 %, w_C there 10.89 mm; with the shear
    stiffened ×100 (Kirchhoff limit) +0.03 %: the RM shear compliance is the offset."""
    from fenics_garment.verification import shells

    r = shells.hinged_roof(12.7, 8, method="displacement")
    print(f"P_lim {r.value:.1f} N ({100 * r.rel_error:+.2f} %), {r.extra['increments']} increments")
    assert abs(r.rel_error) < 0.01
    assert r.extra["w_limit"] == pytest.approx(r.extra["w_limit_reference"], rel=0.05)
    assert r.extra["w"][-1] == pytest.approx(30.0, abs=1e-9)


# Sze et al. 2004 §3.5, the open cylinder pulled out (verification.shells.pullout_cylinder,
# 12×8 cells, P2B-P2B): the path snaps between 0.50 and 0.525 P_max (Sze's −U_B jumps from 3.653
# to 4.061). Issue 44: the default first step 0.05 used to give λ 0.108 → 0.514 → 0.671 without
# ever decreasing. Measured with the limit-point refinement: 16 increments (5 refinements), a
# maximum λ = 0.5158 and a minimum 0.5117, at λ = 1 W_A +0.17 %, −U_B +0.34 %, −U_C −0.35 %
# against Sze; 15 s (JIT warm).
@pytest.mark.slow
def test_sze_pullout_snap_traced_at_default_settings():
    from fenics_garment.verification import shells

    with pytest.warns(LimitPointWarning) as caught:
        r = shells.pullout_cylinder(8)
    folds = r.extra["limit_points"]
    path = np.array(r.extra["path"])  # λ, W_A, −U_B, −U_C
    print(
        f"W_A {r.value:.4f} ({100 * r.rel_error:+.2f} %), −U_B {r.extra['u_B']:.4f}, −U_C "
        f"{r.extra['u_C']:.4f}; {r.extra['increments']} increments, {r.extra['refinements']} "
        f"refinements; limit points {folds}; λ {np.round(path[:, 0], 4).tolist()}"
    )
    assert [kind for _, kind, _ in folds] == ["maximum", "minimum"]
    assert all(resolved and 0.50 <= lam <= 0.525 for lam, _, resolved in folds)
    assert len([w for w in caught if "limit point" in str(w.message)]) == 2
    lam, u_b = path[:, 0], path[:, 2]
    assert np.any(np.diff(lam) < 0)  # the descending part of the snap was traced
    snap = (lam >= 0.45) & (lam <= 0.6)
    assert snap.sum() >= 5 and np.max(np.diff(u_b[snap])) < 0.15  # Sze's jump is 0.408
    assert r.extra["jumps"] == 0 and r.extra["cuts"] == 0
    # stopped exactly at full load, converged, and on Sze's reference there
    assert r.extra["load_factor"] == 1.0 and lam[-1] == 1.0
    assert r.extra["residual"] <= r.extra["residual_tolerance"]
    assert abs(r.rel_error) < 0.01
    assert r.extra["u_B"] == pytest.approx(r.extra["u_B_reference"], rel=0.01)
    assert r.extra["u_C"] == pytest.approx(r.extra["u_C_reference"], rel=0.01)


@pytest.mark.slow
def test_sze_pullout_stops_exactly_at_a_displacement():
    """``stop_at = (W_A, 2)``: the path ends where the loaded point has moved out by exactly 2
    (to round-off), converged; Sze's path puts that load between 0.15 P_max (W_A = 1.936) and
    0.20 P_max (2.079)."""
    from fenics_garment.verification import shells

    r = shells.pullout_cylinder(8, stop_w_a=2.0)
    assert abs(r.value - 2.0) <= 1e-12
    assert r.extra["residual"] <= r.extra["residual_tolerance"]
    assert 0.15 < r.extra["load_factor"] < 0.20
