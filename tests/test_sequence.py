"""Mesh sequencing (``[dressing] sequence``, ``scene.sequence``): the dressing's path on a coarser
garment mesh, the answer settled on the scene's.

The carried state is checked against fields the fine mesh represents exactly, and a sequenced
tube against the direct dressing of the same mesh and against Laplace's law
(``verification.contact.tube_pressure``, through test_scene_run's ``_laplace``), also where
friction makes the answer depend on the path.
"""

import tempfile
from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest
from test_scene_run import SCENE, _laplace, _mid_pressure

from fenics_garment._stack import MPI
from fenics_garment.scene import build as scene_build
from fenics_garment.scene import config, sequence
from fenics_garment.scene.run import run


def _tube(h: float, **dressing) -> config.Scene:
    s = config.load(SCENE)
    return replace(s, garment=replace(s.garment, mesh_size=h),
                   dressing=replace(s.dressing, **dressing))  # fmt: skip


def _shared_tmp(comm) -> Path:
    return Path(comm.bcast(tempfile.mkdtemp() if comm.rank == 0 else None, root=0))


def _reference_points(state) -> np.ndarray:
    return state.positions() - state.local_values(state.u_k)


def test_carry_over_is_exact_for_what_the_fine_mesh_represents():
    """An affine displacement, a constant rotation, an affine multiplier and a constant elastic
    slip on the 4 cm tube arrive unchanged at the 2 cm tube's contact points (up to the distance
    between the two quadratic meshes of one cylinder, ≪ 0.1 mm)."""
    comm = MPI.COMM_WORLD
    fine_scene = _tube(0.02, sequence=[0.04])
    coarse_scene = sequence.coarse_scenes(fine_scene)[0]
    assert coarse_scene.garment.mesh_size == 0.04 and not coarse_scene.dressing.sequence
    fine = scene_build.build(fine_scene, comm)
    coarse = scene_build.build(coarse_scene, comm, fine.body)

    A = np.array([[0.01, 0.02, 0.0], [0.0, -0.01, 0.03], [0.02, 0.0, 0.01]])
    b = np.array([1e-3, -2e-3, 5e-4])
    theta = np.array([0.01, -0.02, 0.03])

    def u(x: np.ndarray) -> np.ndarray:  # x: (3, n) as DOLFINx interpolates
        return A @ x + b[:, None]

    q = coarse.model.q
    for i, f in enumerate((u, lambda x: np.tile(theta[:, None], (1, x.shape[1])))):
        V, dofs = q.function_space.sub(i).collapse()
        g = type(q)(V)
        g.interpolate(f)
        q.x.array[dofs] = g.x.array
    q.x.scatter_forward()
    cs = coarse.contact.state
    cs.refresh()
    X = _reference_points(cs)
    cs.set_local_values(cs.lam, 100.0 + 1e3 * X[:, 2])
    slip = np.array([1e-5, -2e-5, 3e-6])
    cs.set_local_values(cs.u_old, cs.local_values(cs.u_k) - slip)

    sequence.carry_over(coarse, fine)
    fs = fine.contact.state
    Xf = _reference_points(fs)
    assert np.abs(fs.local_values(fs.u_k) - u(Xf.T).T).max() < 1e-5  # |u| ~ 1e-2
    rot = fine.model.q.sub(1).collapse()
    assert np.abs(rot.x.array.reshape(-1, 3) - theta).max() < 1e-9
    assert np.abs(fs.local_values(fs.lam) - (100.0 + 1e3 * Xf[:, 2])).max() < 1e-2  # ~ 200 Pa
    carried = fs.local_values(fs.u_k) - fs.local_values(fs.u_old)
    assert np.abs(carried - slip).max() < 1e-12
    # the spring is anchored at the carried state: it pulls nowhere yet
    assert fine.regularisation.stretch(fine.model.q) == 0.0


@pytest.mark.parametrize("friction_while_growing", [True, False])
def test_sequenced_tube_keeps_the_answer(friction_while_growing):
    """The tube on 2 cm cells dressed directly and through a 4 cm level. With friction while
    it grows the answer depends on the path: the middle's pressure lies between Laplace's
    free-end and stuck values (test_scene_run); measured 462.40 Pa direct, 462.48 sequenced
    (+0.02 %). Friction on at s = 0: Laplace's free-end value, 443.50 / 443.87 Pa against
    444.00 (−0.11 / −0.03 %)."""
    comm = MPI.COMM_WORLD
    s = _tube(0.02, friction_while_growing=friction_while_growing)
    direct = run(s, _shared_tmp(comm), quiet=True)
    seq = run(replace(s, dressing=replace(s.dressing, sequence=[0.04])), _shared_tmp(comm),
              quiet=True)  # fmt: skip
    assert direct.completed and seq.completed and seq.checks_passed
    levels = seq.report.levels
    assert [lv["mesh_size_m"] for lv in levels] == [0.04] and levels[0]["completed"]
    assert seq.summary["dressing"]["sequence"] == levels
    # the scene's mesh only settles: a release from the small spring, c = 0, the passes
    assert all(st.stage == "release" for st in seq.report.steps)
    assert seq.report.steps[-1].regularisation == 0.0
    assert seq.report.newton_iterations < direct.report.newton_iterations

    p, p_direct = _mid_pressure(seq), _mid_pressure(direct)
    assert p == pytest.approx(p_direct, rel=2e-3)
    free = _laplace(seq)
    if friction_while_growing:
        assert free * 1.01 < p < _laplace(seq, stuck=True) * 1.005
    else:
        assert p == pytest.approx(free, rel=0.005)


@pytest.mark.parametrize("levels", [[0.02], [0.04, 0.08], [0.01]])
def test_sequence_must_coarsen(levels, tmp_path):
    """Each level coarser than the next and than the scene's mesh (2 cm), coarsest first."""
    text = SCENE.read_text().replace("[dressing]\n", f"[dressing]\nsequence = {levels}\n")
    path = tmp_path / "tube.toml"
    path.write_text(text)
    with pytest.raises(config.SceneError, match=r"dressing\.sequence"):
        config.load(path)


@pytest.mark.mpi
def test_sequenced_tube_on_two_ranks():
    """The carry-over across ranks (``make test`` runs this on 2): each fine point is found in
    whichever rank's coarse cells hold it; Laplace's free-end value to 0.5 %."""
    res = run(_tube(0.02, sequence=[0.04]), _shared_tmp(MPI.COMM_WORLD), quiet=True)
    assert res.completed and res.checks_passed and res.summary["ranks"] == MPI.COMM_WORLD.size
    assert _mid_pressure(res) == pytest.approx(_laplace(res), rel=0.005)


def test_a_state_that_does_not_settle_is_dressed_directly(monkeypatch):
    """A carried state the scene's mesh cannot settle from (here the displacement made 40×
    too large after the carry-over) is not an answer: the run says so, dresses the scene's mesh
    from the start and gets Laplace's free-end value as without a sequence."""
    carry = sequence.carry_over

    def broken(coarse, fine):
        carry(coarse, fine)
        fine.model.q.x.array[:] *= 40.0
        fine.model.q.x.scatter_forward()

    monkeypatch.setattr(sequence, "carry_over", broken)
    res = run(_tube(0.02, sequence=[0.04]), _shared_tmp(MPI.COMM_WORLD), quiet=True)
    assert res.completed and res.checks_passed
    rep = res.report
    assert rep.sequence_failed and rep.levels[0]["completed"]
    assert res.summary["dressing"]["sequence_failed"] == rep.sequence_failed
    assert any(st.stage == "dress" for st in rep.steps)  # the body grew again on this mesh
    assert _mid_pressure(res) == pytest.approx(_laplace(res), rel=0.005)


def test_a_coarse_level_that_does_not_dress_is_left_out(monkeypatch):
    """A coarser level whose dressing stops (here: one Newton iteration allowed, no cut) leaves
    the scene's mesh to be dressed from the start; the report keeps the level and says why."""
    levels = sequence.coarse_scenes

    def failing(scene):
        stop = config.SolverConfig(petsc={"snes_max_it": 1})
        return [replace(s, solver=stop, dressing=replace(s.dressing, max_cuts=0))
                for s in levels(scene)]  # fmt: skip

    monkeypatch.setattr(sequence, "coarse_scenes", failing)
    res = run(_tube(0.02, sequence=[0.04]), _shared_tmp(MPI.COMM_WORLD), quiet=True)
    assert res.completed and res.checks_passed
    rep = res.report
    assert not rep.levels[0]["completed"] and "did not dress" in rep.sequence_failed
    assert any(st.stage == "dress" for st in rep.steps)
    assert _mid_pressure(res) == pytest.approx(_laplace(res), rel=0.005)


def test_levels_that_are_not_one_surface_are_refused(monkeypatch):
    """A fine point farther from the coarse mesh than ``sequence.PADDING`` (here 1 nm: the two
    quadratic meshes of the cylinder differ by more) stops the carry-over on every rank; the
    scene's mesh is then dressed from the start and the report says why."""
    monkeypatch.setattr(sequence, "PADDING", 1e-9)
    res = run(_tube(0.02, sequence=[0.04]), _shared_tmp(MPI.COMM_WORLD), quiet=True)
    assert res.completed and "could not be carried over" in res.report.sequence_failed
    assert any(st.stage == "dress" for st in res.report.steps)
    assert _mid_pressure(res) == pytest.approx(_laplace(res), rel=0.005)


def test_levels_not_coarser_than_the_scene_are_dropped():
    """A scene made coarser in code than its sequence's levels (as ``--error-bars`` makes its
    coarse level) is dressed without them."""
    assert [s.garment.mesh_size for s in sequence.coarse_scenes(_tube(0.02, sequence=[0.04]))] \
        == [0.04]  # fmt: skip
    assert sequence.coarse_scenes(_tube(0.05, sequence=[0.04])) == []
