"""One writer per results file: `FILE.lock`, holding the writer's pid, host and process start time
as JSON (`{"pid", "host", "started", "since", "command"}`, nothing else).

The lock appears whole: it is written to a temporary file beside it and hard-linked into place
(`link` fails when FILE.lock exists), so a lock of ours is never empty or half written.

A second run on the same file is refused with the holder named. Only a lock in this format whose
holder is provably gone (written on this host, and its pid dead or now another process, told by its
start time) is taken over. Anything else at FILE.lock (a lock from another host, text, JSON of
another shape, a folder, a symbolic link) is never removed: the run is refused, naming the file
and what to do.
"""
from __future__ import annotations

import errno
import fcntl
import json
import os
import socket
import stat
import time
from pathlib import Path

from ..running.forking import alive, start_time


class LockHeld(FileExistsError):
    """Another run holds the results file, or something that is not a lock of ours sits at FILE.lock."""


LOCK_KEYS = {"pid", "host", "started", "since", "command"}  # exactly what `acquire` writes
LOCK_BYTES = 4096  # a lock we write is ~150 bytes: more is not ours


def lock_path(path) -> Path:
    path = Path(path)
    return path.with_name(path.name + ".lock")


def _is_ours(holder) -> bool:
    """A lock exactly as `ResultsLock.acquire` writes it."""
    return (isinstance(holder, dict) and set(holder) == LOCK_KEYS
            and type(holder["pid"]) is int and 0 < holder["pid"] < 2**31
            and isinstance(holder["host"], str) and isinstance(holder["since"], str)
            and isinstance(holder["command"], str)
            and (holder["started"] is None or isinstance(holder["started"], str) and holder["started"].isdigit()))


def _read_lock(file: Path) -> tuple[dict | None, str, os.stat_result | None]:
    """(holder, what the file is, its stat): holder is None unless `file` is a regular file (not a
    link) holding a lock of ours; the description says what it is instead."""
    try:
        fd = os.open(file, os.O_RDONLY | os.O_NOFOLLOW | os.O_NONBLOCK)
    except FileNotFoundError:
        return None, "gone", None
    except OSError:
        kind = "a symbolic link" if file.is_symlink() else "a folder" if file.is_dir() else "unreadable"
        return None, kind, None
    try:
        info = os.fstat(fd)
        if not stat.S_ISREG(info.st_mode):
            return None, "a folder" if stat.S_ISDIR(info.st_mode) else "not a regular file", info
        data = os.read(fd, LOCK_BYTES + 1)
    finally:
        os.close(fd)
    try:
        holder = json.loads(data) if len(data) <= LOCK_BYTES else None
    except (ValueError, RecursionError):
        holder = None
    if not _is_ours(holder):
        return None, "empty" if not data else "a file uqflight did not write", info
    return holder, "ours", info


def read_holder(path) -> dict | None:
    """The holder {pid, host, started, since, command} of FILE's lock, or None when there is no lock of
    ours there."""
    return _read_lock(lock_path(path))[0]


def _gone(holder: dict) -> bool:
    """The holder is provably not running: on this host, and its pid dead or another process now."""
    return holder["host"] == socket.gethostname() and not alive(holder["pid"], holder["started"])


def live_holder(path) -> dict | None:
    """The holder of FILE's lock when it is a live run on this host (a run writing the file now), else None."""
    holder = read_holder(path)
    if holder and holder["host"] == socket.gethostname() and alive(holder["pid"], holder["started"]):
        return holder
    return None


def describe_holder(holder: dict | None) -> str:
    if not holder:
        return "a run whose lock file is unreadable"
    return (f"pid {holder.get('pid')} on {holder.get('host')}, since {holder.get('since')}"
            + (f" ({holder['command']})" if holder.get("command") else ""))


HOLDERS_SHOWN = 3  # processes named in a message about a file held open
COMMAND_SHOWN = 200  # bytes of a holder's command line shown; a longer one ends in " …"
PROCESSES_SCANNED = 100_000  # /proc entries looked at for them (bounded: a message, not a census)


def is_lock_error(exc: BaseException) -> bool:
    """HDF5 refused to open a file because another process holds it open (its file lock: EAGAIN)."""
    return isinstance(exc, BlockingIOError) or getattr(exc, "errno", None) in (errno.EAGAIN, errno.EWOULDBLOCK) \
        or "unable to lock file" in str(exc)


def open_elsewhere(path) -> bool:
    """True when another process holds `path` open under HDF5's file lock (flock, shared for a reader,
    exclusive for a writer), so that a writer cannot open it now. Nothing is read or changed."""
    try:
        fd = os.open(path, os.O_RDONLY | os.O_NONBLOCK)
    except OSError:
        return False
    try:
        fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
    except OSError as exc:
        return exc.errno in (errno.EAGAIN, errno.EWOULDBLOCK)
    else:
        fcntl.flock(fd, fcntl.LOCK_UN)
        return False
    finally:
        os.close(fd)


def holders(path) -> list[str]:
    """"pid N (command)" of up to HOLDERS_SHOWN other processes of this host with `path` open, as far as
    /proc lets this user see them (empty when none is visible)."""
    try:
        target = os.stat(path)
        entries = os.scandir("/proc")
    except OSError:
        return []
    found = []
    with entries:
        for count, entry in enumerate(entries):
            if count >= PROCESSES_SCANNED or len(found) >= HOLDERS_SHOWN:
                break
            if not entry.name.isdigit() or int(entry.name) == os.getpid():
                continue
            try:
                fds = os.scandir(f"/proc/{entry.name}/fd")
            except OSError:
                continue
            with fds:
                held = False
                for fd in fds:
                    try:
                        info = os.stat(fd.path)
                    except OSError:
                        continue
                    if (info.st_dev, info.st_ino) == (target.st_dev, target.st_ino):
                        held = True
                        break
            if held:
                try:
                    with open(f"/proc/{entry.name}/cmdline", "rb") as fh:
                        command = fh.read(COMMAND_SHOWN + 1).replace(b"\0", b" ")
                except OSError:
                    command = b""
                text = " ".join(command[:COMMAND_SHOWN].decode("utf-8", "replace").split())
                if len(command) > COMMAND_SHOWN:
                    text += " …"
                found.append(f"pid {entry.name}" + (f" ({text})" if text else ""))
    return found


def held_message(path, to: str = "written") -> str:
    """Why `path` cannot be opened (`to` be "written", or "read" while another process writes it): another
    process holds it open (which says nothing of its contents: never a reason to replace it)."""
    who = holders(path)
    named = ", ".join(repr(w) if not w.isprintable() else w for w in who) or "another process"
    return (f"{path} is open in {named} (HDF5's file lock), so it cannot be {to} now: wait until that "
            "process closes it, or stop it, then run again")


class ResultsLock:
    """`with ResultsLock(path):` holds `path.lock` or raises LockHeld naming the holder."""

    def __init__(self, path):
        self.path = Path(path)
        self.file = lock_path(path)
        self.held = False

    def acquire(self) -> None:
        me = {"pid": os.getpid(), "host": socket.gethostname(), "started": start_time(os.getpid()),
              "since": time.strftime("%Y-%m-%d %H:%M:%S"), "command": "uqflight run"}
        for _ in range(3):
            if self._place(me):
                self.held = True
                return
            holder, kind, info = _read_lock(self.file)
            if kind == "gone":
                continue
            if holder is None:
                raise LockHeld(f"{self.file} exists and is not a uqflight lock ({kind}); uqflight removes only "
                               f"locks it wrote. If no run of uqflight writes {self.path}, move {self.file} away "
                               "or delete it, then run again") from None
            if holder["host"] != socket.gethostname():
                raise LockHeld(f"{self.path} is locked by a run on another host ({describe_holder(holder)}), which "
                               f"cannot be checked from here; wait for it, or if you are sure it no longer runs, "
                               f"remove {self.file}") from None
            if not _gone(holder):
                raise LockHeld(f"{self.path} is being written by another run ({describe_holder(holder)}); "
                               f"wait for it or stop it. If no such run exists, remove {self.file}") from None
            self._remove_if_same(info)
        raise LockHeld(f"{self.path}: cannot take the lock {self.file} (other runs keep taking it)")

    def _place(self, me: dict) -> bool:
        """Create FILE.lock holding `me`, whole (written beside it, then linked); False when it exists."""
        temporary = self.file.with_name(f".{self.file.name}.{os.getpid()}.{time.monotonic_ns()}.tmp")
        try:
            with open(temporary, "x", encoding="utf-8") as fh:
                json.dump(me, fh)
                fh.flush()
                os.fsync(fh.fileno())
            try:
                os.link(temporary, self.file)
            except OSError as exc:
                if exc.errno not in (errno.EPERM, errno.EOPNOTSUPP):  # FileExistsError: someone's lock
                    raise
                self._create_in_place(me)  # a filesystem without hard links
            return True
        except FileExistsError:
            return False
        finally:
            temporary.unlink(missing_ok=True)

    def _create_in_place(self, me: dict) -> None:
        """FILE.lock created with O_EXCL and written (empty for an instant; FileExistsError when it exists)."""
        fd = os.open(self.file, os.O_CREAT | os.O_EXCL | os.O_WRONLY, 0o644)
        try:
            with os.fdopen(fd, "w", encoding="utf-8") as fh:
                json.dump(me, fh)
                fh.flush()
                os.fsync(fh.fileno())
        except OSError:  # e.g. a full disk: leave no empty lock behind
            self.file.unlink(missing_ok=True)
            raise

    def _remove_if_same(self, seen: os.stat_result) -> None:
        """Remove the stale lock `seen`, unless another run replaced it meanwhile: it is first moved
        aside under a name of this process, and put back when it turns out to be another file."""
        aside = self.file.with_name(f".{self.file.name}.{os.getpid()}.stale")
        try:
            os.rename(self.file, aside)
        except FileNotFoundError:
            return
        moved = os.lstat(aside)
        if (moved.st_dev, moved.st_ino) != (seen.st_dev, seen.st_ino):
            try:
                os.link(aside, self.file)  # a fresh lock taken meanwhile: back in place
            except FileExistsError:
                pass
        os.unlink(aside)

    def release(self) -> None:
        if self.held:
            holder = read_holder(self.path)
            if holder and holder["pid"] == os.getpid() and holder["host"] == socket.gethostname():
                try:
                    self.file.unlink()
                except FileNotFoundError:
                    pass
            self.held = False

    def __enter__(self) -> ResultsLock:
        self.acquire()
        return self

    def __exit__(self, *exc) -> None:
        self.release()
