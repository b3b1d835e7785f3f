"""The literate variants demo (``demos/variants.py``) runs and its assertions hold: a
strain-stiffening membrane against its Laplace pressure and membrane force, a tanh friction law
against the conservation of force under gravity, an elastic foundation against Laplace plus the
foundation's force, each with quadratic Newton steps."""

import os
import runpy
from pathlib import Path

import pytest

DEMO = Path(__file__).parent.parent / "demos" / "variants.py"


@pytest.mark.slow  # three tube scenes, each with its own forms (cold JIT: minutes each)
def test_variants_demo(tmp_path, monkeypatch):
    monkeypatch.setitem(os.environ, "VARIANTS_OUTPUT", str(tmp_path))
    runpy.run_path(str(DEMO), run_name="__main__")
