"""Names read from files (XML `file=` attributes, bundle keys) as paths that stay in their folder.

A name is usable only as a relative POSIX path that never climbs above where it starts: no
leading `/`, no drive (`C:`), no backslash, no NUL and no `..` that leaves it. On disk, a path is
inside a folder when its real path (symbolic links followed) is.
"""
from __future__ import annotations

import os
import posixpath
from pathlib import Path


def relative_name(name: str) -> str | None:
    """`name` normalized (`a/./b` -> `a/b`, `a/../b` -> `b`), or None when it is empty, absolute,
    names a drive, holds a backslash or NUL, or climbs out of its folder with `..`."""
    if not name or "\\" in name or "\0" in name or name.startswith("/") or ":" in name.split("/", 1)[0]:
        return None
    normal = posixpath.normpath(name)
    if normal in (".", "..") or normal.startswith("../"):
        return None
    return normal


def is_inside(path: str | os.PathLike, folder: str | os.PathLike) -> bool:
    """True when the real path of `path` is `folder`'s real path or below it."""
    real, base = os.path.realpath(path), os.path.realpath(folder)
    return real == base or real.startswith(base.rstrip(os.sep) + os.sep)


def single_name(name: str) -> bool:
    """True for one plain path component (a file or folder name): no `/`, not `.` or `..`."""
    return isinstance(name, str) and relative_name(name) == name and "/" not in name


def outside_links(folder: Path):
    """The symbolic links under `folder` (not followed) whose target is outside it."""
    for top, dirs, files in os.walk(folder):
        for name in dirs + files:
            path = Path(top, name)
            if path.is_symlink() and not is_inside(path, folder):
                yield path
