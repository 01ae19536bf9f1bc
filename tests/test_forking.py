"""Forked children (uqflight.forking): results through the pipe, failures reported, jobs shared."""
import os
import time

import pytest

from uqflight.forking import FORKS, Child, ChildFailed, share_work, wait_all

pytestmark = pytest.mark.skipif(not FORKS, reason="the system cannot fork")


def test_a_childs_result_comes_back_and_a_failure_is_reported():
    outcomes = wait_all([Child(lambda: {"pid": os.getpid()}), Child(lambda: 1 / 0), Child(lambda: os._exit(9))])
    assert outcomes[0]["pid"] != os.getpid()
    assert isinstance(outcomes[1], ChildFailed) and "exit 1" in str(outcomes[1])
    assert isinstance(outcomes[2], ChildFailed) and "exit 9" in str(outcomes[2])


def test_shared_jobs_each_run_once_and_come_back_in_their_order(tmp_path):
    def job(k):
        (tmp_path / f"{k}-{os.getpid()}").write_text("")  # who ran it
        time.sleep(0.02)
        return k * k

    order = list(range(12))[::-1]  # taken from the last: the results still come back in the jobs' order
    assert share_work([lambda k=k: job(k) for k in range(12)], order, processes=3) == [k * k for k in range(12)]
    runs = sorted(path.name.split("-") for path in tmp_path.iterdir())
    assert sorted(int(k) for k, _ in runs) == list(range(12))  # each job once
    started = []
    assert share_work([lambda: 1, lambda: 2], processes=1, starting=started.append) == [1, 2]
    assert started == [0, 1]  # without children, every job here, each told as it starts


def test_a_job_failing_here_is_raised_after_the_children_are_reaped():
    parent = os.getpid()

    def job():
        if os.getpid() == parent:
            raise ZeroDivisionError("here")
        time.sleep(0.3)

    with pytest.raises(ZeroDivisionError, match="here"):
        share_work([job] * 6, processes=2)
    with pytest.raises(ChildProcessError):  # no child of this test left running or unreaped
        os.waitpid(-1, os.WNOHANG)


def test_a_failing_child_tells_its_error_even_when_the_parent_held_stderr_at_the_fork(monkeypatch, capfd):
    """A thread of the parent inside a write to sys.stderr at the fork (as a progress bar's refresh can
    be) leaves the child a lock no one will release: the child's traceback goes to the descriptor."""
    import io
    import threading

    read, write = os.pipe()
    blocked = io.TextIOWrapper(io.BufferedWriter(io.FileIO(write, "w")), write_through=True)
    monkeypatch.setattr("sys.stderr", blocked)
    def write():
        try:
            blocked.write("x" * (1 << 20))
        except OSError:  # the pipe closed, at the end
            pass

    writer = threading.Thread(target=write, daemon=True)
    writer.start()  # more than the pipe holds: it blocks inside the write, holding the buffer's lock
    for _ in range(3000):  # until the pipe is full: then the writer is blocked inside its write
        if queued(read) >= 60000:
            break
        time.sleep(0.01)
    assert queued(read) >= 60000
    child = Child(lambda: 1 / 0)
    done = first_ready(child, 60.0)
    if not done:
        os.kill(child.pid, 9)
    with pytest.raises(ChildFailed):
        child.wait()
    os.close(read)  # the writer's write fails now, and it ends
    assert done, "the child hung on sys.stderr's lock"
    assert "ZeroDivisionError" in capfd.readouterr().err


def first_ready(child: Child, timeout: float) -> bool:
    import select

    return bool(select.select([child], [], [], timeout)[0])


def queued(fd: int) -> int:
    """The bytes waiting in a pipe."""
    import array
    import fcntl
    import termios

    count = array.array("i", [0])
    fcntl.ioctl(fd, termios.FIONREAD, count)
    return count[0]
