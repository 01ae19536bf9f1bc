"""Work done in a forked child while the parent goes on (the data files beside the page's imports, runs
split over processes, the report's sections shared between processes). The child inherits the parent's
memory, so nothing is pickled on the way in; its result comes back pickled through a pipe. It runs no
handler of the parent's and leaves with os._exit; a child that fails or dies is reported as such when
waited for."""
from __future__ import annotations

import gc
import os
import pickle
import select
import traceback
from typing import Callable

FORKS = hasattr(os, "fork")  # where the system cannot fork, callers do the work themselves


class ChildFailed(RuntimeError):
    """A child that raised (its traceback printed to stderr) or died; the message says which."""


class Child:
    """A forked child doing `work()`; `wait()` gives its result."""

    def __init__(self, work: Callable[[], object]):
        read, write = os.pipe()
        gc.freeze()  # the parent's objects stay out of the child's collections: fewer pages copied on write
        self.pid = os.fork()
        if self.pid == 0:  # the child
            os.close(read)
            code = 0
            try:
                payload = pickle.dumps(work(), protocol=pickle.HIGHEST_PROTOCOL)
                with os.fdopen(write, "wb") as pipe:
                    pipe.write(payload)
            except BaseException:
                _tell_error(traceback.format_exc())
                code = 1
            os._exit(code)
        gc.unfreeze()
        os.close(write)
        self._read = read

    def fileno(self) -> int:
        """The pipe the result comes through: readable once the child has written it, or has ended."""
        return self._read

    def wait(self):
        """The child's result; ChildFailed when it raised or died."""
        with os.fdopen(self._read, "rb") as pipe:  # read first: a large result would block the child
            payload = pipe.read()
        status = os.waitstatus_to_exitcode(os.waitpid(self.pid, 0)[1])
        if status < 0:
            raise ChildFailed(f"died (signal {-status})")
        if status != 0 or not payload:
            raise ChildFailed(f"failed (exit {status})")
        return pickle.loads(payload)


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
    """Wait for every child in turn: its result, or the ChildFailed saying how it failed, in their order."""
    outcomes = []
    for child in children:
        try:
            outcomes.append(child.wait())
        except ChildFailed as exc:
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
        if isinstance(outcome, ChildFailed):
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
