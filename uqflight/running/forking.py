"""Work done in a forked child while the parent goes on (runs split over processes, the report's sections
shared between processes, drawn by a child that got ready during the analysis). The child inherits the
parent's memory, so nothing is pickled on the way in (but a PreparedChild's payload); its result comes back
pickled through a pipe. It runs no handler of the parent's and leaves with os._exit; a child that fails
or dies is reported as such when waited for. A child dies with its parent (die_with_parent)."""
from __future__ import annotations

import gc
import os
import pickle
import select
import signal
import sys
import threading
import time
import traceback
from pathlib import Path
from typing import Callable

from ..text.console import one_line

FORKS = hasattr(os, "fork")  # where the system cannot fork, callers do the work themselves


def start_time(pid: int) -> str | None:
    """The process's start time in clock ticks since boot (/proc/PID/stat field 22), or None."""
    try:
        stat_line = Path(f"/proc/{pid}/stat").read_text()
    except OSError:
        return None
    return stat_line.rsplit(")", 1)[1].split()[19]


def alive(pid: int, started: str | None) -> bool:
    """False only when no process `pid` runs, or the one that does started at another time."""
    if pid <= 0:
        return False
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except PermissionError:
        return True
    now = start_time(pid)
    return started is None or now is None or now == started


class ChildFailed(RuntimeError):
    """A child that raised (its traceback printed to stderr) or died, or a job that raised where the
    caller names it; the message says which, and what was raised."""


class Child:
    """A forked child doing `work()`; `wait()` gives its result."""

    def __init__(self, work: Callable[[], object]):
        read, write = os.pipe()
        parent = os.getpid()
        gc.freeze()  # the parent's objects stay out of the child's collections: fewer pages copied on write
        self.pid = os.fork()
        if self.pid == 0:  # the child
            die_with_parent(parent)
            os.close(read)
            _fresh_standard_streams()
            code = 0
            try:
                try:
                    payload = pickle.dumps((True, work()), protocol=pickle.HIGHEST_PROTOCOL)
                except OSError as exc:  # a file it could not write (a full disk): the parent's error, no traceback
                    error = OSError(exc.errno, exc.strerror, exc.filename) if exc.errno is not None and exc.strerror \
                        else OSError(" ".join(str(exc).split()))
                    payload = pickle.dumps((False, error))
                with os.fdopen(write, "wb") as pipe:
                    pipe.write(payload)
            except BaseException as exc:
                relayed = isinstance(exc, ChildFailed) and exc.__cause__ is None  # its own child printed it
                if not relayed:
                    _tell_error(traceback.format_exc())
                code = 1
                said = str(exc) if isinstance(exc, ChildFailed) else \
                    f"failed (exit 1): {type(exc).__name__}: {one_line(str(exc))}"
                try:  # what it raised, in one line, for the parent's message
                    with os.fdopen(write, "wb") as pipe:
                        pipe.write(pickle.dumps((False, ChildFailed(said))))
                except BaseException:  # the pipe already written or closed: the exit status says it
                    pass
            os._exit(code)
        gc.unfreeze()
        os.close(write)
        self._read = read

    def fileno(self) -> int:
        """The pipe the result comes through: readable once the child has written it, or has ended."""
        return self._read

    def wait(self):
        """The child's result; ChildFailed when it raised or died, the OSError it raised (errno, message and
        file) raised here. After a wait cut short (an interrupt while reading), a second one reaps the child."""
        read, self._read, payload = self._read, None, b""
        if read is not None:
            with os.fdopen(read, "rb") as pipe:  # read first: a large result would block the child
                payload = pipe.read()
        status = os.waitstatus_to_exitcode(os.waitpid(self.pid, 0)[1])
        if status < 0:
            raise ChildFailed(f"died (signal {-status})")
        try:  # a child that failed sent what it raised, unless writing its result is what failed
            done, result = pickle.loads(payload)
        except Exception:
            raise ChildFailed(f"failed (exit {status})") from None
        if not done:
            raise result
        if status != 0:
            raise ChildFailed(f"failed (exit {status})")
        return result


def die_with_parent(parent: int, watch: bool = False) -> None:
    """Ask the kernel to SIGKILL this process when its parent `parent` dies (Linux): a parent killed outright
    (SIGKILL, a crash) leaves no child working on for no one. `watch`: a thread checks for it as well, every
    half second, for a worker (not for a forked Child, which starts no thread of its own: it may fork)."""
    if sys.platform.startswith("linux"):
        try:
            import ctypes

            ctypes.CDLL(None, use_errno=True).prctl(1, signal.SIGKILL, 0, 0, 0)  # PR_SET_PDEATHSIG
        except (OSError, AttributeError):
            pass
    if os.getppid() != parent:  # the parent died before the prctl
        os._exit(70)

    def watching():
        while os.getppid() == parent:
            time.sleep(0.5)
        os._exit(70)

    if watch:
        threading.Thread(target=watching, daemon=True, name="uqflight-parent-watchdog").start()


def _tell_error(text: str) -> None:
    """`text` on the standard error's file descriptor itself: in a forked child, sys.stderr's lock may be
    held for good by a thread of the parent that was writing at the fork (a progress bar's refresh) and
    does not exist here."""
    data = text.encode(errors="replace")
    try:
        while data:
            data = data[os.write(2, data):]
    except OSError:
        pass


def wait_all(children: list[Child]) -> list:
    """Wait for every child in turn: its result, or the ChildFailed saying how it failed (the OSError it
    raised), in their order."""
    outcomes = []
    for child in children:
        try:
            outcomes.append(child.wait())
        except (ChildFailed, OSError) as exc:
            outcomes.append(exc)
    return outcomes


def share_work(jobs: list[Callable[[], object]], order: list[int] | None = None, processes: int | None = None,
               starting: Callable[[int], None] | None = None) -> list:
    """The result of every job, in the jobs' order, the jobs shared between this process and `processes` − 1
    forked children (default: one per further CPU). Each process takes the next job no process has taken,
    in `order` (a permutation of the indices, default as given: put the costliest first), so none idles
    while another has several left. `starting(index)` is told here as each of this process's own jobs
    starts. A job's error here is raised once the children are reaped; ChildFailed when a child's job
    raised (its traceback printed) or a child died, as soon as this process's job at the time is done."""
    order = list(range(len(jobs))) if order is None else list(order)
    processes = min(len(order), processes or os.cpu_count() or 1) if FORKS else 1
    if processes <= 1:
        results = _results_of(jobs, order, starting)
        return [results[index] for index in range(len(jobs))]
    read, write = os.pipe()  # the queue: each job's index as 4 bytes, taken by one read of 4 bytes

    def taken():
        while record := os.read(read, 4):  # b"" once the queue is empty and written to the end
            yield int.from_bytes(record, "little")

    def child_work():
        os.close(write)
        return _results_of(jobs, taken())

    def taken_here():  # until a child has ended: it ends when the queue is empty, or when it failed
        for index in taken():
            yield index
            if select.select(children, [], [], 0)[0]:
                return

    queue, children = os.fdopen(write, "wb"), []
    try:
        for _ in range(processes - 1):
            children.append(Child(child_work))
        queue.write(b"".join(index.to_bytes(4, "little") for index in order))
        queue.close()
        results = _results_of(jobs, taken_here(), starting)
    finally:
        queue.close()
        for _ in taken():  # the jobs no one has taken yet are dropped: the children end with their current one
            pass
        outcomes = wait_all(children)
        os.close(read)
    for outcome in outcomes:
        if isinstance(outcome, (ChildFailed, OSError)):
            raise outcome
        results.update(outcome)
    return [results[index] for index in range(len(jobs))]


def _results_of(jobs: list[Callable[[], object]], indices, starting=None) -> dict[int, object]:
    """{index: jobs[index]()} for each index taken from `indices`, told to `starting` first."""
    results = {}
    for index in indices:
        if starting is not None:
            starting(index)
        results[index] = jobs[index]()
    return results


class PreparedChild:
    """A child forked now that gets ready (`prepare()`, e.g. imports) while this process goes on, then
    waits for its work: `start(payload)` sends it `payload` (pickled, from a thread: this process goes on
    at once) and the child returns `work(payload, tell)`; `tell(message)` sends this process a small
    picklable message (under 4 kB), which `wait(on_message)` passes to `on_message` as it comes. The child leads a
    process group of its own with the children it forks: an interrupt of the terminal reaches this
    process only, and `close()` ends the whole group, whatever it was doing. (Like every Child, it writes
    through sys.stdout and sys.stderr opened anew.)"""

    def __init__(self, prepare: Callable[[], None], work: Callable[[object, Callable[[object], None]], object]):
        payload_read, self._payload = os.pipe()
        self._messages, messages_write = os.pipe()
        self._sender: threading.Thread | None = None
        self._reaped = False

        def child_main():
            os.setpgid(0, 0)
            os.close(self._payload)
            os.close(self._messages)
            prepare()
            with os.fdopen(payload_read, "rb") as pipe:
                data = pipe.read()
            if not data:  # closed without work
                return None
            return work(pickle.loads(data), lambda message: _send_message(messages_write, message))

        self.child = Child(child_main)
        try:
            os.setpgid(self.child.pid, self.child.pid)  # also here: close() may come before the child's own call
        except OSError:  # the child did it first (or has already ended)
            pass
        os.close(payload_read)
        os.close(messages_write)

    def start(self, payload) -> None:
        """Send the child its work's payload."""
        data, fd = pickle.dumps(payload, protocol=pickle.HIGHEST_PROTOCOL), self._payload
        self._payload = None

        def send():
            try:
                with os.fdopen(fd, "wb") as pipe:
                    pipe.write(data)
            except BrokenPipeError:  # the child ended before reading it: wait() says how
                pass

        self._sender = threading.Thread(target=send, daemon=True)
        self._sender.start()

    def wait(self, on_message: Callable[[object], None] | None = None):
        """The child's result, its messages passed to `on_message` first; ChildFailed as for a Child."""
        if self._sender is not None:
            self._sender.join()
        with os.fdopen(self._messages, "rb", buffering=0) as messages:
            self._messages = None
            while (message := self._next_message(messages)) is not None:
                if on_message is not None:
                    on_message(message)
        try:
            result = self.child.wait()
        except ChildFailed:  # reaped all the same
            self._reaped = True
            raise
        self._reaped = True
        return result

    def _next_message(self, messages):
        """The next message, or None once the child's result is there (or it has ended) and every message
        it sent before is read."""
        ready = select.select([messages, self.child], [], [])[0]
        if messages not in ready and not select.select([messages], [], [], 0)[0]:
            return None
        return _read_message(messages)  # None at the messages' end: the child and its children have ended

    def close(self) -> None:
        """End the child and the children it forked, unless it has been waited for, and reap it."""
        for fd in (self._payload, self._messages):
            if fd is not None:
                os.close(fd)
        self._payload = self._messages = None
        if self._reaped:
            return
        try:
            os.killpg(self.child.pid, signal.SIGTERM)
        except OSError:  # it has ended, and the group with it
            pass
        wait_all([self.child])
        self._reaped = True


def _fresh_standard_streams() -> None:
    """sys.stdout and sys.stderr opened anew on their descriptors, in a forked child: a thread of the
    parent inside a write to one at the fork (a progress bar's refresh) leaves its lock held for good
    there, and a child may well write (a library's warning). Buffered as Python buffers them (stderr by
    line); streams without a descriptor (a test's capture) stay."""
    for name, buffering in (("stdout", -1), ("stderr", 1)):
        stream = getattr(sys, name)
        try:
            fd = stream.fileno()
        except (AttributeError, OSError, ValueError):
            continue
        setattr(sys, name, open(fd, "w", buffering=buffering, encoding=getattr(stream, "encoding", None) or "utf-8",
                                errors="backslashreplace", closefd=False))


def _send_message(fd: int, message) -> None:
    data = pickle.dumps(message, protocol=pickle.HIGHEST_PROTOCOL)
    os.write(fd, len(data).to_bytes(4, "little") + data)  # one write under PIPE_BUF: never interleaved


def _read_message(pipe):
    """The next message on `pipe`, or None at its end."""
    head = pipe.read(4)
    if len(head) < 4:
        return None
    size, data = int.from_bytes(head, "little"), b""
    while len(data) < size:
        data += pipe.read(size - len(data))
    return pickle.loads(data)
