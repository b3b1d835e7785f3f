"""Waiting for another process's FFCx compilation of the same form in a shared JIT cache.

FFCx marks a form being compiled by making ``<module>.c`` (exclusively) and a compiled one by
``<module>.c.cached``. A second process that needs the same form polls for the ``.cached`` file
for ``timeout`` seconds (DOLFINx's default: 10) and then raises ``TimeoutError`` — although the
first compiler is alive and well (the P1-P1 gilet's Jacobian takes 25–60 s of gcc). And a
compiler that was killed leaves ``<module>.c`` behind for good, so every later run of the form
times out.

:func:`install` replaces that wait (``ffcx.codegeneration.jit.get_cached_module``) by one that

* records the compiling process next to the form (``<module>.c.owner``: host and pid);
* waits as long as the compiler lives: its recorded process exists, or (no record: another
  program) a process on this machine names the module on its command line (gcc), or a file of
  the module changed within :data:`STALE_AFTER` seconds;
* otherwise takes the compilation over (one waiter only, ``<module>.c.takeover``): the stale
  ``.c`` is moved aside and compiled afresh.

So a run never fails because someone else compiles its forms.
"""

from __future__ import annotations

import json
import os
import socket
import sys
import time
from pathlib import Path

#: Seconds without any sign of life after which a compilation with no recorded owner is stale.
STALE_AFTER = 300.0
#: Seconds per poll of FFCx's own wait.
POLL = 2
_HOST = socket.gethostname()
_original = None


def pid_alive(pid: int) -> bool:
    """Whether process ``pid`` exists on this host (a lock or compile marker's owner)."""
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except PermissionError:
        return True
    return True


def _read_json(path: Path) -> dict:
    try:
        data = json.loads(path.read_text())
    except (OSError, ValueError):
        return {}
    return data if isinstance(data, dict) else {}


def _mentioned(module_name: str) -> bool:
    """Whether a process on this machine has ``module_name`` on its command line."""
    proc = Path("/proc")
    if not proc.is_dir():
        return False
    needle = module_name.encode()
    for d in proc.iterdir():
        if d.name.isdigit() and int(d.name) != os.getpid():
            try:
                if needle in (d / "cmdline").read_bytes():
                    return True
            except OSError:
                continue
    return False


def _recent(cache_dir: Path, module_name: str) -> bool:
    now = time.time()
    for f in cache_dir.glob(f"{module_name}*"):
        try:
            if now - f.stat().st_mtime < STALE_AFTER:
                return True
        except OSError:
            continue
    return False


def _owner_alive(c: Path) -> bool:
    owner = _read_json(c.with_suffix(".c.owner"))
    pid = owner.get("pid")
    if owner.get("host") == _HOST and isinstance(pid, int):
        return pid_alive(pid)
    name = c.name.removesuffix(".c")
    return _mentioned(name) or _recent(c.parent, name)


def compiler_alive(cache_dir: Path, module_name: str) -> bool:
    """Whether the compilation of ``module_name`` in ``cache_dir`` still has a live compiler."""
    c = Path(cache_dir) / f"{module_name}.c"
    takeover = c.with_suffix(".c.takeover")
    try:
        if time.time() - takeover.stat().st_mtime < 60:
            return True  # another waiter is taking over
    except OSError:
        pass
    return _owner_alive(c)


def _mark_owner(c: Path) -> None:
    owner = c.with_suffix(".c.owner")
    tmp = owner.with_name(f".{owner.name}.{os.getpid()}")
    try:
        tmp.write_text(json.dumps({"host": _HOST, "pid": os.getpid()}))
        os.replace(tmp, owner)
    except OSError:
        tmp.unlink(missing_ok=True)  # no record: waiters fall back on the other signs of life


def _take_over(c: Path) -> None:
    """Move a stale ``.c`` aside (one waiter only), so that the next attempt compiles it."""
    takeover = c.with_suffix(".c.takeover")
    try:
        fd = os.open(takeover, os.O_CREAT | os.O_EXCL | os.O_WRONLY)
    except FileExistsError:
        if time.time() - takeover.stat().st_mtime >= 60:  # left by a waiter that died
            takeover.unlink(missing_ok=True)
        return
    os.close(fd)
    try:
        if not _owner_alive(c):
            os.replace(c, c.with_suffix(f".c.stale{os.getpid()}"))
            print(f"fenics-garment: the compilation of {c.name} was left by a process that is "
                  "gone; compiling it here", file=sys.stderr, flush=True)  # fmt: skip
    except FileNotFoundError:
        pass
    finally:
        takeover.unlink(missing_ok=True)


def get_cached_module(
    module_name: str, object_names: list[str], cache_dir: str | Path, timeout: int
) -> tuple[object | None, object | None]:
    """FFCx's ``get_cached_module`` that waits for a live compiler as long as it takes and takes
    over a dead one's compilation (the module doc)."""
    cache_dir = Path(cache_dir)
    c = cache_dir / f"{module_name}.c"
    told = False
    while True:
        try:
            obj, mod = _original(module_name, object_names, cache_dir, POLL)
        except TimeoutError:
            if not c.exists():
                continue  # the other compiler failed and cleared its mark: try again
            if compiler_alive(cache_dir, module_name):
                if not told:
                    print(f"fenics-garment: waiting for another process compiling {c.name} "
                          "(FFCx JIT)", file=sys.stderr, flush=True)  # fmt: skip
                    told = True
                continue
            _take_over(c)
            continue
        if obj is None:  # this process compiles it now
            _mark_owner(c)
        return obj, mod


def install() -> None:
    """Use :func:`get_cached_module` for every FFCx compilation of this process (idempotent)."""
    global _original
    import ffcx.codegeneration.jit as ffcx_jit

    if _original is None:
        _original = ffcx_jit.get_cached_module
        ffcx_jit.get_cached_module = get_cached_module
