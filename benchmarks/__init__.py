"""Benchmarks: each module has ``main(argv=None) -> int`` and writes ``benchmarks/results/``."""

from __future__ import annotations

import sys
from collections.abc import Callable, Collection


def check_args(
    argv: list[str],
    doc: str | None,
    flags: Collection[str] = (),
    valued: Collection[str] = (),
    names: Collection[str] | Callable[[str], bool] | None = None,
) -> int | None:
    """``None`` when ``argv`` is a valid command line; else the exit code after printing the
    module's ``doc`` (``-h``/``--help``: 0) or a one-line error (2).

    ``flags`` take no value, ``valued`` take the next word; every other word must be one of
    ``names`` (or pass it, if a predicate; ``None``: any word). A mistyped option or scene name
    stops here instead of silently running every scene for an hour.
    """
    if "-h" in argv or "--help" in argv:
        print((doc or "").strip())
        return 0
    i = 0
    while i < len(argv):
        a = argv[i]
        if a in valued:
            if i + 1 == len(argv):
                return _error(f"option {a} needs a value")
            i += 2
            continue
        if a.startswith("-"):
            if a not in flags:
                known = ", ".join(sorted({*flags, *valued})) or "none"
                return _error(f"unknown option {a} (options: {known}; --help for more)")
        elif names is not None and not (names(a) if callable(names) else a in names):
            choice = "" if callable(names) else f": one of {', '.join(sorted(names))}"
            return _error(f"unknown name {a!r}{choice or ' (--help lists what is accepted)'}")
        i += 1
    return None


def _error(message: str) -> int:
    print(f"error: {message}", file=sys.stderr)
    return 2
