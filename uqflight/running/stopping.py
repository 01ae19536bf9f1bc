"""A stop asked for by SIGINT or SIGTERM, delivered even when its exception is lost.

Python runs a signal handler at the next bytecode of the main thread. When that bytecode is inside a
weakref callback or a __del__, the exception the handler raises is printed ("Exception ignored in
...") and dropped, and a campaign would fly on to its end. The handlers here also record the request,
and the long loops call `check()`, which raises it again; the command that catches the stop clears it
(`restore`)."""
from __future__ import annotations

import signal


class Terminated(KeyboardInterrupt):
    """SIGTERM, handled like SIGINT: a clean stop."""


_pending: list[type[KeyboardInterrupt]] = []  # the stops asked for and not yet caught


def _handler(signum, frame):
    stop = Terminated if signum == signal.SIGTERM else KeyboardInterrupt
    _pending.append(stop)
    raise stop()


def install() -> dict:
    """Handle SIGINT and SIGTERM as stops (also when SIGINT was inherited ignored, as by `cmd &` in a
    script: Ctrl-C or kill -INT would be lost otherwise); the previous handlers, for `restore`."""
    return {number: signal.signal(number, _handler) for number in (signal.SIGINT, signal.SIGTERM)}


def restore(previous: dict) -> None:
    """Put the previous handlers back and forget any stop: the command has handled it."""
    for number, handler in previous.items():
        signal.signal(number, handler)
    _pending.clear()


def check() -> None:
    """Raise the stop asked for since `install` whose exception may have been lost (once)."""
    if _pending:
        stop = _pending[-1]
        _pending.clear()
        raise stop()
