"""Contact laws from a file next to the scene (``[physics] terms = "file.py:function"``).

* A friction law written the natural way — it holds its own warp and weft coefficients and
  ignores the scene's μ — on the tight tube (``demos/tube_on_cylinder.toml``, friction off while
  the body grows): the dressing switches it off while the body grows like the default law, so
  the tube ends at the free-end equilibrium of Laplace's law (``tube_pressure``), not at the
  axially stuck one (``stuck=True``), 6.8 % higher. Measured −0.21 %; with the law on while
  the body grows (``friction_while_growing = true``: what setting ``mu.value = 0`` left such a
  law to do) +3.9 %. The summary names the law from the file.
* A soft normal law (no multiplier) under the scene's default augmented Lagrangian: refused
  before any solve, in one line naming the scene file and ``[physics.contact]``.
"""

from pathlib import Path

import pytest

from fenics_garment.scene import config
from fenics_garment.scene.run import run
from fenics_garment.stack import MPI
from fenics_garment.verification.contact import band_pressure, tube_pressure

TUBE = Path(__file__).parent.parent / "demos" / "tube_on_cylinder.toml"

LAWS = '''
from dataclasses import replace

import ufl

from fenics_garment.contact import laws

MU_WARP, MU_WEFT = 0.3, 0.15  # the law's own coefficients: the scene's μ is not read
TINY = 1e-9  # [Pa]: finite where t_N = 0


def tangential(d, n):
    """The unit part of d tangent to the body (normal n)."""
    t = d - ufl.dot(d, n) * n
    return t / ufl.sqrt(ufl.dot(t, t))


def yarn_friction(c):
    """Coulomb along each yarn, smoothed: t_T = −t_N Σ μ_i tanh(κ_T s_i/(μ_i t_N)) a_i."""
    t = 0
    for mu, d in ((MU_WARP, c.warp), (MU_WEFT, c.weft)):
        a = tangential(d, c.normal)
        z = c.kappa_t * ufl.dot(c.slip, a) / (mu * c.normal_traction + TINY)
        t += -mu * c.normal_traction * ufl.tanh(ufl.max_value(ufl.min_value(z, 20.0), -20.0)) * a
    return t


def use_yarn_friction(built):
    built.contact.friction = replace(built.contact.friction, law=yarn_friction)


def soft(c):
    """An exponential pressure law of the gap alone (not a constraint)."""
    return 1.0e3 * ufl.exp(-c.gap / 2e-3)


def use_soft(built):
    built.contact.normal_law = soft
'''


def _scene_file(folder: Path, terms: str, physics: str = "") -> Path:
    """The tube scene with ``[physics] terms``, its outputs off, in ``folder`` with the laws."""
    (folder / "my_laws.py").write_text(LAWS)
    text = TUBE.read_text().replace("[physics]\n", f'[physics]\nterms = "{terms}"\n{physics}')
    text += "\n[output]\npictures = false\nvtx = false\nxdmf = false\nreport = false\n"
    path = folder / "tube.toml"
    path.write_text(text)
    return path


def _shared_tmp(tmp_path: Path) -> Path:
    return Path(MPI.COMM_WORLD.bcast(str(tmp_path), root=0))


def test_a_soft_law_with_the_augmented_lagrangian_is_refused_before_solving(tmp_path):
    folder = _shared_tmp(tmp_path)
    scene = config.load(_scene_file(folder, "my_laws.py:use_soft"))
    assert scene.physics.contact == "augmented-lagrangian"  # the default
    with pytest.raises(config.SceneError) as err:
        run(scene, folder / "out", quiet=True)
    message = str(err.value)
    print(f"\n{message}")
    assert "\n" not in message and "[physics.contact]" in message and "tube.toml" in message
    assert "soft" in message and 'contact = "penalty"' in message
    assert not list((folder / "out").rglob("summary.json"))  # nothing was solved


@pytest.mark.slow  # one tube dressing (about a minute with a cold JIT cache)
def test_a_friction_law_from_a_file_is_switched_by_the_dressing(tmp_path):
    folder = _shared_tmp(tmp_path)
    scene = config.load(_scene_file(folder, "my_laws.py:use_yarn_friction"))
    assert not scene.dressing.friction_while_growing
    result = run(scene, folder / "out", quiet=True)
    assert result.completed, result.message
    assert result.summary["terms"]["friction_law"].endswith(".yarn_friction")
    b = result.built
    s, R = b.model.stiffness, b.scene.body.radius
    r0, R_c = R + b.garment.level("mid").clearance, R + s.thickness / 2
    free = tube_pressure(R_c, r0, s, warp="axial")
    stuck = tube_pressure(R_c, r0, s, warp="axial", stuck=True)
    p = band_pressure(b, 0.05, 0.15)  # the middle half
    print(f"\np = {p:.1f} Pa, Laplace free ends {free:.1f} Pa ({p / free - 1:+.2%}), "
          f"stuck {stuck:.1f} Pa")  # fmt: skip
    assert abs(stuck / free - 1) > 0.02  # the two ends are told apart
    assert p == pytest.approx(free, rel=0.005)
