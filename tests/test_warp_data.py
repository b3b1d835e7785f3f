"""The warp direction is data of the compiled forms (``ShellGeometry.set_warp``): a new direction
changes a ``fem.Constant``, not the kernels, and the fabric's stiffnesses turn with it.

Reference (independent of the shell code): a flat orthotropic strip under a uniform dead edge
load t [N/m of reference width] along x, free to contract sideways (N₂₂ = 0). With the
St Venant–Kirchhoff membrane law S = A E (Green–Lagrange E, second Piola–Kirchhoff resultant S)
and A11 = E₁h/(1−ν12ν21), A22 = E₂h/(1−ν12ν21), A12 = ν12 A22 (``materials.Fabric``), the
uniaxial state has S₁₁ = (A11 − A12²/A22) E₁₁ = E₁ h E₁₁: the stiffness along the load is the
Young's modulus of the direction that lies along x. The nominal load is t = λ S₁₁ with stretch
λ and E₁₁ = (λ² − 1)/2, so

    t = E_x h λ (λ² − 1)/2,   E_x = E_warp (warp along x) or E_weft (warp along y),

a cubic for λ. The uniform state is in the finite element space, so the discrete solution is
exact up to the Newton tolerance.
"""

import ffcx.codegeneration.jit as ffcx_jit
import numpy as np
import pytest

from fenics_garment._stack import MPI, dolfinx, ufl
from fenics_garment.materials import Fabric
from fenics_garment.shell import bcs as B
from fenics_garment.shell.geometry import parametric_surface_mesh
from fenics_garment.shell.kinematics import ShellGeometry
from fenics_garment.shell.model import ShellModel, evaluate_at_points
from fenics_garment.solve import LoadStepper, NonlinearSolver
from fenics_garment.verification.shells import edge_measure

L, W = 0.1, 0.02
FABRIC = Fabric(E_warp=2.0e6, E_weft=0.5e6, G12=2.0e5, B_warp=1e-4, B_weft=2.5e-5,
                thickness=1e-3, density=0.0, nu12=0.3)  # fmt: skip
T = FABRIC.E_warp * FABRIC.thickness * 1.05 * (1.05**2 - 1) / 2  # λ = 1.05 with warp along x


def stretch_of(t: float, E: float) -> float:
    """The real root λ > 1 of E h λ(λ² − 1)/2 = t."""
    roots = np.roots([E * FABRIC.thickness / 2, 0.0, -E * FABRIC.thickness / 2, -t])
    real = roots[np.abs(roots.imag) < 1e-12].real
    return float(real[real > 1.0][0])


def strip(warp):
    mesh = parametric_surface_mesh(MPI.COMM_WORLD, lambda x, y: np.array([x, y, 0.0 * x]),
                                   (0, L), (0, W), (4, 2))  # fmt: skip
    model = ShellModel(ShellGeometry.from_mesh(mesh, warp=warp), FABRIC)
    model.add_edge_load((T, 0.0, 0.0), edge_measure(mesh, lambda x: np.isclose(x[0], L)))
    edges = lambda x: np.full(x.shape[1], True)  # noqa: E731
    bcs = (B.fix_components(model, edges, u=(2,), theta=(0, 1, 2))  # plane state
           + B.fix_components(model, lambda x: np.isclose(x[0], 0.0), u=(0,))
           + B.fix_components(model, lambda x: np.isclose(x[1], 0.0), u=(1,)))  # fmt: skip
    return model, NonlinearSolver(model, bcs)


def end_stretch(model, solver) -> float:
    model.q.x.array[:] = 0.0
    stepper = LoadStepper(solver, steps=4)
    stepper.run()
    return 1.0 + evaluate_at_points(model.displacement(), [(L, W / 2, 0.0)])[0, 0] / L


@pytest.fixture
def compiles(monkeypatch):
    """Counts FFCx compilations (the C code generation and build of a cache miss)."""
    calls = []
    original = ffcx_jit._compile_objects

    def counted(*args, **kwargs):
        calls.append(1)
        return original(*args, **kwargs)

    monkeypatch.setattr(ffcx_jit, "_compile_objects", counted)
    return calls


def test_the_counter_sees_a_compilation(compiles):
    """A form with a literal never seen before is a cache miss: counted (the counter works)."""
    mesh = dolfinx.mesh.create_unit_square(MPI.COMM_SELF, 1, 1)
    literal = float(np.random.default_rng().uniform(1.0, 2.0))
    value = dolfinx.fem.assemble_scalar(dolfinx.fem.form(literal * ufl.dx(domain=mesh)))
    assert value == pytest.approx(literal) and len(compiles) == 1


def test_reference_cubic():
    """The cubic itself: small loads give Hooke's law, λ − 1 ≈ t/(E h)."""
    assert stretch_of(1e-3, 2e6) - 1 == pytest.approx(1e-3 / (2e6 * 1e-3), rel=1e-5)


def test_warp_direction_turns_the_stiffness_without_recompiling(compiles):
    model, solver = strip((1.0, 0.0, 0.0))
    lam_warp = end_stretch(model, solver)
    assert lam_warp == pytest.approx(stretch_of(T, FABRIC.E_warp), rel=1e-7)  # 1.05

    before = len(compiles)
    model.geometry.set_warp((0.0, 1.0, 0.0))  # same solver, same compiled forms
    lam_weft = end_stretch(model, solver)
    assert lam_weft == pytest.approx(stretch_of(T, FABRIC.E_weft), rel=1e-7)  # 1.1598
    assert lam_weft - 1 > 3 * (lam_warp - 1)

    # a fresh model with another direction: the same form signature, a JIT cache hit
    other, other_solver = strip((0.0, -2.0, 0.0))
    assert end_stretch(other, other_solver) == pytest.approx(lam_weft, rel=1e-7)
    assert len(compiles) == before


def test_bad_warp_direction():
    mesh = parametric_surface_mesh(MPI.COMM_WORLD, lambda x, y: np.array([x, y, 0.0 * x]),
                                   (0, L), (0, W), (1, 1))  # fmt: skip
    with pytest.raises(ValueError, match="finite nonzero"):
        ShellGeometry.from_mesh(mesh, warp=(0.0, 0.0, 0.0))
    with pytest.raises(ValueError, match="3 numbers"):
        ShellGeometry.from_mesh(mesh, warp=(1.0, 0.0))
