"""The command line's file arguments, checked before any work with one message for every command:
an output whose folder is missing, is not a folder or cannot be written, and an input of the wrong
kind, named for what it is ("r.h5 is a results file (HDF5), not a campaign file"); and the group every
command runs in, which prints any refusal as that one message and exits 2 (`RefusingGroup`)."""
from __future__ import annotations

import os
import stat
from pathlib import Path

import typer

from ..text import Refusal
from ..text.console import refuse

CAMPAIGN_KEYS = ("simulator:", "parameters:", "design:")  # lines a campaign file starts


class RefusingGroup(typer.core.TyperGroup):
    """The group of the `uqflight` commands: a `Refusal` raised by any command or sub-command, or by an
    option's parsing, is printed as one line, "error: MESSAGE", with exit 2 (`refuse`). The one place a
    refusal becomes an exit code."""

    def invoke(self, ctx):
        try:
            return super().invoke(ctx)
        except Refusal as exc:
            refuse(str(exc))


def check_output(path: Path, option: str, folder: bool = False, create: bool = False, inputs=()) -> None:
    """A Refusal naming `option` when `path` cannot be written: a file (a folder with `folder`) whose
    folder exists and is writable; with `create`, missing folders are made later, under a writable one.
    `inputs`: the command's input files, which its output must not replace."""
    problem = output_problem(Path(path), folder, create, inputs)
    if problem:
        raise Refusal(f"{option} {path}: {problem}; choose another path")


def output_problem(path: Path, folder: bool = False, create: bool = False, inputs=()) -> str | None:
    """Why `path` cannot be written, or None: among the reasons, it is one of `inputs` (the command would
    destroy what it reads), or a device, pipe or socket (written through a temporary file and a rename,
    it would be replaced by a regular file)."""
    if path.is_dir() and not folder:
        return "is a folder, not a file"
    if folder and (path.is_file() or path.is_symlink() and not path.is_dir()):
        return "is a file, not a folder"
    for given in inputs:
        if path.exists() and Path(given).exists() and os.path.samefile(path, given):
            return f"is the input {given}: it would be overwritten"
    if path.exists() and not path.is_dir() and not stat.S_ISREG(path.stat().st_mode):
        return "is not a regular file (a device, pipe or socket)"
    parent = Path(os.path.abspath(path)).parent
    while create and not parent.exists() and parent != parent.parent:
        parent = parent.parent
    if not parent.exists():
        return f"the folder {parent} does not exist"
    if not parent.is_dir():
        return f"{parent} is not a folder"
    if path.exists() and not path.is_dir() and not os.access(path, os.W_OK):
        return "the file cannot be written (permission denied)"
    if not os.access(parent, os.W_OK | os.X_OK):
        return f"cannot write in {parent} (permission denied or a read-only file system)"
    return None


def check_results_file(path: Path) -> None:
    """A Refusal unless `path` is an HDF5 file, naming what it is instead."""
    problem = results_problem(Path(path))
    if problem:
        raise Refusal(problem)


def results_problem(path: Path) -> str | None:
    import h5py

    if path.is_dir():
        return f"{path} is a folder, not a results file"
    if path.exists() and not path.is_file():
        return f"{path} is not a regular file (a device, a FIFO or a socket), not a results file"
    if not path.is_file():
        return f"{path}: no such results file"
    if h5py.is_hdf5(path):
        return None
    if is_campaign_text(path):
        return f"{path} is a campaign file, not a results file: `uqflight run {path}` makes its results file"
    return f"{path} is not a results file (a results file is HDF5, written by `uqflight run`)"


def check_campaign_file(path: Path) -> None:
    """A Refusal when `path` is a results file given for a campaign file."""
    import h5py

    if Path(path).is_file() and h5py.is_hdf5(path):
        raise Refusal(f"{path} is a results file (HDF5), not a campaign file: `uqflight info {path}` describes it")


def is_campaign_text(path: Path) -> bool:
    """A .yaml/.yml file, or UTF-8 text with a line that starts a campaign's key."""
    if path.suffix.lower() in (".yaml", ".yml"):
        return True
    with open(path, "rb") as fh:
        head = fh.read(1 << 16)
    try:
        lines = head.decode("utf-8").splitlines()
    except UnicodeDecodeError:
        return False
    return any(line.startswith(CAMPAIGN_KEYS) for line in lines)
