"""Work done in a forked child while the parent goes on (figures written in the background, runs split
over processes). The child inherits the parent's memory, so nothing is pickled on the way in; its
result comes back pickled through a pipe. It runs no handler of the parent's and leaves with
os._exit; a child that fails or dies is reported as such when waited for."""
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
                traceback.print_exc()
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


def wait_all(children: list[Child]) -> list:
    """Wait for every child in turn: its result, or the ChildFailed saying how it failed, in their order."""
    outcomes = []
    for child in children:
        try:
            outcomes.append(child.wait())
        except ChildFailed as exc:
            outcomes.append(exc)
    return outcomes


def first_done(children: list[Child]) -> int:
    """The index of a child among `children` that has finished (or is writing its result), waiting
    until one has."""
    ready, _, _ = select.select(children, [], [])
    return children.index(ready[0])
