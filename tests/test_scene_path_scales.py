"""The scales that enter a frictional answer do not change with the garment mesh.

With friction the answer depends on the dressing path, so everything that shapes the path must be
a property of the problem, not of the discretisation: the stick penalty κ_T (how far a sticking
point gives before it slides) is the skin's tangential stiffness G / depth, and the spring scale
c₀ = regularisation · E h / L² uses a fixed length L — whereas the normal penalty κ = κ̂ E h / ℓ²
does scale with the cell size ℓ (its effect is removed by the augmented Lagrangian).
"""

from dataclasses import replace
from pathlib import Path

import pytest

from fenics_garment._stack import MPI
from fenics_garment.contact.terms import BODY_MODULUS_PA, BODY_POISSON
from fenics_garment.scene import build, config

SCENE = Path(__file__).parent.parent / "demos" / "tube_on_cylinder.toml"


def test_stick_stiffness_is_the_skins():
    s = config.load(SCENE)
    depth = s.body.tissue_depth
    shear_modulus = BODY_MODULUS_PA / (2 * (1 + BODY_POISSON))  # seed paper Table 1: E, ν
    assert build.stick_stiffness(s) == pytest.approx(shear_modulus / depth, rel=1e-12)
    # docs/theory/dressing.md quotes 3.9e5
    assert BODY_MODULUS_PA / (2 * 1.3 * 0.02) == pytest.approx(3.866e5, rel=1e-3)
    given = replace(s, physics=replace(s.physics, stick_stiffness=1e6))
    assert build.stick_stiffness(given) == 1e6


def test_path_scales_do_not_follow_the_mesh():
    s = config.load(SCENE)
    built = [build.build(replace(s, garment=replace(s.garment, mesh_size=h)), MPI.COMM_WORLD)
             for h in (0.04, 0.02)]  # fmt: skip
    kappa = [float(b.contact.kappa.value) for b in built]
    kappa_t = [float(b.contact.friction.kappa_t.value) for b in built]
    c0 = [b.regularisation.c0 for b in built]
    assert kappa[1] > 2 * kappa[0]  # the normal penalty grows as the cells shrink (1/ℓ²)
    assert kappa_t[0] == kappa_t[1] == pytest.approx(build.stick_stiffness(s))
    d = s.dressing
    membrane = built[0].model.stiffness.membrane_scale
    assert c0[0] == c0[1] == pytest.approx(d.regularisation * membrane / d.spring_length**2)
