"""Sphinx configuration of the fenics-garment documentation (``make docs``).

Built offline: no intersphinx, no remote images. Pages are MyST Markdown; the scene reference,
the command-line help, the exit codes, the demo pages and the verification tables are generated
at build time from the code and the committed records by ``docs/_ext/garment_docs.py``.
"""

import sys
from pathlib import Path

DOCS = Path(__file__).resolve().parent
ROOT = DOCS.parent
sys.path.insert(0, str(DOCS / "_ext"))
sys.path.insert(0, str(ROOT))  # the package and benchmarks/ of this checkout

from fenics_garment import __version__  # noqa: E402

project = "fenics-garment"
author = "fenics-garment developers"
copyright = "fenics-garment developers"
release = version = __version__

extensions = [
    "myst_parser",
    "sphinx.ext.autodoc",
    "sphinx.ext.autosummary",
    "sphinx.ext.mathjax",
    "sphinx-mathjax-offline",  # MathJax 3 copied into _static/: the pages' math renders offline
    "sphinx.ext.napoleon",
    "garment_docs",
]

source_suffix = {".md": "markdown", ".rst": "restructuredtext"}
root_doc = "index"
exclude_patterns = ["_build", "Thumbs.db", ".DS_Store"]
myst_enable_extensions = ["dollarmath", "amsmath", "colon_fence", "deflist"]
myst_heading_anchors = 3

autosummary_generate = True
# Functions and classes are not entries of the table of contents: with ~70 API pages the theme's
# navigation tree of every page would be most of the build time (measured: 27 %)
toc_object_entries = False
autodoc_member_order = "bysource"
autodoc_typehints = "description"
autodoc_default_options = {"members": True, "show-inheritance": False}
napoleon_google_docstring = True
napoleon_numpy_docstring = False
napoleon_use_ivar = True

smartquotes = False  # keep "--resume", quotes and dashes as the program prints them

html_theme = "furo"
html_title = f"fenics-garment {release}"
html_static_path = ["_static"]
html_css_files = ["garment.css"]
html_show_sourcelink = False
html_last_updated_fmt = None

# Nitpicky: every cross-reference must resolve. Types of other projects (no intersphinx: the
# build is offline) are ignored; references written in the package's docstrings that name
# objects the API pages do not document are collected by garment_docs (``missing-reference``)
# into _build/docstring-xrefs.txt instead of failing the build — the hand-written pages are
# held to nitpicky.
nitpicky = True
# "more than one target found" for a relative reference in a docstring (":mod:`.model`" where
# the package has shell.model and pattern.model): the docstrings' ambiguity, not a broken link
suppress_warnings = ["ref.python"]
nitpick_ignore_regex = [
    (
        r"py:.*",
        r"(ufl|numpy|np|npt|dolfinx|petsc4py|PETSc|mpi4py|MPI|basix|gmsh|meshio|scipy"
        r"|trimesh|igl|ezdxf|collections|pathlib|typing|types|argparse|dataclasses|enum|abc"
        r"|concurrent|subprocess|io|os|json|tomllib)(\..*)?",
    ),
    (
        r"py:class",
        r"(Path|Callable|Iterable|Sequence|Mapping|Any|Expr|Form|Measure|Constant"
        r"|Function|FunctionSpace|Mesh|Comm|NDArray|ArrayLike|F64|I32|optional)",
    ),
    # Python's built-in types (no intersphinx to the Python docs: offline)
    (
        r"py:(class|obj|exc)",
        r"(float|int|str|bool|None|dict|list|tuple|set|object|bytes|type|callable|Exception"
        r"|ValueError|RuntimeError|TypeError|OSError|KeyError|TimeoutError)",
    ),
]
