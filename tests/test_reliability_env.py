"""The environment (issue 48): no crash nor internal error for a missing ``HOME``, a JIT cache
that cannot be written (a private temporary cache, a one-line warning), an ASCII-only terminal
or a plotting backend that does not exist (``fenics_garment.environment``).
"""

import os
import subprocess
import sys
from pathlib import Path

import pytest
from test_reliability import small_tube

from fenics_garment import environment
from fenics_garment._stack import MPI
from fenics_garment.scene import config

ROOT = Path(__file__).parent.parent
pytestmark = pytest.mark.skipif(MPI.COMM_WORLD.size > 1, reason="serial")


def _python(code: str, **env: str | None) -> subprocess.CompletedProcess:
    full = {**os.environ, "PYTHONPATH": str(ROOT)}
    for k, v in env.items():
        full.pop(k, None) if v is None else full.__setitem__(k, v)
    return subprocess.run([sys.executable, "-c", code], env=full, capture_output=True,
                          text=True, timeout=600)  # fmt: skip


def test_no_home_no_segfault_when_the_vtx_writer_is_made(tmp_path):
    """ADIOS2 crashed (SIGSEGV) looking for its user configuration without HOME."""
    code = (
        "from fenics_garment import environment\n"
        "print(environment.prepare())\n"
        "from fenics_garment._stack import MPI, dolfinx\n"
        "m = dolfinx.mesh.create_unit_square(MPI.COMM_SELF, 2, 2)\n"
        "f = dolfinx.fem.Function(dolfinx.fem.functionspace(m, ('Lagrange', 1)))\n"
        f"w = dolfinx.io.VTXWriter(m.comm, {str(tmp_path / 'x.bp')!r}, [f], engine='BP4')\n"
        "w.write(0.0); w.close(); print('written')\n"
    )
    p = _python(code, HOME=None)
    assert p.returncode == 0 and "written" in p.stdout, p.stderr[-2000:]


def test_home_set_from_the_password_database_or_a_private_folder(monkeypatch):
    monkeypatch.delenv("HOME")
    home, warning = environment._home()
    assert Path(home).is_dir() and "HOME is not set" in warning
    monkeypatch.setenv("HOME", "/nonexistent/home")
    home, warning = environment._home()
    assert Path(home).is_dir() and "is not a folder" in warning


def test_a_cache_that_is_a_file_gives_a_private_cache(tmp_path, monkeypatch):
    blocker = tmp_path / "cache"
    blocker.write_text("")  # $XDG_CACHE_HOME/fenics cannot be made
    monkeypatch.setenv("XDG_CACHE_HOME", str(blocker))
    warning = environment._cache()
    private = Path(os.environ["XDG_CACHE_HOME"])
    assert warning.startswith(f"the JIT cache {blocker / 'fenics'} cannot be written")
    assert private != blocker and private.is_dir() and "\n" not in warning
    assert environment.cache_fault(private / "fenics") is None


def test_a_cache_that_refuses_writes_gives_a_private_cache(tmp_path, monkeypatch):
    """A full or read-only cache (root ignores permissions: the write is refused instead)."""
    import errno
    import tempfile

    real = tempfile.NamedTemporaryFile
    full = tmp_path / "full"

    def refusing(*args, dir=None, **kw):
        if dir is not None and Path(dir).is_relative_to(full):
            raise OSError(errno.ENOSPC, os.strerror(errno.ENOSPC))
        return real(*args, dir=dir, **kw)

    monkeypatch.setattr(tempfile, "NamedTemporaryFile", refusing)
    monkeypatch.setenv("XDG_CACHE_HOME", str(full))
    assert "(No space left on device)" in environment._cache()
    assert not Path(os.environ["XDG_CACHE_HOME"]).is_relative_to(full)


def test_a_writable_cache_is_kept(tmp_path, monkeypatch):
    monkeypatch.setenv("XDG_CACHE_HOME", str(tmp_path))
    assert environment._cache() is None and os.environ["XDG_CACHE_HOME"] == str(tmp_path)


@pytest.mark.parametrize("backend, warns", [("nonsense", True), ("QtAgg", False),
                                            ("agg", False)])  # fmt: skip
def test_a_bad_plotting_backend_is_replaced(monkeypatch, backend, warns):
    monkeypatch.setenv("MPLBACKEND", backend)
    warning = environment._backend()
    assert (warning is not None) == warns
    assert os.environ["MPLBACKEND"].lower() == "agg"


@pytest.mark.slow
def test_an_ascii_terminal_and_a_bad_backend_in_a_real_process(tmp_path):
    scene = tmp_path / "tube.toml"
    scene.write_text(config.dumps(small_tube()))
    env = {**os.environ, "PYTHONPATH": str(ROOT), "PYTHONIOENCODING": "ascii",
           "MPLBACKEND": "nonsense"}  # fmt: skip
    p = subprocess.run([sys.executable, "-m", "fenics_garment.cli", "check", str(scene)],
                       env=env, capture_output=True, timeout=600)  # fmt: skip
    assert p.returncode == 0, p.stderr.decode()[-2000:]
    p.stdout.decode("ascii")  # the em dash of the check line is replaced
    assert b"ok ? body" in p.stdout and b"warning: MPLBACKEND='nonsense' ignored" in p.stderr
