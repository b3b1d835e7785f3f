"""The command line program: --version, info, help."""

import pytest

from fenics_garment import __version__
from fenics_garment.cli import main, stack_info


def test_version(capsys):
    with pytest.raises(SystemExit) as exc:
        main(["--version"])
    assert exc.value.code == 0
    assert __version__ in capsys.readouterr().out


def test_info_reports_the_stack():
    info = stack_info()
    assert info["dolfinx"].startswith("0.11")
    assert info["petsc"].startswith("3.")
    assert info["gmsh"].startswith("4.")
    assert int(info["mpi ranks"]) >= 1
    assert info["ffcx jit cache"].split()[0] in ("warm", "cold")


def test_info_runs(capsys):
    assert main(["info"]) == 0


def test_help(capsys):
    assert main([]) == 0
    assert "info" in capsys.readouterr().out
