"""Bounded input (issue 48): scene and pattern files are regular files of a stated size, nested
at most ``bounded.MAX_DEPTH`` deep, not empty; control characters are refused in names and
paths; an echoed value is cut to a readable length. Each a one-line error, exit code 2.
"""

import json
import os
import tomllib
from pathlib import Path

import pytest
from test_reliability import small_tube

from fenics_garment import bounded, cli
from fenics_garment._stack import MPI
from fenics_garment.pattern.io import read_pattern
from fenics_garment.pattern.model import PatternError
from fenics_garment.scene import checkpoint, config

pytestmark = pytest.mark.skipif(MPI.COMM_WORLD.size > 1, reason="serial")


def _refused(capsys, *argv: str) -> str:
    assert cli.main(["run", "-q", *argv]) == 2
    err = capsys.readouterr().err.strip()
    assert err.startswith("error: ") and len(err.splitlines()) == 1, err[:500]
    assert len(err) < 1200, f"an error line of {len(err)} characters"
    return err


@pytest.fixture
def scene_text() -> str:
    return config.dumps(small_tube())


def test_a_device_never_ending_is_refused(capsys):
    assert "a character device, not a scene file" in _refused(capsys, "/dev/urandom")


def test_a_fifo_without_writer_is_refused_without_blocking(tmp_path, capsys):
    fifo = tmp_path / "scene.toml"
    os.mkfifo(fifo)
    assert "a FIFO (named pipe), not a scene file" in _refused(capsys, str(fifo))


def test_a_folder_is_refused(tmp_path, capsys):
    assert "a folder, not a scene file" in _refused(capsys, str(tmp_path))


def test_a_scene_file_over_the_size_limit(tmp_path, capsys, scene_text):
    big = tmp_path / "big.toml"
    big.write_text("# " + "x" * bounded.MAX_SCENE_BYTES + "\n" + scene_text)
    assert "larger than 1024 kB, the limit of a scene file" in _refused(capsys, str(big))


@pytest.mark.parametrize("depth", [40, 5000])  # past the limit; past the parser's recursion
def test_nesting_beyond_the_limit(tmp_path, capsys, depth):
    deep = tmp_path / "deep.toml"
    deep.write_text("a = " + "[" * depth + "]" * depth + "\n")
    assert f"nested deeper than {bounded.MAX_DEPTH} levels" in _refused(capsys, str(deep))


@pytest.mark.parametrize("text", ["", "\n\n", "# only a comment\n"])
def test_an_empty_scene_is_refused(tmp_path, capsys, text):
    empty = tmp_path / "empty.toml"
    empty.write_text(text)
    assert "empty scene file: nothing to dress" in _refused(capsys, str(empty))


@pytest.mark.parametrize("value", ["out\x1b[31m", "out\nput", "a\x7fb", "tab\there"])
def test_control_characters_in_the_output_folder(tmp_path, capsys, scene_text, value):
    scene = tmp_path / "scene.toml"
    scene.write_text(scene_text.replace('folder = "output"', f"folder = {json.dumps(value)}"))
    err = _refused(capsys, str(scene))
    assert "[output.folder] has a control character" in err


def test_a_newline_in_the_scene_path(tmp_path, capsys, scene_text):
    scene = tmp_path / "tu\nbe.toml"
    scene.write_text(scene_text)
    assert "the scene file's path has a control character" in _refused(capsys, str(scene))


def test_scene_used_reads_back_whatever_its_source_path():
    """The run's own scene_used.toml stays valid TOML: the source in its comment, and every
    string, escaped (a scene made in code is not checked as a file is)."""
    s = small_tube(garment={"fabric": "cot\x01ton"})
    s = config.Scene(**{**s.__dict__, "source": "/tmp/a\nname = 'evil'\n.toml"})
    text = config.dumps(s)
    data = tomllib.loads(text)
    assert data["name"] == s.name and data["garment"]["fabric"] == "cot\x01ton"


@pytest.mark.parametrize("where", ["name", "key"])
def test_a_huge_value_is_echoed_cut(tmp_path, capsys, scene_text, where):
    huge = "n" * 500_000
    text = (scene_text.replace('name = "tube-on-cylinder"', f'name = "{huge}"') if where == "name"
            else f"{huge} = 1\n" + scene_text)  # fmt: skip
    scene = tmp_path / "scene.toml"
    scene.write_text(text)
    err = _refused(capsys, str(scene))
    assert "(500002 characters)" in err or "(500000 characters)" in err


def test_a_fifo_as_pattern_file(tmp_path):
    fifo = tmp_path / "pattern.toml"
    os.mkfifo(fifo)
    with pytest.raises(PatternError, match="a FIFO"):
        read_pattern(fifo)


def test_a_pattern_nested_too_deep(tmp_path):
    deep = tmp_path / "pattern.json"
    deep.write_text("[" * 10_000 + "]" * 10_000)
    with pytest.raises(PatternError, match="nested deeper"):
        read_pattern(deep)


def test_a_progress_file_nested_too_deep(tmp_path, capsys, scene_text):
    folder = tmp_path / "tube-on-cylinder"
    (folder / "checkpoint").mkdir(parents=True)
    (folder / "scene_used.toml").write_text(scene_text)
    (folder / "checkpoint" / "progress.json").write_text("[" * 100_000 + "]" * 100_000)
    err = _refused(capsys, "--resume", str(folder))
    assert "damaged" in err and "nested deeper" in err


def test_a_progress_file_over_the_size_limit(tmp_path, monkeypatch):
    monkeypatch.setattr(bounded, "MAX_PROGRESS_BYTES", 1000)
    (tmp_path / "checkpoint").mkdir()
    (tmp_path / "checkpoint" / "progress.json").write_text(" " * 2000 + "{}")
    with pytest.raises(checkpoint.ResumeError, match="larger than"):
        checkpoint._read_meta(tmp_path)


def test_the_shipped_scenes_and_patterns_are_within_the_bounds():
    root = Path(__file__).parent.parent
    for path in [*root.glob("demos/*.toml"), *root.glob("fenics_garment/scenes/*.toml")]:
        config.load(path)
    for path in root.glob("fenics_garment/scenes/patterns/*"):
        read_pattern(path)
