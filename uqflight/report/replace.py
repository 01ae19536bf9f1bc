"""A finished report folder put at DIR with no moment when DIR is absent.

The report is written into a staging folder beside DIR, `.DIR.<pid>-<start>-<host>.<random>.partial`
(the writer's pid, process start time and a hash of its host name). Then, holding `flock` on
`.DIR.lock` in the same parent (so concurrent reports to one DIR take turns; the last one wins):
  1. leftovers of killed reports to DIR are cleaned: staging folders whose writer is provably gone
     (this host, pid dead or another process now) and that hold only what a report writes;
  2. DIR is checked again to be nothing, an empty folder or an earlier report;
  3. the staging folder and DIR are swapped in one step, `renameat2(RENAME_EXCHANGE)` (Linux 3.15+,
     most local filesystems), or the staging folder is renamed to DIR when DIR is absent;
  4. the earlier report, now at the staging name, is deleted.
A SIGKILL at any point leaves DIR holding the old report or the new one, plus at most a staging
folder that the next report to DIR deletes.

Where the exchange is not available (ENOSYS, EINVAL: an old kernel, a filesystem without it), DIR
is renamed aside to `.DIR.old-<pid>-<start>-<host>.<random>` and the staging folder renamed to DIR:
for the instant between the two renames DIR is absent, and a kill there leaves the old report
aside, which the next report to DIR moves back before anything else.
"""
from __future__ import annotations

import ctypes
import errno
import fcntl
import hashlib
import os
import re
import secrets
import shutil
import socket
import stat
from contextlib import contextmanager
from pathlib import Path

from ..running.forking import alive, start_time

REPORT_FILES = {"report.html": None, "report.md": None, "summary.json": None,  # what a report writes, and
                "plots": ".png", "tables": ".csv", "summaries": ".json"}      # its folders' file types
AT_FDCWD, RENAME_EXCHANGE = -100, 2
LOCK_TEXT = b"uqflight: reports to the folder beside this file take turns on it\n"
TAG = re.compile(r"(\d+)-(\d+|x)-([0-9a-f]{8})\.[0-9a-f]{8}")
OUT_NAME_BYTES = 192  # the longest report folder name: its staging folder's name (+ about 50 bytes) fits in 255


def _host() -> str:
    return hashlib.sha256(socket.gethostname().encode()).hexdigest()[:8]


def _tag() -> str:
    """This process's part of a staging name: pid, start time, host hash and a random part."""
    return f"{os.getpid()}-{start_time(os.getpid()) or 'x'}-{_host()}.{secrets.token_hex(4)}"


def make_staging(out_dir: Path) -> Path:
    """A new, empty staging folder for a report to `out_dir` (readable by all, like a report)."""
    staging = out_dir.with_name(f".{out_dir.name}.{_tag()}.partial")
    staging.mkdir(mode=0o755)
    staging.chmod(0o755)  # whatever the umask: a report is for reading
    return staging


def check_replaceable(out_dir: Path) -> None:
    """Refuse (FileExistsError) to replace anything at `out_dir` but nothing, an empty folder or an
    earlier report: a folder holding only what a report writes (a user's file there is never deleted);
    OSError(ENAMETOOLONG) for a name longer than OUT_NAME_BYTES of UTF-8."""
    if len(out_dir.name.encode()) > OUT_NAME_BYTES:
        raise OSError(errno.ENAMETOOLONG, f"the report folder's name is {len(out_dir.name.encode())} bytes (UTF-8), "
                      f"at most {OUT_NAME_BYTES} are taken (its staging folder beside it needs the rest): "
                      "choose a shorter --out")
    if not out_dir.exists() and not out_dir.is_symlink():
        return
    if out_dir.is_dir() and not out_dir.is_symlink():
        entries = list(out_dir.iterdir())
        if not entries or (out_dir / "report.html").is_file() and all(_written_by_a_report(e) for e in entries):
            return
    raise FileExistsError(f"{out_dir} exists and is not a uqflight report (it holds other files, or is not a "
                          "folder); a report replaces only an earlier report: choose another --out, or move it away")


def _written_by_a_report(entry: Path) -> bool:
    if entry.name not in REPORT_FILES or entry.is_symlink():
        return False
    suffix = REPORT_FILES[entry.name]
    if suffix is None:
        return entry.is_file()
    return entry.is_dir() and all(f.is_file() and not f.is_symlink() and f.suffix == suffix for f in entry.iterdir())


def replace_dir(staging: Path, out_dir: Path) -> None:
    """Put the finished `staging` folder at `out_dir`, replacing an earlier report there (see the module)."""
    with _turn(out_dir):
        clean_leftovers(out_dir)
        check_replaceable(out_dir)
        if not os.path.lexists(out_dir):
            os.rename(staging, out_dir)
            return
        try:
            _exchange(staging, out_dir)
        except OSError as exc:
            if exc.errno not in (errno.ENOSYS, errno.EINVAL, errno.ENOTSUP):
                raise
            aside = out_dir.with_name(f".{out_dir.name}.old-{_tag()}")
            os.rename(out_dir, aside)
            try:
                os.rename(staging, out_dir)
            except BaseException:
                os.rename(aside, out_dir)
                raise
            staging = aside
        shutil.rmtree(staging)


def _exchange(a: Path, b: Path) -> None:
    """Swap the two paths atomically (renameat2 with RENAME_EXCHANGE); OSError(ENOSYS) without it."""
    renameat2 = getattr(ctypes.CDLL(None, use_errno=True), "renameat2", None)
    if renameat2 is None:  # a C library older than glibc 2.28
        raise OSError(errno.ENOSYS, "renameat2 is not available")
    if renameat2(AT_FDCWD, os.fsencode(a), AT_FDCWD, os.fsencode(b), RENAME_EXCHANGE) != 0:
        code = ctypes.get_errno()
        raise OSError(code, os.strerror(code), str(a), None, str(b))


@contextmanager
def _turn(out_dir: Path):
    """Hold `flock` on `.DIR.lock` beside DIR, removed on leaving. Once locked, a holder checks that the
    file it locked is still the one at that name (a removed lock file is never shared) and that it is
    a lock of ours: empty, or LOCK_TEXT; anything else there is refused (FileExistsError), never removed."""
    path = out_dir.with_name(f".{out_dir.name}.lock")
    while True:
        created = True
        try:
            fd = os.open(path, os.O_RDWR | os.O_CREAT | os.O_EXCL | os.O_NOFOLLOW, 0o644)
        except FileExistsError:
            created = False
            try:
                fd = os.open(path, os.O_RDWR | os.O_NOFOLLOW | os.O_NONBLOCK)
            except FileNotFoundError:
                continue
            except OSError:  # a link, a folder, a file we may not write
                raise FileExistsError(f"{path} is in the way of the report's lock: it is not a lock of "
                                      "uqflight's; move it away") from None
        try:
            fcntl.flock(fd, fcntl.LOCK_EX)
            if created:
                os.write(fd, LOCK_TEXT)
            held = os.fstat(fd)
            try:
                current = os.stat(path, follow_symlinks=False)
            except FileNotFoundError:
                current = None
            if current is not None and (held.st_dev, held.st_ino) == (current.st_dev, current.st_ino):
                if not stat.S_ISREG(held.st_mode) or os.pread(fd, len(LOCK_TEXT) + 1, 0) not in (b"", LOCK_TEXT):
                    raise FileExistsError(f"{path} is in the way of the report's lock: it is not a lock of "
                                          "uqflight's; move it away")
                break
        except BaseException:
            os.close(fd)
            raise
        os.close(fd)
    try:
        yield
    finally:
        try:
            os.unlink(path)
        except FileNotFoundError:  # removed by hand meanwhile
            pass
        os.close(fd)


def _gone(tag: str) -> bool:
    """A staging tag whose writer is provably not running: this host, and its pid dead or another
    process now (a legacy tag without pid: never)."""
    found = TAG.fullmatch(tag)
    if not found or found.group(3) != _host():
        return False
    return not alive(int(found.group(1)), None if found.group(2) == "x" else found.group(2))


def clean_leftovers(out_dir: Path) -> list[Path]:
    """Delete what killed reports to `out_dir` left beside it: staging folders of gone writers that hold
    only report files. An earlier report left aside (`.DIR.old-...`, a kill between the fallback's two
    renames) goes back to DIR when DIR is absent. Returns the folders deleted or moved back."""
    cleaned = []
    prefix = f".{out_dir.name}."
    for entry in sorted(out_dir.parent.iterdir()):
        if not entry.name.startswith(prefix) or entry.is_symlink() or not entry.is_dir():
            continue
        rest = entry.name[len(prefix):]
        aside = rest.startswith("old-")
        tag = rest[4:] if aside else rest.removesuffix(".partial")
        if not (aside or rest.endswith(".partial")) or not (_gone(tag) or aside and not TAG.fullmatch(tag)):
            continue
        if not all(_written_by_a_report(e) for e in entry.iterdir()):
            continue
        if aside and not os.path.lexists(out_dir) and (entry / "report.html").is_file():
            os.rename(entry, out_dir)
        else:
            shutil.rmtree(entry)
        cleaned.append(entry)
    return cleaned
