"""One law, one place: replacing a contact law by one assignment changes the scene residual, the
point-wise algorithm that uses it (the stick/slip anchor, the multiplier update) and the outputs
(the body's reaction) together.

Set-up: one eighth of a tube of rest radius r0 on a rigid cylinder R > r0 (P1-P1 shell, nodal
contact points: cheap to compile), at the undeformed state q = 0, where the garment penetrates
the body everywhere (t_N > 0) and the internal forces vanish (stress-free pattern). Every
contact point is given the same axial slip s·e_z since its anchor (e_z is tangential: the body
normals are horizontal), small enough to stick (κ_T s ≪ μ t_N). The references are by hand:

* reaction along z = ∫ t_T·e_z dA = −κ_T s A for the stick of the Coulomb return map, and
  −κ_T s A/2 for a friction law of half the stick stiffness, t_T = −κ_T Δu_T / 2, with A the
  reference area by the contact-point rule (≈ π r0 L / 4);
* the scene residual tested with the rigid translation e_z: F(e_z) = −reaction (a rigid
  translation does no internal virtual work);
* the anchor: each law keeps the slip at which it carries its traction, so in stick both keep
  it; sliding (s = 1 cm) the return map keeps its elastic slip μ t_N/κ_T, and the same law
  with half the coefficient half of it.
"""

from fenics_garment._stack import MPI  # noqa: I001

from dataclasses import replace

import numpy as np
import pytest

from fenics_garment._stack import dolfinx, ufl
from fenics_garment.contact import laws, terms, uzawa
from fenics_garment.contact import pressure as cpressure
from fenics_garment.contact import shell as shell_contact
from fenics_garment.contact.primitives import cylinder
from fenics_garment.contact.search import SearchSurface
from fenics_garment.materials import Isotropic
from fenics_garment.shell.geometry import parametric_surface_mesh
from fenics_garment.shell.kinematics import ShellGeometry
from fenics_garment.shell.model import ShellModel

R, R0, L, N = 0.1, 0.093, 0.1, (4, 2)
SLIP = 1e-6  # [m]: κ_T s ≈ 0.05 κ_T µm ≪ μ t_N = μ κ (R_c − r0) ≈ 0.4 κ × 7 mm


def _half_stiffness(c: laws.Inputs):
    """A friction law of half the stick stiffness and no Coulomb limit: t_T = −κ_T Δu_T / 2."""
    return -0.5 * c.kappa_t * c.slip


@pytest.fixture(scope="module")
def tube():
    comm = MPI.COMM_WORLD
    mesh = parametric_surface_mesh(
        comm, lambda t, z: np.vstack([R0 * np.cos(t), R0 * np.sin(t), z]),
        (0.0, np.pi / 2), (0.0, L / 2), N,
    )  # fmt: skip
    geo = ShellGeometry.from_mesh(mesh, warp=(0.0, 0.0, 1.0),
                                  outward=lambda x: x * np.array([1.0, 1.0, 0.0]))  # fmt: skip
    model = ShellModel(geo, Isotropic(E=1.0e6, nu=0.3, thickness=1.0e-3), element="P1-P1")
    body = SearchSurface(*cylinder(R, -L, L, 256, 4))
    contact = shell_contact.attach(model, body, rule="vertex", mu=0.4)
    return model, contact


def _slip_everywhere(contact, slip: float) -> None:
    """q = 0 refreshed, every anchor at −s e_z (so Δu_T = s e_z at every point)."""
    st = contact.state
    st.refresh()
    st.lam.x.array[:] = 0.0
    st.u_old.x.array[:] = 0.0
    st.u_old.x.array[2::3] = -slip
    st.u_old.x.scatter_forward()


def _translation(model) -> dolfinx.fem.Function:
    """The rigid translation e_z as a function of the mixed space (θ = 0)."""
    e = dolfinx.fem.Function(model.Q)
    V, dofs = model.Q.sub(0).collapse()
    ez = dolfinx.fem.Function(V)
    ez.interpolate(lambda x: np.vstack([0 * x[0], 0 * x[0], 1 + 0 * x[0]]))
    e.x.array[dofs] = ez.x.array
    return e


def _residual_along(model, e: dolfinx.fem.Function) -> float:
    """F(q; e) of the model's residual as built now (collective)."""
    vec = dolfinx.fem.assemble_vector(dolfinx.fem.form(model.residual()))
    vec.scatter_reverse(dolfinx.la.InsertMode.add)
    n = model.Q.dofmap.index_map.size_local * model.Q.dofmap.index_map_bs
    return model.geometry.mesh.comm.allreduce(float(vec.array[:n] @ e.x.array[:n]), op=MPI.SUM)


def _anchor_z(contact) -> np.ndarray:
    return contact.state.local_values(contact.state.u_old)[:, 2]


def test_a_friction_law_changes_residual_and_outputs_together(tube):
    """Stick (s = 1 µm): the reaction and the residual follow the law in use; both laws keep
    their anchor (each carries its traction at the slip it has)."""
    model, contact = tube
    area = contact.state.mesh.comm.allreduce(
        dolfinx.fem.assemble_scalar(dolfinx.fem.form(1.0 * contact.state.dx)), op=MPI.SUM
    )  # ∫ dA by the contact-point rule, A ≈ π r0 L / 4
    assert area == pytest.approx(np.pi * R0 * L / 4, rel=0.03)
    kappa_t = float(contact.friction.kappa_t.value)
    e = _translation(model)
    default = contact.friction
    try:
        for law, share in ((laws.coulomb_return_map, 1.0), (_half_stiffness, 0.5)):
            contact.friction = replace(default, law=law)  # the one change
            _slip_everywhere(contact, SLIP)
            expected = -share * kappa_t * SLIP * area
            assert contact.reaction((0.0, 0.0, 1.0)) == pytest.approx(expected, rel=1e-9)
            assert _residual_along(model, e) == pytest.approx(-expected, rel=1e-9)
            contact.accept_step()
            assert np.allclose(_anchor_z(contact), -SLIP, rtol=1e-9, atol=0.0)
    finally:
        contact.friction = default


def _half_coefficient(c: laws.Inputs):
    """The return map with half the friction coefficient."""
    return laws.coulomb_return_map(replace(c, mu=0.5 * c.mu))


def test_a_friction_law_changes_the_stick_slip_update(tube):
    """Slip (s = 1 cm ≫ μ t_N/κ_T): every point slides on the cone, carrying μ t_N per area with
    t_N = κ(−g) (the refreshed gap g < 0, per point), so the reaction is −μ Σ κ(−g) w dA and the
    anchor keeps the elastic slip μ t_N/κ_T = μ(−g) (κ_T = κ): u_old = −μ(−g) e_z. With half
    the coefficient, half of both."""
    _, contact = tube
    st = contact.state
    mu = float(contact.friction.mu.value)
    default = contact.friction
    try:
        for law, share in ((laws.coulomb_return_map, 1.0), (_half_coefficient, 0.5)):
            contact.friction = replace(default, law=law)  # the one change
            _slip_everywhere(contact, 1e-2)
            depth = -st.local_values(st.gap)
            kappa = float(contact.kappa.value)
            areas = cpressure.point_areas(st, ufl.as_ufl(1.0))
            normal = st.mesh.comm.allreduce(float((kappa * depth * areas).sum()), op=MPI.SUM)
            reaction = contact.reaction((0.0, 0.0, 1.0))
            assert reaction == pytest.approx(-share * mu * normal, rel=1e-6)
            contact.accept_step()
            assert np.allclose(_anchor_z(contact), -share * mu * depth, rtol=1e-6, atol=0.0)
    finally:
        contact.friction = default


def test_a_normal_law_changes_the_multiplier_update(tube):
    """Uzawa's λ ← t_N(c) evaluates the normal law in use: with a law of twice the
    penalty, t_N = ⟨λ − 2κ g⟩₊, one update from λ = 0 gives λ = 2κ⟨−g⟩₊ (g the refreshed gap)."""
    _, contact = tube
    st = contact.state
    kappa = float(contact.kappa.value)
    try:
        contact.normal_law = lambda c: laws.macaulay(c.multiplier - 2.0 * c.kappa * c.gap)
        st.refresh()
        st.lam.x.array[:] = 0.0
        uzawa.update_multiplier(st, kappa)
        g = st.local_values(st.gap)
        assert g.max() < 0.0  # the pattern penetrates everywhere
        assert np.allclose(st.local_values(st.lam), 2.0 * kappa * -g, rtol=1e-12)
        assert np.all(st.local_values(st.lam) > 0.0)
    finally:
        contact.normal_law = laws.augmented_lagrangian
        st.lam.x.array[:] = 0.0


def test_replace_membrane_with_contact_attached(tube):
    """``dataclasses.replace(model, membrane=...)`` keeps the unknown, so the contact terms built
    on it stay valid, and the copy's membrane forces follow its law: for ψ = 2 ψ_quad at a
    uniform stretch the forces are twice those of the original."""
    model, _ = tube
    doubled = replace(model, membrane=lambda kin, C: 2.0 * model.membrane(kin, C))
    assert doubled.q is model.q and doubled.Q is model.Q
    assert len(doubled.added_residuals) == len(model.added_residuals)
    doubled.residual()  # builds with the contact terms (no "Found different Arguments")
    q = model.q
    V, dofs = model.Q.sub(0).collapse()
    u = dolfinx.fem.Function(V)
    u.interpolate(lambda x: np.vstack([0.01 * x[0], 0.01 * x[1], 0 * x[0]]))  # hoop stretch
    try:
        q.x.array[dofs] = u.x.array
        q.x.scatter_forward()
        st = tube[1].state
        n_old = st.evaluate(model.membrane_forces()[1, 1])
        n_new = st.evaluate(doubled.membrane_forces()[1, 1])
        assert np.abs(n_old).min() > 0.0
        assert np.allclose(n_new, 2.0 * n_old, rtol=1e-12)
    finally:
        q.x.array[:] = 0.0
        q.x.scatter_forward()


def test_add_energy_expression_and_law(tube):
    """``add_energy`` takes a UFL density or a law (kin, C) -> ψ; on a ``replace`` copy it does
    not touch the original. At a rigid translation c the shell's own energy vanishes, so
    Π = ∫ (½ k |u|² + ½ k |u|²) dA = k |c|² A."""
    model, _ = tube
    copy = replace(model)
    k = 3.0e4
    copy.add_energy(0.5 * k * ufl.dot(copy.u, copy.u))
    copy.add_energy(lambda kin, C: 0.5 * k * ufl.dot(copy.u, copy.u))
    assert model.added_energies == () and len(copy.added_energies) == 2
    c = np.array([1e-3, -2e-3, 5e-4])
    V, dofs = model.Q.sub(0).collapse()
    u = dolfinx.fem.Function(V)
    u.interpolate(lambda x: np.outer(c, np.ones(x.shape[1])))
    comm = model.geometry.mesh.comm
    area = comm.allreduce(
        dolfinx.fem.assemble_scalar(dolfinx.fem.form(1.0 * model.dx_full)), op=MPI.SUM
    )
    try:
        model.q.x.array[dofs] = u.x.array
        model.q.x.scatter_forward()
        energy = copy.energy_value(copy.internal_energy())
        assert energy == pytest.approx(k * (c @ c) * area, rel=1e-8)
    finally:
        model.q.x.array[:] = 0.0
        model.q.x.scatter_forward()


MU_WARP, MU_WEFT = 0.6, 0.2  # the law's own coefficients (in a closure: the scene's μ unused)


def _unit_tangent(d, n):
    t = d - ufl.dot(d, n) * n
    return t / ufl.sqrt(ufl.dot(t, t))


def _yarn_coulomb(c: laws.Inputs):
    """Sliding Coulomb friction along each yarn with its own coefficient (no stick range):
    t_T = −t_N Σ μ_i sign(s_i) a_i, a_i the warp and weft made tangent to the body."""
    t = 0
    for mu, d in ((MU_WARP, c.warp), (MU_WEFT, c.weft)):
        a = _unit_tangent(d, c.normal)
        t += -mu * c.normal_traction * ufl.sign(ufl.dot(c.slip, a)) * a
    return t


def _torque_z(st) -> float:
    """∫ (x × t_T)·e_z dA of the friction traction in use (collective)."""
    x = ufl.SpatialCoordinate(st.mesh) + st.u
    t_t = terms.tractions(st, st.kappa)[1]
    form = dolfinx.fem.form((x[0] * t_t[1] - x[1] * t_t[0]) * st.dx)
    return st.mesh.comm.allreduce(dolfinx.fem.assemble_scalar(form), op=MPI.SUM)


def test_a_law_gets_the_warp_and_weft_and_is_switched(tube):
    """Sliding along the warp (the tube's axis, s e_z) the law carries μ_warp t_N, along the
    weft (the hoop, s e_θ) μ_weft t_N: a reaction −μ_warp Σ t_N dA along z, a torque
    −μ_weft Σ t_N r dA about it (t_N = κ(−g) at q = 0, g the refreshed gap per point). With the
    dressing's switch off (``friction_on`` = 0) the same law carries nothing."""
    _, contact = tube
    st = contact.state
    kappa = float(contact.kappa.value)
    default = contact.friction
    try:
        contact.friction = replace(default, law=_yarn_coulomb)
        _slip_everywhere(contact, 0.0)
        x = st.positions()
        depth = -st.local_values(st.gap)
        areas = cpressure.point_areas(st, ufl.as_ufl(1.0))
        comm = st.mesh.comm
        normal = comm.allreduce(float((kappa * depth * areas).sum()), op=MPI.SUM)
        r = np.hypot(x[:, 0], x[:, 1])
        moment = comm.allreduce(float((kappa * depth * r * areas).sum()), op=MPI.SUM)
        _slip_everywhere(contact, 1e-2)  # along the axis: the warp
        assert contact.reaction((0.0, 0.0, 1.0)) == pytest.approx(-MU_WARP * normal, rel=1e-9)
        hoop = np.column_stack([-x[:, 1], x[:, 0], 0 * r]) / r[:, None]
        st.set_local_values(st.u_old, st.local_values(st.u_k) - 1e-2 * hoop)  # along the weft
        assert _torque_z(st) == pytest.approx(-MU_WEFT * moment, rel=1e-3)  # n ≈ radial
        st.friction_on.value = 0.0
        assert _torque_z(st) == 0.0  # (of the friction traction alone)
        assert abs(contact.reaction((0.0, 0.0, 1.0))) < 1e-9 * MU_WARP * normal  # t_N n·e_z
    finally:
        st.friction_on.value = 1.0
        contact.friction = default


def test_a_soft_law_is_refused_by_the_augmented_lagrangian(tube):
    """A normal law that ignores the multiplier is not a constraint: Uzawa refuses it in one
    line before its first solve; the default law (⟨λ − κg⟩₊) is let through."""
    _, contact = tube
    st = contact.state

    def never():
        raise AssertionError("solved")

    try:
        contact.normal_law = lambda c: 1.0e3 * ufl.exp(-c.gap / 2e-3)
        with pytest.raises(uzawa.SoftLawError) as err:
            uzawa.augmented_lagrangian(st, float(contact.kappa.value), never, tol=1e-5)
        assert "\n" not in str(err.value) and "soft" in str(err.value)
    finally:
        contact.normal_law = laws.augmented_lagrangian
    uzawa.require_constraint(st)
