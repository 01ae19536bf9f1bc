"""Forked children (uqflight.forking): results through the pipe, failures reported, the first one done."""
import os
import time

import pytest

from uqflight.forking import FORKS, Child, ChildFailed, first_done, wait_all

pytestmark = pytest.mark.skipif(not FORKS, reason="the system cannot fork")


def test_a_childs_result_comes_back_and_a_failure_is_reported():
    outcomes = wait_all([Child(lambda: {"pid": os.getpid()}), Child(lambda: 1 / 0), Child(lambda: os._exit(9))])
    assert outcomes[0]["pid"] != os.getpid()
    assert isinstance(outcomes[1], ChildFailed) and "exit 1" in str(outcomes[1])
    assert isinstance(outcomes[2], ChildFailed) and "exit 9" in str(outcomes[2])


def test_first_done_is_the_child_that_finished_not_the_oldest():
    slow = Child(lambda: time.sleep(5) or "slow")
    quick = Child(lambda: "quick")
    children = [slow, quick]
    assert first_done(children) == 1
    assert quick.wait() == "quick"
    os.kill(slow.pid, 9)  # not waited for its sleep: killed, and reported as such
    with pytest.raises(ChildFailed, match="signal 9"):
        slow.wait()
