"""A group of a results file replaced whole: written under a staging name (NAME_next), marked complete,
then moved in place, so that a kill leaves the old group or the new one, never a mix; a reader prefers a
complete staged group (a writer killed before its move).

A writer killed while it writes the staged group can leave a link whose object header never reached the
disk: HDF5 can then neither read, move nor delete it ("bad object header version number"). Such a link is
left where it is and ignored (`h5py.Group.get` gives None for it), and the next staging takes the next free
name (NAME_next_2, ...), so that it never blocks a resume.
"""
from __future__ import annotations

import re
from typing import Callable

import h5py

COMPLETE = "complete"


def staged_names(f: h5py.File, name: str) -> list[str]:
    """The staging names of `name` that `f`'s root holds, damaged ones too (their links are listed)."""
    pattern = re.compile(rf"{re.escape(name)}_next(?:_[0-9]+)?")
    return [key for key in f.keys() if pattern.fullmatch(key)]


def current_group(f: h5py.File, name: str) -> h5py.Group | h5py.Dataset | None:
    """The complete staged group of `name` if there is one, else what `f` holds at `name` (None: nothing)."""
    for key in staged_names(f, name):
        staged = f.get(key)
        if isinstance(staged, h5py.Group) and staged.attrs.get(COMPLETE, False):
            return staged
    return f.get(name)


def replace_group(f: h5py.File, name: str, fill: Callable[[h5py.Group], None]) -> None:
    """Replace the group `name` of `f` by a new one that `fill(group)` writes (see the module docstring)."""
    for key in staged_names(f, name):
        try:
            del f[key]
        except (KeyError, OSError, RuntimeError):  # a header never written: its link stays, ignored
            pass
    taken = set(f.keys())
    staging = next(key for key in (f"{name}_next", *(f"{name}_next_{k}" for k in range(2, len(taken) + 3)))
                   if key not in taken)
    staged = f.create_group(staging)
    fill(staged)
    staged.attrs[COMPLETE] = True
    f.flush()
    if name in f:
        del f[name]
    f.move(staging, name)
    del f[name].attrs[COMPLETE]
