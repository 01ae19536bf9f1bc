"""Ending the `uqflight` process once its command is done, without tearing the interpreter down.

After a report's last file is written, a normal exit frees every object one by one and collects
cycles several times over (matplotlib's figures and caches, the analysis, the modules): 0.4-1 s of a
6-10 s command, with nothing left to write. `exit_fast(code)` runs what a normal exit runs that reaches
outside the process (the atexit handlers: temporary folders, worker pools, Dask, logging; then stdout
and stderr flushed) and ends the process with os._exit. Where skipping the teardown could lose
something it exits normally instead: a thread that is not a daemon still running (a normal exit waits
for it), or an HDF5 file still open (the HDF5 library flushes it at exit)."""
from __future__ import annotations

import atexit
import os
import sys
import threading

BROKEN_STDOUT = 120  # Python's own exit status when flushing stdout at exit fails


def exit_fast(code) -> None:
    """End the process with `code` (a SystemExit code: None, an int, or a message printed to stderr
    with status 1), quickly where nothing can be lost (see the module's docstring)."""
    if code is not None and not isinstance(code, int):
        print(code, file=sys.stderr)
        code = 1
    code = code or 0
    if not _nothing_left_open():
        sys.exit(code)
    atexit._run_exitfuncs()
    for stream in (sys.stdout, sys.stderr):
        try:
            stream.flush()
        except (OSError, ValueError):  # a closed pipe (`uqflight info | head`) or a closed stream
            code = code or BROKEN_STDOUT
    os._exit(code)


def _nothing_left_open() -> bool:
    """No other thread that a normal exit would wait for, and no HDF5 file open."""
    if any(t is not threading.main_thread() and t.is_alive() and not t.daemon for t in threading.enumerate()):
        return False
    h5f = sys.modules.get("h5py.h5f")
    return h5f is None or h5f.get_obj_count(h5f.OBJ_ALL, h5f.OBJ_FILE) == 0
