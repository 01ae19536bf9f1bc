"""Reading a file whose size is bounded before it is read: a regular file of at most so many bytes. A
FIFO, a device (/dev/zero never ends, a FIFO's reader waits for a writer), a folder or a socket is
refused before any byte is read, and so is a file larger than the bound; nothing is read beyond it."""
from __future__ import annotations

import os
import stat
from typing import BinaryIO


class OutsideBounds(ValueError):
    """The file is outside the bounds a reader sets: no regular file, or larger than the bound; the message says
    which (without the path: the caller names the file and makes it a Refusal)."""


KINDS = ((stat.S_ISDIR, "a folder"), (stat.S_ISFIFO, "a FIFO (named pipe)"), (stat.S_ISCHR, "a character device"),
         (stat.S_ISBLK, "a block device"), (stat.S_ISSOCK, "a socket"))


def open_bounded(path, limit: int, what: str) -> BinaryIO:
    """`path` open for reading in binary, once it is known to be a regular file of at most `limit`
    bytes; OutsideBounds naming what it is instead, or its size and `what` the bound is for (e.g. "a
    baseline"). OSError when it cannot be opened. The caller reads at most `limit` + 1 bytes (a file
    that grows meanwhile: `read_bounded`)."""
    fd = os.open(path, os.O_RDONLY | os.O_NONBLOCK | getattr(os, "O_CLOEXEC", 0))  # a FIFO's open does not wait
    try:
        info = os.fstat(fd)
        if not stat.S_ISREG(info.st_mode):
            kind = next((name for test, name in KINDS if test(info.st_mode)), "not a regular file")
            raise OutsideBounds(f"{kind}, not a regular file: {what} is read from a file")
        if info.st_size > limit:
            raise OutsideBounds(f"{info.st_size / 2**20:.0f} MiB, more than the {limit / 2**20:g} MiB {what} may take")
        os.set_blocking(fd, True)
        return os.fdopen(fd, "rb")
    except BaseException:
        os.close(fd)
        raise


def read_bounded(path, limit: int, what: str) -> bytes:
    """The bytes of the regular file `path`, at most `limit` of them (see `open_bounded`)."""
    with open_bounded(path, limit, what) as fh:
        data = fh.read(limit + 1)
    if len(data) > limit:
        raise OutsideBounds(f"more than the {limit / 2**20:g} MiB {what} may take (it grew while read)")
    return data
