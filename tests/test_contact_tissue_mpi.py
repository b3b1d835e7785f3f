"""Soft-tissue body (pressure independent of the penalty) and 1-vs-2-rank consistency."""

from fenics_garment._stack import MPI  # noqa: I001

import numpy as np
import pytest
from scipy.optimize import brentq

import contact_models as cm
from fenics_garment.contact import pressure, terms
from test_contact_laplace import dress, mid_pressure


def test_soft_tissue_tube_matches_laplace_on_a_winkler_layer():
    tissue = terms.SoftTissue(depth=0.01)
    k = tissue.stiffness
    scene = cm.laplace_tube(MPI.COMM_WORLD, kappa=k)
    fab, R_c, r0 = scene.fabric, scene.extra["R"] + scene.fabric.h / 2, scene.extra["r0"]
    dress(scene, steps=(0.5, 0.0))

    # the tube settles at radius r where Laplace's law meets the foundation: p(r) = k (R_c − r)
    def balance(r: float) -> float:
        return cm.laplace_tube_pressure(r, r0, fab.E2, fab.nu21, fab.h) - k * (R_c - r)

    r = brentq(balance, r0, R_c)
    ref = k * (R_c - r)
    p = mid_pressure(scene)
    print(f"\nsoft tissue k = {k:.3e} Pa/m: p = {p:.2f} Pa, reference {ref:.2f} Pa, "
          f"compression {1e3 * (R_c - r):.2f} mm, error {100 * (p / ref - 1):+.3f} %")  # fmt: skip
    assert abs(p / ref - 1) < 0.01


@pytest.mark.mpi
def test_same_pressure_on_every_rank_count():
    """The distributed run gives the pressures of a serial run of the same scene (each rank
    repeats the serial run on COMM_SELF), and the body pressure map integrates to the force."""
    world = cm.laplace_tube(MPI.COMM_WORLD)
    dress(world)
    p_world = mid_pressure(world)
    serial = cm.laplace_tube(MPI.COMM_SELF)
    dress(serial)
    p_self = mid_pressure(serial)
    assert abs(p_world / p_self - 1) < 1e-8
    assert abs(p_world / world.extra["reference"] - 1) < 0.01
    # transfer to the body: same total normal force on the body as on the garment
    st = world.state
    t_n = terms.normal_traction(st, world.kappa)
    body_p = pressure.body_pressure(st, t_n, st.body)
    f_garment = MPI.COMM_WORLD.allreduce(pressure.point_forces(st, t_n).sum(), op=MPI.SUM)
    v, t = st.body.vertices, st.body.triangles
    area = 0.5 * np.linalg.norm(np.cross(v[t[:, 1]] - v[t[:, 0]], v[t[:, 2]] - v[t[:, 0]]), axis=1)
    lumped = np.zeros(len(v))
    np.add.at(lumped, t.ravel(), np.repeat(area / 3.0, 3))
    assert abs((body_p * lumped).sum() / f_garment - 1) < 1e-10
    # body pressure at mid-length ≈ garment pressure scaled by the radii (force balance)
    mid = (np.abs(v[:, 2]) < world.extra["L"] / 4) & (np.hypot(v[:, 0], v[:, 1]) > 0.099)
    scale = (world.extra["R"] + world.fabric.h / 2) / world.extra["R"]
    assert abs(body_p[mid].mean() / (p_world * scale) - 1) < 0.02
