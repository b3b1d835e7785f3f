"""Scene files: defaults, round trip of the scene used, and errors that name file and key."""

import tomllib
from pathlib import Path

import pytest

from fenics_garment.scene import config

DEMOS = Path(__file__).parent.parent / "demos"


def _load_text(tmp_path: Path, text: str) -> config.Scene:
    path = tmp_path / "scene.toml"
    path.write_text(text)
    return config.load(path)


def test_defaults_and_round_trip(tmp_path):
    s = _load_text(tmp_path, 'name = "x"\n[garment]\nease = { waist = -0.03 }\n')
    assert s.garment.ease == {"waist": -0.03}
    assert s.physics.friction == pytest.approx(0.4)
    again = config.from_dict(tomllib.loads(config.dumps(s)))
    assert again == s


@pytest.mark.parametrize("name", ["cotton_gilet", "nylon_gilet", "tube_on_cylinder"])
def test_bundled_scenes_load(name):
    s = config.load(DEMOS / f"{name}.toml")
    assert s.name.replace("-", "_") == name or s.name


@pytest.mark.parametrize(
    "text, key, words",
    [
        ("[garmnet]\nkind = 'gilet'\n", "garmnet", "did you mean 'garment'"),
        ("[garment]\nfabrik = 'cotton'\n", "garment.fabrik", "did you mean 'fabric'"),
        ("[body]\nmeasurements = { waist_grith = 0.7 }\n", "body.measurements.waist_grith",
         "did you mean 'waist_girth'"),
        ("[garment]\nfabric_overrides = { thickness = -0.0004 }\n",
         "garment.fabric_overrides.thickness", "must be positive"),
        ("[dressing]\nsteps = '4'\n", "dressing.steps", "must be an integer, got str"),
        ("[physics]\ngravity = 1\n", "physics.gravity", "must be a boolean"),
        ("[physics]\ncontact = 'penalti'\n", "physics.contact", "did you mean 'penalty'"),
        ("[physics]\nfriction = -0.1\n", "physics.friction", "must lie in [0, 2]"),
        ("[physics]\nbody_surface = 'smoth'\n", "physics.body_surface", "did you mean 'smooth'"),
        ("[garment]\nmesh_size = 0\n", "garment.mesh_size", "must be positive"),
        ("[garment]\nkind = 'tube'\n", "garment.kind", "needs a cylinder body"),
        ("[solver]\nlinear = 'gmag'\n", "solver.linear", "did you mean 'gamg'"),
        ("[garment]\nrefine_edges = 'armhole'\n", "garment.refine_edges",
         "must be an array of strings"),
        ("[garment]\nrefine_edges = ['armpit']\n", "garment.refine_edges", "no edge 'armpit'"),
        ("[garment]\nedge_ratio = 1.5\n", "garment.edge_ratio", "in (0, 1]"),
        ("[physics]\npenalty_length = -0.04\n", "physics.penalty_length", "must be ≥ 0"),
        ("[dressing]\npredictor = 'tangent'\n", "dressing.predictor", "secant"),
        ("[dressing]\npath_tolerance = 0.5\n", "dressing.path_tolerance", "in (0, 0.01]"),
        ("[dressing]\nrelease_multipliers = 1\n", "dressing.release_multipliers",
         "must be a boolean"),
    ],
)  # fmt: skip
def test_errors_name_file_and_key(tmp_path, text, key, words):
    with pytest.raises(config.SceneError) as err:
        _load_text(tmp_path, text)
    msg = str(err.value)
    assert str(tmp_path / "scene.toml") in msg
    assert f"[{key}]" in msg and words in msg
    assert err.value.key == key


def test_invalid_toml_and_missing_file(tmp_path):
    with pytest.raises(config.SceneError, match="not valid TOML"):
        _load_text(tmp_path, "name = \n")
    with pytest.raises(config.SceneError, match="no such scene file"):
        config.load(tmp_path / "nope.toml")


def test_every_bundled_scene_and_the_default_use_a_verified_element():
    """The verified element (it passes ``verification/shells.py``) is the default and every
    shipped scene's element; an unverified one gets a WARNING line."""
    from fenics_garment.scene.run import element_warning
    from fenics_garment.shell.model import DEFAULT_ELEMENT, ELEMENTS

    assert config.GarmentConfig().element == DEFAULT_ELEMENT
    assert ELEMENTS[DEFAULT_ELEMENT].verified
    for path in sorted(DEMOS.glob("*.toml")):
        element = config.load(path).garment.element
        assert ELEMENTS[element].verified, f"{path.name}: {element}"
        assert element_warning(ELEMENTS[element]) is None
    assert "WARNING" in element_warning(ELEMENTS["P1-P1"])
    assert set(config.ELEMENTS) <= set(ELEMENTS)


@pytest.mark.parametrize(
    "spec, words",
    [
        ("no_colon", "must be 'module:function'"),
        ("mod:not-a-name", "must be 'module:function'"),
        ("no_such_module_xyz:terms", "cannot import 'no_such_module_xyz'"),
        ("missing.py:terms", "cannot import 'missing.py'"),
        ("hooks.py:absent", "has no function 'absent'"),
    ],
)
def test_physics_terms_errors_are_one_line(tmp_path, spec, words):
    (tmp_path / "hooks.py").write_text("def terms(built):\n    pass\n")
    with pytest.raises(config.SceneError) as err:
        _load_text(tmp_path, f'[physics]\nterms = "{spec}"\n')
    message = str(err.value)
    assert "[physics.terms]" in message and words in message and "\n" not in message


@pytest.mark.parametrize("spec", ["hooks.py:terms", "hooks:terms"])
def test_physics_terms_found_next_to_the_scene(tmp_path, spec):
    (tmp_path / "hooks.py").write_text("def terms(built):\n    built.touched = True\n")
    s = _load_text(tmp_path, f'[physics]\nterms = "{spec}"\n')
    hook = config.load_terms(s.physics.terms, s.source)

    class Problem:
        touched = False

    problem = Problem()
    hook(problem)
    assert problem.touched
