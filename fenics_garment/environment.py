"""The process environment made safe before the numerical stack is loaded.

Called by the command line first thing (:func:`prepare`), before DOLFINx, ADIOS2 or matplotlib
is imported, since each reads its configuration once, at import or first use:

* ``HOME`` unset (a cron job, ``env -i``): ADIOS2 looks for its user configuration under it and
  crashes (a segfault when the VTX writer is made). ``HOME`` is set to the user's home from the
  password database or, failing that, to a private temporary folder.
* the FFCx/DOLFINx JIT cache (``$XDG_CACHE_HOME/fenics``, default ``~/.cache/fenics``) cannot
  be written (read-only, full, or a file where the folder should be): compiling the forms
  would fail. A private temporary cache is used instead, with a one-line warning.
* ``MPLBACKEND`` naming a backend that does not exist: the package draws into files only, so
  the backend is set to ``Agg``.
* an ASCII-only (or otherwise narrow) ``stdout``: characters it cannot show are replaced
  instead of failing the run at its first ``→``.

:func:`prepare` returns the warnings to print (rank 0 prints them once MPI is up).
"""

from __future__ import annotations

import atexit
import os
import pwd
import shutil
import sys
import tempfile
from pathlib import Path

#: Bytes written to probe the JIT cache (about one compiled form).
PROBE_BYTES = 1 << 20
#: Backends that draw into files, whatever the display.
FILE_BACKENDS = ("agg", "pdf", "svg", "ps", "cairo", "pgf", "template")


def _private_folder(what: str) -> Path:
    path = Path(tempfile.mkdtemp(prefix=f"fenics-garment-{what}-"))
    atexit.register(shutil.rmtree, path, ignore_errors=True)
    return path


def _home() -> tuple[str, str | None]:
    """A home folder that exists, and a warning when it is not ``$HOME``."""
    home = os.environ.get("HOME", "")
    if home and Path(home).is_dir():
        return home, None
    try:
        entry = pwd.getpwuid(os.getuid()).pw_dir
    except KeyError:
        entry = ""
    why = "not set" if not home else f"{home!r} is not a folder"
    if entry and Path(entry).is_dir() and entry != home:
        return entry, f"HOME is {why}: using {entry}"
    private = str(_private_folder("home"))
    return private, f"HOME is {why}: using a private temporary folder {private}"


def jit_cache() -> Path:
    """The JIT cache DOLFINx will use (its default rule)."""
    base = os.environ.get("XDG_CACHE_HOME") or str(Path.home() / ".cache")
    return Path(base) / "fenics"


def cache_fault(cache: Path) -> str | None:
    """Why ``cache`` cannot hold compiled forms (a probe of :data:`PROBE_BYTES` is written and
    removed), or None."""
    try:
        cache.mkdir(parents=True, exist_ok=True)
        with tempfile.NamedTemporaryFile(dir=cache, prefix=".probe-") as f:
            f.write(b"\0" * PROBE_BYTES)
            f.flush()  # (a full disk refuses the write itself: the blocks are reserved)
    except OSError as err:
        return err.strerror or type(err).__name__
    return None


def _cache() -> str | None:
    """A private JIT cache when the usual one cannot be written; the warning, or None."""
    cache = jit_cache()
    why = cache_fault(cache)
    if why is None:
        return None
    private = _private_folder("jit")
    os.environ["XDG_CACHE_HOME"] = str(private)
    return (f"the JIT cache {cache} cannot be written ({why}): compiling into a private "
            f"temporary cache {private / 'fenics'} (removed at exit)")  # fmt: skip


def _backend() -> str | None:
    backend = os.environ.get("MPLBACKEND")
    if backend is None or backend.lower() in FILE_BACKENDS:
        return None
    os.environ["MPLBACKEND"] = "Agg"
    return None if backend.lower().startswith(("qt", "tk", "gtk", "wx", "macosx")) else (
        f"MPLBACKEND={backend!r} ignored: the pictures are drawn with Agg")  # fmt: skip


def _tolerant_stdio() -> None:
    for stream in (sys.stdout, sys.stderr):
        reconfigure = getattr(stream, "reconfigure", None)
        if reconfigure is not None:
            reconfigure(errors="replace")


def ensure_home() -> str | None:
    """Set ``HOME`` to a folder that exists (:func:`_home`); the warning, or None. Called by
    :mod:`fenics_garment._stack` too, so that a program using the package without its command
    line does not crash in ADIOS2 either."""
    home, warning = _home()
    os.environ["HOME"] = home
    return warning


def prepare() -> list[str]:
    """Make the environment safe (the module doc); the warnings to print."""
    _tolerant_stdio()
    return [w for w in (ensure_home(), _cache(), _backend()) if w]
