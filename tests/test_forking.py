"""Forked children (uqflight.running.forking): results through the pipe, failures reported, jobs shared."""
import os
import time

import pytest

from uqflight.running.forking import FORKS, Child, ChildFailed, PreparedChild, share_work, wait_all

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


def test_a_standby_gets_ready_then_does_its_work_telling_on_the_way(tmp_path):
    def prepare():
        (tmp_path / "ready").write_text(str(os.getpid()))

    def work(payload, tell):
        for k in range(3):
            tell(("step", k))
        return {"twice": [2 * x for x in payload], "pid": os.getpid(), "group": os.getpgid(0)}

    prepared = PreparedChild(prepare, work)
    prepared.start(list(range(100000)))  # larger than a pipe holds: sent from a thread, this process goes on
    messages = []
    result = prepared.wait(messages.append)
    prepared.close()  # after a wait: nothing left to do
    assert messages == [("step", 0), ("step", 1), ("step", 2)]
    assert result["twice"] == [2 * x for x in range(100000)]
    assert result["pid"] != os.getpid() and result["group"] == result["pid"]  # a process group of its own
    assert (tmp_path / "ready").read_text() == str(result["pid"])


def test_a_standby_closed_before_its_work_ends_without_doing_it(tmp_path):
    prepared = PreparedChild(lambda: None, lambda payload, tell: (tmp_path / "worked").write_text(""))
    prepared.close()
    assert not (tmp_path / "worked").exists()
    with pytest.raises(ChildProcessError):  # reaped
        os.waitpid(prepared.child.pid, os.WNOHANG)


def test_closing_a_working_standby_ends_it_and_the_children_it_forked(tmp_path):
    def work(payload, tell):
        helper = Child(lambda: time.sleep(120))
        (tmp_path / "helper").write_text(str(helper.pid))
        time.sleep(120)

    prepared = PreparedChild(lambda: None, work)
    prepared.start(None)
    for _ in range(3000):
        if (tmp_path / "helper").exists() and (tmp_path / "helper").read_text():
            break
        time.sleep(0.01)
    helper = int((tmp_path / "helper").read_text())
    prepared.close()  # without it this test waits two minutes for the prepared child
    with pytest.raises(ChildProcessError):
        os.waitpid(prepared.child.pid, os.WNOHANG)
    for _ in range(3000):  # the helper, the prepared child's own child, ends too (then reaped by init)
        if not alive(helper):
            break
        time.sleep(0.01)
    assert not alive(helper)


def test_a_standby_whose_work_fails_is_reported_with_its_error(capfd):
    prepared = PreparedChild(lambda: None, lambda payload, tell: payload / 0)
    prepared.start(1)
    with pytest.raises(ChildFailed, match="exit 1"):
        prepared.wait()
    prepared.close()
    assert "ZeroDivisionError" in capfd.readouterr().err


@pytest.mark.parametrize("kind", ["child", "prepared"])
def test_a_child_writes_to_stderr_even_when_the_parent_held_it_at_the_fork(kind, monkeypatch, capfd):
    """As for a failing Child, but the child writes through sys.stderr itself (a library's warning while
    a prepared child imports, or while a child draws): it gets sys.stderr opened anew on its descriptor."""
    import io
    import sys
    import threading

    inside, release = threading.Event(), threading.Event()

    class Stalling(io.RawIOBase):  # the standard error, whose write stalls (a refresh in progress)
        def writable(self):
            return True

        def fileno(self):
            return 2

        def write(self, data):
            inside.set()
            release.wait()
            return len(data)

    blocked = io.TextIOWrapper(io.BufferedWriter(Stalling()), write_through=True)
    monkeypatch.setattr("sys.stderr", blocked)
    writer = threading.Thread(target=lambda: blocked.write("r" * 100000), daemon=True)  # beyond its buffer
    writer.start()
    assert inside.wait(60)  # the writer is inside its write, holding the stream's lock
    def warn():
        print(f"warning from the {kind}", file=sys.stderr)
        return "done"

    if kind == "prepared":
        prepared = PreparedChild(warn, lambda payload, tell: "done")
        prepared.start(None)
        child = prepared.child
    else:
        child = Child(warn)
    done = first_ready(child, 60.0)
    if not done:
        os.kill(child.pid, 9)
    try:
        assert done, f"the {kind} hung on sys.stderr's lock"
        assert (prepared.wait() if kind == "prepared" else child.wait()) == "done"
    finally:
        if kind == "prepared":
            prepared.close()
        release.set()
    assert f"warning from the {kind}" in capfd.readouterr().err


def alive(pid: int) -> bool:
    """Whether process `pid` exists and is not a zombie."""
    try:
        with open(f"/proc/{pid}/stat") as stat:
            return stat.read().rsplit(")", 1)[1].split()[0] != "Z"
    except FileNotFoundError:
        return False


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


KILLED_PARENT = """
import os, sys, time
from uqflight.running.forking import Child, PreparedChild

def work(payload, tell):
    helper = Child(lambda: time.sleep(120))
    print(helper.pid, flush=True)
    time.sleep(120)

child = Child(lambda: time.sleep(120))
print(child.pid, flush=True)
PreparedChild(lambda: None, work).start(None)
time.sleep(120)
"""


def test_children_die_with_a_parent_killed_outright(tmp_path):
    """A parent killed by SIGKILL (no handler runs) takes its children along: a Child, and a PreparedChild with the
    helper it forked. Without it they would each sleep on for two minutes."""
    import signal
    import subprocess
    import sys

    parent = subprocess.Popen([sys.executable, "-c", KILLED_PARENT], stdout=subprocess.PIPE, text=True)
    try:
        child, helper = int(parent.stdout.readline()), int(parent.stdout.readline())
        assert alive(child) and alive(helper)
    finally:
        parent.send_signal(signal.SIGKILL)
        parent.wait()
    for _ in range(3000):
        if not alive(child) and not alive(helper):
            break
        time.sleep(0.01)
    assert not alive(child) and not alive(helper)
