"""Reliability tries: the machine around a run (issue 48), each try a real ``fenics-garment``
process on the small tube scene, its outcome classified.

    python -m benchmarks.reliability [class ...]

Classes: ``signals``, ``checkpoint``, ``input``, ``environment``, ``output`` (default: all).
Every try states what a correct program does (exit code, one ``error:`` line, ``run.json``,
outputs, a resume to the reference answer) and is classified as

* ``held`` — it did that;
* ``hang`` — no exit within :data:`TIMEOUT` seconds (the process is killed);
* ``crash`` — ended by SIGABRT/SIGSEGV/SIGBUS/SIGFPE or with their shell codes;
* ``internal error`` — exit 1, an ``internal error`` line or a traceback;
* ``unreported kill`` — ended by another signal, or with 128 + a signal, without an error line;
* ``silent wrong`` — anything else: a wrong exit code, a missing or many-line message, a lie
  accepted, a wrong status in ``run.json``, a partial file under a real name, a resume that
  failed or gave another answer.

A 2-rank try runs ``mpiexec -n 2 fenics-garment …``, or, when its name says "by run -n 2",
``fenics-garment run -n 2 …`` (the package's launcher, :mod:`fenics_garment.launcher`): the
signals that end MPICH's ``mpiexec`` itself (SIGHUP, a closed stdout) are tried through the
launcher only.

Writes ``benchmarks/results/reliability.json`` and the table between the markers of
``docs/reliability.md``. Needs root for the small file systems (tmpfs, read-only bind mounts);
without it those tries are skipped and listed as such.
"""

from __future__ import annotations

import json
import os
import re
import shutil
import signal
import subprocess
import sys
import tempfile
import time
from collections.abc import Callable
from dataclasses import asdict, dataclass, field
from pathlib import Path

import numpy as np

from benchmarks import check_args

ROOT = Path(__file__).resolve().parent.parent
BIN = Path(sys.executable).parent
RESULTS = ROOT / "benchmarks" / "results" / "reliability.json"
DOC = ROOT / "docs" / "reliability.md"
BEGIN, END = "<!-- reliability table: begin -->", "<!-- reliability table: end -->"
CLASSES = ("signals", "checkpoint", "input", "environment", "output")
OUTCOMES = ("held", "hang", "crash", "internal error", "silent wrong", "unreported kill")
#: Seconds a try may take before it counts as a hang.
TIMEOUT = 400.0
CRASH_SIGNALS = (signal.SIGABRT, signal.SIGSEGV, signal.SIGBUS, signal.SIGFPE)


@dataclass
class Proc:
    """A finished (or timed-out: ``code`` None) process."""

    code: int | None
    out: str
    err: str
    seconds: float


@dataclass
class Result:
    klass: str
    name: str
    outcome: str
    detail: str = ""
    seconds: float = 0.0


@dataclass
class Bench:
    """The working folder, the scene files and the reference answers."""

    work: Path
    scene: Path
    reference: dict[int, str] = field(default_factory=dict)  # ranks -> pressure_regions.csv
    results: list[Result] = field(default_factory=list)


# -- processes --------------------------------------------------------------------------------
def _env(**changes: str | None) -> dict[str, str]:
    env = {**os.environ, "PYTHONPATH": str(ROOT)}
    for k, v in changes.items():
        if v is None:
            env.pop(k, None)
        else:
            env[k] = v
    return env


def _command(args: list[str], ranks: int, launcher: bool = False) -> list[str]:
    """The command of a try: ``mpiexec -n N fenics-garment …`` on several ranks, or, with
    ``launcher``, ``fenics-garment run -n N …`` (the package starts mpiexec itself)."""
    cli = [sys.executable, "-m", "fenics_garment.cli", *args]
    if launcher:
        return [*cli[:4], "-n", str(ranks), *cli[4:]]
    return [str(BIN / "mpiexec"), "-n", str(ranks), *cli] if ranks > 1 else cli


def start(args: list[str], *, ranks: int = 1, env: dict | None = None, launcher: bool = False,
          **kw) -> subprocess.Popen:  # fmt: skip
    return subprocess.Popen(_command(args, ranks, launcher), env=env or _env(),
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
                            errors="replace", start_new_session=True, **kw)  # fmt: skip


def finish(p: subprocess.Popen, t0: float, timeout: float = TIMEOUT) -> Proc:
    try:
        out, err = p.communicate(timeout=max(timeout - (time.monotonic() - t0), 1.0))
        return Proc(p.returncode, out, err, time.monotonic() - t0)
    except subprocess.TimeoutExpired:
        os.killpg(p.pid, signal.SIGKILL)
        out, err = p.communicate()
        return Proc(None, out, err, time.monotonic() - t0)


def run(args: list[str], timeout: float = TIMEOUT, **kw) -> Proc:
    t0 = time.monotonic()
    return finish(start(args, **kw), t0, timeout)


def wait_for(path: Path, p: subprocess.Popen, limit: float = TIMEOUT) -> bool:
    t0 = time.monotonic()
    while not path.exists() and p.poll() is None and time.monotonic() - t0 < limit:
        time.sleep(0.01)
    return p.poll() is None and path.exists()


# -- verdicts ---------------------------------------------------------------------------------
def error_lines(err: str) -> list[str]:
    """The lines of stderr that are not warnings nor the MPI launcher's own."""
    skip = ("warning:", "[mpiexec@")
    return [ln for ln in err.splitlines() if ln.strip() and not ln.startswith(skip)]


def verdict(p: Proc, expect: int, problems: list[str]) -> tuple[str, str]:
    """(outcome, detail) of a process expected to exit ``expect`` with ``problems`` found by
    the try's own checks (empty: all held)."""
    lines = error_lines(p.err)
    head = lines[0] if lines else ""
    if p.code is None:
        return "hang", f"no exit in {TIMEOUT:.0f} s"
    if p.code == 1 or "internal error" in p.err or "Traceback" in p.err:
        return "internal error", head
    crash = {-int(s) for s in CRASH_SIGNALS} | {128 + int(s) for s in CRASH_SIGNALS}
    if p.code in crash and p.code != expect:
        return "crash", f"exit {p.code}: {head}"
    if (p.code < 0 or p.code > 128) and p.code != expect and not lines:
        return "unreported kill", f"exit {p.code}, no message"
    if expect != 0 and len(lines) != 1:
        problems = [f"{len(lines)} error lines", *problems]
    if p.code != expect:
        problems = [f"exit {p.code}, not {expect}", *problems]
    if problems:
        return "silent wrong", "; ".join(problems) + (f" ({head})" if head else "")
    return "held", head


def record(b: Bench, klass: str, name: str, p: Proc, expect: int, problems: list[str]) -> None:
    outcome, detail = verdict(p, expect, problems)
    detail = detail.replace(str(b.work), "<work>")[:240]
    b.results.append(Result(klass, name, outcome, detail, round(p.seconds, 1)))
    print(f"  {klass:<12} {name:<44} {outcome:<15} {p.seconds:6.1f} s  {detail[:110]}",
          flush=True)  # fmt: skip


def skipped(b: Bench, klass: str, name: str, why: str) -> None:
    b.results.append(Result(klass, name, "skipped", why))
    print(f"  {klass:<12} {name:<44} skipped: {why}", flush=True)


# -- the scene, its folders and checks ---------------------------------------------------------
FOLDER = "tube-on-cylinder"


def write_scene(work: Path) -> Path:
    sys.path.insert(0, str(ROOT / "tests"))
    from test_reliability import small_tube

    from fenics_garment.scene import config

    path = work / "tube.toml"
    path.write_text(config.dumps(small_tube()))
    return path


def status(folder: Path) -> dict:
    try:
        return json.loads((folder / "run.json").read_text())
    except (OSError, ValueError):
        return {}


def partial_files(folder: Path) -> list[str]:
    """Temporary files left, and real files that do not read back whole."""
    bad = []
    for path in folder.rglob("*"):
        if ".part" in path.name:
            bad.append(path.name)
        elif path.is_file():
            try:
                if path.suffix == ".json":
                    json.loads(path.read_text())
                elif path.suffix == ".npz":
                    with np.load(path) as d:
                        [d[k] for k in d.files]
            except (OSError, ValueError, EOFError) as err:
                bad.append(f"{path.name} ({type(err).__name__})")
    return bad


def same_answer(b: Bench, folder: Path, ranks: int) -> list[str]:
    try:
        csv = (folder / "pressure_regions.csv").read_text()
    except OSError:
        return ["no pressure_regions.csv"]
    same = csv == reference(b, ranks)
    return [] if same else ["the answer differs from the uninterrupted run's"]


def resume_check(b: Bench, folder: Path, ranks: int, env: dict | None = None,
                 launcher: bool = False) -> list[str]:  # fmt: skip
    """Resume ``folder`` and compare its answer with the reference (problems, or [])."""
    p = run(["run", "-q", "--resume", str(folder)], ranks=ranks, env=env, launcher=launcher)
    if p.code != 0:
        return [f"resume exit {p.code}: {' '.join(error_lines(p.err))[:120]}"]
    return same_answer(b, folder, ranks)


def reference(b: Bench, ranks: int) -> str:
    """The pressure table of an uninterrupted run on ``ranks`` ranks (made once)."""
    if ranks not in b.reference:
        out = b.work / f"reference{ranks}"
        p = run(["run", "-q", str(b.scene), "-o", str(out)], ranks=ranks)
        if p.code != 0:
            raise SystemExit(f"the reference run on {ranks} rank(s) failed: {p.err[-400:]}")
        b.reference[ranks] = (out / FOLDER / "pressure_regions.csv").read_text()
        print(f"  reference on {ranks} rank(s): {p.seconds:.1f} s", flush=True)
    return b.reference[ranks]


# -- signals ----------------------------------------------------------------------------------
def _interrupt(b: Bench, out: Path, sig: int, *, ranks: int = 1, when: str = "checkpoint",
               target: Callable[[subprocess.Popen], list[int]] | None = None,
               launcher: bool = False) -> Proc:  # fmt: skip
    """A run sent ``sig`` (to the launcher or to ``target``'s pids) after its first checkpoint
    (or ``when`` seconds after the start); ``launcher``: started as ``run -n N``."""
    t0 = time.monotonic()
    p = start(["run", str(b.scene), "-o", str(out)], ranks=ranks, launcher=launcher)
    if when == "checkpoint":
        wait_for(out / FOLDER / "checkpoint" / "progress.json", p)
    else:
        time.sleep(float(when))
    pids = target(p) if target else [p.pid]
    for pid in pids:
        try:
            os.kill(pid, sig)
        except ProcessLookupError:
            pass
    return finish(p, t0)


def _descendants(pid: int) -> list[int]:
    """Every process started, directly or not, by ``pid``."""
    children: dict[int, list[int]] = {}
    for d in Path("/proc").iterdir():
        if not d.name.isdigit():
            continue
        try:
            ppid = int((d / "stat").read_text().rsplit(")", 1)[1].split()[1])
        except (OSError, ValueError, IndexError):
            continue
        children.setdefault(ppid, []).append(int(d.name))
    found, todo = [], [pid]
    while todo:
        kids = children.get(todo.pop(), [])
        found += kids
        todo += kids
    return found


def rank_pids(p: subprocess.Popen, ranks: tuple[int, ...] = (1,)) -> list[int]:
    """The pids of the given MPI ranks started by launcher ``p`` (from their PMI_RANK)."""
    found = []
    for pid in _descendants(p.pid):
        try:
            env = Path(f"/proc/{pid}/environ").read_bytes().split(b"\0")
            cmd = Path(f"/proc/{pid}/cmdline").read_bytes()
        except OSError:
            continue
        rank = next((int(e[9:]) for e in env if e.startswith(b"PMI_RANK=")), -1)
        if b"fenics_garment.cli" in cmd and rank in ranks:
            found.append(pid)
    return found


def job_pids(p: subprocess.Popen) -> list[int]:
    """The launcher and every process of its job (a closed terminal signals them all)."""
    return [p.pid, *_descendants(p.pid)]


def _signal_problems(p: Proc, folder: Path, checkpoint: bool) -> list[str]:
    problems = []
    lines = error_lines(p.err)
    if lines and "interrupted by SIG" not in lines[0]:
        problems.append("no 'interrupted by' line")
    if lines and checkpoint and "--resume" not in lines[0]:
        problems.append("no --resume command")
    if status(folder).get("status") != "interrupted":
        problems.append(f"run.json status {status(folder).get('status')!r}")
    return problems


#: How a 2-rank try is started: MPICH's mpiexec run directly (SIGHUP and a closed stdout end it
#: and its ranks: a limit of that launcher, not tried), or the package's launcher.
LAUNCHER = " by run -n 2"


def try_signals(b: Bench) -> None:
    k = "signals"
    every = (signal.SIGINT, signal.SIGTERM, signal.SIGHUP)
    for ranks, launcher, sigs in ((1, False, every), (2, False, every[:2]), (2, True, every)):
        how = LAUNCHER if launcher else ""
        for sig in sigs:
            out = b.work / f"sig-{ranks}-{sig.name}{'-launcher' if launcher else ''}"
            p = _interrupt(b, out, sig, ranks=ranks, launcher=launcher)
            problems = _signal_problems(p, out / FOLDER, True)
            if p.code == 128 + sig and not problems:
                problems = resume_check(b, out / FOLDER, ranks, launcher=launcher)
            record(b, k, f"{sig.name} after a checkpoint, {ranks} rank(s){how}, resume", p,
                   128 + sig, problems)  # fmt: skip
    for sig, launcher in ((signal.SIGTERM, False), (signal.SIGINT, False), (signal.SIGTERM, True)):
        how = LAUNCHER if launcher else ""
        out = b.work / f"sig-one-rank-{sig.name}{'-launcher' if launcher else ''}"
        p = _interrupt(b, out, sig, ranks=2, target=rank_pids, launcher=launcher)
        record(b, k, f"{sig.name} to rank 1 of 2 only{how}", p, 128 + sig,
               _signal_problems(p, out / FOLDER, True))  # fmt: skip
    for sig, what in ((signal.SIGHUP, "terminal closed"), (signal.SIGTERM, "a process-tree kill"),
                      (signal.SIGINT, "a process-tree kill")):  # fmt: skip
        out = b.work / f"sig-job-{sig.name}"
        p = _interrupt(b, out, sig, ranks=2, target=job_pids, launcher=True)
        record(b, k, f"{sig.name} to the whole job ({what}), 2 ranks{LAUNCHER}", p, 128 + sig,
               _signal_problems(p, out / FOLDER, True))  # fmt: skip
    out = b.work / "sig-early-launcher"
    p = _interrupt(b, out, signal.SIGINT, ranks=2, when="1.5", launcher=True)
    problems = [] if p.code == 0 else _signal_problems(p, out / FOLDER, False)
    record(b, k, f"SIGINT 1.5 s after the start (ranks starting), 2 ranks{LAUNCHER}", p,
           130 if p.code else 0, problems)  # fmt: skip
    for when in ("2.5", "5"):
        out = b.work / f"sig-early-{when}"
        p = _interrupt(b, out, signal.SIGINT, when=when)
        problems = [] if p.code == 0 else _signal_problems(p, out / FOLDER, False)
        record(b, k, f"SIGINT {when} s after the start (build)", p, 130 if p.code else 0,
               problems)  # fmt: skip
    out = b.work / "sig-twice"
    t0 = time.monotonic()
    q = start(["run", str(b.scene), "-o", str(out)])
    wait_for(out / FOLDER / "checkpoint" / "progress.json", q)
    q.send_signal(signal.SIGINT)
    time.sleep(0.05)
    q.send_signal(signal.SIGINT)
    p = finish(q, t0)
    record(b, k, "SIGINT twice", p, 130, [])
    out = b.work / "sig-twice-launcher"
    t0 = time.monotonic()
    q = start(["run", str(b.scene), "-o", str(out)], ranks=2, launcher=True)
    wait_for(out / FOLDER / "checkpoint" / "progress.json", q)
    q.send_signal(signal.SIGINT)
    time.sleep(0.05)
    q.send_signal(signal.SIGINT)
    p = finish(q, t0)
    record(b, k, f"SIGINT twice, 2 ranks{LAUNCHER}", p, 130,
           _signal_problems(p, out / FOLDER, True))  # fmt: skip
    _closed_stdout(b, 1)
    _closed_stdout(b, 2, launcher=True)


def _closed_stdout(b: Bench, ranks: int, launcher: bool = False) -> None:
    """The run's reader goes away after the first line, as ``| head -1`` does."""
    out = b.work / f"sig-pipe-{ranks}"
    t0 = time.monotonic()
    q = start(["run", str(b.scene), "-o", str(out)], ranks=ranks, launcher=launcher)
    q.stdout.readline()
    q.stdout.close()
    try:
        q.wait(timeout=TIMEOUT)
        p = Proc(q.returncode, "", q.stderr.read(), time.monotonic() - t0)
    except subprocess.TimeoutExpired:
        os.killpg(q.pid, signal.SIGKILL)
        p = Proc(None, "", "", TIMEOUT)
    problems = same_answer(b, out / FOLDER, ranks)
    if status(out / FOLDER).get("status") != "completed":
        problems.append("run.json not completed")
    how = LAUNCHER if launcher else ""
    record(b, "signals", f"stdout closed by its reader (as head -1 does), {ranks} rank(s){how}",
           p, 0, problems)  # fmt: skip


# -- checkpoints that lie ---------------------------------------------------------------------
def _interrupted_folder(b: Bench, name: str, scene: Path | None = None) -> Path:
    out = b.work / name
    t0 = time.monotonic()
    p = start(["run", "-q", str(scene or b.scene), "-o", str(out)])
    wait_for(out / FOLDER / "checkpoint" / "progress.json", p)
    p.send_signal(signal.SIGTERM)
    finish(p, t0)
    return out / FOLDER


def edit_progress(folder: Path, change: Callable[[dict], None], *, reseal: bool) -> None:
    from fenics_garment.scene import checkpoint

    path = folder / "checkpoint" / "progress.json"
    meta = json.loads(path.read_text())
    change(meta)
    if reseal:
        meta["seal"] = checkpoint.seal(meta)
    path.write_text(json.dumps(meta))


def _set(key: str, value: object) -> Callable[[dict], None]:
    def change(meta: dict) -> None:
        *head, last = key.split(".")
        t = meta
        for h in head:
            t = t[h] if not h.isdigit() else t[int(h)]
        t[last] = value

    return change


def _rank_file(folder: Path) -> Path:
    return next((folder / "checkpoint").glob("state-*.r0.npz"))


def _flip(folder: Path) -> None:
    f = _rank_file(folder)
    data = bytearray(f.read_bytes())
    data[len(data) // 2] ^= 0xFF
    f.write_bytes(bytes(data))


def _scale_q(folder: Path) -> None:
    f = _rank_file(folder)
    with np.load(f) as d:
        arrays = {k: d[k] for k in d.files}
    arrays["q"] = arrays["q"] * 1.01
    with open(f, "wb") as out:
        np.savez(out, **arrays)


LIES: list[tuple[str, Callable[[Path], None]]] = [
    ("stage 'release' (hand edit)", lambda f: edit_progress(f, _set("progress.stage", "release"),
                                                     reseal=False)),
    ("stage 'release' (resealed)", lambda f: edit_progress(f, _set("progress.stage", "release"),
                                                    reseal=True)),
    ("stage 'done' (resealed)", lambda f: edit_progress(f, _set("progress.stage", "done"),
                                                       reseal=True)),
    ("negative shrink (resealed)", lambda f: edit_progress(f, _set("progress.shrink", -0.003),
                                                    reseal=True)),
    ("negative step (resealed)", lambda f: edit_progress(f, _set("progress.step", -0.001),
                                                  reseal=True)),
    ("negative spring constant (resealed)", lambda f: edit_progress(f, _set("progress.c", -5.0),
                                                             reseal=True)),
    ("NaN shrink (resealed)", lambda f: edit_progress(f, _set("progress.shrink", float("nan")),
                                               reseal=True)),
    ("shrink above s0 (resealed)", lambda f: edit_progress(f, _set("progress.shrink", 1.0),
                                                    reseal=True)),
    ("solve count negative (resealed)", lambda f: edit_progress(f, _set("progress.solves", -1),
                                                         reseal=True)),
    ("other package version (resealed)", lambda f: edit_progress(
        f, _set("depends.fenics-garment version", "0.0.9"), reseal=True)),
    ("other meshes (resealed)", lambda f: edit_progress(f, _set("depends.meshes", "0" * 16),
                                                 reseal=True)),
    ("other friction coefficient (resealed)", lambda f: edit_progress(f, _set("progress.mu", 0.05),
                                                               reseal=True)),
    ("rank file byte flipped", _flip),
    ("rank file rewritten, q x 1.01", _scale_q),
]  # fmt: skip


def try_checkpoint(b: Bench) -> None:
    """The lies are told of a checkpoint written while the body grows (6 grow steps: the
    signal lands a step or two after the first checkpoint, the body still shrunk)."""
    k = "checkpoint"
    six = b.work / "tube6.toml"
    six.write_text(_scene_text(b).replace("steps = 2\n", "steps = 6\n"))
    base = _interrupted_folder(b, "lies-base", six)
    for name, lie in LIES:
        folder = b.work / "lies" / name.replace(" ", "_").replace("'", "")
        shutil.copytree(base, folder)
        lie(folder)
        p = run(["run", "-q", "--resume", str(folder)])
        record(b, k, name, p, 2, [])
    hook = b.work / "hook.py"
    hook.write_text("def terms(built):\n    pass\n")
    text = b.scene.read_text().replace('terms = ""', f'terms = "{hook}:terms"')
    scene = b.work / "tube_hook.toml"
    scene.write_text(text)
    folder = _interrupted_folder(b, "lies-hook", scene)
    hook.write_text("def terms(built):\n    built.model.membrane = built.model.membrane\n")
    p = run(["run", "-q", "--resume", str(folder)])
    record(b, k, "terms hook edited before --resume", p, 2,
           [] if "terms hook" in p.err else ["does not name the hook"])  # fmt: skip
    other = b.work / "other.toml"
    other.write_text(b.scene.read_text().replace("ease = -0.07", "ease = -0.08"))
    p = run(["run", "-q", str(other), "--resume", str(base)])
    record(b, k, "another scene with --resume", p, 2, [])


# -- input that never ends --------------------------------------------------------------------
def _scene_text(b: Bench) -> str:
    return b.scene.read_text()


def try_input(b: Bench) -> None:
    k = "input"
    w = b.work / "input"
    w.mkdir()
    fifo = w / "fifo.toml"
    os.mkfifo(fifo)
    deep = w / "deep.toml"
    deep.write_text("a = " + "[" * 5000 + "]" * 5000 + "\n")
    deep40 = w / "deep40.toml"
    deep40.write_text("x = " + "[" * 40 + "1" + "]" * 40 + "\n")
    big = w / "big.toml"
    big.write_text("# " + "x" * (2 << 20) + "\n" + _scene_text(b))
    empty, comments = w / "empty.toml", w / "comments.toml"
    empty.write_text("")
    comments.write_text("# nothing here\n\n")
    ctrl = w / "ctrl.toml"
    ctrl.write_text(_scene_text(b).replace('folder = "output"', 'folder = "out\\u001b[31m"'))
    nl = w / "tu\nbe.toml"
    nl.write_text(_scene_text(b))
    long_name = w / "long_name.toml"
    long_name.write_text(_scene_text(b).replace('name = "tube-on-cylinder"',
                                                f'name = "{"n" * 500_000}"'))  # fmt: skip
    long_key = w / "long_key.toml"
    long_key.write_text(f"{'k' * 500_000} = 1\n" + _scene_text(b))
    tries = [("/dev/urandom as the scene", "/dev/urandom"), ("/dev/zero as the scene", "/dev/zero"),
             ("a FIFO without a writer", fifo), ("a folder as the scene", w),
             ("TOML nested 5000 deep", deep), ("TOML nested 40 deep", deep40),
             ("a 2 MB scene file", big), ("an empty scene", empty),
             ("a scene of comments only", comments), ("control character in [output] folder", ctrl),
             ("newline in the scene's path", nl), ("a 500 kB name", long_name),
             ("a 500 kB key", long_key)]  # fmt: skip
    for name, path in tries:
        p = run(["run", "-q", str(path), "-o", str(w / "out")], timeout=60)
        long = [f"error line of {len(p.err)} characters"] if len(p.err) > 1500 else []
        record(b, k, name, p, 2, long)
    folder = _interrupted_folder(b, "input-progress")
    (folder / "checkpoint" / "progress.json").write_text("[" * 100_000 + "]" * 100_000)
    p = run(["run", "-q", "--resume", str(folder)])
    record(b, k, "progress.json nested 100000 deep", p, 2, [])
    _pattern_fifo(b, w)


def _pattern_fifo(b: Bench, w: Path) -> None:
    fifo = w / "pattern.toml"
    os.mkfifo(fifo)
    src = ROOT / "fenics_garment" / "scenes" / "darted_top.toml"
    text = src.read_text()
    scene = w / "pattern_scene.toml"
    scene.write_text(text.replace('"patterns/darted_top.toml"', f'"{fifo}"'))
    p = run(["check", str(scene)], timeout=60)
    record(
        b,
        "input",
        "a FIFO as the pattern file",
        p,
        2,
        [] if '"patterns/darted_top.toml"' in text else ["scene has no pattern line"],
    )


# -- environment ------------------------------------------------------------------------------
def _mount(where: Path, size: str, *, fill: bool = False, read_only: bool = False) -> bool:
    if os.geteuid() != 0 or shutil.which("mount") is None:
        return False
    where.mkdir(parents=True, exist_ok=True)
    if subprocess.run(["mount", "-t", "tmpfs", "-o", f"size={size}", "tmpfs", str(where)],
                      capture_output=True).returncode:  # fmt: skip
        return False
    if fill:
        subprocess.run(["dd", "if=/dev/zero", f"of={where / 'filler'}", "bs=4k"],
                       capture_output=True)  # fmt: skip
    if read_only:
        subprocess.run(["mount", "-o", "remount,ro", str(where)], capture_output=True)
    return True


def _umount(where: Path) -> None:
    subprocess.run(["umount", "-l", str(where)], capture_output=True)


def _full_run_problems(b: Bench, folder: Path, p: Proc, ascii: bool = False) -> list[str]:
    problems = same_answer(b, folder, 1) if p.code == 0 else []
    if ascii and not p.out.isascii():
        problems.append("non-ASCII stdout")
    return problems


def try_environment(b: Bench) -> None:
    k = "environment"
    w = b.work / "env"
    cases: list[tuple[str, dict, str]] = [
        ("HOME unset", _env(HOME=None), ""),
        ("HOME a missing folder", _env(HOME=str(w / "nowhere")), ""),
        ("PYTHONIOENCODING=ascii", _env(PYTHONIOENCODING="ascii"), "ascii"),
        ("LANG=C LC_ALL=C PYTHONIOENCODING=ascii",
         _env(LANG="C", LC_ALL="C", PYTHONIOENCODING="ascii"), "ascii"),
        ("MPLBACKEND=nonsense, pictures on", _env(MPLBACKEND="nonsense"), "pictures"),
        ("JIT cache is a file", _env(XDG_CACHE_HOME=str(w / "cache_file")), "warning"),
    ]  # fmt: skip
    w.mkdir()
    (w / "cache_file").write_text("")  # $XDG_CACHE_HOME/fenics cannot be made
    pictures = b.work / "tube_pictures.toml"
    pictures.write_text(_scene_text(b).replace("pictures = false", "pictures = true"))
    for name, env, check in cases:
        out = w / name.replace(" ", "_").replace("=", "-")
        scene = pictures if check == "pictures" else b.scene
        p = run(["run", str(scene), "-o", str(out)], env=env)
        problems = (
            []
            if check == "pictures"
            else _full_run_problems(b, out / FOLDER, p, ascii=check == "ascii")
        )
        if check == "ascii" and p.code == 0 and p.out.count("\n") < 5:
            problems.append("progress lines missing")
        if check == "pictures" and not (out / FOLDER / "pressure_garment.png").exists():
            problems.append("no pressure_garment.png")
        if check == "warning" and "warning: the JIT cache" not in p.err:
            problems.append("no warning about the cache")
        record(b, k, name, p, 0, problems)
    for name, opts in (("JIT cache on a read-only file system", {"read_only": True}),
                       ("JIT cache on a full file system", {"fill": True})):  # fmt: skip
        disk = w / name.replace(" ", "_")
        if not _mount(disk, "256k", **opts):
            skipped(b, k, name, "needs root and tmpfs mounts")
            continue
        try:
            out = w / (name.replace(" ", "_") + "_out")
            p = run(["run", str(b.scene), "-o", str(out)], env=_env(XDG_CACHE_HOME=str(disk)))
            problems = _full_run_problems(b, out / FOLDER, p)
            if "warning: the JIT cache" not in p.err:
                problems.append("no warning about the cache")
            record(b, k, name, p, 0, problems)
        finally:
            _umount(disk)


# -- output faults ----------------------------------------------------------------------------
#: tmpfs sizes: the run needs about 3.1 MB on 1 rank (its checkpoints, the VTX series, the
#: outputs); the largest sizes fail while the series or the last outputs are written.
SIZES = {1: ("160k", "600k", "1200k", "2000k", "2600k", "2900k", "2960k", "3020k", "3060k",
             "3100k"),
         2: ("600k", "1500k", "2600k", "3000k", "3400k")}  # fmt: skip


def _disk_try(b: Bench, size: str, ranks: int, *extra: str) -> None:
    """A run on a tmpfs of ``size``; ``extra``: more arguments (``--no-checkpoints``: the VTX
    series and the outputs are the only files, so ADIOS2 meets the full disk)."""
    disk = b.work / f"disk-{ranks}-{size}{'-'.join(extra)}"
    name = f"{size} disk, {ranks} rank(s){''.join(' ' + e for e in extra)}, then continue"
    if not _mount(disk, size):
        skipped(b, "output", name, "needs root and tmpfs mounts")
        return
    try:
        p = run(["run", "-q", str(b.scene), "-o", str(disk), *extra], ranks=ranks)
        folder = disk / FOLDER
        problems = partial_files(folder) if folder.exists() else []
        st = status(folder).get("status") if folder.exists() else None
        if p.code == 5:
            if st != "failed" or not status(folder).get("error"):
                problems.append(f"run.json status {st!r} without the error")
            subprocess.run(["mount", "-o", "remount,size=64m", str(disk)], check=True)
            if "--resume" in p.err:
                problems += resume_check(b, folder, ranks)
            elif "start it again" in p.err:  # failed before its first checkpoint
                again = run(["run", "-q", str(b.scene), "-o", str(disk), *extra], ranks=ranks)
                problems += [f"again: exit {again.code}"] if again.code else []
                problems += same_answer(b, folder, ranks)
            else:
                problems.append("the line says neither --resume nor start again")
        elif p.code == 0:
            problems += same_answer(b, folder, ranks)
        elif p.code == 2 and not folder.exists():
            pass  # refused before the run: the folder could not be made
        expect = p.code if p.code in (0, 2) else 5
        record(b, "output", name, p, expect, problems)
    finally:
        _umount(disk)


def try_output(b: Bench) -> None:
    for ranks, sizes in SIZES.items():
        for size in sizes:
            _disk_try(b, size, ranks)
    for ranks, size in ((1, "600k"), (1, "1200k"), (1, "2000k"), (2, "1200k"), (2, "2000k")):
        _disk_try(b, size, ranks, "--no-checkpoints")
    deep = b.work / "long"
    deep.mkdir()
    path = deep / ("d" * 200)
    while len(str(path)) < 4000:
        path = path / ("d" * 200)
    p = run(["run", "-q", str(b.scene), "-o", str(path)])
    record(b, "output", "an output path of 4000+ characters", p, 2, [])
    p = run(["run", "-q", str(b.scene), "-o", str(deep / ("x" * 300))])
    record(b, "output", "an output folder name of 300 bytes", p, 2, [])


# -- the report -------------------------------------------------------------------------------
TRIES = {"signals": try_signals, "checkpoint": try_checkpoint, "input": try_input,
         "environment": try_environment, "output": try_output}  # fmt: skip


def table(results: list[Result]) -> str:
    """The Markdown table: per class, the tries and the count of each outcome."""
    head = "| class | tries | " + " | ".join(OUTCOMES) + " | skipped |"
    rows = [head, "|" + "---|" * (len(OUTCOMES) + 3)]
    for klass in (*CLASSES, "all"):
        mine = [r for r in results if r.klass == klass or klass == "all"]
        if not mine:
            continue
        counts = [sum(r.outcome == o for r in mine) for o in (*OUTCOMES, "skipped")]
        name = "**all**" if klass == "all" else klass
        rows.append(f"| {name} | {len(mine) - counts[-1]} | " + " | ".join(map(str, counts))
                    + " |")  # fmt: skip
    rows += ["", "| class | try | outcome | s |", "|---|---|---|---|"]
    rows += [f"| {r.klass} | {r.name.replace('|', '/')} | {r.outcome} | {r.seconds:.0f} |"
             for r in results]  # fmt: skip
    return "\n".join(rows)


def _plain(r: Result) -> dict:
    """The record, its working folder written as <work> (the machine's paths are not data)."""
    d = asdict(r)
    d["detail"] = re.sub(r"/tmp/\S*$", "<work>…", re.sub(r"/\S*/reliability-[^/\s]+", "<work>",
                                                         d["detail"]))  # fmt: skip
    return d


def write(results: list[Result]) -> None:
    RESULTS.write_text(json.dumps([_plain(r) for r in results], indent=1) + "\n")
    if DOC.exists():
        text = DOC.read_text()
        if BEGIN in text and END in text:
            before, rest = text.split(BEGIN, 1)
            after = rest.split(END, 1)[1]
            DOC.write_text(f"{before}{BEGIN}\n{table(results)}\n{END}{after}")


def main(argv: list[str] | None = None) -> int:
    argv = list(sys.argv[1:] if argv is None else argv)
    bad = check_args(argv, __doc__, names=CLASSES)
    if bad is not None:
        return bad
    chosen = argv or list(CLASSES)
    work = Path(tempfile.mkdtemp(prefix="reliability-"))
    b = Bench(work, write_scene(work))
    records = [Result(**r) for r in json.loads(RESULTS.read_text())] if RESULTS.exists() else []
    try:
        for klass in chosen:  # a class's records replace its old ones as soon as it ends
            TRIES[klass](b)
            records = [r for r in records if r.klass != klass]
            records += [r for r in b.results if r.klass == klass]
            write(sorted(records, key=lambda r: CLASSES.index(r.klass)))
    finally:
        shutil.rmtree(work, ignore_errors=True)
    print(table(b.results))
    return 0


if __name__ == "__main__":
    sys.exit(main())
