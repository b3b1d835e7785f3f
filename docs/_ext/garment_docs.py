"""Sphinx extension of the fenics-garment docs: pages and tables generated from the code and the
committed records at build time, so that they cannot drift from either.

Directives (usable from MyST as ```` ```{scene-reference} ```` etc.):

* ``scene-reference``: every scene key of :mod:`fenics_garment.scene.config` — type, default, unit,
  accepted values and range — read from the dataclasses, their comments, the range table
  ``LENGTH_RANGES`` and the validator ``_check`` (its ``_one_of``/``_require`` calls);
* ``cli-help``: ``--help`` of every ``fenics-garment`` command, from ``cli.build_parser``;
* ``exit-codes``: the exit codes, their constants in the code and the meaning ``run --help`` gives;
* ``demo-list``: the bundled demos of :data:`fenics_garment.demos.REGISTRY`;
* ``record-table``: a table built from a JSON record of ``benchmarks/results/`` (argument: which).

At ``builder-inited`` the demo pages are written to ``docs/demos/generated/`` (not committed):
one per scene demo (its TOML file and the committed pictures of it) and one per literate demo
(``demos/*.py``, jupytext "light" format) rendered as Markdown text and code cells.
"""

from __future__ import annotations

import argparse
import ast
import inspect
import io
import json
import math
import os
import re
import tokenize
import typing
from dataclasses import MISSING, fields
from pathlib import Path

from docutils import nodes
from docutils.parsers.rst import directives
from docutils.statemachine import StringList
from sphinx.util.docutils import SphinxDirective

DOCS = Path(__file__).resolve().parents[1]
ROOT = DOCS.parent
RESULTS = ROOT / "benchmarks" / "results"
GENERATED = DOCS / "demos" / "generated"


# ------------------------------------------------------------------------------------------------
# Small table builder (docutils nodes, so no escaping of Markdown/RST is needed)
# ------------------------------------------------------------------------------------------------


def _cell(content) -> nodes.entry:
    """A table cell: a string, ("code", s), or a list of those (joined by spaces); or a
    tuple ("blocks", [paragraph, ...]) of ready body elements."""
    entry = nodes.entry()
    if isinstance(content, tuple) and content[0] == "blocks":
        entry.extend(content[1])
        return entry
    entry += _para(content)
    return entry


def _para(content) -> nodes.paragraph:
    para = nodes.paragraph()
    parts = content if isinstance(content, list) else [content]
    for i, part in enumerate(parts):
        if i and not isinstance(part, nodes.Node):
            para += nodes.Text(" ")
        if isinstance(part, tuple) and part[0] == "code":
            para += nodes.literal(text=str(part[1]))
        elif isinstance(part, nodes.Node):
            para += part
        else:
            para += nodes.Text(str(part))
    return para


def make_table(
    headers: list[str], rows: list[list], widths: list[int] | None = None
) -> nodes.table:
    table = nodes.table(classes=["garment-table"])
    group = nodes.tgroup(cols=len(headers))
    table += group
    for w in widths or [1] * len(headers):
        group += nodes.colspec(colwidth=w)
    head = nodes.thead()
    row = nodes.row()
    for h in headers:
        row += _cell(h)
    head += row
    group += head
    body = nodes.tbody()
    for r in rows:
        row = nodes.row()
        for c in r:
            row += _cell(c)
        body += row
    group += body
    return table


# ------------------------------------------------------------------------------------------------
# Scene reference
# ------------------------------------------------------------------------------------------------

_UNIT = re.compile(r"\[(m|mm|Pa|Pa/m|kPa|N|N/m|s|m/s²|kg/m²|kg/m³)\]")


def _field_comments(source: str, tree: ast.Module) -> dict[tuple[str, str], str]:
    """(class, field) -> the comment of the field: the ``#``/``#:`` lines just above it and the
    comment at the end of its line."""
    comments: dict[int, str] = {}
    for tok in tokenize.generate_tokens(io.StringIO(source).readline):
        if tok.type == tokenize.COMMENT:
            comments[tok.start[0]] = tok.string
    lines = source.splitlines()
    out: dict[tuple[str, str], str] = {}
    for cls in tree.body:
        if not isinstance(cls, ast.ClassDef):
            continue
        for stmt in cls.body:
            if not (isinstance(stmt, ast.AnnAssign) and isinstance(stmt.target, ast.Name)):
                continue
            above = []
            n = stmt.lineno - 1
            while n >= 1 and lines[n - 1].strip().startswith("#"):
                above.insert(0, lines[n - 1].strip().lstrip("#").lstrip(":").strip())
                n -= 1
            trailing = [
                comments[n].lstrip("#").strip()
                for n in range(stmt.lineno, stmt.end_lineno + 1)
                if n in comments and not lines[n - 1].strip().startswith("#")
            ]
            text = " ".join(p for p in [*above, *trailing] if p and not p.startswith("fmt:"))
            out[(cls.name, stmt.target.id)] = text
    return out


class _Validators(ast.NodeVisitor):
    """The checks of ``config._check`` per dotted key: accepted values (``_one_of``), conditions
    (``_require``) and the known sub-keys of tables (``_unknown``)."""

    def __init__(self, module, func: ast.FunctionDef):
        self.module = module
        self.namespace = dict(vars(module))
        self.aliases: dict[str, str] = {}  # b -> body, ...
        self.assigns: list[tuple[int, str, ast.expr]] = []
        self.values: dict[str, list[str]] = {}
        self.conditions: dict[str, list[str]] = {}
        self.subkeys: dict[str, list[str]] = {}
        for node in ast.walk(func):
            if isinstance(node, ast.ImportFrom) and node.module:
                mod = __import__(node.module, fromlist=[a.name for a in node.names])
                for a in node.names:
                    self.namespace[a.asname or a.name] = getattr(mod, a.name)
            if isinstance(node, ast.Assign):
                self._note_assign(node)
        self.visit(func)

    def _note_assign(self, node: ast.Assign) -> None:
        tgt, val = node.targets[0], node.value
        if isinstance(tgt, ast.Tuple) and isinstance(val, ast.Tuple):
            for t, v in zip(tgt.elts, val.elts, strict=False):
                if isinstance(t, ast.Name) and isinstance(v, ast.Attribute):
                    if isinstance(v.value, ast.Name) and v.value.id == "s":
                        self.aliases[t.id] = v.attr
        elif isinstance(tgt, ast.Name):
            if isinstance(val, ast.Attribute) and isinstance(val.value, ast.Name):
                if val.value.id == "s":
                    self.aliases[tgt.id] = val.attr
            self.assigns.append((node.lineno, tgt.id, val))

    def _resolve(self, expr: ast.expr, lineno: int) -> ast.expr:
        if isinstance(expr, ast.Name):
            before = [v for n, name, v in self.assigns if name == expr.id and n < lineno]
            if before:
                return before[-1]
        return expr

    def _key(self, node: ast.expr) -> str | None:
        if isinstance(node, ast.Constant) and isinstance(node.value, str):
            return node.value
        if isinstance(node, ast.JoinedStr):
            return "".join(v.value if isinstance(v, ast.Constant) else "*" for v in node.values)
        return None

    def _plain(self, expr: ast.expr) -> str:
        """Source of ``expr`` with ``g.mesh_size`` written ``mesh_size`` (the key's own name)."""
        aliases = self.aliases

        class Strip(ast.NodeTransformer):
            def visit_Attribute(self, node):
                self.generic_visit(node)
                if isinstance(node.value, ast.Name) and node.value.id in aliases:
                    return ast.copy_location(ast.Name(id=node.attr, ctx=ast.Load()), node)
                return node

        return ast.unparse(Strip().visit(ast.parse(ast.unparse(expr), mode="eval")).body)

    def _eval(self, expr: ast.expr):
        try:
            return eval(compile(ast.Expression(expr), "<config>", "eval"), self.namespace)
        except Exception:
            return None

    def visit_Call(self, node: ast.Call) -> None:
        self.generic_visit(node)
        name = node.func.id if isinstance(node.func, ast.Name) else None
        if name == "_one_of" and len(node.args) >= 4:
            key = self._key(node.args[3])
            allowed = self._eval(node.args[1])
            if key and allowed is not None:
                self.values[key] = [str(a) for a in allowed]
        elif name == "_require" and len(node.args) >= 4:
            key = self._key(node.args[2])
            cond = self._resolve(node.args[0], node.lineno)
            if key:
                self.conditions.setdefault(key, []).append(self._plain(cond))
        elif name == "_unknown" and len(node.args) >= 3:
            key = self._key(node.args[2])
            known = self._eval(self._resolve(node.args[1], node.lineno))
            if key and known is not None:
                self.subkeys.setdefault(key, []).append([str(k) for k in known])


def scene_reference_tables() -> list[tuple[str, str, list[str], list[list]]]:
    """(section, docstring, headers, rows) for every section of a scene."""
    from fenics_garment.scene import config

    source = Path(config.__file__).read_text()
    tree = ast.parse(source)
    comments = _field_comments(source, tree)
    # the validator and the checks of the scene kinds' own sections (``_check_drape``)
    checkers = [n for n in tree.body if isinstance(n, ast.FunctionDef)
                and (n.name == "_check" or n.name.startswith("_check_"))
                and n.name not in ("_check_ranges",)]  # fmt: skip
    val = _Validators(config, checkers[0])
    for extra in checkers[1:]:
        more = _Validators(config, extra)
        val.values.update(more.values)
        for key, conds in more.conditions.items():
            val.conditions.setdefault(key, []).extend(conds)
        for key, names in more.subkeys.items():
            val.subkeys.setdefault(key, []).extend(names)
    hints = typing.get_type_hints(config.Scene)
    sections = [("", config.Scene)]
    for f in fields(config.Scene):
        tp = hints.get(f.name)
        if isinstance(tp, type) and hasattr(tp, "__dataclass_fields__"):
            sections.append((f.name, tp))
    out = []
    headers = ["key", "type", "default", "unit", "accepted", "meaning"]
    for section, cls in sections:
        cls_hints = typing.get_type_hints(cls)
        rows = []
        for f in fields(cls):
            tp = cls_hints[f.name]
            if f.name == "source" or hasattr(tp, "__dataclass_fields__"):
                continue
            key = f"{section}.{f.name}" if section else f.name
            if f.default is not MISSING:
                default = f.default
            elif f.default_factory is not MISSING:
                default = f.default_factory()
            else:
                default = None
            note = comments.get((cls.__name__, f.name), "")
            unit = ""
            rng = config.LENGTH_RANGES.get(key)
            numeric = any(t in (float, int) for t in (tp, *typing.get_args(tp)))
            if rng:
                unit = rng[2]
            elif numeric and (m := _UNIT.search(note)):
                unit = m.group(1)
            accepted: list = []
            if key in val.values:
                accepted.append("one of")
                accepted += [("code", v) for v in val.values[key]]
            if rng:
                accepted.append(f"[{rng[0]:g}, {rng[1]:g}] {rng[2]} ({rng[3]})")
                if key in config.ZERO_MEANS_DEFAULT:
                    accepted.append("or 0")
            for cond in dict.fromkeys(val.conditions.get(key, [])):
                accepted.append(("code", cond))
            for i, names in enumerate(val.subkeys.get(key, [])):
                accepted.append("keys:" if i == 0 else "or (another kind) keys:")
                accepted += [("code", n) for n in names]
            for k, conds in val.conditions.items():
                if k.startswith(key + ".") and k != key:
                    accepted += [f"{k}:", *[("code", c) for c in dict.fromkeys(conds)]]
            rows.append([
                ("code", key),
                config._type_name(tp),
                ("code", config._toml_value(default).replace("{  }", "{}"))
                if default is not None
                else "",
                unit,
                accepted or "",
                note,
            ])  # fmt: skip
        doc = inspect.cleandoc(cls.__doc__ or "") if section else ""
        out.append((section or "top level", doc, headers, rows))
    return out


_ROLE = re.compile(r":(\w+):`([^`]+)`")


def rst_to_myst(text: str) -> str:
    """The package's docstring and comment markup for a MyST page (these directives sit on
    Markdown pages): roles :x:`y` as {x}`y`, "|" escaped (a table cell and a substitution
    otherwise)."""
    text = _ROLE.sub(lambda m: "{" + m.group(1) + "}`" + m.group(2) + "`", text)
    return text.replace("|", "\\|")


class SceneReference(SphinxDirective):
    has_content = False

    def run(self):
        from fenics_garment.scene import config

        self.env.note_dependency(config.__file__)
        self.env.note_dependency(__file__)
        result = []
        for section, doc, headers, rows in scene_reference_tables():
            sid = nodes.make_id(f"scene-{section}")
            sec = nodes.section(ids=[sid], names=[sid])
            sec += nodes.title(text=f"[{section}]" if section != "top level" else section)
            self.state.document.note_explicit_target(sec)  # a label: {ref}`scene-body` etc.
            if doc and not doc.startswith(f"{section.capitalize()}Config("):
                holder = nodes.container()
                self.state.nested_parse(StringList(rst_to_myst(doc).splitlines(), "config.py"),
                                        0, holder)  # fmt: skip
                sec += holder.children
            merged = []
            for *first, accepted, note in rows:
                # the field comment (``code`` and roles, as in docstrings), then what is accepted
                parsed, messages = self.state.inline_text(rst_to_myst(note), self.lineno)
                blocks = [nodes.paragraph("", "", *parsed), *messages] if note else []
                if accepted:
                    blocks.append(_para([nodes.emphasis(text="Accepted:"), *accepted]))
                merged.append([*first, ("blocks", blocks)])
            head = [*headers[:-2], "meaning; accepted values"]
            sec += make_table(head, merged, widths=[16, 9, 10, 5, 60])
            result.append(sec)
        return result


# ------------------------------------------------------------------------------------------------
# Command line
# ------------------------------------------------------------------------------------------------


def _subparsers(parser: argparse.ArgumentParser) -> dict[str, argparse.ArgumentParser]:
    for action in parser._actions:
        if isinstance(action, argparse._SubParsersAction):
            return dict(action.choices)
    return {}


class CliHelp(SphinxDirective):
    has_content = False

    def run(self):
        from fenics_garment import cli

        self.env.note_dependency(cli.__file__)
        self.env.note_dependency(__file__)
        os.environ["COLUMNS"] = "100"
        parser = cli.build_parser()
        out = []
        for name, sub in [("fenics-garment", parser), *_subparsers(parser).items()]:
            sid = nodes.make_id(f"cli-{name}")
            sec = nodes.section(ids=[sid])
            title = name if name == "fenics-garment" else f"fenics-garment {name}"
            sec += nodes.title(text=title)
            text = sub.format_help()
            sec += nodes.literal_block(text, text, language="text")
            out.append(sec)
        return out


def exit_codes() -> list[tuple[int, list[str], str]]:
    """(code, constant names, meaning) from ``cli.py``/``scene/run.py`` and ``run --help``."""
    from fenics_garment import cli
    from fenics_garment.scene import run

    names: dict[int, list[str]] = {}
    for mod in (cli, run):
        for k, v in vars(mod).items():
            if k.startswith("EXIT_") and isinstance(v, int):
                names.setdefault(v, []).append(f"{mod.__name__.split('.', 1)[1]}.{k}")
    os.environ["COLUMNS"] = "100"
    desc = " ".join(_subparsers(cli.build_parser())["run"].description.split())
    text = desc.split("Exit codes:", 1)[-1].strip().rstrip(".") if "Exit codes:" in desc else ""
    meaning = {int(m.group(1)): m.group(2) for m in re.finditer(r"(\d+) (.*?)(?=; \d+ |$)", text)}
    codes = sorted(set(names) | set(meaning))
    return [(c, names.get(c, []), meaning.get(c, "")) for c in codes]


class ExitCodes(SphinxDirective):
    has_content = False

    def run(self):
        from fenics_garment import cli

        self.env.note_dependency(cli.__file__)
        rows = [[("code", str(c)), [("code", n) for n in ns] or "", m]
                for c, ns, m in exit_codes()]  # fmt: skip
        return [
            make_table(["exit code", "constant", "meaning (from run --help)"], rows, [8, 22, 70])
        ]


# ------------------------------------------------------------------------------------------------
# Demos
# ------------------------------------------------------------------------------------------------


class DemoList(SphinxDirective):
    has_content = False

    def run(self):
        from fenics_garment import demos

        self.env.note_dependency(demos.__file__)
        rows = []
        for name, demo in demos.REGISTRY.items():
            default = " (default: make demo)" if name == demos.DEFAULT else ""
            rows.append([("code", f"fenics-garment demo {name}"), demo.summary + default])
        return [make_table(["command", "what it shows"], rows, [35, 65])]


def _scene_demo_files() -> dict[str, str]:
    """demo name -> scene file of the scene demos (found by running the registry's closures'
    cell contents would be fragile: the file names are read from demos.py's source)."""
    from fenics_garment import demos

    src = Path(demos.__file__).read_text()
    out = {}
    chunks = re.split(r'\n\s*"([a-z-]+)": Demo\(', src)
    for name, body in zip(chunks[1::2], chunks[2::2], strict=True):
        m = re.search(r'"([a-z_]+\.toml)"', body.split("\n    ),", 1)[0])
        if m and name in demos.REGISTRY:
            out[name] = m.group(1)
    return out


def _pictures(stem: str) -> list[Path]:
    """Committed pictures of a scene: docs/img/<stem>*.png (and the convergence plot)."""
    pics = sorted((DOCS / "img").glob(f"{stem}_*.png"))
    conv = RESULTS / f"convergence-{stem}.png"
    return pics + ([conv] if conv.exists() else [])


def _rel(path: Path, page: Path) -> str:
    return os.path.relpath(path, page.parent).replace(os.sep, "/")


def scene_demo_page(name: str, toml: str, summary: str) -> str:
    page = GENERATED / f"{toml[:-5]}.md"
    scene = ROOT / "fenics_garment" / "scenes" / toml
    stem = toml[:-5]
    lines = [
        f"# `{name}`",
        "",
        summary[0].upper() + summary[1:] + ".",
        "",
        "```bash",
        f"fenics-garment demo {name}                      # the bundled scene",
        f".venv/bin/mpiexec -n 2 .venv/bin/fenics-garment run demos/{toml} -o out",
        "```",
        "",
        f"The scene file (`demos/{toml}`, shipped in the package as "
        f"`fenics_garment/scenes/{toml}`); every key is explained in the "
        "[scene reference](../../reference/scene.md):",
        "",
        f"```{{literalinclude}} {_rel(scene, page)}",
        ":language: toml",
        "```",
        "",
    ]
    pics = _pictures(stem)
    if pics:
        lines += ["## Pictures from committed runs", ""]
        lines += ["Not made while building these pages (a run takes a minute or more): the "
                  "pictures committed with the runs that produced them.", ""]  # fmt: skip
        for p in pics:
            label = p.stem.replace("_", " ").replace("-", " ")
            lines += [f"```{{figure}} {_rel(p, page)}", ":width: 90%", "", label, "```", ""]
    else:
        lines += ["No picture of this scene is committed; run it and open the run folder "
                  "([outputs](../../guide/outputs.md)).", ""]  # fmt: skip
    return "\n".join(lines)


def literate_page(path: Path) -> str:
    """A jupytext "light" script as MyST Markdown: Markdown cells as text, code cells as code."""
    import jupytext

    nb = jupytext.read(path, fmt="py:light")
    page = GENERATED / f"{path.stem}.md"
    out = [f"% generated from demos/{path.name} by docs/_ext/garment_docs.py", ""]
    for cell in nb.cells:
        text = cell.source.rstrip()
        if not text:
            continue
        if cell.cell_type == "markdown":
            out += [text, ""]
        else:
            out += ["```python", text, "```", ""]
    out += [
        "---",
        "",
        f"Source: `demos/{path.name}` ([the file as a whole](#literate-source-{path.stem})). "
        "Not executed while building these pages (it runs for minutes); the pictures of its "
        "runs are on the [cotton gilet](cotton_gilet.md) and [nylon gilet](nylon_gilet.md) "
        "pages.",
        "",
        f"(literate-source-{path.stem})=",
        "## The whole script",
        "",
        f"```{{literalinclude}} {_rel(path, page)}",
        ":language: python",
        "```",
        "",
    ]
    return "\n".join(out)


def write_demo_pages(app) -> None:
    from fenics_garment import demos

    GENERATED.mkdir(parents=True, exist_ok=True)
    pages = {}
    for name, toml in _scene_demo_files().items():
        pages[f"{toml[:-5]}.md"] = scene_demo_page(name, toml, demos.REGISTRY[name].summary)
    for py in sorted((ROOT / "demos").glob("*.py")):
        if py.read_text().startswith("# # "):  # a literate demo (not a hook file such as
            pages[f"{py.stem}.md"] = literate_page(py)  # knit_curve.py: theory/variants.md)
    for old in GENERATED.glob("*.md"):
        if old.name not in pages:
            old.unlink()
    for name, text in pages.items():
        target = GENERATED / name
        if not target.exists() or target.read_text() != text:  # keep mtimes: incremental builds
            target.write_text(text)


# ------------------------------------------------------------------------------------------------
# Tables from the committed records (benchmarks/results/*.json)
# ------------------------------------------------------------------------------------------------


def _load(name: str) -> dict:
    return json.loads((RESULTS / name).read_text())


def _pct(x: float | None, digits: int = 2) -> str:
    if x is None or (isinstance(x, float) and not math.isfinite(x)):
        return "—"
    return f"{100 * x:+.{digits}f} %"


def table_shells():
    d = _load("shells.json")
    rows = []
    for r in d["runs"]:
        extra = ", ".join(f"{k} = {v:.6g}" if isinstance(v, float) else f"{k} = {v}"
                          for k, v in (r.get("extra") or {}).items())  # fmt: skip
        status = r.get("status", "")
        if status != "ok" and r.get("error"):
            why = re.sub(r"/(root|home/[^/\s]+)\b", "~", str(r["error"]).strip().splitlines()[-1])
            status = f"{status}: {why[:120]}"  # (no home folder of the measuring machine)
        solver = r.get("solver", "") + (f", {r['steps']} steps" if r.get("steps") else "")
        rows.append([("code", r["case"]), extra, r.get("variant", ""), solver,
                     str(r.get("n", "")), f"{r.get('dofs', 0):,}",
                     f"{r['value']:.6g}" if "value" in r else "—",
                     f"{r['reference']:.6g}" if "reference" in r else "—",
                     _pct(r.get("rel_error")), status])  # fmt: skip
    head = ["case", "settings", "element", "solver, load steps", "n", "dofs", "value",
            "reference", "error", "status"]  # fmt: skip
    meta = d["meta"]
    note = (f"`benchmarks/results/shells.json`: {len(rows)} runs, {meta.get('ranks')} rank(s), "
            f"{d['meta'].get('total_s', 0):.0f} s in all. Cases and the sources of the reference "
            "values: `fenics_garment/verification/shells.py`.")  # fmt: skip
    return head, rows, note


def table_contact():
    d = _load("contact.json")
    rows = []
    for r in d["runs"]:
        rows.append([("code", r["case"]), r.get("variant", ""), r.get("rule", ""),
                     str(r.get("cells", "")), f"{r.get('dofs', 0):,}",
                     f"{r['value']:.2f}" if "value" in r else "—",
                     f"{r['reference']:.2f}" if "reference" in r else "—",
                     _pct(r.get("rel_error")), f"{r.get('newton_its', '')}"])  # fmt: skip
    head = ["case", "variant", "contact points", "cells", "dofs", "pressure [Pa]",
            "Laplace [Pa]", "error", "Newton its"]  # fmt: skip
    note = (
        "`benchmarks/results/contact.json`: a tight sleeve on a rigid cylinder against "
        "Laplace's law p = n_θθ / R (`python -m benchmarks contact`)."
    )
    return head, rows, note


def _key_regions() -> tuple[str, ...]:
    src = (ROOT / "benchmarks" / "convergence.py").read_text()
    m = re.search(r"^KEY_REGIONS = (\(.*?\))", src, flags=re.M)
    return ast.literal_eval(m.group(1))


def table_answers():
    """The finest value ± the least-squares error bar of every key region (records
    ``<scene>:body-0.015`` of convergence.json, the scenes as shipped)."""
    scenes = _load("convergence.json")["scenes"]
    regions = _key_regions()
    rows = []
    for stem in ("cotton_gilet", "nylon_gilet", "cotton_dress"):
        rec = scenes.get(f"{stem}:body-0.015")
        if not rec:
            continue
        ana, runs = rec["analysis"], rec["runs"]
        label = (
            f"{stem.replace('_', ' ')} ({ana['sizes'][-1] * 1e3:.1f} mm, {ana['dofs'][-1]:,} dofs)"
        )
        for stat, unit in (("sensor_p95", "kPa"), ("mean", "kPa")):
            row = [label if stat == "sensor_p95" else "", f"{stat.replace('_', ' ')} [{unit}]"]
            for reg in regions:
                ls = ana["regions"][reg][stat]["least_squares"]
                v, e, rel = ls["values"][-1], ls["error"][-1], ls["relative_error"][-1]
                ok = " ✓" if rel <= 0.03 else ""
                pct = f"{100 * rel:.1f}" if rel < 0.1 else f"{100 * rel:.0f}"
                row.append(f"{v:.3f} ± {e:.3f} ({pct} %){ok}")
            rows.append(row)
        last = [r for r in runs if r.get("completed")][-3:]
        row = ["", "force [N]"]
        for reg in regions:
            f = [r["regions_force_N"][reg] for r in last]
            spread = (max(f) - min(f)) / abs(f[-1]) if f[-1] else float("nan")
            row.append(f"{f[-1]:.2f} (range {100 * spread:.1f} %)")
        rows.append(row)
    head = ["scene (finest mesh)", "statistic", *[r.replace("_", " ") for r in regions]]
    note = (
        "Records `<scene>:body-0.015` of `benchmarks/results/convergence.json` (the scenes as "
        "shipped, garment meshes in the ratio 1/√2). Each cell: the value on the finest "
        "garment mesh ± the least-squares error bar of all levels (Eça & Hoekstra, J. Comput. "
        "Phys. 262 (2014) 104–130); ✓: within the ±3 % target. Force: the region's contact "
        "force on the finest mesh and its range over the last three meshes."
    )
    return head, rows, note


def table_convergence_runs():
    """Every convergence record: levels, dofs, completed runs and the least-squares verdict."""
    scenes = _load("convergence.json")["scenes"]
    rows = []
    for name, rec in scenes.items():
        ana = rec.get("analysis") or {}
        sizes = ana.get("sizes") or [r.get("mesh_size") for r in rec.get("runs", [])]
        dofs = ana.get("dofs") or [r.get("dofs") for r in rec.get("runs", [])]
        done = ana.get("completed") or [r.get("completed") for r in rec.get("runs", [])]
        met = ana.get("key_sensor_p95_least_squares_met")
        n = [d for d in dofs if d]
        span = f"{min(n):,} … {max(n):,}" if n else ""
        verdict = ", ".join(m.replace("_", " ") for m in met) if met else ""
        verdict = verdict or ("none" if met == [] else "—")
        rows.append([("code", name), " / ".join(f"{1e3 * s:.1f}" for s in sizes if s), span,
                     f"{sum(bool(c) for c in done)} / {len(done)}", verdict])  # fmt: skip
    head = ["record", "garment meshes [mm]", "dofs", "completed",
            "key regions within ±3 % (sensor p95, least squares)"]  # fmt: skip
    note = (
        "All records of `benchmarks/results/convergence.json`; their per-level tables are in "
        "the benchmark report."
    )
    return head, rows, note


def table_stress():
    d = _load("stress.json")
    rows = [[("code", r.get("test", r.get("case", ""))), r.get("status", ""),
             r.get("measured", ""), f"{r.get('wall_s', 0):.0f}"] for r in d["runs"]]  # fmt: skip
    head = ["test", "status", "measured", "wall [s]"]
    note = f"`benchmarks/results/stress.json` ({d['meta'].get('note', '')})."
    return head, rows, note


def table_targets():
    d = _load("targets.json")
    rows = []
    for r in d.get("demo_runs", []):
        rows.append([("code", f"{r.get('case')}{':' + r['variant'] if r.get('variant') else ''}"),
                     f"{1e3 * r['mesh_size']:.1f}" if r.get("mesh_size") else "",
                     f"{r.get('dofs', 0):,}", str(r.get("ranks", "")),
                     f"{r.get('warm_wall_s', r.get('wall_s', 0)):.0f}",
                     str(r.get("newton_its", "")), str(r.get("status", ""))])  # fmt: skip
    head = ["scene", "garment mesh [mm]", "dofs", "ranks", "warm wall [s]", "Newton its", "status"]
    note = (
        "`benchmarks/results/targets.json` (`python -m benchmarks.targets`): the shipped "
        "demos' own runs."
    )
    return head, rows, note


RECORD_TABLES = {
    "shells": table_shells,
    "contact": table_contact,
    "answers": table_answers,
    "convergence-records": table_convergence_runs,
    "stress": table_stress,
    "targets": table_targets,
}


class RecordTable(SphinxDirective):
    required_arguments = 1
    option_spec: typing.ClassVar = {"no-note": directives.flag}

    def run(self):
        which = self.arguments[0]
        if which not in RECORD_TABLES:
            raise self.error(
                f"record-table: unknown table {which!r}; known: {', '.join(RECORD_TABLES)}"
            )
        for f in RESULTS.glob("*.json"):
            self.env.note_dependency(str(f))
        self.env.note_dependency(__file__)
        head, rows, note = RECORD_TABLES[which]()
        out = [make_table(head, rows)]
        if "no-note" not in self.options:
            para = nodes.paragraph()
            for i, part in enumerate(note.split("`")):
                para += nodes.literal(text=part) if i % 2 else nodes.Text(part)
            out.insert(0, para)
        return out


def _docstring_xref(app, env, node, contnode):
    """A py-domain reference in an autodoc'd docstring that names an object the API pages do
    not document: shown as code, and listed in ``_build/docstring-xrefs.txt`` (not an error:
    the docstrings are the package's, the pages' own references stay nitpicky)."""
    if node.get("refdomain") != "py" or not env.docname.startswith("reference/"):
        return None
    kind, target = f"py:{node.get('reftype')}", node.get("reftarget", "")
    for kind_re, target_re in app.config.nitpick_ignore_regex:  # other projects' types
        if re.fullmatch(kind_re, kind) and re.fullmatch(target_re, target):
            return None
    log = Path(app.outdir).parent / "docstring-xrefs.txt"
    with log.open("a") as f:
        f.write(f"{env.docname}: {node.get('reftype')} {node.get('reftarget')}\n")
    return contnode


_INLINE_LITERAL = re.compile(r"(``.+?``)")


def _indent(line: str) -> int:
    return len(line) - len(line.lstrip())


def plain_docstring(lines: list[str]) -> None:
    """Make the package's plain-text docstrings valid reStructuredText, in place: an indented
    display after a line ending in ":" becomes a literal block ("::"), and "|x|" (an absolute
    value) outside literal blocks and ``inline literals`` is escaped (else a substitution)."""
    n = len(lines)
    for i in range(n - 2):
        a = lines[i].rstrip()
        if a.endswith(":") and not a.endswith("::") and not a.lstrip().startswith((":", "..")):
            j = i + 1
            while j < n and not lines[j].strip():
                j += 1
            nested_list = j < n and re.match(r"\s*([*+-]|\d+\.)\s", lines[j])
            if j > i + 1 and j < n and _indent(lines[j]) > _indent(a) and not nested_list:
                lines[i] = a + ":"
    block_indent = None
    for i, line in enumerate(lines):
        if block_indent is not None:
            if not line.strip() or _indent(line) > block_indent:
                continue
            block_indent = None
        if line.rstrip().endswith("::"):
            block_indent = _indent(line)
        bare = line.strip()
        table = re.fullmatch(r"\+[-=+]+\+", bare) or (
            bare.startswith("|") and bare.endswith("|") and bare.count("|") >= 3
        )
        if "|" in line and not table:
            parts = _INLINE_LITERAL.split(line)
            lines[i] = "".join(p if k % 2 else p.replace("|", r"\|") for k, p in enumerate(parts))


def _process_docstring(app, what, name, obj, options, lines):
    plain_docstring(lines)


def _no_machine_paths(app, doctree, docname):
    """Values autodoc prints (``SCENES = Path(__file__)…``) hold this checkout's absolute path:
    written as ``<repository>`` instead, so that no page names a path of the building machine."""
    root = str(ROOT)
    for text in list(doctree.findall(nodes.Text)):
        if root in text:
            text.parent.replace(text, nodes.Text(str(text).replace(root, "<repository>")))


def _start_xref_log(app):
    (Path(app.outdir).parent / "docstring-xrefs.txt").write_text("")


def setup(app):
    app.connect("builder-inited", _start_xref_log)
    app.connect("doctree-resolved", _no_machine_paths)
    app.connect("autodoc-process-docstring", _process_docstring, priority=600)
    app.connect("missing-reference", _docstring_xref)
    app.add_directive("scene-reference", SceneReference)
    app.add_directive("cli-help", CliHelp)
    app.add_directive("exit-codes", ExitCodes)
    app.add_directive("demo-list", DemoList)
    app.add_directive("record-table", RecordTable)
    app.connect("builder-inited", write_demo_pages)
    return {"version": "1", "parallel_read_safe": True, "parallel_write_safe": True}
