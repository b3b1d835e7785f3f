"""FFCx JIT in a shared cache (issue 18, item 9): a run waits for another process compiling the
same form for as long as that process lives (FFCx alone gives up after 10 s), and takes over
the compilation of a process that was killed (FFCx alone would time out on it for good).

Real processes in a fresh cache; the first compiler's C compiler is slowed down by a wrapper
(``CC`` = sleep, then gcc), so that its compilation outlasts FFCx's 10 s.
"""

import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest

from fenics_garment._stack import MPI

pytestmark = pytest.mark.skipif(MPI.COMM_WORLD.size > 1, reason="serial")

FORM = """
import time
from fenics_garment._stack import MPI, dolfinx, ufl
t0 = time.time()
mesh = dolfinx.mesh.create_unit_square(MPI.COMM_SELF, 2, 2)
V = dolfinx.fem.functionspace(mesh, ("Lagrange", 3))
u, v = ufl.TrialFunction(V), ufl.TestFunction(V)
a = dolfinx.fem.form(ufl.inner(ufl.grad(u), ufl.grad(v)) * ufl.dx + 3.5 * u * v * ufl.dx)
print(f"compiled in {time.time() - t0:.1f} s", flush=True)
"""


def _env(tmp_path: Path, slow_cc: float | None = None) -> dict:
    env = {**os.environ, "XDG_CACHE_HOME": str(tmp_path / "cache")}
    if slow_cc is not None:
        cc = tmp_path / "slow-cc"
        cc.write_text(f'#!/bin/sh\nsleep {slow_cc}\nexec gcc "$@"\n')
        cc.chmod(0o755)
        env["CC"] = str(cc)
    return env


def _start_compiler(tmp_path: Path, slow_cc: float) -> subprocess.Popen:
    """A process compiling FORM with a slow C compiler; returns once it holds the form."""
    script = tmp_path / "form.py"
    script.write_text(FORM)
    first = subprocess.Popen([sys.executable, str(script)], env=_env(tmp_path, slow_cc),
                             stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
                             start_new_session=True)  # fmt: skip
    cache = tmp_path / "cache" / "fenics"
    t0 = time.time()
    while not list(cache.glob("*.c.owner")):
        assert first.poll() is None, first.communicate()
        assert time.time() - t0 < 120, "the first process never started compiling"
        time.sleep(0.1)
    return first


def _compile(tmp_path: Path) -> subprocess.CompletedProcess:
    return subprocess.run([sys.executable, str(tmp_path / "form.py")], env=_env(tmp_path),
                          capture_output=True, text=True, timeout=600)  # fmt: skip


@pytest.mark.slow
def test_waits_for_another_process_compiling_the_same_form(tmp_path):
    first = _start_compiler(tmp_path, slow_cc=15)
    t0 = time.time()
    second = _compile(tmp_path)
    waited = time.time() - t0
    assert second.returncode == 0, second.stderr
    assert "TimeoutError" not in second.stderr and "waiting for another process" in second.stderr
    assert waited > 10  # longer than FFCx's own timeout
    assert first.wait(timeout=300) == 0


def test_takes_over_the_form_of_a_killed_compiler(tmp_path):
    first = _start_compiler(tmp_path, slow_cc=60)
    os.killpg(first.pid, signal.SIGKILL)  # the process and its (sleeping) C compiler
    first.wait()
    cache = tmp_path / "cache" / "fenics"
    assert list(cache.glob("*.c")) and not list(cache.glob("*.c.cached"))  # a stale mark
    t0 = time.time()
    second = _compile(tmp_path)
    assert second.returncode == 0, second.stderr
    assert "is gone; compiling it here" in second.stderr
    assert time.time() - t0 < 60  # taken over at once, not after a timeout
    assert list(cache.glob("*.c.cached"))
