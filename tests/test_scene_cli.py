"""``fenics-garment run SCENE.toml`` and the scene demos in ``demo --list``."""

import json
from pathlib import Path

from fenics_garment.cli import main

DEMOS = Path(__file__).parent.parent / "demos"


def test_run_rejects_a_bad_scene(tmp_path, capsys):
    bad = tmp_path / "bad.toml"
    bad.write_text("[garment]\nthickness = 0.001\n")
    assert main(["run", str(bad), "-o", str(tmp_path)]) == 2
    err = capsys.readouterr().err
    assert "bad.toml" in err and "[garment.thickness] unknown key" in err


def test_run_tube_scene_quietly(tmp_path, capsys):
    assert main(["run", str(DEMOS / "tube_on_cylinder.toml"), "-o", str(tmp_path), "-q"]) == 0
    assert capsys.readouterr().out == ""
    summary = json.loads((tmp_path / "tube-on-cylinder" / "summary.json").read_text())
    assert summary["completed"] and summary["dressing"]["newton_iterations"] > 0


def test_demo_list_has_the_gilets(capsys):
    assert main(["demo", "--list"]) == 0
    out = capsys.readouterr().out
    assert "cotton-gilet" in out and "nylon-gilet" in out
