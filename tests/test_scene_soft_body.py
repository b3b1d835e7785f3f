"""The seed paper's soft body in a scene: ``[body] tissue = "soft"`` is a Winkler layer with the
paper's Table 1 modulus (205 gf/cm²) and Poisson ratio (0.3); the tight tube on it is checked
against the analytic balance of Laplace's law and the layer's compression."""

from __future__ import annotations

import tempfile
from dataclasses import replace
from pathlib import Path

import pytest
from scipy.optimize import brentq

from fenics_garment._stack import MPI
from fenics_garment.scene import config
from fenics_garment.scene.build import tissue_stiffness
from fenics_garment.verification.contact import tube_pressure

SCENE = Path(__file__).parent.parent / "demos" / "tube_on_cylinder.toml"


def _soft(depth: float = 0.01) -> config.Scene:
    s = config.load(SCENE)
    # the layer's compliance is the law: the penalty (a scene file must say so, see below;
    # replace() skips the loader's check, and the augmented Lagrangian would remove it)
    return replace(s, body=replace(s.body, tissue="soft", tissue_depth=depth),
                   physics=replace(s.physics, contact="penalty"))  # fmt: skip


def test_tissue_stiffness_is_table_1():
    # k = E (1 − ν) / ((1 + ν)(1 − 2ν) d), E = 205 gf/cm² = 205 · 9.80665e-3 N / 1e-4 m²
    E, nu, d = 205 * 9.80665e-3 / 1e-4, 0.3, 0.01
    assert tissue_stiffness(_soft(d)) == pytest.approx(E * (1 - nu) / ((1 + nu) * (1 - 2 * nu) * d))
    assert tissue_stiffness(config.load(SCENE)) is None  # rigid: the numerical penalty


def test_soft_body_needs_the_penalty_law():
    s = config.to_dict(_soft())
    s["physics"]["contact"] = "augmented-lagrangian"
    with pytest.raises(config.SceneError, match=r"physics\.contact"):
        config.from_dict(s, "soft.toml")


@pytest.mark.slow
def test_tight_tube_on_soft_tissue_scene():
    from fenics_garment.contact import pressure as cpressure
    from fenics_garment.scene.run import run

    comm = MPI.COMM_WORLD
    folder = Path(comm.bcast(tempfile.mkdtemp() if comm.rank == 0 else None, root=0))
    result = run(_soft(0.01), folder, quiet=True)
    assert result.completed
    b = result.built
    s = b.model.stiffness
    k = float(b.contact.kappa.value)
    R_c = b.scene.body.radius + s.thickness / 2  # the tube's mid-surface on the undeformed skin
    r0 = b.scene.body.radius + b.garment.level("mid").clearance

    def balance(r: float) -> float:
        return tube_pressure(r, r0, s, warp="axial") - k * (R_c - r)

    r = brentq(balance, r0 * 1.0001, R_c)
    ref = k * (R_c - r)
    st, c = b.contact.state, b.contact
    f = cpressure.point_forces(st, c.traction)
    a = cpressure.point_areas(st, c.area_stretch())
    z = cpressure.positions(st)[:, 2]
    sel = abs(z - 0.1) < 0.05
    p = comm.allreduce(f[sel].sum(), op=MPI.SUM) / comm.allreduce(a[sel].sum(), op=MPI.SUM)
    rigid = tube_pressure(R_c, r0, s, warp="axial")
    print(f"\nsoft tube: p = {p:.2f} Pa, analytic {ref:.2f} Pa, rigid {rigid:.2f} Pa")
    assert p == pytest.approx(ref, rel=0.02)
    assert ref < rigid  # the soft body gives: less stretch, less pressure
