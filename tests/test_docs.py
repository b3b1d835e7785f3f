"""The README (short, with the two commands, every demo and only links that resolve) and the
documentation site: built offline with Sphinx, nitpicky, warnings as errors, and every local link
and anchor of the built HTML resolving (the slow test, in ``make test-slow``)."""

import re
import subprocess
import sys
import time
from dataclasses import fields
from html.parser import HTMLParser
from pathlib import Path
from urllib.parse import unquote, urlsplit

import pytest

ROOT = Path(__file__).resolve().parents[1]
README = ROOT / "README.md"
DOCS = ROOT / "docs"


def test_readme_is_short_and_keeps_the_two_commands():
    text = README.read_text()
    assert len(text.splitlines()) <= 200
    assert "make demo" in text and "make test" in text  # .ci/run runs `make test`


def test_readme_lists_every_bundled_demo():
    from fenics_garment import demos

    text = README.read_text()
    missing = [name for name in demos.REGISTRY if f"`{name}`" not in text]
    assert not missing, f"demos missing from the README's demo table: {missing}"


_MD_LINK = re.compile(r"\]\(([^)\s]+)\)")


@pytest.mark.parametrize("page", [README, *sorted((DOCS / "guide").glob("*.md"))],
                         ids=lambda p: str(p.relative_to(ROOT)))  # fmt: skip
def test_markdown_links_resolve(page):
    """Relative links and pictures of the README and the guide point at files that exist."""
    bad = []
    for target in _MD_LINK.findall(page.read_text()):
        if re.match(r"[a-z]+:", target) or target.startswith("#"):
            continue
        path = (page.parent / unquote(target.split("#", 1)[0])).resolve()
        if not path.exists():
            bad.append(target)
    assert not bad, f"{page.name}: links to missing files: {bad}"


def test_every_output_file_is_described():
    from fenics_garment.scene.folder import OUTPUT_DIRS, OUTPUT_FILES

    guide = (DOCS / "guide" / "outputs.md").read_text()
    readme = README.read_text()
    for name in (*OUTPUT_FILES, *OUTPUT_DIRS):
        assert f"`{name}" in guide, f"docs/guide/outputs.md does not describe {name}"
        assert f"`{name}" in readme, f"the README's outputs table does not list {name}"


def _blocks(path: Path, lang: str) -> list[str]:
    return re.findall(rf"^```{lang}\n(.*?)^```", path.read_text(), flags=re.M | re.S)


@pytest.mark.parametrize("page", [README, DOCS / "guide" / "scenes.md"], ids=lambda p: p.name)
def test_the_quickstart_scenes_are_valid(page):
    """The TOML of the quickstarts loads as a scene (names, types, ranges), and the Python
    quickstart imports names that exist."""
    import importlib
    import tomllib

    from fenics_garment.scene import config

    tomls = _blocks(page, "toml")
    assert tomls
    for text in tomls:
        config.from_dict(tomllib.loads(text), f"{page.name} quickstart")
    for code in _blocks(page, "python"):
        for m in re.finditer(r"^from ([\w.]+) import (.+)$", code, flags=re.M):
            module = importlib.import_module(m.group(1))
            for name in m.group(2).split(","):
                assert hasattr(module, name.strip()), f"{m.group(1)}.{name.strip()}"


class _Links(HTMLParser):
    def __init__(self):
        super().__init__()
        self.links: list[str] = []
        self.ids: set[str] = set()
        self.remote: list[str] = []  # scripts, styles and pictures loaded from the network

    def handle_starttag(self, tag, attrs):
        a = dict(attrs)
        if a.get("id"):
            self.ids.add(a["id"])
        if tag == "a" and a.get("name"):
            self.ids.add(a["name"])
        for key in ("href", "src"):
            if a.get(key):
                self.links.append(a[key])
        loads = (
            a.get("src") if tag in ("script", "img") else a.get("href") if tag == "link" else None
        )
        if loads and urlsplit(loads).netloc:
            self.remote.append(loads)


def _parse(path: Path) -> _Links:
    p = _Links()
    p.feed(path.read_text(errors="replace"))
    return p


def broken_local_links(html_root: Path) -> list[str]:
    """Every href/src of the built site that is not a URL with a scheme must name an existing
    file, and its #fragment an id in that file."""
    pages = {p: _parse(p) for p in html_root.rglob("*.html")}
    bad = []
    for page, parsed in pages.items():
        for link in parsed.links:
            parts = urlsplit(link)
            if parts.scheme or parts.netloc or link.startswith(("mailto:", "javascript:")):
                continue
            target = page if not parts.path else (page.parent / unquote(parts.path)).resolve()
            if target.is_dir():
                target = target / "index.html"
            if not target.exists():
                bad.append(f"{page.relative_to(html_root)}: {link} (no such file)")
                continue
            frag = unquote(parts.fragment)
            if frag and target.suffix == ".html":
                ids = pages[target].ids if target in pages else _parse(target).ids
                if frag not in ids:
                    bad.append(f"{page.relative_to(html_root)}: {link} (no id {frag!r})")
    return bad


@pytest.mark.slow
def test_the_site_builds_offline_without_warnings_and_its_links_resolve(tmp_path):
    """``make docs`` as CI runs it: nitpicky (-n), warnings as errors (-W), a clean build (fresh
    output and doctree folders), nothing loaded from the network (MathJax ships with the site).
    Measured 2026-12-07 on the shared 2-core machine: ~32 s of CPU; 97–155 s wall under the
    load of two other developers' simulations (load average 6–9)."""
    # the `docs` extra (`make docs` and `make test-slow` install it; the Docker image has not)
    for module in ("sphinx", "myst_parser", "furo", "jupytext"):
        pytest.importorskip(module)
    out = tmp_path / "html"
    t0 = time.perf_counter()
    cmd = [sys.executable, "-m", "sphinx", "-b", "html", "-n", "-W", "--keep-going", "-q",
           "-d", str(tmp_path / "doctrees"), str(DOCS), str(out)]  # fmt: skip
    proc = subprocess.run(cmd, cwd=ROOT, capture_output=True, text=True, timeout=900)
    wall = time.perf_counter() - t0
    assert proc.returncode == 0, f"sphinx failed ({wall:.0f} s):\n{proc.stderr[-6000:]}"
    assert (out / "index.html").exists()
    for page in ("reference/scene.html", "guide/troubleshooting.html", "guide/cli.html",
                 "verification/index.html", "theory/weak-form.html", "benchmarks.html",
                 "demos/generated/gilet.html", "reference/api.html"):  # fmt: skip
        assert (out / page).exists(), page
    scene = (out / "reference" / "scene.html").read_text()
    from fenics_garment.scene import config

    for section in ("body", "garment", "physics", "dressing", "solver", "output"):
        for f in fields(getattr(config.Scene(), section)):  # every key, from the dataclasses
            assert f">{section}.{f.name}<" in scene, f"{section}.{f.name}"
    for key in config.LENGTH_RANGES:
        assert key in scene, key
    bad = broken_local_links(out)
    assert not bad, "broken local links:\n" + "\n".join(bad[:40])
    machine = (str(ROOT), str(Path.home()) + "/")  # the checkout and the home folder
    pages = {p.name: p.read_text(errors="replace") for p in out.rglob("*.html")}
    leaks = [name for name, text in pages.items() if any(m in text for m in machine)]
    assert not leaks, f"pages naming the checkout's absolute path: {leaks}"
    remote = {u for page in out.rglob("*.html") for u in _parse(page).remote}
    assert not remote, f"pages load from the network (not offline): {sorted(remote)[:10]}"
    print(f"docs built in {wall:.0f} s")
