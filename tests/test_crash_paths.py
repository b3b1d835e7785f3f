"""The crash paths of issue 40, each driven through the command line as a user meets it.

* Lengths and stiffnesses that enter the arithmetic squared or as a divisor (``[physics]
  penalty_length`` ℓ in κ = κ̂ E h / ℓ², ``[dressing] spring_length``, ``[body] tissue_depth``
  …) at 1e300, 1e-300, inf or nan: before, ``fenics-garment run`` ended in ``internal error:
  OverflowError`` / ``ZeroDivisionError`` (exit 1); now the scene is refused on load with one
  line naming the file, the key and the accepted range (exit 2).
* A 10 m cylinder with the tube demo's 2 cm garment mesh: 1,276,344 dofs, 97 s a Newton
  iteration on one rank, and nothing printed after "compiling the forms" for minutes. Now the
  run announces the large problem (dofs, memory, the mesh size that would be small), reports
  every slow Newton iteration, and refuses before solving a problem whose direct solve would not
  fit in the machine's memory.

(The third, path following that stops exactly at a load or a displacement, is in
``test_path.py``.)
"""

from __future__ import annotations

import math
import os
import subprocess
import sys
import time
import typing
from dataclasses import is_dataclass, replace
from pathlib import Path

import pytest

from fenics_garment import cli
from fenics_garment._stack import MPI
from fenics_garment.scene import config, preflight
from fenics_garment.scene import run as scene_run

ROOT = Path(__file__).resolve().parents[1]
TUBE = ROOT / "demos" / "tube_on_cylinder.toml"
pytestmark = pytest.mark.skipif(MPI.COMM_WORLD.size > 1, reason="serial")


def _tube(**changes) -> config.Scene:
    s = config.load(TUBE)
    s = replace(s, body=replace(s.body, mesh_size=0.01), output=replace(s.output, pictures=False))
    for section, kw in changes.items():
        s = replace(s, **{section: replace(getattr(s, section), **kw)})
    return s


def _write(path: Path, scene: config.Scene, section: str, key: str, value: float) -> Path:
    """The scene's TOML with ``[section] key = value`` (TOML writes inf and nan as such)."""
    lines = config.dumps(scene).splitlines()
    at = lines.index(f"[{section}]")
    end = next((i for i in range(at + 1, len(lines)) if lines[i].startswith("[")), len(lines))
    text = "inf" if value == math.inf else "nan" if math.isnan(value) else repr(value)
    lines = [x for x in lines[:end] if not x.startswith(f"{key} = ")] + [f"{key} = {text}"] + \
        lines[end:]  # fmt: skip
    path.write_text("\n".join(lines) + "\n")
    return path


CASES = [(k, v) for k, (lo, hi, *_) in config.LENGTH_RANGES.items() for v in (1e300, 1e-300)
         if not lo <= v <= hi] + [
    (k, v) for k in ("physics.penalty_length", "dressing.spring_length")
    for v in (math.inf, math.nan)
]  # fmt: skip


@pytest.mark.parametrize("dotted, value", CASES, ids=[f"{k}={v:g}" for k, v in CASES])
def test_extreme_lengths_are_refused_on_load_by_run(dotted, value, tmp_path, capsys):
    section, key = dotted.split(".")
    path = _write(tmp_path / "scene.toml", _tube(), section, key, value)
    code = cli.main(["run", str(path), "-q", "-o", str(tmp_path / "out")])
    err = capsys.readouterr().err.strip()
    assert code == 2, err
    assert err.startswith("error: ") and len(err.splitlines()) == 1, err
    assert str(path) in err and f"[{dotted}]" in err, err
    ranges = ("accepted range", "finite number", " in (", " in [", "must be >=", "must be in")
    assert any(r in err for r in ranges), err  # (a key's own check may name its range first)
    assert "internal error" not in err


def test_the_reported_cases_exit_2_in_a_real_process(tmp_path):
    """The two reproductions of the issue, ``fenics-garment run`` in its own process: exit 2 and
    one line (before: exit 1, ``internal error: OverflowError`` / ``ZeroDivisionError``)."""
    s = _tube()
    for dotted, value in (("physics.penalty_length", 1e300), ("dressing.spring_length", 1e-300)):
        section, key = dotted.split(".")
        path = _write(tmp_path / f"{key}.toml", s, section, key, value)
        p = subprocess.run([sys.executable, "-m", "fenics_garment.cli", "run", str(path), "-q",
                            "-o", str(tmp_path / "out")], capture_output=True, text=True,
                           timeout=300, env={**os.environ, "PYTHONPATH": str(ROOT)})  # fmt: skip
        assert p.returncode == 2, p.stderr
        lines = p.stderr.strip().splitlines()
        assert len(lines) == 1 and f"[{dotted}]" in lines[0] and "[0.0001, 10] m" in lines[0]


#: float keys at 1e-300 that are the same as their valid 0 (no friction, no extra shrink, no
#: spring on a finer mesh level): accepted, and run (below)
ZERO_LIKE = {"physics.friction", "dressing.margin", "dressing.sequence_spring",
             "garment.fabric_overrides.density", "drape.imperfection",
             "drape.dc_measured"}  # fmt: skip
#: the scene each key is checked on (where it is used; the tube otherwise)
WHERE = {"body.scale": "scan_gilet", "body.landmarks.waist": "scan_gilet",
         "body.measurements.waist_girth": "cotton_gilet",
         "body.measurements.wrist_girth": "sleeve_on_arm"}  # fmt: skip


def _float_keys() -> list[str]:
    """Every number of a scene: the float fields of every section, found from the dataclasses
    (a key added later is checked without a change here), and the numbers of its tables."""
    keys = []
    for section, cls in typing.get_type_hints(config.Scene).items():
        if not is_dataclass(cls):
            continue
        for name, tp in typing.get_type_hints(cls).items():
            if tp is float:
                keys.append(f"{section}.{name}")
    fabric = ("E_warp", "E_weft", "G12", "B_warp", "B_weft", "thickness", "density")
    return keys + [f"garment.fabric_overrides.{k}" for k in fabric] + list(WHERE)[1:]


def _outcome(dotted: str, value: float) -> str:
    """'ok', or the one-line refusal of the scene with ``dotted`` = ``value`` on load and in the
    pre-build limits (the checks ``fenics-garment run`` makes before building anything)."""
    section, key, *sub = dotted.split(".")
    demo = WHERE.get(dotted, "drape_wool_tropical" if section == "drape" else "tube_on_cylinder")
    path = ROOT / "demos" / f"{demo}.toml"
    if not path.exists():  # shipped only in the package (the drape scene)
        path = ROOT / "fenics_garment" / "scenes" / f"{demo}.toml"
    data = config.to_dict(config.load(path))
    if sub:
        data[section][key] = {**data[section][key], sub[0]: value}
    else:
        data[section][key] = value
    try:
        preflight.scene_limits(config.from_dict(data, str(path)))
    except (config.SceneError, preflight.PreflightError) as err:
        return str(err)
    return "ok"


def test_every_number_of_a_scene_at_1e300_and_1e_300_is_refused_naming_its_key():
    """All float keys in a loop: 1e300 and 1e-300 are refused before anything is built, in one
    line naming the key and its accepted range or limit — or, at 1e-300, mean their valid 0
    (:data:`ZERO_LIKE`, run in the next test)."""
    keys = _float_keys()
    assert {"physics.penalty_length", "dressing.spring_length", "body.tissue_depth"} <= set(keys)
    assert len(keys) >= 30, keys
    for dotted in keys:
        for value in (1e300, 1e-300):
            got = _outcome(dotted, value)
            if value == 1e-300 and dotted in ZERO_LIKE:
                assert got == "ok", (dotted, got)
                continue
            assert got != "ok", f"{dotted} = {value:g} is accepted"
            assert "\n" not in got and f"[{dotted}]" in got, (dotted, got)
            bound = ("accepted range", "more than", "less than", "at least", "must be", "must lie",
                     "in (", "in [", "outside", "; use ", "not a human body")  # fmt: skip
            assert any(b in got for b in bound), (dotted, got)


@pytest.mark.slow
def test_the_numbers_that_mean_zero_at_1e_300_run(tmp_path, capsys):
    """The accepted 1e-300s together, on the small tube with a mesh sequence (so that
    sequence_spring is used): the run ends with exit 0, no internal error (307 s on the loaded
    2-core machine)."""
    s = _tube(physics={"friction": 1e-300}, output={"pictures": False, "vtx": False,
                                                    "xdmf": False})  # fmt: skip
    path = tmp_path / "tiny.toml"
    path.write_text(config.dumps(s))
    for section, key in (("physics", "friction"), ("dressing", "margin"),
                         ("dressing", "sequence_spring")):  # fmt: skip
        _write(path, config.load(path), section, key, 1e-300)
    _write(path, config.load(path), "dressing", "sequence", 0.0)
    text = path.read_text().replace("sequence = 0.0", f"sequence = [{1.5 * s.garment.mesh_size}]")
    path.write_text(text)
    assert config.load(path).dressing.sequence == [1.5 * s.garment.mesh_size]
    code = cli.main(["run", str(path), "-q", "--no-checkpoints", "-o", str(tmp_path / "out")])
    err = capsys.readouterr().err
    assert code == 0, err
    assert "internal error" not in err


def test_the_ranges_admit_every_shipped_scene():
    for path in [*(ROOT / "demos").glob("*.toml"), *(ROOT / "fenics_garment" / "scenes").glob(
            "*.toml")]:  # fmt: skip
        config.load(path)  # raises SceneError otherwise


# -- the 10 m cylinder -------------------------------------------------------------------------
def test_a_large_problem_is_announced_and_its_slow_iterations_reported(
    tmp_path, capsys, monkeypatch
):
    """The run path of a large problem, on the small tube with the thresholds lowered: the notice
    (dofs, memory, a mesh size) comes before the forms are compiled, and every Newton iteration
    that takes longer than SLOW_ITERATION_S prints a line."""
    monkeypatch.setattr(preflight, "LARGE_DOFS_PER_RANK", 1000)
    monkeypatch.setattr(scene_run, "SLOW_ITERATION_S", 0.0)
    path = tmp_path / "tube.toml"
    path.write_text(config.dumps(_tube(output={"pictures": False, "vtx": False,
                                                "xdmf": False})))  # fmt: skip
    code = cli.main(["run", str(path), "--no-checkpoints", "-o", str(tmp_path / "out")])
    out = capsys.readouterr().out
    assert code == 0, out
    lines = out.splitlines()
    notice = next(i for i, x in enumerate(lines) if "a large problem:" in x)
    compiling = next(i for i, x in enumerate(lines) if "compiling the forms" in x)
    assert notice < compiling
    assert "dofs on 1 rank(s)" in lines[notice] and "garment.mesh_size >= " in lines[notice]
    iterations = [x for x in lines if x.strip().startswith("Newton iteration")]
    assert len(iterations) >= 5 and "residual" in iterations[0]


def test_a_problem_larger_than_the_memory_is_refused_before_solving(tmp_path, capsys, monkeypatch):
    monkeypatch.setattr(preflight, "machine_memory", lambda comm: 50e6)  # 50 MB
    path = tmp_path / "tube.toml"
    path.write_text(config.dumps(_tube()))
    assert cli.main(["run", str(path), "-q", "-o", str(tmp_path / "out")]) == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and "[garment.mesh_size]" in err, err
    assert "dofs: a direct solve needs about" in err and "use garment.mesh_size >= " in err


def test_the_notice_names_a_mesh_size_within_the_limit():
    s = _tube(body={"radius": 10.0, "mesh_size": 0.5})
    dofs = 1_276_344  # the 10 m tube at the demo's 2 cm garment mesh, as built
    notice = preflight.problem_size(s, dofs, MPI.COMM_SELF)
    assert notice is not None and "1,276,344 dofs on 1 rank(s)" in notice
    h = float(notice.split("garment.mesh_size >= ")[1].split()[0])
    assert dofs * (0.02 / h) ** 2 == pytest.approx(preflight.LARGE_DOFS_PER_RANK, rel=0.05)
    assert preflight.problem_size(s, 100_000, MPI.COMM_SELF) is None


@pytest.mark.slow
def test_the_10_m_cylinder_says_what_it_does(tmp_path):
    """The reported scene in its own process (the tube demo on a 10 m cylinder, body mesh 0.5 m):
    the notice comes right after meshing, then the compile, then one line per Newton iteration.
    Measured on the loaded 2-core machine: notice at 48 s (after the garment mesh), "compiling"
    at 105 s (the initial contact search on 68,960 cells), the first iteration's line at 241 s
    (68 s for the iteration). The run is stopped there; it would take about an hour."""
    s = _tube(body={"radius": 10.0, "mesh_size": 0.5})
    path = tmp_path / "r10.toml"
    path.write_text(config.dumps(s))
    cmd = [sys.executable, "-u", "-m", "fenics_garment.cli", "run", str(path), "--no-checkpoints",
           "-o", str(tmp_path / "out")]  # fmt: skip
    p = subprocess.Popen(cmd, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True,
                         env={**os.environ, "PYTHONPATH": str(ROOT)})  # fmt: skip
    t0, seen = time.monotonic(), []
    try:
        for line in p.stdout:
            seen.append((time.monotonic() - t0, line.rstrip()))
            if line.strip().startswith("Newton iteration") or time.monotonic() - t0 > 900:
                break
    finally:
        p.kill()
        code = p.wait()
    text = "\n".join(f"{t:6.1f} s  {x}" for t, x in seen) + f"\n(exit {code})"
    print(text)
    assert any("a large problem: 1,276,344 dofs" in x for _, x in seen), text
    assert "Newton iteration 1: residual" in seen[-1][1], text


# -- no scene sits in meshing or the JIT for good -----------------------------------------------
@pytest.mark.parametrize(
    "patch, words",
    [
        ("from fenics_garment.geometry import gmsh_utils; gmsh_utils.GMSH_TIME_LIMIT = 1e-3",
         "error: the build did not finish the cylinder body within 0.001 s"),
        ("from fenics_garment.scene import run; run.JIT_TIME_LIMIT = 1e-3",
         "error: the FFCx JIT did not finish compiling the forms and allocating the Jacobian "
         "within 0.001 s"),
    ],
    ids=["meshing", "jit"],
)  # fmt: skip
def test_meshing_and_the_jit_have_a_time_limit(patch, words, tmp_path):
    """``fenics-garment run`` in its own process with the body's meshing or the JIT's limit
    lowered to 1 ms: the stage that overran is named in one line, exit 2 (the progress line
    says what is going on before: ``[meshing and building the model · 30 s]``, ``[JIT: …]``)."""
    path = tmp_path / "tube.toml"
    path.write_text(config.dumps(_tube()))
    args = ["run", str(path), "-q", "-o", str(tmp_path / "o")]
    script = f"{patch}\nimport sys\nfrom fenics_garment import cli\nsys.exit(cli.main({args!r}))"
    p = subprocess.run([sys.executable, "-c", script], capture_output=True, text=True,
                       timeout=600, env={**os.environ, "PYTHONPATH": str(ROOT)})  # fmt: skip
    lines = [x for x in p.stderr.splitlines() if x.startswith("error: ")]
    assert p.returncode == 2, p.stderr
    assert len(lines) == 1 and lines[0].startswith(words), p.stderr
    assert "Traceback" not in p.stderr
