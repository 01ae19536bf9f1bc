"""uqflight.running.stopping: a SIGINT or SIGTERM stops a campaign even when the handler's exception is lost."""
import os
import signal
import weakref

import pytest

from uqflight.running import stopping


def _signal_inside_a_weakref_callback(number: int) -> None:
    """Deliver `number` while Python runs a weakref callback: the handler's exception is printed and dropped."""
    class Thing:
        pass

    def callback(_):
        os.kill(os.getpid(), number)
        for _ in range(10_000):  # bytecode for the pending handler to run in, here
            pass

    thing = Thing()
    ref = weakref.ref(thing, callback)  # noqa: F841 (kept alive so that its callback runs)
    del thing


@pytest.mark.filterwarnings("ignore::pytest.PytestUnraisableExceptionWarning")
@pytest.mark.parametrize("number, stop", [(signal.SIGTERM, stopping.Terminated), (signal.SIGINT, KeyboardInterrupt)])
def test_a_stop_whose_exception_a_callback_swallowed_is_raised_by_check_once(number, stop):
    previous = stopping.install()
    try:
        _signal_inside_a_weakref_callback(number)  # returns: the exception was lost
        with pytest.raises(stop):
            stopping.check()
        stopping.check()  # raised once, not again during the clean-up that follows
    finally:
        stopping.restore(previous)
    assert signal.getsignal(number) is previous[number]


def test_a_stop_caught_by_the_command_is_forgotten_when_it_restores_the_handlers():
    previous = stopping.install()
    try:
        with pytest.raises(stopping.Terminated):
            os.kill(os.getpid(), signal.SIGTERM)
            for _ in range(10_000):
                pass
    finally:
        stopping.restore(previous)
    stopping.check()  # nothing pending
