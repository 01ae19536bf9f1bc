"""Staged writes in a results file: a group written under a staging key, marked complete, then moved in
place, so that a kill leaves the old state or the new one, never a mix; a reader prefers a complete
staged group (a writer killed before its move). Used for whole groups (`replace_group`: an adaptive grid's
/design, a rare-event design's /rare_event) and for an output's tSVD factors (store.compressed).

A writer killed while it writes the staged group can leave a link whose object header never reached the
disk: HDF5 can then neither read, move nor delete it ("bad object header version number"). Such a link is
left where it is and ignored (`h5py.Group.get` gives None for it), and the next staging takes the next free
key (STEM_2, STEM_3, ...), so that it never blocks a resume.
"""
from __future__ import annotations

import re
from typing import Callable

import h5py

COMPLETE = "complete"


def staged_keys(parent: h5py.Group, stem: str) -> list[str]:
    """The staging keys of `stem` that `parent` holds (STEM, STEM_2, ...), damaged ones too (their links
    are listed)."""
    pattern = re.compile(rf"{re.escape(stem)}(?:_[0-9]+)?")
    return [key for key in parent.keys() if pattern.fullmatch(key)]


def complete_staged(parent: h5py.Group, stem: str) -> h5py.Group | None:
    """A staged group of `stem` whose writer marked it complete, or None."""
    for key in staged_keys(parent, stem):
        staged = parent.get(key)
        if isinstance(staged, h5py.Group) and staged.attrs.get(COMPLETE, False):
            return staged
    return None


def drop_staged(parent: h5py.Group, stem: str) -> None:
    """Delete every staged group of `stem` that can be deleted (one whose header was never written stays)."""
    for key in staged_keys(parent, stem):
        try:
            del parent[key]
        except (KeyError, OSError, RuntimeError):  # "bad object header": its link stays, ignored
            pass


def new_staged(parent: h5py.Group, stem: str) -> h5py.Group:
    """An empty staged group of `stem` in `parent`, under the first free staging key, the old ones dropped."""
    drop_staged(parent, stem)
    taken = set(parent.keys())
    key = next(key for key in (stem, *(f"{stem}_{k}" for k in range(2, len(taken) + 3))) if key not in taken)
    return parent.create_group(key)


def current_group(f: h5py.File, name: str) -> h5py.Group | h5py.Dataset | None:
    """The complete staged group of `name` if there is one, else what `f` holds at `name` (None: nothing)."""
    staged = complete_staged(f, f"{name}_next")
    return staged if staged is not None else f.get(name)


def replace_group(f: h5py.File, name: str, fill: Callable[[h5py.Group], None]) -> None:
    """Replace the group `name` of `f` by a new one that `fill(group)` writes, staged as NAME_next."""
    staged = new_staged(f, f"{name}_next")
    fill(staged)
    staged.attrs[COMPLETE] = True
    f.flush()
    if name in f:
        del f[name]
    f.move(staged.name, name)
    del f[name].attrs[COMPLETE]
