"""One writer per results file: `FILE.lock`, created with O_EXCL, holding the writer's pid, host
and process start time.

A second run on the same file is refused with the holder named. A lock whose process is gone (same
host, pid dead or reused by another process) is stale and taken over; a lock from another host is
never taken over automatically: the message says how to remove it.
"""
from __future__ import annotations

import json
import os
import socket
import time
from pathlib import Path


class LockHeld(FileExistsError):
    """Another run holds the results file."""


def lock_path(path) -> Path:
    path = Path(path)
    return path.with_name(path.name + ".lock")


def _start_time(pid: int) -> str | None:
    """The process's start time in clock ticks since boot (/proc/PID/stat field 22), or None."""
    try:
        stat = Path(f"/proc/{pid}/stat").read_text()
    except OSError:
        return None
    return stat.rsplit(")", 1)[1].split()[19]


def _alive(pid: int, started: str | None) -> bool:
    if pid <= 0:
        return False
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except PermissionError:
        return True
    now = _start_time(pid)
    return started is None or now is None or now == started


LOCK_BYTES = 4096  # a lock we write is ~150 bytes: more is not ours


def read_holder(path) -> dict | None:
    """The lock's holder {pid, host, started, since, command}, or None when the lock is unreadable or
    not one a run of ours wrote (empty, being written, foreign, damaged)."""
    try:
        with open(lock_path(path), "rb") as fh:
            holder = json.loads(fh.read(LOCK_BYTES + 1))
    except (OSError, ValueError, RecursionError):
        return None
    pid = holder.get("pid") if isinstance(holder, dict) else None
    if type(pid) is not int or not 0 < pid < 2**31:
        return None
    return holder


def live_holder(path) -> dict | None:
    """The holder of FILE's lock when it is a live run on this host (a run writing the file now), else None."""
    holder = read_holder(path)
    if holder and holder.get("host") == socket.gethostname() and _alive(int(holder.get("pid", 0)), holder.get("started")):
        return holder
    return None


def describe_holder(holder: dict | None) -> str:
    if not holder:
        return "a run whose lock file is unreadable"
    return (f"pid {holder.get('pid')} on {holder.get('host')}, since {holder.get('since')}"
            + (f" ({holder['command']})" if holder.get("command") else ""))


class ResultsLock:
    """`with ResultsLock(path):` holds `path.lock` or raises LockHeld naming the holder."""

    def __init__(self, path):
        self.path = Path(path)
        self.file = lock_path(path)
        self.held = False

    def acquire(self) -> None:
        me = {"pid": os.getpid(), "host": socket.gethostname(), "started": _start_time(os.getpid()),
              "since": time.strftime("%Y-%m-%d %H:%M:%S"), "command": "uqflight run"}
        for _ in range(3):
            try:
                fd = os.open(self.file, os.O_CREAT | os.O_EXCL | os.O_WRONLY, 0o644)
            except FileExistsError:
                holder = read_holder(self.path)
                if self._stale(holder):
                    try:
                        self.file.unlink()
                    except FileNotFoundError:
                        pass
                    continue
                raise LockHeld(f"{self.path} is being written by another run ({describe_holder(holder)}); "
                               f"wait for it or stop it. If no such run exists, remove {self.file}") from None
            try:
                with os.fdopen(fd, "w") as fh:
                    json.dump(me, fh)
                    fh.flush()
                    os.fsync(fh.fileno())
            except OSError:  # e.g. a full disk: leave no empty lock behind
                self.file.unlink(missing_ok=True)
                raise
            self.held = True
            return
        raise LockHeld(f"{self.path}: cannot take the lock {self.file} (other runs keep taking it)")

    def _stale(self, holder: dict | None) -> bool:
        if holder is None:  # being written right now, or left empty by a crash: stale once old
            try:
                return time.time() - self.file.stat().st_mtime > 10
            except FileNotFoundError:
                return True
        if holder.get("host") != socket.gethostname():
            return False
        return not _alive(int(holder.get("pid", -1)), holder.get("started"))

    def release(self) -> None:
        if self.held:
            holder = read_holder(self.path)
            if holder and holder.get("pid") == os.getpid():
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
