"""Input that cannot run away: files of a stated size, data of a stated depth, echoes of a
readable length.

A scene, pattern or checkpoint file is read only when it is a regular file (not a FIFO, which
blocks, nor a device such as ``/dev/urandom``, which never ends) of at most a stated number of
bytes; parsed data nested deeper than :data:`MAX_DEPTH` is refused (a parser's recursion limit
would otherwise surface as an internal error), and a value echoed in an error message is cut to
:data:`ECHO` characters.
"""

from __future__ import annotations

import os
import stat
from pathlib import Path
from typing import Any

#: Largest scene file [bytes]: a scene is a few kB; 1 MiB leaves room for long comments.
MAX_SCENE_BYTES = 1 << 20
#: Largest pattern file (TOML, JSON, DXF) [bytes].
MAX_PATTERN_BYTES = 64 << 20
#: Largest checkpoint progress file [bytes] (the report of thousands of solves fits).
MAX_PROGRESS_BYTES = 64 << 20
#: Deepest nesting of tables and arrays accepted in a scene, pattern or checkpoint file.
MAX_DEPTH = 32
#: Characters of a value echoed in an error message.
ECHO = 80
#: Characters of a path echoed in an error message.
PATH_ECHO = 400


class BoundError(ValueError):
    """A file or value outside the bounds (one line, naming the file)."""


def cut(text: str, limit: int = ECHO) -> str:
    """``text`` cut to about ``limit`` characters (its start and its end), saying how long it
    was."""
    if len(text) <= limit:
        return text
    half = max(limit // 2 - 1, 1)
    return f"{text[:half]}…{text[-half:]} ({len(text)} characters)"


def cut_path(path: object) -> str:
    """A path for an error message, cut to :data:`PATH_ECHO` characters."""
    return cut(str(path), PATH_ECHO)


def shown(value: Any, limit: int = ECHO) -> str:
    """``repr(value)`` cut to ``limit`` characters (:func:`cut`)."""
    return cut(repr(value), limit)


def has_control(text: str) -> bool:
    """Whether ``text`` holds a control character (C0, DEL or C1): not for names or paths."""
    return any(ord(c) < 0x20 or 0x7F <= ord(c) < 0xA0 for c in text)


def _kind(mode: int) -> str:
    for test, name in ((stat.S_ISDIR, "a folder"), (stat.S_ISFIFO, "a FIFO (named pipe)"),
                       (stat.S_ISCHR, "a character device"), (stat.S_ISBLK, "a block device"),
                       (stat.S_ISSOCK, "a socket")):  # fmt: skip
        if test(mode):
            return name
    return "not a regular file"


def check_regular(path: Path, limit: int, what: str) -> None:
    """BoundError unless ``path`` is a regular file of at most ``limit`` bytes (OSError as the
    file system raises it); the file is not opened, so a FIFO never blocks."""
    st = os.stat(path)
    if not stat.S_ISREG(st.st_mode):
        raise BoundError(f"{cut_path(path)}: {_kind(st.st_mode)}, not a {what} file")
    if st.st_size > limit:
        raise BoundError(_too_large(path, limit, what))


def _too_large(path: Path, limit: int, what: str) -> str:
    return f"{cut_path(path)}: larger than {limit // 1024} kB, the limit of a {what} file"


def read_bytes(path: Path, limit: int, what: str) -> bytes:
    """The bytes of ``path``, a regular file of at most ``limit`` bytes (:func:`check_regular`;
    a file that grows while it is read is cut off at the limit and refused too)."""
    path = Path(path)
    check_regular(path, limit, what)
    with open(path, "rb") as f:
        data = f.read(limit + 1)
    if len(data) > limit:
        raise BoundError(_too_large(path, limit, what))
    return data


def depth(data: Any) -> int:
    """The nesting depth of parsed data (tables and arrays), without recursion."""
    deepest, stack = 0, [(data, 1)]
    while stack:
        item, d = stack.pop()
        if isinstance(item, dict | list):
            deepest = max(deepest, d)
            if d > MAX_DEPTH:
                return d
            stack.extend((v, d + 1) for v in (item.values() if isinstance(item, dict) else item))
    return deepest


def check_depth(data: Any, where: str) -> None:
    """BoundError when ``data`` is nested deeper than :data:`MAX_DEPTH`."""
    if depth(data) > MAX_DEPTH:
        raise BoundError(f"{cut_path(where)}: nested deeper than {MAX_DEPTH} levels")
